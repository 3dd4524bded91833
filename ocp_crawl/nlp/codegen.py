"""Compiled evaluation of an NLP's per-step kernel, with the derivatives IPOPT needs.

A transcribed OCP applies one small function (the step equations of one interval: the *kernel*) at
every node, ``kernel.map(N)``.  IPOPT with exact Hessians then evaluates, every iteration, the
kernel, its Jacobian (CasADi: reverse or forward directional derivatives of the map, several
directions at once) and the Hessian of the Lagrangian (forward derivatives of the kernel's adjoint).
CasADi's virtual machine spends most of an OCP solve there.  :func:`compiled_kernel` generates C
code for the kernel and for those derivatives, compiles it once into the package's compiled-library
cache (:func:`ocp_crawl.model.compiled.build_library`: keyed by the kernel's expression graph, the
CasADi version and the compiler; built in a private directory and renamed into place) and returns a
CasADi ``external`` of it.  The external finds its derivatives in the library by CasADi's naming
convention (``fwd<n>_f``, ``adj<n>_f``, ``fwd<n>_adj1_f``, ``jac_f``, ``jac_adj1_f``): a map of it,
and every derivative CasADi takes of the map, runs compiled code.  The Jacobians in the library give
CasADi the exact sparsity of the kernel's first and second derivatives (an external without them is
taken as dense, which would make the Hessian's colouring and the KKT system denser).  CasADi asks
for ``n`` directions at a time; ``n`` not in :data:`DIRECTIONS` is evaluated as ``n`` compiled
one-direction calls.

The kernel must not depend on N (it is compiled once for every N).  Without a working C compiler (or
a failed build) the kernel itself is returned with a warning: same numbers, CasADi's virtual
machine; ``OCP_CRAWL_NO_COMPILE=1`` does the same on purpose, silently.
"""
from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import casadi as cs

from ocp_crawl.model.compiled import build_library

#: numbers of directions of the derivatives in a kernel's library (CasADi uses an external's
#: ``fwd<n>`` or ``adj<n>`` only for a power of two n, and ``n`` one-direction calls otherwise)
DIRECTIONS = (1, 2, 4, 8)

#: what a kernel's library holds besides the kernel (part of its cache key)
_TAG = "kernel-v1:jac,jac_adj1,fwd,adj,fwd_adj1:" + ",".join(map(str, DIRECTIONS))

#: externals already loaded in this process, by library path
_LOADED: dict[str, cs.Function] = {}


def kernel_functions(fun: cs.Function) -> list[cs.Function]:
    """``fun`` and the derivatives that go into its library, named by CasADi's convention: its
    Jacobian and the Jacobian of its adjoint (for their sparsity), forward and reverse derivatives
    in :data:`DIRECTIONS` directions (Jacobians), and forward derivatives of its one-direction
    adjoint (Hessians)."""
    adj = fun.reverse(1)
    return [fun, fun.jacobian(), adj.jacobian(), *(fun.forward(n) for n in DIRECTIONS),
            *(fun.reverse(n) for n in DIRECTIONS), *(adj.forward(n) for n in DIRECTIONS)]


@dataclass(frozen=True)
class KernelBuild:
    """A kernel and the function to use in its place (see :func:`kernel_library`)."""

    fun: cs.Function
    """the kernel as given"""
    function: cs.Function
    """the compiled external (or ``fun`` itself when not compiled)"""
    library: Path | None
    """its shared library in the cache (None: not compiled)"""

    @property
    def compiled(self) -> bool:
        return self.library is not None


def kernel_library(fun: cs.Function) -> KernelBuild:
    """The compiled kernel of ``fun`` with its library (built into the cache if not there yet).

    Parameters
    ----------
    fun : a CasADi function independent of the number of nodes (typically SX, dense inputs and
    outputs).

    Returns
    -------
    KernelBuild : ``function`` evaluates like ``fun`` (same inputs, outputs, sparsity and
    derivatives) from compiled code; it is ``fun`` itself, with a RuntimeWarning, when no C compiler
    works, and silently when ``OCP_CRAWL_NO_COMPILE`` is set.
    """
    if not isinstance(fun, cs.Function):
        raise TypeError(f"compiled_kernel: fun must be a casadi.Function, got {type(fun).__name__}")
    if os.environ.get("OCP_CRAWL_NO_COMPILE", "") not in ("", "0"):
        return KernelBuild(fun, fun, None)
    try:
        lib = build_library(fun, lambda: kernel_functions(fun), _TAG)
    except RuntimeError as exc:  # CasADi cannot generate code for fun
        lib, reason = None, str(exc).strip().splitlines()[-1]
    else:
        reason = "no working C compiler, or its build failed"
    if lib is None:
        warnings.warn(f"compiled_kernel: {fun.name()} is not compiled ({reason}); it is evaluated "
                      "by CasADi's virtual machine: same results, slower", RuntimeWarning,
                      stacklevel=3)
        return KernelBuild(fun, fun, None)
    ext = _LOADED.get(str(lib))
    if ext is None:
        ext = _LOADED[str(lib)] = cs.external(fun.name(), str(lib))
    return KernelBuild(fun, ext, lib)


def compiled_kernel(fun: cs.Function) -> cs.Function:
    """``fun`` evaluated by compiled C code, derivatives included: use it in place of ``fun``, e.g.
    ``compiled_kernel(step).map(N)``.  See :func:`kernel_library` (the fall-back without a
    compiler)."""
    return kernel_library(fun).function
