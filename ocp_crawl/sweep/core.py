"""Parameter sweeps: S, W+ and CoT+ over a grid of problem keys, in parallel and resumable.

A sweep evaluates every point of a rectangular grid (one axis per problem key, e.g.
``gait.psi_deg``; the first key varies slowest) by setting the point's values on the base problem,
as ``--set`` would, and running :func:`~ocp_crawl.problem.core.run_problem`.  Each point gives one row:
the grid values, ``S``, ``W_plus``, ``CoT_plus``, ``status`` (the status name: ``success``,
``fold``, ``lift_off``, ..., or ``bad_input`` for a point whose problem is invalid, ``error`` for
an unexpected exception) and ``message``.  Failed points are data: they are recorded, never
dropped and never raised.

Points run in worker processes (``jobs``), or on a Dask cluster (``scheduler``).  With an output
directory the sweep writes:

``settings.json``
    the base problem, the grid, the solver and the package version; written first, and compared
    on ``resume`` so that a resumed sweep never mixes results of different settings.
``results.partial.csv``
    the journal: one line per finished point in completion order, flushed and fsync'd as it
    arrives, so that a killed run loses only the points in flight.
``results.csv``
    one row per point in grid order, written atomically when the sweep completes (the journal is
    then removed).  A resumed sweep writes the same file as an uninterrupted one.
``summary.json``
    counts by status, the best point, timing.

Nothing is lost when a sweep is killed (even by SIGKILL): settings.json, results.csv and
summary.json are written atomically (temporary file and rename, :mod:`ocp_crawl.io.files`); a journal
line torn by the kill is not a finished point and is cut off by the resuming run; the lock
(``.sweep.lock``, an advisory ``flock``) dies with its process, so a killed sweep never blocks its
resume; temporary files of the killed run are removed when the sweep is resumed or started again.
A resumed sweep writes the same results.csv, byte for byte, as an uninterrupted one.
"""
from __future__ import annotations

import csv
import difflib
import io
import itertools
import json
import math
import multiprocessing
import os
import re
import sys
import threading
import time
import tomllib
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from contextlib import closing
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Iterable, Iterator, Mapping, Sequence

import numpy as np

from ocp_crawl import __version__
from ocp_crawl.io.files import atomic_write, jsonable, remove_stale_temps, write_json
from ocp_crawl.problem.core import SCHEMA, Key, Problem, ProblemError, apply_overrides, load_problem, problem_from_dict, run_problem
from ocp_crawl.sim.result import ARRAY_FIELDS, CrawlResult

#: columns of every row after the grid keys
RESULT_COLUMNS = ("S", "W_plus", "CoT_plus", "status", "message")
#: statuses of points that did not produce a CrawlResult (the others are ``Status`` names)
BAD_INPUT, ERROR, MISSING = "bad_input", "error", "missing"
SUCCESS = "success"
#: solvers a sweep can use; "event": ``run_problem`` (event-driven for the torque drive,
#: prescribed angles for the angles drive)
SOLVERS = ("event",)

SETTINGS_FILE, JOURNAL_FILE, RESULTS_FILE, SUMMARY_FILE = (
    "settings.json", "results.partial.csv", "results.csv", "summary.json")
LOCK_FILE = ".sweep.lock"
FORMAT = "ocp_crawl.sweep/1"


class SweepError(ValueError):
    """A sweep that must not start: bad settings, an output directory holding another sweep, ..."""

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))


class SweepFailed(RuntimeError):
    """The sweep itself could not complete (a worker process died, the cluster went away)."""


# --------------------------------------------------------------------------------------------
# grids
# --------------------------------------------------------------------------------------------
_GRID_KEY_RE = re.compile(r"^([A-Za-z0-9_-]+)\.([A-Za-z0-9_-]+)$")
_GRID_HELP = "expected SECTION.KEY=START:STOP:NUM or SECTION.KEY=A,B,C, e.g. gait.psi_deg=0:180:37"


def _schema_key(name: str, where: str) -> Key:
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
    dtype = {str: str, int: np.int64, float: np.float64}[key.type]
    return np.array(out, dtype=dtype)


def _list_item(text: str, key: Key, where: str) -> Any:
    text = text.strip()
    if not text:
        raise ProblemError(f"{where} is invalid: empty value in the list ({_GRID_HELP})")
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        if key.type is str:
            return text  # bare words for string keys, as --set accepts them
        try:
            return float(text)  # Python spellings TOML lacks, e.g. "1e3" is TOML but "1." is not
        except ValueError:
            raise ProblemError(f"{where} is invalid: {text!r} is not a number") from None


