"""Grids of a sweep: axes ``SECTION.KEY=START:STOP:NUM`` or ``SECTION.KEY=A,B,C``, typed by the schema.

A grid is ``{key: values}``, one axis per problem key (the first key varies slowest); its values
are typed after the schema (float, int or str), checked against the key's rule, and set on the
base problem with :meth:`~ocp_crawl.problem.Problem.with_values` (no text round trip).
"""
from __future__ import annotations

import difflib
import itertools
import math
import re
import tomllib
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from ocp_crawl.problem import SCHEMA, Key, Problem, ProblemError
from ocp_crawl.problem.overrides import toml_loads

_GRID_KEY_RE = re.compile(r"^([A-Za-z0-9_-]+)\.([A-Za-z0-9_-]+)$")
#: numpy dtype of the values of a key of each schema type
VALUE_DTYPES = {str: str, int: np.int64, float: np.float64}
#: most points of one sweep (and values of one axis): a point takes 0.03 to 1 s with the event solver, so 20,000
#: points are 10 to 20 minutes of the paper's gaits on 2 cores (the full reproduce grids have 777 at most)
MAX_GRID_POINTS = 20_000
_GRID_HELP = "expected SECTION.KEY=START:STOP:NUM or SECTION.KEY=A,B,C, e.g. gait.psi_deg=0:180:37"


def schema_key(name: str, where: str) -> Key:
    """The schema entry of a grid key ``section.key``; unknown keys raise ProblemError with a hint."""
    m = _GRID_KEY_RE.match(name)
    if not m:
        raise ProblemError(f"{where} is invalid: the key {name!r} must be SECTION.KEY ({_GRID_HELP})")
    section, key = m.groups()
    if section not in SCHEMA:
        close = difflib.get_close_matches(section, list(SCHEMA), n=1)
        hint = f"did you mean {close[0]}? " if close else ""
        raise ProblemError(f"{where} is invalid: unknown section [{section}]; {hint}valid sections: "
                           f"{', '.join(SCHEMA)}")
    keys = SCHEMA[section].key_map
    if key not in keys:
        close = difflib.get_close_matches(key, list(keys), n=1)
        hint = f"did you mean {section}.{close[0]}? " if close else ""
        raise ProblemError(f"{where} is invalid: unknown key {key} in [{section}]; {hint}valid keys: "
                           f"{', '.join(keys)}")
    return keys[key]


def _coerce(values: Sequence[Any], key: Key, name: str, where: str) -> np.ndarray:
    """Values of one axis as a 1-D array of the key's type; wrong types and duplicates raise ProblemError."""
    if len(values) == 0:
        raise ProblemError(f"{where} is invalid: no values ({_GRID_HELP})")
    out: list[Any] = []
    for v in values:
        v = v.item() if isinstance(v, np.generic) else v
        if key.type is str:
            if not isinstance(v, str):
                raise ProblemError(f"{where} is invalid: {name} takes strings, {key.valid_text}; got {v!r}")
            if key.choices and v not in key.choices:
                raise ProblemError(f"{where} is invalid: {name} = {v!r} must be {key.valid_text}")
        else:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ProblemError(f"{where} is invalid: {name} takes numbers ({key.what}); got {v!r}")
            if not math.isfinite(v):
                raise ProblemError(f"{where} is invalid: {name} = {v!r} must be finite")
            if key.type is int:
                if v != int(v):
                    raise ProblemError(f"{where} is invalid: {name} takes integers ({key.what}); got {v!r}")
                v = int(v)
            else:
                v = float(v)
            # a value its own key rejects makes every point with it invalid: bad input, not data
            if key.rule is not None and not key.rule.test(v):
                raise ProblemError(f"{where} is invalid: {name} = {v!r} must be {key.rule.text} ({key.what})")
        out.append(v)
    seen: set = set()
    for v in out:
        if v in seen:
            raise ProblemError(f"{where} is invalid: {name} = {v!r} appears twice; each value once")
        seen.add(v)
    return np.array(out, dtype=VALUE_DTYPES[key.type])


def _list_item(text: str, key: Key, where: str) -> Any:
    text = text.strip()
    if not text:
        raise ProblemError(f"{where} is invalid: empty value in the list ({_GRID_HELP})")
    try:
        return toml_loads(f"v = {text}", f"{where} is invalid")["v"]
    except tomllib.TOMLDecodeError:
        if key.type is str:
            return text  # bare words for string keys, as --set accepts them
        try:
            return float(text)  # Python spellings TOML lacks, e.g. "1e3" is TOML but "1." is not
        except ValueError:
            raise ProblemError(f"{where} is invalid: {text!r} is not a number") from None


