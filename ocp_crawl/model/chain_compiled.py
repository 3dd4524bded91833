"""The n-link chain's statics as compiled C functions (:mod:`ocp_crawl.model.compiled`), for the hot
loops of its torque-driven stepper.

A mode's Newton solve is one compiled call (CasADi's ``fast_newton`` root finder on the chain's
mode system, :func:`~ocp_crawl.model.chain_statics.chain_symbolic`, followed by its outputs): about
20 us for the five-link chain, against about 200 us for the same iterations driven from Python
with each evaluation of the mode system in CasADi's virtual machine (14 us a column there, 1 us
compiled).  Each column of a map is solved on its own, as a single call.  One library per
function and number of links n, built on first use and kept in the cache; ``ocp-crawl warmup``
builds those of the five-link chain (the shipped file's; the builders' default n), another n
compiles once on its first run (about 5 s).  Without a compiler (or with
``OCP_CRAWL_NO_COMPILE=1``) CasADi evaluates them: the same numbers, slower.

Matrix inputs of the mapped functions are taken in chunks of :data:`WIDE` columns, the last ones in
chunks of :data:`NARROW` (:class:`Columns`).
"""
from __future__ import annotations

from functools import lru_cache

import casadi as cs
import numpy as np

from ocp_crawl.model.chain_stability import chain_margin_function
from ocp_crawl.model.chain_statics import chain_symbolic
from ocp_crawl.model.compiled import FastFunction, compiled_function

#: the number of links whose functions ``ocp-crawl warmup`` builds (the builders' default)
WARM_LINKS = 5
#: widths of the compiled column maps (a call costs about 1 us a column, padding included)
WIDE, NARROW = 64, 16


#: the Newton solve of a mode (CasADi's ``fast_newton`` root finder, compiled as a loop): stops
#: when the largest scaled residual |G| is at most ``abstol`` or a step at most ``abstolStep``
#: (the residual then at the rounding level of its largest term, as for very stiff joints), after
#: at most ``max_iter`` steps; the caller judges the point by its residual (``res`` in the outputs)
NEWTON_OPTIONS = {"abstol": 1e-13, "abstolStep": 1e-14, "max_iter": 40, "error_on_fail": False}


@lru_cache(maxsize=None)
def _newton(n: int, with_jacobian: bool) -> cs.Function:
    """``(x0, tau, dtau, q, p) -> (x, aux[, J])``: the mode's equilibrium by Newton's method from
    x0, its outputs (:attr:`~ocp_crawl.model.chain_statics.ChainSymbolic.evaluate`) and, with
    ``with_jacobian``, the mode system's Jacobian there (n x n)."""
    sym = chain_symbolic(n)
    p = cs.SX.sym("p", sym.system.size1_in(3))
    x, x0 = cs.SX.sym("x", n), cs.SX.sym("x0", n)
    tau, dtau, q = cs.SX.sym("tau", n - 1), cs.SX.sym("dtau", n - 1), cs.SX.sym("q", 4)
    rest = cs.vertcat(tau, q, p)
    g = cs.Function("g", [x, rest], [sym.system(x, tau, q, p)[0]])
    root = cs.rootfinder(f"chain{n}_root", "fast_newton", g, NEWTON_OPTIONS)
    xs = root(x0, rest)
    outs = [xs, sym.evaluate(xs, tau, dtau, q, p)]
    if with_jacobian:
        outs.append(sym.system(xs, tau, q, p)[1])
    name = f"chain{n}_newton" + ("" if with_jacobian else "_point")
    return cs.Function(name, [x0, tau, dtau, q, p], outs)


@compiled_function
@lru_cache(maxsize=None)
def fast_chain_newton(n: int = WARM_LINKS) -> FastFunction:
    """The Newton solve of a mode of the n-link chain, its outputs and Jacobian, compiled."""
    return FastFunction(_newton(n, True))


@compiled_function
@lru_cache(maxsize=None)
def fast_chain_ddot2(n: int = WARM_LINKS) -> FastFunction:
    """``(x, tau, dtau, q, p) -> (a, b)`` with d'' = a + b . tau'' of the n-link chain, compiled."""
    return FastFunction(chain_symbolic(n).ddot2)


def _mapped(fun: cs.Function, width: int, shared: tuple[int, ...]) -> cs.Function:
    """``fun`` over ``width`` columns, the inputs ``shared`` passed once for all."""
    # MX symbols keep the map a loop over one copy of the kernel in the generated C
    args = [cs.MX.sym(fun.name_in(i), fun.size1_in(i), 1 if i in shared else width)
            for i in range(fun.n_in())]
    outs = fun.map(width, "serial")(*[cs.repmat(a, 1, width) if i in shared else a
                                      for i, a in enumerate(args)])
    outs = outs if isinstance(outs, (list, tuple)) else [outs]
    return cs.Function(f"{fun.name()}_x{width}", args, list(outs))


