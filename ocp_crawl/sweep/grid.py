"""Grids of a sweep: axes ``SECTION.KEY=START:STOP:NUM``, ``SECTION.KEY=START:STOP:step=STEP`` or
``SECTION.KEY=A,B,C``, typed by the schema.

A grid is ``{key: values}``, one axis per problem key (the first key varies slowest); its values
are typed after the schema (float, int or str), checked against the key's rule, and set on the
base problem with :meth:`~ocp_crawl.problem.Problem.with_values` (no text round trip).
"""
from __future__ import annotations

import dataclasses
import difflib
import itertools
import math
import re
import tomllib
from decimal import Decimal, localcontext
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from ocp_crawl.checks import is_finite, parse_integer, parse_number, short_repr
from ocp_crawl.problem import SCHEMA, Key, Problem, ProblemError
from ocp_crawl.problem.overrides import INDEX, entry, toml_loads

_GRID_KEY_RE = re.compile(rf"^([A-Za-z0-9_-]+)\.([A-Za-z0-9_-]+)({INDEX})?$")
#: numpy dtype of the values of a key of each schema type
VALUE_DTYPES = {str: str, int: np.int64, float: np.float64}
#: most points of one sweep (and values of one axis): a point takes 0.03 to 1 s with the event
#: solver, so 20,000 points are 10 to 20 minutes of the paper's gaits on 2 cores (the full reproduce
#: grids have 777 at most)
MAX_GRID_POINTS = 20_000
_GRID_HELP = ("expected SECTION.KEY=START:STOP:NUM (NUM values), SECTION.KEY=START:STOP:step=STEP "
              "or SECTION.KEY=A,B,C, e.g. gait.psi_deg=0:180:37 or gait.psi_deg=0:180:step=5 "
              "(an array's entry: SECTION.KEY[i], e.g. robot.stiffness[1]=0.1:0.5:5)")
#: relative tolerance of "STEP divides STOP - START" (decimal steps such as 0.1 are not exact in
#: binary)
STEP_RTOL = 1e-9
#: values of an axis echoed one by one; longer axes are shown by their first and last values and
#: step
ECHO_ALL = 20


def schema_key(name: str, where: str) -> Key:
    """The schema entry of a grid key ``section.key``, or of ``section.key[i]`` (entry i of an
    array key: a number under the array's rule); unknown keys raise ProblemError with a hint."""
    m = _GRID_KEY_RE.match(name)
    if not m:
        raise ProblemError(f"{where} is invalid: the key {name!r} must be SECTION.KEY "
                           f"({_GRID_HELP})")
    section, key, index = m.groups()
    if section not in SCHEMA:
        close = difflib.get_close_matches(section, list(SCHEMA), n=1)
        hint = f"did you mean {close[0]}? " if close else ""
        raise ProblemError(f"{where} is invalid: unknown section [{section}]; {hint}valid "
                           f"sections: {', '.join(SCHEMA)}")
    keys = SCHEMA[section].key_map
    if key not in keys:
        close = difflib.get_close_matches(key, list(keys), n=1)
        hint = f"did you mean {section}.{close[0]}? " if close else ""
        raise ProblemError(f"{where} is invalid: unknown key {key} in [{section}]; {hint}valid "
                           f"keys: {', '.join(keys)}")
    if index is not None and keys[key].type is list:
        return dataclasses.replace(keys[key], name=key + index, type=float)
    if keys[key].type not in (float, int, str) or index is not None:
        what = ("an array key (an axis may vary one of its entries, e.g. "
                f"{section}.{key}[0])" if keys[key].type is list else
                "a table key" if index is None else "not an array key")
        raise ProblemError(f"{where} is invalid: {section}.{key} is {what}; an axis varies a "
                           "number or a string")
    return keys[key]


def _coerce(values: Sequence[Any] | np.ndarray, key: Key, name: str, where: str) -> np.ndarray:
    """Values of one axis as a 1-D array of the key's type; wrong types and duplicates raise
    ProblemError."""
    if len(values) == 0:
        raise ProblemError(f"{where} is invalid: no values ({_GRID_HELP})")
    out: list[Any] = []
    for v in values:
        v = v.item() if isinstance(v, np.generic) else v
        if key.type is str:
            if not isinstance(v, str):
                raise ProblemError(f"{where} is invalid: {name} takes strings, {key.valid_text}; "
                                   f"got {v!r}")
            if key.choices and v not in key.choices:
                raise ProblemError(f"{where} is invalid: {name} = {v!r} must be {key.valid_text}")
        else:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ProblemError(f"{where} is invalid: {name} takes numbers ({key.what}); got "
                                   f"{v!r}")
            if not is_finite(v):
                raise ProblemError(f"{where} is invalid: {name} = {short_repr(v)} must be finite")
            if key.type is int:
                if v != int(v):
                    raise ProblemError(f"{where} is invalid: {name} takes integers ({key.what}); "
                                       f"got {v!r}")
                v = int(v)
            else:
                v = float(v)
            # a value its own key rejects makes every point with it invalid: bad input, not data
            if key.rule is not None and not key.rule.test(v):
                raise ProblemError(f"{where} is invalid: {name} = {v!r} must be {key.rule.text} "
                                   f"({key.what})")
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
            # Python spellings TOML lacks, e.g. "1e3" is TOML but "1." is not
            return parse_number(text)
        except ValueError:
            raise ProblemError(f"{where} is invalid: {text!r} is not a number") from None


