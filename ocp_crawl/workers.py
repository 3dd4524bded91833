"""Worker processes of the package (floor 0: imports nothing of the package): the process pool of
sweeps, reproduce, fits and the baselines' search (:func:`worker_pool`, its start method
:func:`mp_context`), the default number of workers, and :func:`overlap` (a task in a forked process
while this one does something else).

Every worker dies with the process that started it (Linux: a parent-death signal, and elsewhere too
a watchdog thread that polls the parent): a pool worker of a killed sweep would otherwise live on,
blocked on its pipe, holding the sweep directory's lock (an inherited ``flock``) and refusing
``--resume``."""
from __future__ import annotations

import multiprocessing
import os
import pickle
import signal
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Callable, TypeVar, cast

#: seconds between two looks of a worker's watchdog at its parent
WATCH_SECONDS = 0.5


def mp_context():
    """The multiprocessing context of the package's worker pools: fork when safe, else forkserver
    (else spawn)."""
    methods = multiprocessing.get_all_start_methods()
    # fork is the fastest start: workers inherit the imported modules and the loaded compiled
    # functions (measured ~1 s less per worker than forkserver), but forking a process with other
    # threads running can deadlock a child on a lock held by one of them (this sees Python's threads
    # only; the bundled OpenBLAS's own threads are shut down by its fork handler)
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


def worker_pool(jobs: int, initializer: Callable | None = None,
                initargs: tuple = ()) -> ProcessPoolExecutor:
    """A process pool of ``jobs`` workers (start method :func:`mp_context`) that die with this
    process.

    ``initializer(*initargs)`` runs in each worker after it is tied to this process's life."""
    return ProcessPoolExecutor(jobs, mp_context=mp_context(), initializer=_start_worker,
                               initargs=(os.getpid(), initializer, initargs))


def _start_worker(parent: int, initializer: Callable | None, initargs: tuple) -> None:
    # a forked worker's parent is this process; a forkserver's or spawn's is the server, which ends
    # when the package's process does, so the watchdog follows the parent the worker has now
    _die_with(parent if os.getppid() == parent else os.getppid(), signal.SIGKILL)
    if initializer is not None:
        initializer(*initargs)


def _watch(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(WATCH_SECONDS)
    os._exit(1)


_Task = TypeVar("_Task")
_Meanwhile = TypeVar("_Meanwhile")


def overlap(task: Callable[[Callable[[object], None]], _Task],
            meanwhile: Callable[[], _Meanwhile],
            forward: Callable[[object], None]) -> tuple[_Task, _Meanwhile]:
    """``task(send)`` in a forked process while this one runs ``meanwhile()``; returns (task's
    result, meanwhile's).

    The task may call ``send(message)`` (picklable) any number of times: each message reaches
    ``forward(message)`` here, in order, after ``meanwhile`` returns.  The task's result must be
    picklable; an exception it raises is raised here (as itself when it pickles, else as
    RuntimeError with its text).  Where fork is not safe (threads running, no fork on the platform:
    :func:`mp_context`), or when the child dies without a result (killed, out of memory), the task
    runs here, after ``meanwhile`` (its messages forwarded from where the child's stopped).  The
    child is terminated when this process dies (Linux).  For a task whose inputs the child inherits
    (large or unpicklable objects, e.g. built CasADi solvers) and whose result is small."""
    ctx = mp_context()
    if ctx.get_start_method() != "fork":
        other = meanwhile()
        return task(forward), other
    reader, writer = ctx.Pipe(duplex=False)
    child = ctx.Process(target=_child, args=(task, reader, writer, os.getpid()))
    child.start()
    writer.close()  # the child's copy is the only writer left: its exit ends the pipe
    kind, payload, forwarded = "died", None, 0
    try:
        other = meanwhile()
        kind, payload = _receive(reader)
        while kind == "message":
            forward(payload)
            forwarded += 1
            kind, payload = _receive(reader)
    finally:
        if kind not in ("result", "error"):
            child.kill()
        child.join()
        reader.close()
    if kind == "result":
        return cast(_Task, payload), other  # the task's result, from the child
    if kind == "error":
        raise cast(BaseException, payload)  # _child sends ("error", exc)
    # the child died without a result: the task here, its messages forwarded from where the child's
    # stopped
    seen = [0]

    def send(message) -> None:
        seen[0] += 1
        if seen[0] > forwarded:
            forward(message)
    return task(send), other


def _receive(reader) -> tuple[str, object]:
    """The next (kind, payload) from the child, or ("died", None) when its end of the pipe closed
    first."""
    try:
        return reader.recv()
    except EOFError:
        return "died", None


#: Linux's prctl option that signals a process when its parent dies
_PR_SET_PDEATHSIG = 1


def _die_with(parent: int, sig: int = signal.SIGTERM) -> None:
    """Have this (forked) process end when ``parent`` dies: signal ``sig`` from the kernel on Linux
    (the pools fork from the thread that submits, the forkserver from its main thread: the signal
    follows the forking thread), elsewhere a daemon thread that exits the process within
    :data:`WATCH_SECONDS` of it having another parent (not on Linux: a thread running would keep
    this process's own pools from forking, :func:`mp_context`).  A child whose parent was killed
    would otherwise go on solving, or block for ever on a full pipe."""
    try:
        import ctypes

        linux = ctypes.CDLL(None).prctl(_PR_SET_PDEATHSIG, sig) == 0
    except (OSError, AttributeError):
        linux = False
    if os.getppid() != parent:  # the parent died before the prctl
        os._exit(1)
    if not linux:
        threading.Thread(target=_watch, args=(parent,), daemon=True, name="parent-watchdog").start()


def _child(task, reader, writer, parent: int) -> None:
    """In the forked process: run the task, sending its messages and then its result or its
    exception."""
    reader.close()  # a send to a parent that is gone then fails instead of blocking
    _die_with(parent)
    try:
        result = task(lambda message: writer.send(("message", message)))
        writer.send(("result", result))
    except BaseException as exc:  # noqa: BLE001 - every failure goes back to the parent
        try:
            pickle.loads(pickle.dumps(exc))
        except Exception:  # noqa: BLE001 - an exception that does not survive pickling: its text
            exc = RuntimeError(f"{type(exc).__name__}: {exc}")
        writer.send(("error", exc))
    finally:
        writer.close()