def parse_grid(spec: str) -> tuple[str, np.ndarray]:
    """Parse one axis: ``SECTION.KEY=START:STOP:NUM`` (NUM values, both ends included, like
    ``numpy.linspace``) or ``SECTION.KEY=A,B,C`` (a list; one value is a list of one).

    Returns the key and its values (float, int or str array after the schema type of the key).
    Bad specs raise :class:`ProblemError` with a one-line message naming the spec.
    """
    if not isinstance(spec, str):
        raise ProblemError(f"--grid {spec!r} is invalid: {_GRID_HELP}")
    where = f"--grid {spec.strip()!r}"
    if "=" not in spec:
        raise ProblemError(f"{where} is invalid: {_GRID_HELP}")
    lhs, rhs = (s.strip() for s in spec.split("=", 1))
    key = _schema_key(lhs, where)
    if not rhs:
        raise ProblemError(f"{where} is invalid: no values ({_GRID_HELP})")
    if ":" in rhs and "," not in rhs and key.type is not str:
        parts = [p.strip() for p in rhs.split(":")]
        if len(parts) != 3:
            raise ProblemError(f"{where} is invalid: a range is START:STOP:NUM, got {len(parts)} fields")
        try:
            start, stop = float(parts[0]), float(parts[1])
        except ValueError:
            raise ProblemError(f"{where} is invalid: START and STOP must be numbers, got {parts[0]!r}, "
                               f"{parts[1]!r}") from None
        try:
            num = int(parts[2])
        except ValueError:
            raise ProblemError(f"{where} is invalid: NUM must be an integer >= 1, got {parts[2]!r}") from None
        if num < 1:
            raise ProblemError(f"{where} is invalid: NUM must be an integer >= 1, got {num}")
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
        key = _schema_key(str(name), where)
        arr = np.asarray(values, dtype=object if key.type is str else None)
        if arr.ndim > 1:
            raise ProblemError(f"{where} is invalid: values must be 1-D, got shape {arr.shape}")
        out[str(name)] = _coerce(list(np.atleast_1d(arr)), key, str(name), where)
    names = list(out)
    for name in names:
        section, key = name.split(".")
        for other in SCHEMA[section].key_map[key].exclusive_with:
            if f"{section}.{other}" in out:
                raise ProblemError(f"grid keys {name} and {section}.{other} are alternatives: sweep one of them")
    return out


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
    base = problem.to_dict()
    first = None
    n = 0
    for n, values in enumerate(itertools.product(*(v.tolist() for v in grid.values())), 1):
        overrides = [f"{k}={_toml_value(v)}" for k, v in zip(grid, values)]
        try:
            data, _ = apply_overrides(base, overrides, problem.source)
            problem_from_dict(data, source=problem.source)
            return
        except ProblemError as exc:
            first = first or exc
    raise ProblemError(f"{first} (every one of the {n} points of the grid is invalid; grid: "
                       f"{', '.join(f'{k} = {len(v)} values' for k, v in grid.items())})")


def _toml_value(value: Any) -> str:
    """A grid value as the right-hand side of a ``--set`` override (exact for floats)."""
    if isinstance(value, str):
        return json.dumps(value)
    return repr(value)


# --------------------------------------------------------------------------------------------
# settings
# --------------------------------------------------------------------------------------------
def _plain(data: Any) -> Any:
    """JSON-normal form (lists, dicts, floats), so that in-memory settings compare equal to a file's."""
    return json.loads(json.dumps(jsonable(data), allow_nan=False))


def _extra_column_names() -> frozenset[str]:
    blank = CrawlResult(success=False, status=0, message="")
    names = {f.name for f in fields(CrawlResult)} | set(blank.summary())
    # time series and event lists do not fit in a cell; the status columns are always there
    return frozenset(names - set(ARRAY_FIELDS) - set(RESULT_COLUMNS) - {"events", "extra"})


EXTRA_COLUMNS = _extra_column_names()


