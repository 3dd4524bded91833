"""Executors of a sweep: serial, a process pool, a Dask cluster; each yields (index, row) in completion order.

Also the progress bar (tqdm, on stderr) and the default number of worker processes.
"""
from __future__ import annotations

import multiprocessing
import os
import sys
import threading
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Iterator, Sequence

from ocp_crawl.sweep.point import PointTask, evaluate_point
from ocp_crawl.sweep.settings import SweepError, SweepFailed


def _mp_context():
    methods = multiprocessing.get_all_start_methods()
    # fork is the fastest start: workers inherit the imported modules and the loaded compiled
    # functions (measured ~1 s less per worker than forkserver), but forking a process with other
    # threads running can deadlock a child on a lock held by one of them
    if "fork" in methods and threading.active_count() == 1:
        return multiprocessing.get_context("fork")
    if "forkserver" in methods:
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["ocp_crawl.problem"])
        return ctx
    return multiprocessing.get_context("spawn")


def serial_runner(tasks: Sequence[PointTask]) -> Iterator[tuple[int, dict]]:
    """The points one after the other, in this process."""
    for task in tasks:
        yield evaluate_point(task)


def pool_runner(tasks: Sequence[PointTask], jobs: int) -> Iterator[tuple[int, dict]]:
    """The points in ``jobs`` worker processes; SweepFailed if a worker dies."""
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


def dask_runner(tasks: Sequence[PointTask], scheduler: str, jobs: int) -> Iterator[tuple[int, dict]]:
    """The points on the Dask cluster at ``scheduler`` ("local": a local cluster of ``jobs`` workers)."""
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


def progress_bar(progress: bool, total: int, initial: int):
    """A tqdm bar on stderr of ``total`` points, ``initial`` done; a bar that shows nothing unless ``progress``."""
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

