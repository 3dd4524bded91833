"""Prebuild the per-user cache of compiled libraries (``ocp-crawl warmup``).

The first simulation on a machine compiles the model's C functions (a few seconds, see
:mod:`ocp_crawl.model.compiled`); every later process loads them from the cache.  On a fresh
cluster node, or in a container image, building them once beforehand keeps that cost out of the
first sweep points and out of every worker that would otherwise compile them at the same time.

Every compiled function of the package is made by a builder registered with
:func:`ocp_crawl.model.compiled.compiled_function`; :func:`warmup` imports the package's modules up
to this floor (so that each registers its builders) and builds them all.
"""
from __future__ import annotations

import importlib
import os
import pkgutil
import time
from dataclasses import dataclass
from pathlib import Path

from ocp_crawl.model.compiled import BUILD_FAILURES, BUILDERS, cache_dir, usable_cache_dir

#: subpackages whose modules may define compiled functions (the floors up to sweep, ARCHITECTURE.md)
PACKAGES = ("ocp_crawl.model", "ocp_crawl.nlp", "ocp_crawl.sim", "ocp_crawl.ocp",
            "ocp_crawl.problem", "ocp_crawl.sweep")


@dataclass(frozen=True)
class Built:
    """One compiled function after warm-up."""

    builder: str
    """the registered builder (module.function)"""
    function: str
    """the CasADi function's name"""
    library: Path | None
    """its shared library in the cache (None: not compiled, evaluated by CasADi)"""
    state: str
    """"built" (compiled now), "cached" (already in the cache) or "not compiled\""""
    seconds: float
    """wall time of the build [s]"""
    failure: tuple[str, str] | None = None
    """why it is not compiled: (kind, text), kind "compiler", "disk" or "build"
    (compiled.BUILD_FAILURES)"""


@dataclass(frozen=True)
class WarmupResult:
    """What :func:`warmup` did: the cache directory, each function, the total time [s]."""

    cache: Path
    functions: tuple[Built, ...]
    seconds: float
    disabled: bool
    """OCP_CRAWL_NO_COMPILE is set: nothing is compiled, by request"""

    def count(self, state: str) -> int:
        """Number of functions in ``state`` ("built", "cached" or "not compiled")."""
        return sum(f.state == state for f in self.functions)

    @property
    def failure(self) -> str:
        """Why functions are not compiled, in one line: a cache that cannot be written (a full
        disk; naming the file) before a failed compiler, before a missing compiler."""
        found = {f.failure[0]: f.failure[1] for f in reversed(self.functions) if f.failure}
        disk = "cannot write the compiled-library cache: "
        for kind, prefix in (("disk", disk), ("build", ""), ("compiler", "")):
            if kind in found:
                return prefix + found[kind]
        return "" if self.ok else f"{self.count('not compiled')} functions not compiled"

    @property
    def ok(self) -> bool:
        """Every function is compiled (or compilation is disabled on purpose)."""
        return self.disabled or self.count("not compiled") == 0


def _register_all() -> None:
    """Import every module of :data:`PACKAGES`: each registers its builders in BUILDERS."""
    for name in PACKAGES:
        package = importlib.import_module(name)
        for info in pkgutil.walk_packages(package.__path__, prefix=name + "."):
            importlib.import_module(info.name)


def warmup() -> WarmupResult:
    """Build every compiled function of the package into the cache
    (:func:`~ocp_crawl.model.compiled.cache_dir`: ``$OCP_CRAWL_CACHE``, else
    ``$XDG_CACHE_HOME/ocp_crawl`` or ``~/.cache/ocp_crawl``).

    A library already in the cache is not rebuilt; builds are safe to run concurrently with other
    processes (each library is renamed into place when complete).

    Returns
    -------
    WarmupResult : the cache directory and, per function, its library and whether it was built now.

    Raises
    ------
    CacheError : the cache is not a writable directory (checked first; unless OCP_CRAWL_NO_COMPILE
    is set).
    """
    start = time.perf_counter()
    disabled = os.environ.get("OCP_CRAWL_NO_COMPILE", "") not in ("", "0")
    # an unusable cache would fail every build, which then looks like a missing compiler: say what
    # is wrong
    cache = cache_dir() if disabled else usable_cache_dir()
    _register_all()
    functions = []
    for name in sorted(BUILDERS):
        before = set(cache.glob("*.so")) if cache.is_dir() else set()
        t0 = time.perf_counter()
        builder = BUILDERS[name]
        # a fresh build, not the process's cached one (which may come from another cache directory)
        fast = getattr(builder, "__wrapped__", builder)()
        library = fast.library if fast.compiled else None
        state = "not compiled" if library is None else "cached" if library in before else "built"
        failure = BUILD_FAILURES.get(fast.fun.name()) if library is None and not disabled else None
        functions.append(Built(name, fast.fun.name(), library, state, time.perf_counter() - t0,
                               failure))
    return WarmupResult(cache, tuple(functions), time.perf_counter() - start, disabled)