@dataclass(frozen=True)
class SweepSettings:
    """What a sweep computes; two sweeps with equal settings give the same rows."""

    problem: Mapping[str, Any]
    """base problem as a plain dict of sections (``Problem.to_dict()``, JSON-normal)"""
    grid: tuple[tuple[str, tuple], ...]
    """(key, values) per axis in grid order; the first key varies slowest"""
    solver: str = "event"
    """one of SOLVERS"""
    extra_columns: tuple[str, ...] = ()
    """CrawlResult attributes or summary keys recorded after the standard columns"""
    version: str = __version__
    """package version that computed the rows"""
    source: str = field(default="<dict>", compare=False)
    """where the base problem came from (informational; not compared on resume)"""

    def __post_init__(self) -> None:
        if not isinstance(self.problem, Mapping):
            raise TypeError(f"SweepSettings.problem must be a dict of sections, got {type(self.problem).__name__}")
        object.__setattr__(self, "problem", _plain(self.problem))
        grid = normalize_grid(dict(self.grid))
        object.__setattr__(self, "grid", tuple((k, tuple(v.tolist())) for k, v in grid.items()))
        if self.solver not in SOLVERS:
            raise ValueError(f"SweepSettings.solver = {self.solver!r} is invalid: must be one of {SOLVERS}")
        extra = tuple(self.extra_columns)
        for name in extra:
            if name not in EXTRA_COLUMNS:
                hint = difflib.get_close_matches(str(name), sorted(EXTRA_COLUMNS), n=1)
                raise ValueError(f"extra column {name!r} is invalid: " + (f"did you mean {hint[0]!r}? " if hint else "")
                                 + f"valid: {', '.join(sorted(EXTRA_COLUMNS))}")
            if name in self.keys:
                raise ValueError(f"extra column {name!r} is invalid: it is a grid key")
        if len(set(extra)) != len(extra):
            raise ValueError(f"extra columns {extra} are invalid: a column is named twice")
        object.__setattr__(self, "extra_columns", extra)

    @classmethod
    def build(cls, problem: Problem, grid: Mapping[str, Any], extra_columns: Sequence[str] = (),
              solver: str = "event") -> "SweepSettings":
        return cls(problem=problem.to_dict(), grid=tuple(normalize_grid(grid).items()), solver=solver,
                   extra_columns=tuple(extra_columns), source=problem.source)

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(k for k, _ in self.grid)

    @property
    def axes(self) -> dict[str, np.ndarray]:
        types = {k: _schema_key(k, k).type for k in self.keys}
        return {k: np.array(v, dtype={str: str, int: np.int64, float: np.float64}[types[k]]) for k, v in self.grid}

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for _, v in self.grid)

    @property
    def size(self) -> int:
        return int(np.prod(self.shape))

    @property
    def columns(self) -> tuple[str, ...]:
        """Columns of ``results.csv``."""
        return self.keys + RESULT_COLUMNS + self.extra_columns

    def point(self, index: int) -> dict[str, Any]:
        """Grid values of the point with flat index ``index`` (C order: the last key varies fastest)."""
        idx = np.unravel_index(index, self.shape)
        return {k: v[i] for (k, v), i in zip(self.grid, idx)}

    def to_dict(self) -> dict:
        return {"format": FORMAT, "version": self.version, "solver": self.solver, "source": self.source,
                "grid": {k: list(v) for k, v in self.grid}, "shape": list(self.shape), "points": self.size,
                "columns": list(self.columns), "extra_columns": list(self.extra_columns), "problem": self.problem}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], where: str = "settings") -> "SweepSettings":
        if not isinstance(data, Mapping) or data.get("format") != FORMAT:
            raise SweepError(f"{where}: not a sweep settings file (expected format {FORMAT!r})")
        try:
            return cls(problem=data["problem"], grid=tuple((k, tuple(v)) for k, v in data["grid"].items()),
                       solver=data["solver"], extra_columns=tuple(data["extra_columns"]), version=data["version"],
                       source=data.get("source", "<dict>"))
        except (KeyError, TypeError, AttributeError, ValueError) as exc:
            raise SweepError(f"{where}: malformed sweep settings: {exc}") from None

    def differences(self, other: "SweepSettings") -> list[str]:
        """How ``other`` (e.g. the settings on disk) differs from these, in words ("other -> these");
        empty when the two sweeps compute the same rows."""
        def axis(values) -> str:
            return f"{len(values)} values {values[0]!r}..{values[-1]!r}"

        out = []
        if self.version != other.version:
            out.append(f"package version {other.version} -> {self.version}")
        if self.solver != other.solver:
            out.append(f"solver {other.solver} -> {self.solver}")
        if self.extra_columns != other.extra_columns:
            out.append(f"extra columns {list(other.extra_columns)} -> {list(self.extra_columns)}")
        if self.keys != other.keys:
            out.append(f"grid keys {', '.join(other.keys)} -> {', '.join(self.keys)}")
        else:
            out += [f"grid {k}: {axis(b)} -> {axis(a)}" for (k, a), (_, b) in zip(self.grid, other.grid) if a != b]
        for section in sorted(set(self.problem) | set(other.problem)):
            mine, theirs = self.problem.get(section, {}), other.problem.get(section, {})
            for key in sorted(set(mine) | set(theirs)):
                if mine.get(key) != theirs.get(key):
                    out.append(f"[{section}] {key} {theirs.get(key, '(absent)')!r} -> {mine.get(key, '(absent)')!r}")
        return out


# --------------------------------------------------------------------------------------------
# one point
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PointTask:
    """One point to evaluate: picklable (plain dicts, no Model), sent to worker processes."""

    index: int
    problem: Mapping[str, Any]
    point: tuple[tuple[str, Any], ...]
    source: str = "<dict>"
    extra_columns: tuple[str, ...] = ()


# The compiled model functions keep their argument buffers per process (ocp_crawl.model.compiled), so two
# threads of one process must not run a point at once (a Dask worker may have several threads).
_RUN_LOCK = threading.Lock()


def _extra_value(result: CrawlResult, name: str, summary: dict) -> Any:
    if name in {f.name for f in fields(CrawlResult)}:
        return getattr(result, name)
    return summary[name]


