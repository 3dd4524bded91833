"""Input and output: atomic files, JSON-safe values, the shipped paper data."""
