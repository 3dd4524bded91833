"""Newton solves of a contact mode for the event-driven stepper, one point at a time or many at
once, counted.

:class:`ModeSolver` is the one place where the stepper calls the compiled mode system; every other
part asks it for solved points (:class:`~ocp_crawl.sim.event_state._Point`).
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.model.statics import AUX, NAUX, solve_many
from ocp_crawl.sim.event_context import StepperContext
from ocp_crawl.sim.event_kinks import InputPieces
from ocp_crawl.sim.event_state import _LeftPoint, _Point

#: positions in the flat output (x (3), aux (NAUX)[, extra]) of a compiled solve: the residual, the
#: end of aux
_RES3, _EXTRA3 = 3 + AUX["res"], 3 + NAUX


class ModeSolver:
    """Solves of the compiled mode system with the input of ``pieces`` (its values at kinks) and the
    model's parameters; ``nfev`` counts the solves since :meth:`reset`."""

    def __init__(self, ctx: StepperContext, pieces: InputPieces):
        self._newton, self._step_fn, self._res_tol = ctx.newton, ctx.step_fn, ctx.res_tol
        self._p, self._p_list = ctx.p, ctx.p_list
        self._pieces = pieces
        self.nfev = 0
        self._tails: dict = {}
        """id(q) -> (q, the solves' last inputs (q, p) as a list) of the mode parameters q of the
        run"""

    def reset(self) -> None:
        """Start a run: no solves counted, no mode parameters kept."""
        self.nfev = 0
        self._tails.clear()

    def solve(self, t: float, x0: np.ndarray | list, q: np.ndarray, step: bool = False,
              left: bool = False, held: bool = False) -> _Point | None:
        """Newton solve of the mode q at phase t from x0 (an array or a list); None if it does not
        converge.

        ``step``: a continuation step, solved by :func:`~ocp_crawl.model.stability.fast_step` (the
        point then carries its stability numbers and d'' coefficients).  At a kink of the input the
        rates are those after it, or before it with ``left`` (:mod:`ocp_crawl.sim.event_kinks`);
        ``held``: with the rates of a hold (zero)."""
        pieces = self._pieces
        tq = pieces.values(float(t)) if not left else \
            pieces.kink_values(t, True) or pieces.values(float(t))
        if held:
            tq = tq[:2] + [0.0, 0.0]
        fn, tol = self._step_fn if step else self._newton, self._res_tol
        tail = self._tails.get(id(q))
        # (q, its inputs q and p as a list, kept in the compiled buffer)
        if tail is None or tail[0] is not q:
            tail = self._tails[id(q)] = (q, q.tolist() + self._p_list)
        xl = x0 if type(x0) is list else x0.tolist()
        for _ in range(4):
            out = fn.flat(xl + tq, tail[1])  # x (3), aux (NAUX)[, extra]
            self.nfev += 1
            lst = out.tolist()
            xl, res = lst[:3], lst[_RES3]
            # (the compiled max norm of a NaN residual can read 0)
            if not math.isfinite(xl[0] + xl[1] + xl[2]):
                return None
            if not res <= tol:  # also catches NaN
                if not math.isfinite(res) or res > 1e3:
                    return None
                continue
            kind = _LeftPoint if left else _Point
            return kind(t, out[:3], out[3:_EXTRA3], tau=tq[:2], dtau=tq[2:], q=q,
                        extra=out[_EXTRA3:] if step else None, a=lst[3:_EXTRA3], xl=xl)
        return None

    def solve_many(self, guesses: np.ndarray, tau: np.ndarray, dtau: np.ndarray,
                   Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Independent Newton solves (one batched compiled call) of the modes Q (4, n) from the
        guesses (3, n) with the torques and rates (2, n): x (3, n), aux (NAUX, n)
        (:func:`~ocp_crawl.model.statics.solve_many`)."""
        out = solve_many(guesses, tau, dtau, Q, self._p)
        self.nfev += guesses.shape[1]
        return out

    @property
    def res_tol(self) -> float:
        """the accepted residual of a solve"""
        return self._res_tol