def evaluate_point(task: PointTask) -> tuple[int, dict[str, Any]]:
    """Run one point; returns (index, row).  Failures come back as the row's status, never raised."""
    row: dict[str, Any] = dict(task.point)
    row.update({"S": math.nan, "W_plus": math.nan, "CoT_plus": math.nan})
    row.update({name: None for name in task.extra_columns})
    overrides = [f"{k}={_toml_value(v)}" for k, v in task.point]
    try:
        data, _ = apply_overrides(task.problem, overrides, task.source)
        problem = problem_from_dict(data, source=task.source)
        with _RUN_LOCK:
            result = run_problem(problem)
        summary = result.summary() if task.extra_columns else {}
        row.update({name: _extra_value(result, name, summary) for name in task.extra_columns})
        row.update(S=float(result.S), W_plus=float(result.W_plus), CoT_plus=float(result.CoT_plus),
                   status=result.status_name, message=result.message)
    except ProblemError as exc:
        row.update(status=BAD_INPUT, message=str(exc))
    except Exception as exc:  # noqa: BLE001 - one broken point must not lose a long sweep; it is recorded
        row.update(status=ERROR, message=f"{type(exc).__name__}: {exc}")
    # a resumed sweep reads its finished rows back from the journal: normalise every row to what the file
    # holds (extra columns, one-line messages), so that resumed and uninterrupted runs give the same rows
    return task.index, {k: _parse_cell(_cell(v)) if k in task.extra_columns else _cell(v) if k == "message" else v
                        for k, v in row.items()}


# --------------------------------------------------------------------------------------------
# CSV cells: exact round trip (floats by repr), so a resumed sweep writes the same file
# --------------------------------------------------------------------------------------------
def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        x = float(value)
        return "" if math.isnan(x) else repr(x)
    if isinstance(value, str):
        return " ".join(value.splitlines())  # one line per row keeps the journal line-oriented
    return json.dumps(jsonable(value), separators=(",", ":"), allow_nan=False)


def _parse_cell(text: str) -> Any:
    """Inverse of :func:`_cell` for columns of unknown type (extra columns)."""
    if text == "":
        return math.nan
    if text in ("true", "false"):
        return text == "true"
    if text[0] in "[{":
        try:
            return json.loads(text)
        except json.JSONDecodeError:
            return text
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    return text


def _parser(settings: SweepSettings, column: str):
    if column in settings.keys:
        kind = _schema_key(column, column).type
        return kind if kind is not float else float
    if column in ("S", "W_plus", "CoT_plus"):
        return lambda t: math.nan if t == "" else float(t)
    if column in ("status", "message"):
        return str
    return _parse_cell


def _row_line(cells: Sequence[str]) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(cells)
    return buf.getvalue()


def _parse_rows(lines: Sequence[str], columns: Sequence[str], settings: SweepSettings, where: str,
                first_line: int) -> list[dict[str, Any]]:
    parsers = [_parser(settings, c) for c in columns]
    out = []
    for n, cells in enumerate(csv.reader(lines), first_line):
        if len(cells) != len(columns):
            raise SweepError(f"{where}:{n}: malformed row ({len(cells)} fields, expected {len(columns)}); "
                             "start the sweep again with --force")
        try:
            out.append({c: p(t) for c, p, t in zip(columns, parsers, cells)})
        except ValueError as exc:
            raise SweepError(f"{where}:{n}: malformed row: {exc}; start the sweep again with --force") from None
    return out


