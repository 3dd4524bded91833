"""Low-overhead evaluation of small CasADi functions in hot loops.

Calling a CasADi ``Function`` from Python costs ~50 us of argument conversion, far more than
evaluating a 3x3 Newton solve.  For the event-driven stepper (hundreds of solves per cycle) we
generate C code from the same CasADi function, compile it once per machine with the system C
compiler (cached on disk, keyed by a hash of the source), and call it through ctypes with
preallocated buffers (~3 us per call).  Without a working compiler, or with
``OCP_CRAWL_NO_COMPILE=1``, the CasADi function itself is used: same numbers, slower.
"""
from __future__ import annotations

import ctypes
import errno
import hashlib
import os
import shutil
import stat
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Callable, Sequence, TypeVar

import casadi as cs
import numpy as np

from ocp_crawl.io.files import remove_stale_temps, temp_prefix
from ocp_crawl.model.buffered import Buffered


#: zero-argument builders of the package's compiled functions ("module.qualname" -> builder
#: returning a FastFunction), registered by :func:`compiled_function`; ``ocp-crawl warmup`` builds
#: them all, and tests/test_warmup.py checks that every FastFunction of the package is made by a
#: registered builder
BUILDERS: dict[str, Callable[[], "FastFunction"]] = {}


_Builder = TypeVar("_Builder", bound=Callable[..., "FastFunction"])


def compiled_function(builder: _Builder) -> _Builder:
    """Decorator: register ``builder`` (callable without arguments, returns a
    :class:`FastFunction`; arguments with defaults choose variants, e.g. a chain's number of
    links) in :data:`BUILDERS`."""
    BUILDERS[f"{builder.__module__}.{builder.__qualname__}"] = builder
    return builder


#: C compiler flags of the libraries.  -fno-math-errno lets the compiler use the square-root
#: instruction instead of a libm call that sets errno (the same correctly rounded value; 20-25 %
#: faster solves); no flag that changes floating-point results (no -ffast-math, no -march that would
#: allow fused multiply-adds)
CFLAGS = ("-O2", "-fno-math-errno")

#: say on stderr, once per process, when a library is compiled because the cache does not hold it
#: yet (the first run on a machine pauses for seconds); False: silent (the test suite, whose checks
#: of stderr must not depend on the state of the cache)
ANNOUNCE_BUILDS = True
_announced = False


def _announce_build(out_dir: Path) -> None:
    """One line on stderr (never stdout, which may carry --json output) the first time this process
    compiles."""
    global _announced
    if not ANNOUNCE_BUILDS or _announced:
        return
    _announced = True
    print(f"ocp-crawl: compiling the model's C functions into {out_dir} (not in the cache yet; "
          "once per machine)", file=sys.stderr, flush=True)


class CacheError(ValueError):
    """The compiled-library cache cannot be used (bad input: ``OCP_CRAWL_CACHE`` or
    ``XDG_CACHE_HOME``).

    The message is one line naming the variable, the path and what is wrong with it.
    """

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))


def cache_dir() -> Path:
    """The compiled-library cache: ``$OCP_CRAWL_CACHE``, else ``$XDG_CACHE_HOME/ocp_crawl`` or
    ``~/.cache/ocp_crawl`` (not checked: see :func:`usable_cache_dir`)."""
    base = os.environ.get("OCP_CRAWL_CACHE")
    if base:
        return Path(base)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return Path(xdg if xdg else Path.home() / ".cache") / "ocp_crawl"


def _cache_name(path: Path) -> str:
    """The cache directory in messages, with the variable that chose it."""
    if os.environ.get("OCP_CRAWL_CACHE"):
        return f"OCP_CRAWL_CACHE={path}"
    if os.environ.get("XDG_CACHE_HOME"):
        return f"compiled-library cache {path} (XDG_CACHE_HOME={os.environ['XDG_CACHE_HOME']})"
    return f"compiled-library cache {path}"


