"""One value of a problem file checked against its key: type, finiteness, rule, choices, arrays of
numbers and arrays of tables; every message names the file, the ``[section] key`` and the value."""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping

from ocp_crawl.problem.messages import format_value, suggest, toml_type
from ocp_crawl.ocp.objectives import check_terms
from ocp_crawl.problem.keys import MAX_ARRAY, TYPE_WORDS, Key, ProblemError, Tables
from ocp_crawl.problem.schema import constraint_error


class Context:
    """Where values came from, for messages: the file, and which keys were set on the command
    line."""

    def __init__(self, source: str, overridden: set[tuple[str, str]] | None = None):
        self.source = source
        self.overridden = overridden or set()

    @property
    def base(self) -> Path:
        """The directory relative file names in the problem are read from: the problem file's (else
        the current)."""
        return Path(self.source).parent if not self.source.startswith("<") else Path.cwd()

    def at(self, section: str, key: str, value: Any) -> str:
        origin = " (from --set)" if (section, key) in self.overridden else ""
        return f"{self.source}: [{section}] {key} = {format_value(value)}{origin}"

    def error(self, msg: str) -> ProblemError:
        return ProblemError(f"{self.source}: {msg}")


def _check_array(ctx: Context, section: str, key: Key, value: Any) -> list[float]:
    """An array key's value as a list of floats (JSON's and TOML's arrays), each finite and passing
    the key's rule."""
    where = ctx.at(section, key.name, value)
    if not isinstance(value, (list, tuple)):
        raise ProblemError(f"{where} is invalid: expected {TYPE_WORDS[list]} ({key.what}), "
                           f"got {toml_type(value)}")
    if len(value) > MAX_ARRAY:
        raise ProblemError(f"{where} is invalid: {len(value)} entries, at most {MAX_ARRAY} "
                           f"({key.what})")
    for j, v in enumerate(value):
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ProblemError(f"{where} is invalid: entry {j} is {toml_type(v)}, expected a "
                               f"number ({key.what})")
        if not math.isfinite(v):
            raise ProblemError(f"{where} is invalid: entry {j} = {format_value(v)} must be finite "
                               f"({key.what})")
        if key.rule is not None and not key.rule.test(v):
            raise ProblemError(f"{where} is invalid: entry {j} = {format_value(v)} must be "
                               f"{key.rule.text} ({key.what})")
    return [float(v) for v in value]


def _check_tables(ctx: Context, section: str, key: Key, value: Any) -> list[dict]:
    """An array-of-tables key's value (``[[ocp.constraint]]``): each table checked by the key's
    rule."""
    where = ctx.at(section, key.name, value)
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, Mapping) for v in value):
        raise ProblemError(f"{where} is invalid: expected {TYPE_WORDS[Tables]}, one "
                           f"[[{section}.{key.name}]] table each ({key.what})")
    for j, table in enumerate(value):
        wrong = constraint_error(table)
        if wrong is not None:
            raise ProblemError(f"{where} is invalid: table {j + 1}: {wrong}")
    return [dict(table) for table in value]


def _check_table(ctx: Context, section: str, key: Key, value: Any) -> dict:
    """A table key's value: ``[ocp.terms]`` quantities and their weights; ``[ocp.ipopt]`` names and
    finite numbers or strings, then the names and ranges as IPOPT checks them."""
    from ocp_crawl.nlp.ipopt import check_ipopt_options

    where = ctx.at(section, key.name, value)
    if not isinstance(value, Mapping):
        raise ProblemError(f"{where} is invalid: expected {TYPE_WORDS[dict]}, a "
                           f"[{section}.{key.name}] table ({key.what})")
    if key.name == "terms":  # quantity -> weight
        for name, weight in value.items():
            if isinstance(weight, bool) or not isinstance(weight, (int, float)):
                raise ProblemError(f"{where} is invalid: the weight of {name} is "
                                   f"{toml_type(weight)} ({format_value(weight)}), expected a "
                                   "number")
        try:
            check_terms(value)
        except ValueError as exc:
            raise ProblemError(f"{where} is invalid: "
                               f"{str(exc).replace('OCPSettings.terms: ', '')}") from None
        return dict(value)
    try:
        options = check_ipopt_options(f"[{section}.{key.name}]", dict(value), by_ipopt=True)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"{where} is invalid: {exc}") from None
    return options


def check_value(ctx: Context, section: str, key: Key, value: Any) -> Any:
    where = ctx.at(section, key.name, value)
    if key.type is dict:
        return _check_table(ctx, section, key, value)
    if key.type is list:
        return _check_array(ctx, section, key, value)
    if key.type is Tables:
        return _check_tables(ctx, section, key, value)
    if key.type is str:
        if not isinstance(value, str):
            raise ProblemError(f"{where} is invalid: expected a string, {key.valid_text} "
                               f"({key.what}), got {toml_type(value)}")
        if key.choices and value not in key.choices:
            hint = suggest(value, key.choices)
            raise ProblemError(f"{where} is invalid: {hint}must be {key.valid_text} ({key.what})")
        return value
    numeric = isinstance(value, (int, float)) and not isinstance(value, bool)
    if key.type is int and not (numeric and isinstance(value, int)):
        raise ProblemError(f"{where} is invalid: expected {TYPE_WORDS[int]} ({key.what}), "
                           f"got {toml_type(value)}")
    if key.type is float and not numeric:
        raise ProblemError(f"{where} is invalid: expected {TYPE_WORDS[float]} ({key.what}), "
                           f"got {toml_type(value)}")
    try:
        value = key.type(value)
        finite = math.isfinite(value)
    except OverflowError:  # an integer of hundreds of digits
        bound = f"{key.rule.text}, " if key.rule is not None else ""
        raise ProblemError(f"{where} is invalid: too large, must be {bound}finite "
                           f"({key.what})") from None
    if not finite:
        raise ProblemError(f"{where} is invalid: must be finite ({key.what})")
    if key.rule is not None and not key.rule.test(value):
        why = f": {key.rule.why}" if key.rule.why else ""
        raise ProblemError(f"{where} is invalid: must be {key.rule.text} ({key.what}){why}")
    return value