# --------------------------------------------------------------------------------------------
# the result
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SweepResult:
    """Rows of a sweep in grid order, with the settings that produced them."""

    settings: SweepSettings
    rows: list[dict[str, Any]]
    """one dict per point in grid order (C order: the last key varies fastest); keys are the columns"""
    out_dir: Path | None = None
    elapsed: float = math.nan
    """wall time of this run [s] (NaN when read from files)"""
    computed: int = 0
    """points computed by this run (the others were read from a previous, interrupted run)"""

    def __post_init__(self) -> None:
        if len(self.rows) != self.settings.size:
            raise ValueError(f"SweepResult: {len(self.rows)} rows for a grid of {self.settings.size} points")

    @property
    def keys(self) -> tuple[str, ...]:
        return self.settings.keys

    @property
    def axes(self) -> dict[str, np.ndarray]:
        return self.settings.axes

    @property
    def shape(self) -> tuple[int, ...]:
        return self.settings.shape

    @property
    def columns(self) -> tuple[str, ...]:
        return self.settings.columns

    def status_array(self) -> np.ndarray:
        """Status names shaped like the grid."""
        return np.array([r["status"] for r in self.rows], dtype=str).reshape(self.shape)

    def array(self, column: str, successful_only: bool = True) -> np.ndarray:
        """A numeric column shaped like the grid (``+ (n,)`` for list-valued extra columns).

        NaN where a point failed unless ``successful_only=False`` (then a failed point's value as
        recorded, usually NaN).  Grid keys give their values at each point; ``status`` gives
        :meth:`status_array`.
        """
        if column == "status":
            return self.status_array()
        if column not in self.columns:
            raise KeyError(f"no column {column!r}; columns: {', '.join(self.columns)}")
        values = [r[column] for r in self.rows]
        if column in self.keys:
            return np.array(values).reshape(self.shape)
        ok = np.array([r["status"] == SUCCESS for r in self.rows])
        if column == "message":
            return np.array(values, dtype=object).reshape(self.shape)
        try:
            arr = np.array([np.nan if v is None else v for v in values], dtype=float) \
                if not any(isinstance(v, list) for v in values) else self._stack(values)
        except (TypeError, ValueError):
            return np.array(values, dtype=object).reshape(self.shape)
        if successful_only:
            arr[~ok] = np.nan
        return arr.reshape(self.shape + arr.shape[1:])

    @staticmethod
    def _stack(values: list) -> np.ndarray:
        n = max(len(v) for v in values if isinstance(v, list))
        out = np.full((len(values), n), np.nan)
        for i, v in enumerate(values):
            if isinstance(v, list):
                out[i, :len(v)] = [np.nan if x is None else x for x in v]
        return out

    def counts(self) -> dict[str, int]:
        """Number of points per status, most frequent first."""
        c: dict[str, int] = {}
        for r in self.rows:
            c[r["status"]] = c.get(r["status"], 0) + 1
        return dict(sorted(c.items(), key=lambda kv: (-kv[1], kv[0])))

    def _pick(self, score) -> dict | None:
        best, best_score = None, -math.inf
        for r in self.rows:
            if r["status"] != SUCCESS:
                continue
            s = score(r)
            if np.isfinite(s) and s > best_score:
                best, best_score = r, s
        if best is None:
            return None
        return {"point": {k: best[k] for k in self.keys}, "S": best["S"], "W_plus": best["W_plus"],
                "CoT_plus": best["CoT_plus"]}

    def best(self) -> dict | None:
        """The successful point that moves farthest per cycle (largest |S|), or None."""
        return self._pick(lambda r: abs(r["S"]))

    def lowest_cot(self) -> dict | None:
        """The successful point with the lowest finite CoT+, or None."""
        return self._pick(lambda r: -r["CoT_plus"])

    def summary(self) -> dict:
        """JSON-friendly summary: points, counts by status, best point, timing."""
        counts = self.counts()
        n_ok = counts.get(SUCCESS, 0)
        return jsonable({
            "out_dir": str(self.out_dir) if self.out_dir is not None else None,
            "problem": self.settings.source, "keys": list(self.keys), "shape": list(self.shape),
            "points": self.settings.size, "successes": n_ok, "failures": self.settings.size - n_ok,
            "counts": counts, "best": self.best(), "lowest_CoT_plus": self.lowest_cot(),
            "elapsed_s": self.elapsed, "computed": self.computed,
            "s_per_point": self.elapsed / self.computed if self.computed else None,
            "units": {"S": "m", "W_plus": "J", "CoT_plus": "-", "elapsed_s": "s"},
        })

    def format_summary(self) -> str:
        """Readable summary (the CLI's output)."""
        def fmt(v) -> str:
            return f"{v:g}" if isinstance(v, float) else str(v)

        def at(p) -> str:
            return ", ".join(f"{k} = {fmt(v)}" for k, v in p["point"].items())

        axes = " x ".join(f"{k} ({len(v)} values, {fmt(v[0])} .. {fmt(v[-1])})" for k, v in self.settings.grid)
        lines = [f"sweep      {self.settings.source}: {axes} = {self.settings.size} points"]
        if self.out_dir is not None:
            lines.append(f"results    {Path(self.out_dir) / RESULTS_FILE}")
        lines.append("status     " + ", ".join(f"{k} {v}" for k, v in self.counts().items()))
        best, low = self.best(), self.lowest_cot()
        if best is None:
            lines.append("best S     - (no successful point)")
        else:
            lines.append(f"best S     {1e3 * best['S']:.3f} mm per cycle at {at(best)} "
                         f"(W+ {1e3 * best['W_plus']:.3f} mJ, CoT+ {best['CoT_plus']:.3f})")
        if low is not None:
            lines.append(f"lowest CoT+ {low['CoT_plus']:.3f} at {at(low)} (S {1e3 * low['S']:.3f} mm)")
        if np.isfinite(self.elapsed):
            per = f", {1e3 * self.elapsed / self.computed:.1f} ms per point" if self.computed else ""
            resumed = self.settings.size - self.computed
            lines.append(f"time       {self.elapsed:.1f} s ({self.computed} points computed{per}"
                         + (f"; {resumed} from the previous run" if resumed else "") + ")")
        return "\n".join(lines)

    def csv_text(self) -> str:
        return _row_line(self.columns) + "".join(_row_line([_cell(r[c]) for c in self.columns]) for r in self.rows)

    def to_csv(self, path: str | os.PathLike) -> Path:
        """Write the rows in grid order (atomically: temp file + rename)."""
        text = self.csv_text().encode("utf-8")
        return atomic_write(path, lambda fh: fh.write(text))

    @classmethod
    def read(cls, out_dir: str | os.PathLike, partial: bool = False) -> "SweepResult":
        """Read a sweep's directory.  An incomplete sweep raises SweepError unless ``partial``:
        then its unfinished points have status ``missing``."""
        store = _Store(Path(out_dir))
        settings = store.read_settings()
        done = store.read_done(settings)
        if len(done) < settings.size and not partial:
            raise SweepError(f"{out_dir}: the sweep is incomplete ({len(done)} of {settings.size} points); "
                             "finish it with --resume, or read it with partial=True")
        rows = [done.get(i) or _missing_row(settings, i) for i in range(settings.size)]
        return cls(settings=settings, rows=rows, out_dir=Path(out_dir))


