"""One point of a sweep: the base problem with the point's values, simulated; failures become
statuses."""
from __future__ import annotations

import functools
import json
import math
import threading
from dataclasses import dataclass, fields
from typing import Any, Mapping, Sequence

import numpy as np

from ocp_crawl.problem import Problem, ProblemError, problem_from_dict, run_problem
from ocp_crawl.sim.result import CrawlResult
from ocp_crawl.status import Status
from ocp_crawl.sweep.cells import cell, parse_cell


@dataclass(frozen=True)
class PointTask:
    """One point to evaluate: picklable (plain dicts, no Model), sent to worker processes."""

    index: int
    """flat index of the point in the grid (C order)"""
    problem: Mapping[str, Any]
    """the base problem as a plain dict of sections"""
    point: tuple[tuple[str, Any], ...]
    """(SECTION.KEY, value) of the point's grid values"""
    source: str = "<dict>"
    extra_columns: tuple[str, ...] = ()


# The compiled model functions keep their argument buffers per process (ocp_crawl.model.compiled),
# so two threads of one process must not run a point at once (a Dask worker may have several
# threads).
_RUN_LOCK = threading.Lock()


@functools.lru_cache(maxsize=4)
def _base_problem(problem_json: str, source: str) -> Problem:
    """The sweep's base problem, validated once per process (every point of a sweep shares it)."""
    return problem_from_dict(json.loads(problem_json), source=source)


def _extra_value(result: CrawlResult, name: str, summary: dict) -> Any:
    if name in {f.name for f in fields(CrawlResult)}:
        return getattr(result, name)
    return summary[name]


def evaluate_point(task: PointTask) -> tuple[int, dict[str, Any]]:
    """Run one point: the base problem with the point's values (``Problem.with_values``), simulated
    by ``run_problem``.  Returns (index, row), the row's keys being the columns.  Failures come back
    as the row's status (the simulator's, or ``bad_input`` / ``error``), never raised."""
    row: dict[str, Any] = dict(task.point)
    row.update({"S": math.nan, "W_plus": math.nan, "CoT_plus": math.nan})
    row.update({name: None for name in task.extra_columns})
    try:
        base = _base_problem(json.dumps(task.problem), task.source)
        problem = base.with_values(dict(task.point))
        # a point's result carries its status: numpy's floating-point warnings would only clutter
        # the workers' stderr
        with _RUN_LOCK, np.errstate(all="ignore"):
            result = run_problem(problem)
        summary = result.summary() if task.extra_columns else {}
        row.update({name: _extra_value(result, name, summary) for name in task.extra_columns})
        row.update(S=float(result.S), W_plus=float(result.W_plus), CoT_plus=float(result.CoT_plus),
                   status=result.status_name, message=result.message)
    except ProblemError as exc:
        row.update(status=Status.BAD_INPUT.label, message=str(exc))
    # noqa: BLE001 - one broken point must not lose a long sweep; it is recorded
    except Exception as exc:
        row.update(status=Status.ERROR.label, message=f"{type(exc).__name__}: {exc}")
    # a resumed sweep reads its finished rows back from the journal: normalise every row to what the
    # file holds (extra columns, one-line messages), so that resumed and uninterrupted runs give the
    # same rows
    return task.index, {k: parse_cell(cell(v)) if k in task.extra_columns else cell(v) if k
                        == "message" else v for k, v in row.items()}


def evaluate_points(tasks: Sequence[PointTask]) -> list[tuple[int, dict[str, Any]]]:
    """:func:`evaluate_point` on each of ``tasks`` in turn: one call per chunk of points sent to a
    worker (a round trip to a worker process costs ~0.2 ms, as much as a fast point)."""
    return [evaluate_point(task) for task in tasks]