def _kind(path: Path) -> str:
    """What ``path``, which is not a directory, is: "a regular file", "a character device", ..."""
    try:
        mode = path.stat().st_mode
    except OSError:
        return "not a directory"
    kinds = ((stat.S_ISREG, "a regular file"), (stat.S_ISCHR, "a character device"),
             (stat.S_ISBLK, "a block device"),
             (stat.S_ISFIFO, "a named pipe"), (stat.S_ISSOCK, "a socket"))
    return next((name for test, name in kinds if test(mode)), "not a directory")


def _not_usable(exc: OSError, path: Path) -> str:
    """Why ``path`` cannot be created as a directory, in words."""
    if isinstance(exc, FileExistsError):
        return f"not a directory (it is {_kind(path)})"
    if isinstance(exc, NotADirectoryError):
        # the first name of the path that exists and is not a directory
        blocker = next((p for p in reversed(path.parents) if p.exists() and not p.is_dir()),
                       path.parent)
        return f"not a directory ({blocker} in its path is {_kind(blocker)})"
    if exc.errno == errno.ENAMETOOLONG:
        longest, total = (max(len(os.fsencode(part)) for part in path.parts),
                          len(os.fsencode(str(path))))
        return (f"name too long ({exc.strerror}; its longest name has {longest} bytes, the path "
                f"{total})")
    if isinstance(exc, PermissionError) or exc.errno == errno.EROFS:
        return f"not writable: cannot create the directory ({exc.strerror})"
    return f"cannot create the directory: {exc.strerror or exc}"


def usable_cache_dir() -> Path:
    """:func:`cache_dir`, created if absent and checked to be a writable directory.

    Raises
    ------
    CacheError : naming the variable that chose the directory, the path and the reason (not a
        directory, not writable, name too long, ...), before anything is compiled into it.
    """
    path = cache_dir()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CacheError(f"{_cache_name(path)}: {_not_usable(exc, path)}; the cache must be a "
                         "writable directory") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise CacheError(f"{_cache_name(path)}: directory is not writable; the cache must be a "
                         "writable directory")
    return path


def _compiler() -> str | None:
    for cc in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if cc and shutil.which(cc):
            return cc
    return None


def _generate(funs: Sequence[cs.Function]) -> str:
    """The C source of ``funs`` in one file (CasADi's code generator, no header)."""
    with tempfile.TemporaryDirectory() as tmp:
        cwd = os.getcwd()
        try:
            os.chdir(tmp)
            gen = cs.CodeGenerator(f"{funs[0].name()}.c", {"with_header": False})
            for fun in funs:
                gen.add(fun)
            gen.generate()
            return Path(tmp, f"{funs[0].name()}.c").read_text()
        finally:
            os.chdir(cwd)


def _key(fun: cs.Function, cc: str, tag: str = "") -> str:
    """Cache key of ``fun``'s library: a hash of its serialised expression graph (a few ms, against
    10-20 ms for generating the C source, which a warm run thus never does), the CasADi version,
    platform, compiler and flags, and ``tag`` (what else the library holds, see
    :func:`build_library`)."""
    tag = "|".join(("codegen-v2", " ".join(CFLAGS), cs.__version__, sys.platform,
                    cc)) + (f"|{tag}" if tag else "")
    return hashlib.sha256(fun.serialize().encode() + tag.encode()).hexdigest()[:16]


#: why the last build of each function (by name) made no library: ("compiler", text) no working
#: compiler, ("disk", text) the cache could not be written (a full disk, ...; text names the
#: file), ("build", text) the compiler failed otherwise.  Read by ocp_crawl.sweep.warmup.warmup.
BUILD_FAILURES: dict[str, tuple[str, str]] = {}

NO_COMPILER = "no working C compiler (cc, gcc, clang or $CC)"
#: errors of a cache that cannot take a file: full disk, quota, read-only, failing device, too large
DISK_ERRORS = (errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EIO, errno.EFBIG)


def _failed(name: str, kind: str, text: str) -> None:
    BUILD_FAILURES[name] = (kind, " ".join(text.split()))


