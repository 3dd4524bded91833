"""Executors of a sweep: serial, a process pool, a Dask cluster; each yields (index, row) in
completion order.

Also the progress bar (tqdm, on stderr); the pools start as `ocp_crawl.workers.mp_context` says.
"""
from __future__ import annotations

import sys
import time
from concurrent.futures import as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Generator, Sequence

from ocp_crawl.workers import mp_context, worker_pool
from ocp_crawl.sweep.point import PointTask, evaluate_point, evaluate_points
from ocp_crawl.sweep.settings import SweepError, SweepFailed


def serial_runner(tasks: Sequence[PointTask]) -> Generator[tuple[int, dict], None, None]:
    """The points one after the other, in this process."""
    for task in tasks:
        yield evaluate_point(task)


#: work per chunk of points sent to a worker [s]: the round trip to a worker (~0.2 ms) stays below 1
#: % of it, and a killed sweep loses at most about this much finished work per worker
CHUNK_SECONDS = 0.05

#: chunks per worker at least (a slow chunk at the end leaves the other workers idle)
CHUNKS_PER_WORKER = 4


def chunk_size(n: int, jobs: int, seconds_per_point: float) -> int:
    """Points per chunk for ``n`` points on ``jobs`` workers, a point taking ``seconds_per_point``
    [s]: about :data:`CHUNK_SECONDS` of work, and at least :data:`CHUNKS_PER_WORKER` chunks per
    worker."""
    most = max(1, n // (CHUNKS_PER_WORKER * jobs))
    return max(1, min(most, int(CHUNK_SECONDS / max(seconds_per_point, 1e-6))))


def _first_points(tasks: Sequence[PointTask]) -> tuple[list[tuple[int, dict]], Sequence[PointTask],
                                                       float]:
    """Run the first point here (it loads the compiled functions, which forked workers inherit) and,
    if it was fast, a second one, warm, to time a point.  Returns (rows, the remaining tasks,
    seconds per point)."""
    rows: list[tuple[int, dict]] = []
    seconds = 0.0
    while tasks and len(rows) < 2 and seconds < CHUNK_SECONDS:
        start = time.perf_counter()
        rows.append(evaluate_point(tasks[0]))
        seconds, tasks = time.perf_counter() - start, tasks[1:]
    return rows, tasks, seconds


def _chunks(tasks: Sequence[PointTask], size: int) -> list[Sequence[PointTask]]:
    return [tasks[i:i + size] for i in range(0, len(tasks), size)]


def pool_runner(tasks: Sequence[PointTask], jobs: int) -> Generator[tuple[int, dict], None, None]:
    """The points in ``jobs`` worker processes, in chunks (:func:`chunk_size`); SweepFailed if a
    worker dies."""
    ctx = mp_context()
    first, tasks, seconds = (_first_points(tasks) if ctx.get_start_method() == "fork"
                             else ([], tasks, 0.0))
    if not tasks:
        yield from first
        return
    # without a timed point (the workers do not fork from here): a few points per chunk
    size = chunk_size(len(tasks), jobs,
                      seconds) if first else min(4, chunk_size(len(tasks), jobs, 0.0))
    executor = worker_pool(min(jobs, len(tasks)))
    try:
        # the workers fork at the first submit, before the caller sees a row (and starts a progress
        # thread)
        futures = [executor.submit(evaluate_points, chunk) for chunk in _chunks(tasks, size)]
        yield from first
        for fut in as_completed(futures):
            try:
                rows = fut.result()
            except BrokenProcessPool:
                raise SweepFailed("a worker process died (killed, or out of memory); the finished "
                                  "points are saved: resume the sweep with --resume") from None
            yield from rows
    finally:
        # on an interrupt, do not start the queued points; the ones running finish within a chunk's
        # time
        executor.shutdown(wait=True, cancel_futures=True)


def dask_runner(tasks: Sequence[PointTask], scheduler: str,
                jobs: int) -> Generator[tuple[int, dict], None, None]:
    """The points on the Dask cluster at ``scheduler`` ("local": a local cluster of ``jobs``
    workers), in chunks."""
    try:
        from distributed import Client, LocalCluster
        from distributed import as_completed as dask_completed
    except ImportError:
        raise SweepError(f"scheduler {scheduler!r} needs dask.distributed: pip install "
                         "'ocp-crawl[cluster]'") from None
    cluster = client = futures = None
    try:
        try:
            if scheduler == "local":
                cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
                client = Client(cluster)
            else:
                client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise SweepFailed(f"cannot connect to the Dask scheduler {scheduler!r}: "
                              f"{exc}") from None
        except ValueError as exc:  # an address Dask cannot parse (unknown scheme, ...): bad input
            raise SweepError(f"--scheduler {scheduler!r} is invalid: {exc} (give a Dask scheduler "
                             "address such as tcp://host:8786, or 'local')") from None
        # one point timed here sizes the chunks (a Dask task costs about a millisecond of overhead)
        first, tasks, seconds = _first_points(tasks)
        yield from first
        futures = client.map(evaluate_points, _chunks(tasks, chunk_size(len(tasks), jobs, seconds)),
                             pure=False)
        for fut in dask_completed(futures):
            try:
                rows = fut.result()
            # evaluate_point records every failure of a point: this is the cluster's
            except Exception as exc:
                raise SweepFailed(f"the Dask cluster failed to run a point: {type(exc).__name__}: "
                                  f"{exc}; the finished points are saved: resume the sweep with "
                                  "--resume") from None
            yield from rows
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


def progress_bar(progress: bool, total: int, initial: int):
    """A tqdm bar on stderr of ``total`` points, ``initial`` done; a bar that shows nothing unless
    ``progress``."""
    if not progress:
        # not even a disabled tqdm: any tqdm starts a monitor thread, and threads rule out fork
        # (mp_context)
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc="sweep", unit="pt", file=sys.stderr,
                dynamic_ncols=True)
