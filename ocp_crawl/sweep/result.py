"""The rows of a sweep in grid order, with the settings that produced them: :class:`SweepResult`."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ocp_crawl.io import units
from ocp_crawl.io.files import atomic_write, jsonable
from ocp_crawl.status import Status
from ocp_crawl.sweep.cells import cell, row_line
from ocp_crawl.sweep.grid import axis_text, value_text
from ocp_crawl.sweep.journal import RESULTS_FILE, SweepStore
from ocp_crawl.sweep.settings import SweepError, SweepSettings

#: the status of a successful row (the other rows have the simulator's status, or bad_input, error,
#: missing)
SUCCESS = Status.SUCCESS.label


@dataclass(frozen=True)
class SweepResult:
    """Rows of a sweep in grid order, with the settings that produced them."""

    settings: SweepSettings
    rows: list[dict[str, Any]]
    """one dict per point in grid order (C order: the last key varies fastest); keys are the
    columns"""
    out_dir: Path | None = None
    elapsed: float = math.nan
    """wall time of this run [s] (NaN when read from files)"""
    computed: int = 0
    """points computed by this run (the others were read from a previous, interrupted run)"""

    def __post_init__(self) -> None:
        if len(self.rows) != self.settings.size:
            raise ValueError(f"SweepResult: {len(self.rows)} rows for a grid of "
                             f"{self.settings.size} points")

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
            "grid": {k: list(v) for k, v in self.settings.grid},
            "points": self.settings.size, "successes": n_ok, "failures": self.settings.size - n_ok,
            "counts": counts, "best": self.best(), "lowest_CoT_plus": self.lowest_cot(),
            "elapsed_s": self.elapsed, "computed": self.computed,
            "s_per_point": self.elapsed / self.computed if self.computed else None,
            "units": dict(self.column_units(), elapsed_s=units.UNITS["elapsed_s"]),
        })

    def column_units(self) -> dict[str, str]:
        """The unit of every numeric column (:meth:`SweepSettings.column_units`), as results.csv's
        header gives them: grid keys from the problem schema, results in SI units (S [m],
        W_plus [J], CoT_plus [-])."""
        return self.settings.column_units()

    def to_pandas(self):
        """The rows as a :class:`pandas.DataFrame` in grid order, one column per grid key and
        result.

        Numbers are in SI units as in ``results.csv``; ``df.attrs["units"]`` maps each column to its
        unit (e.g. ``{"gait.psi_deg": "deg", "S": "m", "W_plus": "J", ...}``), ``df.attrs["grid"]``
        the axes and ``df.attrs["problem"]`` the base problem file.  Needs pandas (``pip install
        'ocp-crawl[pandas]'``); raises ImportError naming the extra otherwise.
        """
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("SweepResult.to_pandas needs pandas: pip install "
                              "'ocp-crawl[pandas]'") from None
        df = pd.DataFrame([{c: r[c] for c in self.columns} for r in self.rows],
                          columns=list(self.columns))
        df.attrs["units"] = self.column_units()
        df.attrs["grid"] = {k: list(v) for k, v in self.settings.grid}
        df.attrs["problem"] = self.settings.source
        return df

    def format_summary(self) -> str:
        """Readable summary (the CLI's output): every axis with its values, counts, best points,
        timing."""
        def at(p) -> str:
            return ", ".join(f"{k} = {value_text(v)}" for k, v in p["point"].items())

        lines = [f"sweep      {self.settings.source}: {units.plural(self.settings.size, 'point')}"]
        lines += [f"  {k} = {axis_text(v)}" for k, v in self.settings.grid]
        if self.out_dir is not None:
            lines.append(f"results    {Path(self.out_dir) / RESULTS_FILE}")
        lines.append("status     " + ", ".join(f"{k} {v}" for k, v in self.counts().items()))
        best, low = self.best(), self.lowest_cot()
        if best is None:
            lines.append("best S     - (no successful point)")
        else:
            lines.append(f"best S     {units.distance(best['S'])} per cycle at {at(best)} "
                         f"(W+ {units.work(best['W_plus'])}, CoT+ {units.cot(best['CoT_plus'])})")
        # (low is None when best is: no successful point; low == best: its CoT+ is above)
        if low is not None and best is not None and low["point"] != best["point"]:
            lines.append(f"lowest CoT+ {units.cot(low['CoT_plus'])} at {at(low)} (S "
                         f"{units.distance(low['S'])})")
        if np.isfinite(self.elapsed):
            lines.append(f"time       {self._time_text()}")
        return "\n".join(lines)

    def _time_text(self) -> str:
        """This run's time and points, e.g. "4.1 s (1 point computed; 7 from the previous run)"."""
        resumed = self.settings.size - self.computed
        if not self.computed:
            return f"nothing computed: {units.plural(resumed, 'point')} from the previous run"
        each = units.seconds(self.elapsed / self.computed)
        per = f", {each} per point" if self.computed > 1 else ""
        computed = units.plural(self.computed, "point")
        return (f"{units.seconds(self.elapsed)} ({computed} computed{per}"
                + (f"; {resumed} from the previous run" if resumed else "") + ")")

    def csv_text(self) -> str:
        """The text of results.csv: the header (:meth:`SweepSettings.header`), then the rows."""
        rows = "".join(row_line([cell(r[c]) for c in self.columns]) for r in self.rows)
        return row_line(self.settings.header()) + rows

    def to_csv(self, path: str | os.PathLike) -> Path:
        """Write the rows in grid order (atomically: temp file + rename)."""
        text = self.csv_text().encode("utf-8")
        return atomic_write(path, lambda fh: fh.write(text))

    @classmethod
    def read(cls, out_dir: str | os.PathLike, partial: bool = False) -> "SweepResult":
        """Read a sweep's directory.  An incomplete sweep raises SweepError unless ``partial``:
        then its unfinished points have status ``missing``."""
        store = SweepStore(Path(out_dir))
        settings = store.read_settings()
        done = store.read_done(settings)
        if len(done) < settings.size and not partial:
            raise SweepError(f"{out_dir}: the sweep is incomplete ({len(done)} of {settings.size} "
                             "points); finish it with --resume, or read it with partial=True")
        rows = [done.get(i) or _missing_row(settings, i) for i in range(settings.size)]
        return cls(settings=settings, rows=rows, out_dir=Path(out_dir))


def _missing_row(settings: SweepSettings, index: int) -> dict[str, Any]:
    row = settings.point(index)
    row.update({"S": math.nan, "W_plus": math.nan, "CoT_plus": math.nan,
                "status": Status.MISSING.label,
                "message": "not computed (the sweep was interrupted)"})
    row.update({c: math.nan for c in settings.extra_columns})
    return row

