"""Command line ``ocp-crawl``: argument parsing and printing only; every command calls a library function."""
from ocp_crawl.cli.app import COMMANDS, main

__all__ = ["COMMANDS", "main"]
