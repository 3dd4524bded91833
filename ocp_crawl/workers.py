"""Worker processes of the package (floor 0: imports nothing of the package): the start method of every process
pool (sweeps, fits, the harmonic baseline's search) and the default number of workers."""
from __future__ import annotations

import multiprocessing
import os
import threading


def mp_context():
    """The multiprocessing context of the package's worker pools: fork when safe, else forkserver (else spawn)."""
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


def default_jobs() -> int:
    """Worker processes by default: the CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1
