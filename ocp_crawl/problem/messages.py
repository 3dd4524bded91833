"""Values in messages: a value as TOML writes it, what type it is in TOML's words, and the valid
name closest to a misspelt one (every one-line message of bad input uses them)."""
from __future__ import annotations

import difflib
import json
import math
from typing import Any, Mapping, Sequence


def format_value(value: Any, _depth: int = 0) -> str:
    """A value as it would be written in TOML (strings quoted), shortened to keep messages on one
    line (arrays and tables nested more than 3 deep shown as ``...``)."""
    if _depth > 3 and isinstance(value, (Mapping, list, tuple)):
        s = "..."
    elif isinstance(value, bool):
        s = "true" if value else "false"
    elif isinstance(value, str):
        s = json.dumps(value)
    elif isinstance(value, float):
        s = "nan" if math.isnan(value) else ("inf" if value == math.inf
                                             else "-inf" if value == -math.inf else repr(value))
    elif isinstance(value, Mapping):
        s = "{" + ", ".join(f"{k} = {format_value(v, _depth + 1)}"
                            for k, v in list(value.items())[:20]) + "}"
    elif isinstance(value, (list, tuple)):
        s = "[" + ", ".join(format_value(v, _depth + 1) for v in value[:20]) + "]"
    else:
        s = str(value)
    return s if len(s) <= 60 else s[:57] + "..."


def toml_type(value: Any) -> str:
    """What a value is, in TOML's words ("a boolean", "a table", ...), for messages."""
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, int):
        return "an integer"
    if isinstance(value, float):
        return "a number"
    if isinstance(value, Mapping):
        return "a table"
    if isinstance(value, (list, tuple)):
        return "an array"
    return f"a {type(value).__name__}"


def suggest(name: str, valid: Sequence[str]) -> str:
    """"did you mean X? " for the valid name closest to ``name``, or ""."""
    # case slips (Mu for mu) score lower with difflib than a shorter name (M), so they come first
    close = [v for v in valid if v.lower() == name.lower()] or \
        difflib.get_close_matches(name, list(valid), n=1, cutoff=0.6) or \
        sorted((v for v in valid if name.lower().startswith(v.lower())), key=len, reverse=True)
    return f"did you mean {close[0]}? " if close else ""
