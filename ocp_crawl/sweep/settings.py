"""What a sweep computes (:class:`SweepSettings`), its columns, and the sweep's exceptions."""
from __future__ import annotations

import difflib
import json
from dataclasses import dataclass, field, fields
from typing import Any, Mapping, Sequence, cast

import numpy as np

from ocp_crawl.version import __version__
from ocp_crawl.io.files import jsonable
from ocp_crawl.io.units import UNITS, plural
from ocp_crawl.problem import Problem
from ocp_crawl.sim import DEFAULT_SOLVER, SOLVERS
from ocp_crawl.sim.result import ARRAY_FIELDS, CrawlResult
from ocp_crawl.status import Status
from ocp_crawl.sweep.grid import VALUE_DTYPES, normalize_grid, schema_key, value_text

#: columns of every row after the grid keys
RESULT_COLUMNS = ("S", "W_plus", "CoT_plus", "status", "message")
#: SI units of the columns that hold numbers, besides the grid keys (whose units are the schema's);
#: the others (status, message, flags, names, JSON objects) hold text: their header cells have no
#: unit
COLUMN_UNITS = {**{name: UNITS[name] for name in ("S", "W_plus", "CoT_plus", "W_plus_joint")},
                "cycles": "-", "nfev": "-", "nsteps": "-", "t0": "cycles", "failure_t": "cycles",
                "periodicity_residual": "rad"}
#: the ``format`` of settings.json
FORMAT = "ocp_crawl.sweep/1"


class SweepError(ValueError):
    """A sweep that must not start: bad settings, an output directory holding another sweep, ..."""

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))


class SweepFailed(RuntimeError):
    """The sweep itself could not complete (a worker process died, the cluster went away)."""


def _plain(data: Any) -> Any:
    """JSON-normal form (lists, dicts, floats), so that in-memory settings compare equal to a
    file's."""
    return json.loads(json.dumps(jsonable(data), allow_nan=False))