def _endpoints(parts: Sequence[str], where: str) -> tuple[float, float]:
    """START and STOP of a range as finite numbers."""
    try:
        start, stop = parse_number(parts[0]), parse_number(parts[1])
    except ValueError:
        raise ProblemError(f"{where} is invalid: START and STOP must be numbers, got {parts[0]!r}, "
                           f"{parts[1]!r}") from None
    for name, text, value in (("START", parts[0], start), ("STOP", parts[1], stop)):
        if not math.isfinite(value):
            raise ProblemError(f"{where} is invalid: START and STOP must be finite, got {name} = "
                               f"{text}")
    return start, stop


def _count(text: str, where: str) -> int:
    """NUM of a range: an integer in [1, MAX_GRID_POINTS]."""
    try:
        num = parse_integer(text)
    except ValueError:
        raise ProblemError(f"{where} is invalid: NUM must be an integer >= 1, got {text!r} (for a "
                           f"step write START:STOP:step=STEP)") from None
    if num < 1:
        raise ProblemError(f"{where} is invalid: NUM must be an integer >= 1, got {num}")
    if num > MAX_GRID_POINTS:
        raise ProblemError(f"{where} is invalid: NUM = {text} is more than the {MAX_GRID_POINTS} "
                           "points a sweep may have (about 10 to 20 minutes on 2 cores); split the "
                           "sweep")
    return num


def _step_count(start: float, stop: float, text: str, where: str) -> int:
    """The number of values of ``START:STOP:step=STEP``: STEP must be a non-zero number that divides
    STOP - START (to :data:`STEP_RTOL`) and points from START towards STOP."""
    try:
        step = parse_number(text)
    except ValueError:
        raise ProblemError(f"{where} is invalid: STEP must be a number, got {text!r}") from None
    if not math.isfinite(step) or step == 0:
        raise ProblemError(f"{where} is invalid: STEP must be a finite non-zero number, got {text}")
    span = stop - start
    if span != 0 and (span > 0) != (step > 0):
        raise ProblemError(f"{where} is invalid: STEP = {text} goes away from STOP; "
                           f"use step={value_text(-step)}")
    intervals = span / step
    n = round(intervals)
    if abs(intervals - n) > STEP_RTOL * max(1.0, abs(intervals)):
        below = start + math.floor(intervals) * step
        raise ProblemError(f"{where} is invalid: STEP = {text} does not divide STOP - START = "
                           f"{value_text(span)}; the last value would be {value_text(below)}, "
                           "not STOP: change STOP or STEP")
    if n + 1 > MAX_GRID_POINTS:
        raise ProblemError(f"{where} is invalid: STEP = {text} gives {n + 1} values, more than the "
                           f"{MAX_GRID_POINTS} points a sweep may have (about 10 to 20 minutes on "
                           "2 cores); take a larger STEP")
    return n + 1


def _range(rhs: str, where: str) -> np.ndarray:
    """The values of a range ``START:STOP:NUM`` or ``START:STOP:step=STEP`` (both ends included)."""
    parts = [p.strip() for p in rhs.split(":")]
    if len(parts) != 3:
        raise ProblemError(f"{where} is invalid: a range is START:STOP:NUM or "
                           f"START:STOP:step=STEP, got {len(parts)} fields")
    start, stop = _endpoints(parts, where)
    form, _, value = parts[2].rpartition("=")
    form = form.strip().lower()
    if form not in ("", "num", "step"):
        raise ProblemError(f"{where} is invalid: the third field is NUM, num=NUM or step=STEP, got "
                           f"{parts[2]!r}")
    num = _step_count(start, stop, value.strip(),
                      where) if form == "step" else _count(value.strip(), where)
    if num == 1 and start != stop:
        raise ProblemError(f"{where} is invalid: NUM = 1 gives one value, but START != STOP; "
                           f"write a single value instead")
    if not math.isfinite(stop - start):
        raise ProblemError(f"{where} is invalid: STOP - START = {stop!r} - {start!r} overflows a "
                           "float; give closer ends")
    return np.array(decimal_linspace(start, stop, num))