def _range(parts: Sequence[str], where: str) -> tuple[float, float, int]:
    """START, STOP (finite numbers) and NUM (an integer in [1, MAX_GRID_POINTS]) of a range, as written."""
    try:
        start, stop = float(parts[0]), float(parts[1])
    except ValueError:
        raise ProblemError(f"{where} is invalid: START and STOP must be numbers, got {parts[0]!r}, "
                           f"{parts[1]!r}") from None
    for name, text, value in (("START", parts[0], start), ("STOP", parts[1], stop)):
        if not math.isfinite(value):
            raise ProblemError(f"{where} is invalid: START and STOP must be finite, got {name} = {text}")
    try:
        num = int(parts[2])
    except ValueError:
        raise ProblemError(f"{where} is invalid: NUM must be an integer >= 1, got {parts[2]!r}") from None
    if num < 1:
        raise ProblemError(f"{where} is invalid: NUM must be an integer >= 1, got {num}")
    if num > MAX_GRID_POINTS:
        raise ProblemError(f"{where} is invalid: NUM = {parts[2]} is more than the {MAX_GRID_POINTS} points a sweep "
                           "may have (about 10 to 20 minutes on 2 cores); split the sweep")
    return start, stop, num


def parse_grid(spec: str) -> tuple[str, np.ndarray]:
    """Parse one axis: ``SECTION.KEY=START:STOP:NUM`` (NUM values, both ends included, like
    ``numpy.linspace``) or ``SECTION.KEY=A,B,C`` (a list; one value is a list of one).

    Returns the key and its values (float, int or str array after the schema type of the key).
    Bad specs raise :class:`ProblemError` with a one-line message naming the spec.
    """
    if not isinstance(spec, str):
        raise ProblemError(f"--grid {spec!r} is invalid: {_GRID_HELP}")
    shown = spec.strip() if len(spec.strip()) <= 80 else spec.strip()[:77] + "..."
    where = f"--grid {shown!r}"
    if "=" not in spec:
        raise ProblemError(f"{where} is invalid: {_GRID_HELP}")
    lhs, rhs = (s.strip() for s in spec.split("=", 1))
    key = schema_key(lhs, where)
    if not rhs:
        raise ProblemError(f"{where} is invalid: no values ({_GRID_HELP})")
    if ":" in rhs and "," not in rhs and key.type is not str:
        parts = [p.strip() for p in rhs.split(":")]
        if len(parts) != 3:
            raise ProblemError(f"{where} is invalid: a range is START:STOP:NUM, got {len(parts)} fields")
        start, stop, num = _range(parts, where)
        if num == 1 and start != stop:
            raise ProblemError(f"{where} is invalid: NUM = 1 gives one value, but START != STOP; "
                               f"write {lhs}={parts[0]} for a single value")
        return lhs, _coerce(np.linspace(start, stop, num), key, lhs, where)
    return lhs, _coerce([_list_item(t, key, where) for t in rhs.split(",")], key, lhs, where)


def normalize_grid(grid: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """Validate a grid ``{key: values}`` (arrays, lists or single values) and type its values."""
    if not isinstance(grid, Mapping) or not grid:
        raise ProblemError(f"a sweep needs a grid {{key: values}} with at least one key, got {grid!r}")
    out: dict[str, np.ndarray] = {}
    for name, values in grid.items():
        where = f"grid key {name!r}"
        key = schema_key(str(name), where)
        arr = np.asarray(values, dtype=object if key.type is str else None)
        if arr.ndim > 1:
            raise ProblemError(f"{where} is invalid: values must be 1-D, got shape {arr.shape}")
        out[str(name)] = _coerce(list(np.atleast_1d(arr)), key, str(name), where)
    _check_size(out)
    names = list(out)
    for name in names:
        section, key = name.split(".")
        for other in SCHEMA[section].key_map[key].exclusive_with:
            if f"{section}.{other}" in out:
                raise ProblemError(f"grid keys {name} and {section}.{other} are alternatives: sweep one of them")
    return out


def _check_size(grid: Mapping[str, np.ndarray]) -> None:
    """A grid of more than MAX_GRID_POINTS points is a ProblemError stating the limit."""
    points = math.prod(len(v) for v in grid.values())
    if points > MAX_GRID_POINTS:
        shape = " x ".join(f"{len(v)} ({k})" for k, v in grid.items())
        raise ProblemError(f"the grid has {points} points, {shape}: more than the {MAX_GRID_POINTS} points a sweep "
                           "may have (about 10 to 20 minutes on 2 cores); coarsen it or split the sweep")


def grid_from_specs(specs: Iterable[str]) -> dict[str, np.ndarray]:
    """The grid of several ``--grid`` specs (in order); a key given twice raises ProblemError."""
    grid: dict[str, np.ndarray] = {}
    for spec in specs:
        name, values = parse_grid(spec)
        if name in grid:
            raise ProblemError(f"--grid {spec.strip()!r} is invalid: {name} is already a grid key")
        grid[name] = values
    return normalize_grid(grid)


def check_some_point_valid(problem: Problem, grid: Mapping[str, Any]) -> None:
    """Raise ProblemError if no point of the grid is a valid problem (checked in grid order up to the
    first valid point, usually the first: cheap).  Invalid points of a partly valid grid are data
    (status ``bad_input``); a grid of invalid points only is bad input."""
    grid = normalize_grid(grid)
    first = None
    n = 0
    for n, values in enumerate(itertools.product(*(v.tolist() for v in grid.values())), 1):
        try:
            problem.with_values(dict(zip(grid, values)))
            return
        except ProblemError as exc:
            first = first or exc
    raise ProblemError(f"{first} (every one of the {n} points of the grid is invalid; grid: "
                       f"{', '.join(f'{k} = {len(v)} values' for k, v in grid.items())})")