def _compiler_failure(proc: subprocess.CompletedProcess, lib: Path) -> tuple[str, str]:
    """Why the compiler failed: a full disk (or another write error) names the library, else the
    compiler's last line."""
    last = (proc.stderr or "").strip().splitlines()[-1:] or [f"exit status {proc.returncode}"]
    for code in DISK_ERRORS:
        if os.strerror(code) in (proc.stderr or ""):
            return "disk", f"{lib}: {os.strerror(code)} (the compiler could not write it)"
    return "build", f"the C compiler failed on {lib.name}: {last[0]}"


def build_library(fun: cs.Function, companions: Callable[[], Sequence[cs.Function]] | None = None,
                  tag: str = "") -> Path | None:
    """The shared library of ``fun`` in the cache, compiled from its C source if not there yet.

    Parameters
    ----------
    fun : the function; the library is named after it and keyed by its expression graph.
    companions : called only when the library is built: the functions it holds (``fun`` first;
        default ``[fun]``), e.g. ``fun`` and its derivatives, which are functions of ``fun`` alone.
    tag : names what ``companions`` adds (part of the cache key; empty for ``fun`` alone).

    Returns
    -------
    Path or None : the library, or None if not possible (no compiler, a failed build).
    """
    cc = _compiler()
    if cc is None:
        _failed(fun.name(), "compiler", NO_COMPILER)
        return None
    out_dir = cache_dir()
    lib = out_dir / f"{fun.name()}_{_key(fun, cc, tag)}.so"
    if lib.exists():
        return lib
    _announce_build(out_dir)
    try:
        src = _generate(companions() if companions is not None else [fun])
        out_dir.mkdir(parents=True, exist_ok=True)
        # the source and the library are built in a private directory and the library is renamed
        # into place: a reader (or a concurrent builder) never sees a partial library.  A build
        # killed half-way leaves its directory; the next build removes it (files.remove_stale_temps)
        remove_stale_temps(out_dir, lib.name)
        with tempfile.TemporaryDirectory(dir=out_dir, prefix=temp_prefix(lib.name),
                                         suffix=".tmp") as tmp:
            c_file = Path(tmp, "f.c")
            c_file.write_text(src)
            tmp_lib = Path(tmp, "f.so")
            proc = subprocess.run([cc, *CFLAGS, "-shared", "-fPIC", "-o", str(tmp_lib), str(c_file),
                                   "-lm"],
                                  capture_output=True, text=True, timeout=300)
            if proc.returncode != 0:
                _failed(fun.name(), *_compiler_failure(proc, lib))
                return None
            os.replace(tmp_lib, lib)
    except OSError as exc:   # the cache cannot be written (a full disk, ...): name the file
        where = lib if exc.filename is None or ".tmp" in str(exc.filename) else exc.filename
        kind = "disk" if exc.errno in DISK_ERRORS else "build"
        _failed(fun.name(), kind, f"{where}: {exc.strerror or exc}")
        return None
    except subprocess.SubprocessError as exc:
        _failed(fun.name(), "build", f"the C compiler failed on {lib.name}: {exc}")
        return None
    BUILD_FAILURES.pop(fun.name(), None)
    return lib