def _extra_column_names() -> frozenset[str]:
    blank = CrawlResult(success=False, status=Status(0), message="")
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
    solver: str = field(default=DEFAULT_SOLVER["torque"], compare=False)
    """the base problem's solver, a name of :data:`ocp_crawl.sim.SOLVERS` (informational: the
    problem's ``[simulation] solver``, or the grid key ``simulation.solver``, decides each
    point's)"""
    extra_columns: tuple[str, ...] = ()
    """CrawlResult attributes or summary keys recorded after the standard columns"""
    version: str = __version__
    """package version that computed the rows"""
    source: str = field(default="<dict>", compare=False)
    """where the base problem came from (informational; not compared on resume)"""

    def __post_init__(self) -> None:
        if not isinstance(self.problem, Mapping):
            raise TypeError("SweepSettings.problem must be a dict of sections, got "
                            f"{type(self.problem).__name__}")
        object.__setattr__(self, "problem", _plain(self.problem))
        grid = normalize_grid(dict(self.grid))
        object.__setattr__(self, "grid", tuple((k, tuple(v.tolist())) for k, v in grid.items()))
        if self.solver not in SOLVERS:
            raise ValueError(f"SweepSettings.solver = {self.solver!r} is invalid: must be one of "
                             f"{', '.join(SOLVERS)}")
        extra = tuple(self.extra_columns)
        for name in extra:
            if name not in EXTRA_COLUMNS:
                hint = difflib.get_close_matches(str(name), sorted(EXTRA_COLUMNS), n=1)
                raise ValueError(f"extra column {name!r} is invalid: "
                                 + (f"did you mean {hint[0]!r}? " if hint else "")
                                 + f"valid: {', '.join(sorted(EXTRA_COLUMNS))}")
            if name in self.keys:
                raise ValueError(f"extra column {name!r} is invalid: it is a grid key")
        if len(set(extra)) != len(extra):
            raise ValueError(f"extra columns {extra} are invalid: a column is named twice")
        object.__setattr__(self, "extra_columns", extra)

    @classmethod
    def build(cls, problem: Problem, grid: Mapping[str, Any],
              extra_columns: Sequence[str] = ()) -> "SweepSettings":
        """The settings of a sweep of ``problem`` over ``grid`` ({key: values}), recording
        ``extra_columns``."""
        # (key, array) pairs: __post_init__ turns the arrays into tuples
        axes = cast(tuple[tuple[str, tuple], ...], tuple(normalize_grid(grid).items()))
        return cls(problem=problem.to_dict(), grid=axes,
                   solver=problem.solver, extra_columns=tuple(extra_columns), source=problem.source)

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(k for k, _ in self.grid)

    @property
    def axes(self) -> dict[str, np.ndarray]:
        types = {k: schema_key(k, k).type for k in self.keys}
        return {k: np.array(v, dtype=VALUE_DTYPES[types[k]]) for k, v in self.grid}

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for _, v in self.grid)

    @property
    def size(self) -> int:
        return int(np.prod(self.shape))

    @property
    def columns(self) -> tuple[str, ...]:
        """Columns of ``results.csv`` (names without units; :meth:`header`: the header's cells)."""
        return self.keys + RESULT_COLUMNS + self.extra_columns

    def column_units(self) -> dict[str, str]:
        """The unit of every numeric column: grid keys from the problem schema, results in SI units
        (S [m], W_plus [J], CoT_plus [-]), the numeric extra columns from :data:`COLUMN_UNITS`."""
        out = {}
        for name in self.columns:
            if name in self.keys:
                key = schema_key(name, name)
                if key.type is not str:
                    out[name] = key.unit
            elif name in COLUMN_UNITS:
                out[name] = COLUMN_UNITS[name]
        return out

    def header(self) -> tuple[str, ...]:
        """The header cells of ``results.csv``: ``name [unit]`` for a numeric column, as the
        package's input tables write them (``gait.psi_deg [deg]``, ``S [m]``, ``CoT_plus [-]``), the
        bare name for a column of text (``status``, ``message``, a string key such as
        ``model.gravity``)."""
        unit = self.column_units()
        return tuple(f"{c} [{unit[c]}]" if c in unit else c for c in self.columns)

    def point(self, index: int) -> dict[str, Any]:
        """Grid values of the point with flat index ``index`` (C order: the last key varies
        fastest)."""
        idx = np.unravel_index(index, self.shape)
        return {k: v[i] for (k, v), i in zip(self.grid, idx)}

    def to_dict(self) -> dict:
        return {"format": FORMAT, "version": self.version, "solver": self.solver,
                "source": self.source,
                "grid": {k: list(v) for k, v in self.grid}, "shape": list(self.shape),
                "points": self.size,
                "columns": list(self.columns), "extra_columns": list(self.extra_columns),
                "problem": self.problem}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], where: str = "settings") -> "SweepSettings":
        if not isinstance(data, Mapping) or data.get("format") != FORMAT:
            raise SweepError(f"{where}: not a sweep settings file (expected format {FORMAT!r})")
        try:
            return cls(problem=data["problem"],
                       grid=tuple((k, tuple(v)) for k, v in data["grid"].items()),
                       solver=data["solver"], extra_columns=tuple(data["extra_columns"]),
                       version=data["version"], source=data.get("source", "<dict>"))
        except (KeyError, TypeError, AttributeError, ValueError) as exc:
            raise SweepError(f"{where}: malformed sweep settings: {exc}") from None

    def differences(self, other: "SweepSettings") -> list[str]:
        """How ``other`` (e.g. the settings on disk) differs from these, in words ("other ->
        these"); empty when the two sweeps compute the same rows."""
        def axis(values) -> str:
            ends = f"{value_text(values[0])}..{value_text(values[-1])}"
            return f"{plural(len(values), 'value')} {ends}"

        out = []
        if self.version != other.version:
            out.append(f"package version {other.version} -> {self.version}")
        if self.extra_columns != other.extra_columns:
            out.append(f"extra columns {list(other.extra_columns)} -> {list(self.extra_columns)}")
        if self.keys != other.keys:
            out.append(f"grid keys {', '.join(other.keys)} -> {', '.join(self.keys)}")
        else:
            out += [f"grid {k}: {axis(b)} -> "
                    f"{axis(a)}" for (k, a), (_, b) in zip(self.grid, other.grid) if a != b]
        for section in sorted(set(self.problem) | set(other.problem)):
            mine, theirs = self.problem.get(section, {}), other.problem.get(section, {})
            for key in sorted(set(mine) | set(theirs)):
                if mine.get(key) != theirs.get(key):
                    out.append(f"[{section}] {key} {theirs.get(key, '(absent)')!r} -> "
                               f"{mine.get(key, '(absent)')!r}")
        return out

