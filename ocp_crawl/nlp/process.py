"""Process-level resources around IPOPT solves: glibc's heap during a solve
(:func:`heap_allocations`) and the thread count of the OpenBLAS that CasADi bundles for IPOPT's
MUMPS (:func:`single_threaded_blas`).

Both act on the whole process through ctypes, and both leave alone what a user set (malloc's
environment variables and tunables, OpenBLAS's thread-count variables).  Imports no module of the
package.
"""
from __future__ import annotations

import ctypes
import os
from contextlib import contextmanager

#: glibc's mallopt parameters (malloc.h)
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD, _M_MMAP_MAX = -1, -3, -4
#: free memory at the top of the heap that a solve keeps rather than return to the system [bytes]
HEAP_KEEP = 1 << 30
#: glibc's malloc between solves (glibc has no getter, and any mallopt call ends its dynamic
#: thresholds for the process): mmap for blocks of 32 MiB and more, the heap trimmed above 64 MiB
#: free, the values its dynamic rule reaches at its largest (mmap threshold at most 32 MiB on 64-bit
#: systems, trim threshold twice it)
_BETWEEN_SOLVES = {_M_MMAP_MAX: 65536, _M_MMAP_THRESHOLD: 32 << 20, _M_TRIM_THRESHOLD: 64 << 20}
#: environment variables by which a user tunes glibc's malloc (then :func:`heap_allocations` does
#: nothing)
MALLOC_VARIABLES = ("MALLOC_MMAP_MAX_", "MALLOC_TRIM_THRESHOLD_", "MALLOC_MMAP_THRESHOLD_",
                    "MALLOC_TOP_PAD_")
_mallopt: list = []
_heap_depth = [0]


def _find_mallopt():
    """glibc's ``mallopt`` (None on other C libraries, or when the user tunes malloc:
    :data:`MALLOC_VARIABLES` or ``glibc.malloc.`` tunables in ``GLIBC_TUNABLES``)."""
    if not _mallopt:
        fun = None
        if not any(os.environ.get(v) for v in MALLOC_VARIABLES) and (
                "glibc.malloc." not in os.environ.get("GLIBC_TUNABLES", "")):
            try:
                fun = ctypes.CDLL(None).mallopt
                fun.argtypes, fun.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
            except (OSError, AttributeError, TypeError):
                fun = None
        _mallopt.append(fun)
    return _mallopt[0]


@contextmanager
def heap_allocations():
    """During an IPOPT solve, glibc serves large blocks from the heap and keeps freed memory (up to
    :data:`HEAP_KEEP`); afterwards its malloc works with fixed thresholds (:data:`_BETWEEN_SOLVES`).
    Does nothing off glibc or when the user tunes malloc; nested uses act once, at the outermost.

    MUMPS allocates its factorisation workspace (tens of MB for the robust OCP) at every
    factorisation; glibc serves such blocks by mmap and returns them on free, so every iteration
    page-faults its workspace afresh.  Measured, robust_speed's first homotopy stage at N = 50 (150
    IPOPT iterations), three alternating pairs, the other core busy: 9.5 / 10.0 / 10.2 s with heap
    allocations against 11.9 / 14.6 / 11.8 s (system time 0.2 s against 2.2 to 2.8 s), the same peak
    memory (285 MB)."""
    fun = _find_mallopt()
    outer = fun is not None and not _heap_depth[0]
    if outer:
        fun(_M_MMAP_MAX, 0)
        fun(_M_TRIM_THRESHOLD, HEAP_KEEP)
    _heap_depth[0] += 1
    try:
        yield
    finally:
        _heap_depth[0] -= 1
        if outer:
            for param, value in _BETWEEN_SOLVES.items():
                fun(param, value)


#: the soname of the OpenBLAS that CasADi bundles (Linux wheels), which IPOPT's MUMPS links
CASADI_OPENBLAS = "libcasadi-tp-openblas.so.0"
#: environment variables by which a user sets OpenBLAS's thread count (then
#: :func:`single_threaded_blas` does nothing)
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")
_blas_done: list[int] = []


def single_threaded_blas() -> int | None:
    """Run the OpenBLAS bundled with CasADi (under IPOPT's MUMPS) on one thread, unless one of
    :data:`BLAS_THREAD_VARIABLES` is set; returns the thread count it had (None: not loaded, not
    found on this platform, or left as the user set it).  Never loads a library and never raises.

    The KKT systems are small (a few thousand rows): a second thread gains nothing on idle cores and
    spins against other processes on busy ones (measured, the first homotopy stage of max_speed at
    N = 50, 885 IPOPT iterations: idle, 21.0 s on one thread and 20.5-21.1 s on two; the other core
    busy, 36 s of which 15 s system time on two threads, 25 s on one), and the thread count no
    longer depends on the machine's cores.  Called after a solver is built (the library is loaded
    with IPOPT; found by its soname with RTLD_NOLOAD, i.e. the very instance MUMPS uses, without
    changing its symbol scope); done once per process.  numpy's own BLAS is untouched."""
    if _blas_done:
        return _blas_done[0]
    if any(os.environ.get(v) for v in BLAS_THREAD_VARIABLES) or not hasattr(os, "RTLD_NOLOAD"):
        return None
    try:
        lib = ctypes.CDLL(CASADI_OPENBLAS, mode=os.RTLD_NOLOAD)
        before = int(lib.openblas_get_num_threads())
        lib.openblas_set_num_threads(1)
    except (OSError, AttributeError):  # not loaded (yet), another platform's wheel, or another BLAS
        return None
    _blas_done.append(before)
    return before