def _missing_row(settings: SweepSettings, index: int) -> dict[str, Any]:
    row = settings.point(index)
    row.update({"S": math.nan, "W_plus": math.nan, "CoT_plus": math.nan, "status": MISSING,
                "message": "not computed (the sweep was interrupted)"})
    row.update({c: math.nan for c in settings.extra_columns})
    return row


# --------------------------------------------------------------------------------------------
# the output directory
# --------------------------------------------------------------------------------------------
class _Store:
    """The files of one sweep directory: settings, journal, results; one writer at a time."""

    def __init__(self, out_dir: Path):
        self.dir = out_dir
        self.settings_path = out_dir / SETTINGS_FILE
        self.journal_path = out_dir / JOURNAL_FILE
        self.results_path = out_dir / RESULTS_FILE
        self.summary_path = out_dir / SUMMARY_FILE
        self._journal = None
        self._lock = None

    # ---- reading
    def read_settings(self) -> SweepSettings:
        try:
            data = json.loads(self.settings_path.read_text())
        except FileNotFoundError:
            raise SweepError(f"{self.dir}: no {SETTINGS_FILE}: not a sweep directory") from None
        except (OSError, json.JSONDecodeError) as exc:
            raise SweepError(f"{self.settings_path}: cannot read: {exc}") from None
        return SweepSettings.from_dict(data, str(self.settings_path))

    def read_done(self, settings: SweepSettings, repair: bool = False) -> dict[int, dict[str, Any]]:
        """Finished rows by flat index: all of results.csv, else those of the journal.

        ``repair`` (the writer only) cuts a line torn by a kill off the journal before appending to it.
        """
        done: dict[int, dict[str, Any]] = {}
        if self.results_path.exists():
            lines = self.results_path.read_text().splitlines(keepends=True)
            if not lines or next(csv.reader(lines[:1])) != list(settings.columns):
                raise SweepError(f"{self.results_path}: columns differ from {SETTINGS_FILE}; start again with --force")
            rows = _parse_rows(lines[1:], settings.columns, settings, str(self.results_path), 2)
            if len(rows) != settings.size:
                raise SweepError(f"{self.results_path}: {len(rows)} rows for {settings.size} points; "
                                 "start again with --force")
            for i, row in enumerate(rows):
                self._check_point(settings, i, row, self.results_path)
                done[i] = row
        if self.journal_path.exists():
            for i, row in self._read_journal(settings, repair).items():
                done.setdefault(i, row)
        return done

    def _read_journal(self, settings: SweepSettings, repair: bool) -> dict[int, dict[str, Any]]:
        raw = self.journal_path.read_bytes()
        body, _, torn = raw.rpartition(b"\n")
        if torn and repair:
            # a run killed in the middle of writing a line: that point was not finished
            with open(self.journal_path, "r+b") as fh:
                fh.truncate(len(body) + 1 if body else 0)
        lines = (body + b"\n").decode("utf-8").splitlines(keepends=True) if body else []
        columns = ("index",) + settings.columns
        if not lines:
            return {}
        if next(csv.reader(lines[:1])) != list(columns):
            raise SweepError(f"{self.journal_path}: columns differ from {SETTINGS_FILE}; start again with --force")
        done: dict[int, dict[str, Any]] = {}
        for n, row in enumerate(_parse_rows(lines[1:], columns, settings, str(self.journal_path), 2), 2):
            index = row.pop("index")
            if not isinstance(index, int) or not 0 <= index < settings.size:
                raise SweepError(f"{self.journal_path}:{n}: index {index!r} is not a point of the grid")
            self._check_point(settings, index, row, self.journal_path)
            done.setdefault(index, row)
        return done

    @staticmethod
    def _check_point(settings: SweepSettings, index: int, row: dict, path: Path) -> None:
        expected = settings.point(index)
        if any(row[k] != v for k, v in expected.items()):
            raise SweepError(f"{path}: row of point {index} has grid values {[row[k] for k in expected]}, "
                             f"expected {list(expected.values())}; start again with --force")

    # ---- writing
    def _acquire(self) -> None:
        try:
            import fcntl
        except ImportError:  # no advisory locks (Windows): one writer is then the user's business
            return
        self._lock = open(self.dir / LOCK_FILE, "a")
        try:
            fcntl.flock(self._lock.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self._lock.close()
            self._lock = None
            raise SweepError(f"{self.dir}: another sweep is writing to this directory") from None

    def open(self, settings: SweepSettings, resume: bool, force: bool) -> dict[int, dict[str, Any]]:
        """Start or resume the sweep's files; returns the finished rows (empty unless resuming)."""
        self.dir.mkdir(parents=True, exist_ok=True)
        self._acquire()
        try:
            remove_stale_temps(self.dir)  # temporary files of a killed run (see files.atomic_write)
            return self._open(settings, resume, force)
        except BaseException:
            self.close()
            raise

    def _open(self, settings: SweepSettings, resume: bool, force: bool) -> dict[int, dict[str, Any]]:
        ours = [p for p in (self.settings_path, self.journal_path, self.results_path) if p.exists()]
        done: dict[int, dict[str, Any]] = {}
        if resume and self.settings_path.exists():
            old = self.read_settings()
            diff = settings.differences(old)
            if diff:
                raise SweepError(f"{self.dir}: cannot resume: this sweep differs from its {SETTINGS_FILE} "
                                 f"(saved -> now: {'; '.join(diff[:4])}{'; ...' if len(diff) > 4 else ''}); "
                                 "use another output directory, or --force to start over")
            done = self.read_done(settings, repair=True)
        elif resume and ours:
            raise SweepError(f"{self.dir}: cannot resume: no {SETTINGS_FILE} to check the settings against; "
                             "use --force to start over")
        elif ours and not force:
            raise SweepError(f"{self.dir}: already holds a sweep ({', '.join(p.name for p in ours)}); "
                             "continue it with --resume, or overwrite it with --force")
        else:
            for p in (self.journal_path, self.results_path, self.summary_path):
                p.unlink(missing_ok=True)
            write_json(self.settings_path, settings.to_dict())
        # a journal killed before its header was complete is empty (repaired above): it needs the header
        fresh = not self.journal_path.exists() or self.journal_path.stat().st_size == 0
        self._journal = open(self.journal_path, "a", encoding="utf-8", newline="")
        if fresh:
            self._write_line(_row_line(("index",) + settings.columns))
        return done

    def _write_line(self, line: str) -> None:
        self._journal.write(line)
        self._journal.flush()
        os.fsync(self._journal.fileno())

    def append(self, settings: SweepSettings, index: int, row: dict[str, Any]) -> None:
        self._write_line(_row_line([str(index)] + [_cell(row[c]) for c in settings.columns]))

    def finish(self, result: SweepResult) -> None:
        result.to_csv(self.results_path)
        write_json(self.summary_path, result.summary())
        # results.csv holds every row now; a kill before this unlink leaves a journal that resume ignores
        self.journal_path.unlink(missing_ok=True)

    def close(self) -> None:
        if self._journal is not None:
            self._journal.close()
            self._journal = None
        if self._lock is not None:
            self._lock.close()  # releases the flock
            self._lock = None


# --------------------------------------------------------------------------------------------
# executors: each yields (index, row) in completion order
# --------------------------------------------------------------------------------------------
def _mp_context():
    methods = multiprocessing.get_all_start_methods()
    # fork is the fastest start: workers inherit the imported modules and the loaded compiled
    # functions (measured ~1 s less per worker than forkserver), but forking a process with other
    # threads running can deadlock a child on a lock held by one of them
    if "fork" in methods and threading.active_count() == 1:
        return multiprocessing.get_context("fork")
    if "forkserver" in methods:
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["ocp_crawl.problem.core"])
        return ctx
    return multiprocessing.get_context("spawn")