class FastFunction:
    """Callable wrapper of a CasADi function with dense vector inputs and outputs.

    ``f(*inputs) -> list of 1-D arrays``.  Uses compiled C through ctypes when available.
    """

    def __init__(self, fun: cs.Function):
        self.fun = fun
        self.n_in = [fun.nnz_in(i) for i in range(fun.n_in())]
        self.n_out = [fun.nnz_out(i) for i in range(fun.n_out())]
        self.compiled = False
        self.library: Path | None = None
        """the shared library in the cache (None: evaluated by CasADi)"""
        self._buffered: Buffered | None = None
        """without the library: CasADi's evaluation through the function's buffer"""
        if os.environ.get("OCP_CRAWL_NO_COMPILE", "") not in ("", "0"):
            return
        try:
            lib_path = build_library(fun)
            if lib_path is not None:
                self._load(lib_path)
                self.compiled, self.library = True, lib_path
        except OSError:
            self.compiled = False

    def _load(self, path: Path) -> None:
        lib = ctypes.CDLL(str(path))
        name = self.fun.name()
        work = getattr(lib, f"{name}_work")
        ci = ctypes.c_longlong
        sz = [ci() for _ in range(4)]
        work.argtypes = [ctypes.POINTER(ci)] * 4
        if work(*[ctypes.byref(s) for s in sz]) != 0:
            raise OSError("work query failed")
        sz_arg, sz_res, sz_iw, sz_w = (s.value for s in sz)
        # one contiguous buffer for all inputs and one for all outputs (the arguments are views into
        # them): a call fills the inputs with one assignment (:meth:`flat`) and copies the outputs
        # once
        self._inbuf, self._in = _stacked(self.n_in)
        self._outbuf, self._out = _stacked(self.n_out)
        self._cin = ((ctypes.c_double * max(self._inbuf.size, 1)).from_buffer(self._inbuf)
                     if self._inbuf.size else None)
        dp = ctypes.POINTER(ctypes.c_double)
        self._arg = (dp * max(sz_arg, len(self._in)))(*[a.ctypes.data_as(dp) for a in self._in])
        self._res = (dp * max(sz_res, len(self._out)))(*[a.ctypes.data_as(dp) for a in self._out])
        self._iw = (ci * max(sz_iw, 1))()
        self._w = (ctypes.c_double * max(sz_w, 1))()
        self._f = getattr(lib, name)
        self._f.restype = ctypes.c_int
        self._call_args = (self._arg, self._res, self._iw, self._w, 0)
        self._lib = lib
        self._kept: tuple | None = None
        """(list, position) of the inputs that :meth:`flat` keeps in the input buffer, None if
        none"""

    def __call__(self, *inputs) -> list[np.ndarray]:
        if not self.compiled:
            if self._buffered is None:
                self._buffered = Buffered(self.fun)
            out = self._buffered(*inputs)
            return [o.ravel(order="F") for o in (out if isinstance(out, tuple) else (out,))]
        self._kept = None
        for buf, x in zip(self._in, inputs):
            np.copyto(buf, x)
        if self._f(*self._call_args) != 0:
            raise FloatingPointError(f"compiled {self.fun.name()} failed")
        return [o.copy() for o in self._out]

    def flat(self, values: list, kept: list | None = None) -> np.ndarray:
        """The function at flat inputs: the same numbers as ``__call__``, with the least Python work
        per call (one assignment of the inputs, one copy of the outputs; for the stepper's hot
        loop).

        Parameters
        ----------
        values : list of float
            All inputs one after the other (``sum(n_in)`` values, each input in column-major order),
            or the first ones if ``kept`` is given.
        kept : list of float, optional
            The last inputs, as a list that the caller never changes: while the same list (the same
            object) comes again after the same number of ``values``, it is still in the input buffer
            and not written anew.

        Returns
        -------
        ndarray, shape (sum(n_out),)
            All outputs one after the other, in a new array.
        """
        if not self.compiled:
            values = values + kept if kept is not None else values
            ends = np.cumsum(self.n_in).tolist()
            return np.concatenate(self(*(values[a:b] for a, b in zip([0] + ends[:-1], ends))))
        if kept is None:
            self._cin[:] = values
            self._kept = None
        else:
            n = len(values)
            self._cin[:n] = values
            k = self._kept
            if k is None or k[0] is not kept or k[1] != n:
                self._cin[n:] = kept
                self._kept = (kept, n)
        if self._f(*self._call_args) != 0:
            raise FloatingPointError(f"compiled {self.fun.name()} failed")
        return self._outbuf.copy()


def _stacked(sizes: list[int]) -> tuple[np.ndarray, list[np.ndarray]]:
    """A zero buffer of sum(sizes) floats and its consecutive views of the given sizes."""
    buf = np.zeros(sum(sizes))
    ends = np.cumsum([0] + sizes).tolist()
    return buf, [buf[a:b] for a, b in zip(ends[:-1], ends[1:])]