def decimal_linspace(start: float, stop: float, num: int) -> list[float]:
    """``numpy.linspace(start, stop, num)`` computed in decimal from the ends as written (their
    shortest repr), each value then rounded once to a float: every value is the float of the decimal
    it stands for: ``0:0.3:4`` gives 0.0, 0.1, 0.2, 0.3 (numpy.linspace: 0.09999999999999999,
    0.19999999999999998)."""
    if num == 1:
        return [start]
    a, b = Decimal(repr(start)), Decimal(repr(stop))
    with localcontext() as ctx:
        ctx.prec = 60   # more digits than any two floats' difference needs to be rounded once
        inner = [float(a + (b - a) * i / (num - 1)) for i in range(1, num - 1)]
    return [start, *inner, stop]


def parse_grid(spec: str) -> tuple[str, np.ndarray]:
    """Parse one axis: ``SECTION.KEY=START:STOP:NUM`` (NUM values, both ends included, like
    ``numpy.linspace``; ``num=NUM`` says the same), ``SECTION.KEY=START:STOP:step=STEP`` (START,
    START + STEP, ... up to STOP included; STEP must divide STOP - START) or ``SECTION.KEY=A,B,C``
    (a list; one value is a list of one).

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
        return lhs, _coerce(_range(rhs, where), key, lhs, where)
    return lhs, _coerce([_list_item(t, key, where) for t in rhs.split(",")], key, lhs, where)


def normalize_grid(grid: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """Validate a grid ``{key: values}`` (arrays, lists or single values) and type its values."""
    if not isinstance(grid, Mapping) or not grid:
        raise ProblemError(f"a sweep needs a grid {{key: values}} with at least one key, got "
                           f"{grid!r}")
    out: dict[str, np.ndarray] = {}
    for name, values in grid.items():
        where = f"grid key {name!r}"
        key = schema_key(str(name), where)
        arr = np.asarray(values, dtype=object if key.type is str else None)
        if arr.ndim > 1:
            raise ProblemError(f"{where} is invalid: values must be 1-D, got shape {arr.shape}")
        out[str(name)] = _coerce(list(np.atleast_1d(arr)), key, str(name), where)
    _check_size(out)
    bases = {name: entry(name.split(".", 1)[1])[0] for name in out}   # (an entry: its array)
    for name, key in bases.items():
        section = name.split(".")[0]
        for other in SCHEMA[section].key_map[key].exclusive_with:
            clash = [n for n, k in bases.items() if n.startswith(f"{section}.") and k == other]
            if clash:
                raise ProblemError(f"grid keys {name} and {clash[0]} are alternatives: sweep one "
                                   "of them")
    return out


def _check_size(grid: Mapping[str, np.ndarray]) -> None:
    """A grid of more than MAX_GRID_POINTS points is a ProblemError stating the limit."""
    points = math.prod(len(v) for v in grid.values())
    if points > MAX_GRID_POINTS:
        shape = " x ".join(f"{len(v)} ({k})" for k, v in grid.items())
        raise ProblemError(f"the grid has {points} points, {shape}: more than the "
                           f"{MAX_GRID_POINTS} points a sweep may have (about 10 to 20 minutes on "
                           "2 cores); coarsen it or split the sweep")


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
    """Raise ProblemError if no point of the grid is a valid problem (checked in grid order up to
    the first valid point, usually the first: cheap).  Invalid points of a partly valid grid are
    data (status ``bad_input``); a grid of invalid points only is bad input."""
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


def value_text(v: Any) -> str:
    """A grid value as text: a float as its decimal to 12 significant digits (``0.05``, ``45``,
    ``1e-06``; never ``0.049999999999999996``), others as they are."""
    return f"{v:.12g}" if isinstance(v, float) else str(v)


def axis_text(values: Sequence[Any]) -> str:
    """The values of one axis as text, e.g. "0, 45, 90, 135, 180 (5 values, step 45)": every value
    up to :data:`ECHO_ALL` of them, else the first four and the last two (and the step of an evenly
    spaced axis)."""
    vals = list(values)
    texts = [value_text(v) for v in vals]
    text = ", ".join(texts if len(vals) <= ECHO_ALL else texts[:4] + ["..."] + texts[-2:])
    extra = f"{len(vals)} value{'s' if len(vals) != 1 else ''}"
    if len(vals) > 2 and all(isinstance(v, (int, float)) for v in vals):
        steps = np.diff(np.asarray(vals, float))
        if np.allclose(steps, steps[0], rtol=1e-9, atol=0.0):
            extra += f", step {value_text(float(steps[0]))}"
    return f"{text} ({extra})"