def _serial(tasks: Sequence[PointTask]) -> Iterator[tuple[int, dict]]:
    for task in tasks:
        yield evaluate_point(task)


def _pool(tasks: Sequence[PointTask], jobs: int) -> Iterator[tuple[int, dict]]:
    ctx = _mp_context()
    first = None
    if ctx.get_start_method() == "fork":
        # run the first point here: it loads the compiled functions, which the forked workers inherit
        first, tasks = evaluate_point(tasks[0]), tasks[1:]
    if not tasks:
        yield first
        return
    executor = ProcessPoolExecutor(max_workers=min(jobs, len(tasks)), mp_context=ctx)
    try:
        # the workers fork at the first submit, before the caller sees a row (and starts a progress thread)
        futures = [executor.submit(evaluate_point, t) for t in tasks]
        if first is not None:
            yield first
        for fut in as_completed(futures):
            try:
                yield fut.result()
            except BrokenProcessPool:
                raise SweepFailed("a worker process died (killed, or out of memory); the finished points are "
                                  "saved: resume the sweep with --resume") from None
    finally:
        # on an interrupt, do not start the queued points; the ones running finish within a point's time
        executor.shutdown(wait=True, cancel_futures=True)


def _dask(tasks: Sequence[PointTask], scheduler: str, jobs: int) -> Iterator[tuple[int, dict]]:
    try:
        from distributed import Client, LocalCluster
        from distributed import as_completed as dask_completed
    except ImportError:
        raise SweepError(f"scheduler {scheduler!r} needs dask.distributed: pip install 'ocp-crawl[cluster]'") from None
    cluster = client = futures = None
    try:
        try:
            if scheduler == "local":
                cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, dashboard_address=None)
                client = Client(cluster)
            else:
                client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise SweepFailed(f"cannot connect to the Dask scheduler {scheduler!r}: {exc}") from None
        futures = client.map(evaluate_point, list(tasks), pure=False)
        for fut in dask_completed(futures):
            try:
                yield fut.result()
            except Exception as exc:  # evaluate_point records every failure of a point: this is the cluster's
                raise SweepFailed(f"the Dask cluster failed to run a point: {type(exc).__name__}: {exc}; the "
                                  "finished points are saved: resume the sweep with --resume") from None
    finally:
        if client is not None:
            if futures is not None:
                client.cancel(futures)
            client.close()
        if cluster is not None:
            cluster.close()