@compiled_function
@lru_cache(maxsize=None)
def fast_chain_newton_columns(n: int = WARM_LINKS, width: int = WIDE) -> FastFunction:
    """The Newton solves and outputs over ``width`` columns (q and p shared), compiled."""
    return FastFunction(_mapped(_newton(n, False), width, (3, 4)))


@compiled_function
@lru_cache(maxsize=None)
def fast_chain_newton_columns_narrow(n: int = WARM_LINKS) -> FastFunction:
    """:func:`fast_chain_newton_columns` at :data:`NARROW` columns."""
    return fast_chain_newton_columns(n, NARROW)


@compiled_function
@lru_cache(maxsize=None)
def fast_chain_margin_columns(n: int = WARM_LINKS, width: int = NARROW) -> FastFunction:
    """What the stability margins need
    (:func:`~ocp_crawl.model.chain_stability.chain_margin_function`) over ``width`` columns (q and
    p shared; the stepper asks for a segment's points at a time), compiled."""
    return FastFunction(_mapped(chain_margin_function(n), width, (3,)))


@compiled_function
@lru_cache(maxsize=None)
def fast_chain_margin_columns_wide(n: int = WARM_LINKS) -> FastFunction:
    """:func:`fast_chain_margin_columns` at :data:`WIDE` columns."""
    return fast_chain_margin_columns(n, WIDE)


class Columns:
    """A compiled column map at two widths, called on any number of columns.

    ``Columns(wide, narrow, shared)(*args)``: the matrix arguments (rows, N) are cut into chunks
    of the wide map's width while more than three narrow chunks remain, then of the narrow one
    (the last chunk padded with copies of the last column); the arguments ``shared`` are passed
    whole to every chunk.  Returns each output as an array (rows, k N) of the columns in order
    (k: the output's columns per column of the inputs, e.g. n for a Jacobian), N columns only.
    """

    def __init__(self, wide: FastFunction, narrow: FastFunction, shared: tuple[int, ...]):
        self.wide, self.narrow, self.shared = wide, narrow, shared
        fun = wide.fun
        self._widths = (fun.size2_in(next(i for i in range(fun.n_in()) if i not in shared)),
                        narrow.fun.size2_in(next(i for i in range(fun.n_in())
                                                 if i not in shared)))
        self._rows = [fun.size1_out(i) for i in range(fun.n_out())]

    def __call__(self, *args) -> list[np.ndarray]:
        wide, narrow = self._widths
        n = next(np.shape(a)[1] for i, a in enumerate(args) if i not in self.shared)
        if n == 0:
            return [np.zeros((rows, 0)) for rows in self._rows]
        n_wide = max(0, -(-(n - 3 * narrow) // wide))
        widths = [wide] * n_wide + [narrow] * max(0, -(-(n - n_wide * wide) // narrow))
        total = sum(widths)
        cols = [a if i in self.shared else
                np.concatenate([a, np.repeat(a[:, -1:], total - n, axis=1)], axis=1)
                for i, a in enumerate(np.asarray(a, float) for a in args)]
        outs: list[list[np.ndarray]] = [[] for _ in self._rows]
        s = 0
        for width in widths:
            f = self.wide if width == wide else self.narrow
            res = f(*[c if i in self.shared else c[:, s:s + width].ravel(order="F")
                      for i, c in enumerate(cols)])
            for k, (r, rows) in enumerate(zip(res, self._rows)):
                outs[k].append(r.reshape(rows, -1, order="F"))
            s += width
        return [np.concatenate(o, axis=1)[:, :o[0].shape[1] // widths[0] * n]
                for o in outs]


@lru_cache(maxsize=None)
def newton_columns(n: int) -> Columns:
    """The Newton solves and outputs of the n-link chain over columns (:class:`Columns`): (x0 (n,
    N), tau, dtau (n - 1, N), q, p) -> (x (n, N), aux (rows, N))."""
    return Columns(fast_chain_newton_columns(n), fast_chain_newton_columns_narrow(n), (3, 4))


@lru_cache(maxsize=None)
def margin_columns(n: int) -> Columns:
    """What the stability margins of the n-link chain need over columns (:class:`Columns`): (phi
    (n - 1, N), f_t (1, N), q (4, N), p) -> (A (m m, N), slip (1, N)) of
    :func:`~ocp_crawl.model.chain_stability.chain_margin_function`."""
    return Columns(fast_chain_margin_columns_wide(n), fast_chain_margin_columns(n), (3,))
