"""Parameter sweeps: S, W+ and CoT+ over a grid of problem keys, in parallel and resumable.

A sweep evaluates every point of a rectangular grid (one axis per problem key, e.g.
``gait.psi_deg``; the first key varies slowest) by setting the point's values on the base problem
with :meth:`~ocp_crawl.problem.Problem.with_values` and running
:func:`~ocp_crawl.problem.run_problem` (the problem's solver, or the grid key
``simulation.solver``).  Each point gives one row: the grid values, ``S``, ``W_plus``, ``CoT_plus``,
``status`` (the label of a :class:`ocp_crawl.status.Status`: ``success``, ``fold``,
``lift_off``, ..., or ``bad_input`` for a point whose problem is invalid, ``error`` for an
unexpected exception) and ``message``.  Failed points are data: they are recorded, never dropped
and never raised.

Points run in worker processes (``jobs``), or on a Dask cluster (``scheduler``).  With an output
directory the sweep writes:

``settings.json``
    the base problem, the grid, the solver and the package version; written first, and compared
    on ``resume`` so that a resumed sweep never mixes results of different settings.
``results.partial.csv``
    the journal: one line per finished point in completion order, flushed as it arrives (fsync'd
    about once a second, :mod:`ocp_crawl.sweep.journal`), so that a killed run loses only the
    points in flight (in the workers' chunks of points,
    :func:`ocp_crawl.sweep.executors.chunk_size`).
``results.csv``
    one row per point in grid order, written atomically when the sweep completes (the journal is
    then removed).  A resumed sweep writes the same file as an uninterrupted one.
``summary.json``
    counts by status, the best point, timing.

Nothing is lost when a sweep is killed (even by SIGKILL): settings.json, results.csv and
summary.json are written atomically (temporary file and rename, :mod:`ocp_crawl.io.files`); a
journal line torn by the kill is not a finished point and is cut off by the resuming run; the lock
(``.sweep.lock``, an advisory ``flock``) dies with its process, so a killed sweep never blocks its
resume; temporary files of the killed run are removed when the sweep is resumed or started again.
A resumed sweep writes the same results.csv, byte for byte, as an uninterrupted one.
"""

from __future__ import annotations

import os
import time
from contextlib import closing
from pathlib import Path
from typing import Any, Generator, Mapping, Sequence

import numpy as np

from ocp_crawl.problem import Problem, load_problem
from ocp_crawl.sweep.executors import dask_runner, pool_runner, progress_bar, serial_runner
from ocp_crawl.sweep.journal import SweepStore
from ocp_crawl.sweep.point import PointTask
from ocp_crawl.sweep.result import SUCCESS, SweepResult
from ocp_crawl.sweep.settings import SweepSettings


def _check_arguments(jobs, resume: bool, force: bool, scheduler, out_dir) -> None:
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
        raise ValueError(f"jobs = {jobs!r} is invalid: must be an integer >= 1")
    if out_dir is None and (resume or force):
        what = "resume=True continues" if resume else "force=True overwrites"
        raise ValueError(f"{what} the sweep journaled in out_dir, and out_dir is None: give "
                         f"out_dir or drop {'resume' if resume else 'force'}")
    if resume and force:
        raise ValueError("resume and force are mutually exclusive: resume continues a sweep, force "
                         "starts it over")
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
        raise ValueError(f"scheduler = {scheduler!r} is invalid: a Dask scheduler address or "
                         "'local'")


def _runner(pending: Sequence[PointTask], jobs: int,
            scheduler: str | None) -> Generator[tuple[int, dict], None, None]:
    if scheduler is not None and pending:
        return dask_runner(pending, scheduler.strip(), int(jobs))
    if jobs > 1 and len(pending) > 1:
        return pool_runner(pending, int(jobs))
    return serial_runner(pending)


def _collect(runner: Generator[tuple[int, dict], None, None], settings: SweepSettings,
             done: dict[int, dict[str, Any]], store: SweepStore | None, progress: bool) -> None:
    """Rows of ``runner`` into ``done`` (and the journal), with the progress bar."""
    bar = None
    failed = sum(r["status"] != SUCCESS for r in done.values())
    try:
        with closing(runner):
            for index, row in runner:
                if bar is None:
                    # after the first row: the workers have forked by then (see
                    # executors.pool_runner)
                    bar = progress_bar(progress, settings.size, len(done))
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


def run_sweep(problem: Problem | str | os.PathLike, grid: Mapping[str, Any], *,
              out_dir: str | os.PathLike | None = None,
              jobs: int = 1, resume: bool = False, force: bool = False, progress: bool = False,
              scheduler: str | None = None, extra_columns: Sequence[str] = ()) -> SweepResult:
    """Evaluate ``problem`` at every point of ``grid`` ({key: values}; the first key varies
    slowest).

    ``jobs`` worker processes (1: in this process); ``scheduler`` a Dask scheduler address, or
    "local" for a local Dask cluster of ``jobs`` workers.  With ``out_dir`` the rows are journaled
    as they finish and ``results.csv`` is written at the end (see the module docstring);
    ``resume`` continues an interrupted sweep there (its settings must be the same), ``force``
    overwrites an existing sweep.  ``extra_columns`` names further CrawlResult attributes or
    summary keys to record (e.g. "W_plus_joint", "cycles").

    Returns the :class:`SweepResult` (S [m], W+ [J], CoT+ [-] and status per point).
    Bad grids raise ProblemError, refused directories SweepError (both ValueError); a sweep that
    cannot complete raises SweepFailed.  Failed points are rows with their status, not exceptions.
    """
    if isinstance(problem, (str, os.PathLike)):
        problem = load_problem(problem)
    if not isinstance(problem, Problem):
        raise TypeError("run_sweep needs a Problem or a problem file, got "
                        f"{type(problem).__name__}")
    _check_arguments(jobs, resume, force, scheduler, out_dir)
    settings = SweepSettings.build(problem, grid, extra_columns)
    store = SweepStore(Path(out_dir)) if out_dir is not None else None
    done = store.open(settings, resume, force) if store is not None else {}
    try:
        pending = [PointTask(i, settings.problem, tuple(settings.point(i).items()), settings.source,
                             settings.extra_columns) for i in range(settings.size) if i not in done]
        start = time.perf_counter()
        _collect(_runner(pending, jobs, scheduler), settings, done, store, progress)
        result = SweepResult(settings=settings, rows=[done[i] for i in range(settings.size)],
                             out_dir=store.dir if store is not None else None,
                             elapsed=time.perf_counter() - start, computed=len(pending))
        if store is not None:
            store.finish(result)
        return result
    finally:
        if store is not None:
            store.close()