class _NoBar:
    def update(self, n: int = 1) -> None:
        pass

    def set_postfix_str(self, text: str, refresh: bool = True) -> None:
        pass

    def close(self) -> None:
        pass


def _progress_bar(progress: bool, total: int, initial: int):
    if not progress:
        # not even a disabled tqdm: any tqdm starts a monitor thread, and threads rule out fork (_mp_context)
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc="sweep", unit="pt", file=sys.stderr, dynamic_ncols=True)


def default_jobs() -> int:
    """Worker processes by default: the CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


# --------------------------------------------------------------------------------------------
# the sweep
# --------------------------------------------------------------------------------------------
def run_sweep(problem: Problem | str | os.PathLike, grid: Mapping[str, Any], *, out_dir: str | os.PathLike | None = None,
              jobs: int = 1, resume: bool = False, force: bool = False, progress: bool = False,
              scheduler: str | None = None, extra_columns: Sequence[str] = ()) -> SweepResult:
    """Evaluate ``problem`` at every point of ``grid`` ({key: values}; the first key varies slowest).

    ``jobs`` worker processes (1: in this process); ``scheduler`` a Dask scheduler address, or
    "local" for a local Dask cluster of ``jobs`` workers.  With ``out_dir`` the rows are journaled
    as they finish and ``results.csv`` is written at the end (see the module docstring);
    ``resume`` continues an interrupted sweep there (its settings must be the same), ``force``
    overwrites an existing sweep.  ``extra_columns`` names further CrawlResult attributes or
    summary keys to record (e.g. "W_plus_joint", "cycles").

    Bad grids raise ProblemError, refused directories SweepError (both ValueError); a sweep that
    cannot complete raises SweepFailed.  Failed points are rows with their status, not exceptions.
    """
    if isinstance(problem, (str, os.PathLike)):
        problem = load_problem(problem)
    if not isinstance(problem, Problem):
        raise TypeError(f"run_sweep needs a Problem or a problem file, got {type(problem).__name__}")
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
        raise ValueError(f"jobs = {jobs!r} is invalid: must be an integer >= 1")
    if resume and force:
        raise ValueError("resume and force are mutually exclusive: resume continues a sweep, force starts it over")
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
        raise ValueError(f"scheduler = {scheduler!r} is invalid: a Dask scheduler address or 'local'")
    settings = SweepSettings.build(problem, grid, extra_columns)
    store = _Store(Path(out_dir)) if out_dir is not None else None
    done = store.open(settings, resume, force) if store is not None else {}
    try:
        pending = [PointTask(i, settings.problem, tuple(settings.point(i).items()), settings.source,
                             settings.extra_columns) for i in range(settings.size) if i not in done]
        start = time.perf_counter()
        if scheduler is not None and pending:
            runner = _dask(pending, scheduler.strip(), int(jobs))
        elif jobs > 1 and len(pending) > 1:
            runner = _pool(pending, int(jobs))
        else:
            runner = _serial(pending)
        bar = None
        failed = sum(r["status"] != SUCCESS for r in done.values())
        try:
            with closing(runner):
                for index, row in runner:
                    if bar is None:
                        # after the first row: the workers have forked by then (see _pool)
                        bar = _progress_bar(progress, settings.size, len(done))
                    done[index] = row
                    if store is not None:
                        store.append(settings, index, row)
                    if row["status"] != SUCCESS:
                        failed += 1
                        bar.set_postfix_str(f"failed {failed}", refresh=False)
                    bar.update(1)
        finally:
            if bar is not None:
                bar.close()
        result = SweepResult(settings=settings, rows=[done[i] for i in range(settings.size)],
                             out_dir=store.dir if store is not None else None,
                             elapsed=time.perf_counter() - start, computed=len(pending))
        if store is not None:
            store.finish(result)
        return result
    finally:
        if store is not None:
            store.close()
