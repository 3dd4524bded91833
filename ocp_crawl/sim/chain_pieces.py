"""Kinks and holds of an n-link chain's torque input, as its event-driven stepper reads them.

A piecewise-linear input (:class:`~ocp_crawl.model.sampled.JointLinear` tables, trapezoid pulses,
the optimal-control profiles) has kinks, knots where its rate jumps, and may hold still over
pieces.  The chain's stepper (:mod:`ocp_crawl.sim.chain_torque`) follows the rules of the
three-link stepper (:mod:`ocp_crawl.sim.event_kinks`, whose detection it shares):

* every continuation step ends at the next kink; the point there is solved with the rate of the
  piece before it, then again with the rate of the piece after it: a guard that is negative with
  the rate after it is an event at the kink, its mode decided with the rates after it;
* the rates that feed the guards' rates and the cycle integrals are read inside the piece that
  holds the phase (at a kink: the piece before it or after it, never across it);
* a hold (every joint's rate zero over pieces; a zero-length hold, a rest where two edges meet
  at zero rate) is crossed in one step with the state unchanged, and the mode after it is the
  current one when its guards stay positive with the rates after the hold, else the one mode that
  does (:meth:`ChainTorqueStepper._leave_hold`).

An input without kinks or holds (the harmonic, a Fourier series, splines) reads none of this.
"""
from __future__ import annotations

import bisect
import math

import numpy as np

from ocp_crawl.model.inputs import input_knots
from ocp_crawl.sim.event_kinks import KINK_GAP, hold_spans, input_holds, input_kinks


class ChainPieces:
    """The kinks (phases in [0, 1)) and holds (rows [start, end)) of ``torque``, and the offset
    ``e`` [cycles] at which one-sided rates are read (:func:`input_kinks`)."""

    def __init__(self, torque):
        knots = input_knots(torque)
        self.kinks, self.e = input_kinks(torque, knots)
        self.holds = [tuple(h) for h in input_holds(torque, knots).tolist()]
        self._k = self.kinks.tolist()
        self._knots = knots.tolist()

    def _around(self, t: float, phases: list[float] | None = None) -> list[float]:
        """The absolute phases of the kinks (or of ``phases`` in [0, 1)) in the cycles around
        phase t, sorted."""
        c = math.floor(t)
        return [k + j for j in (c - 1, c, c + 1) for k in (self._k if phases is None else phases)]

    def is_kink(self, t: float) -> bool:
        """Whether phase t [cycles] is a kink (to 1e-12 of a cycle)."""
        return bool(self._k) and min(abs((t - k) - round(t - k)) for k in self._k) <= KINK_GAP

    def next_break(self, t: float) -> float:
        """The first kink or hold start after phase t (later than t + KINK_GAP); inf if none."""
        kinks = self._around(t) + [a for a, _ in hold_spans(self.holds, t)]
        return min((k for k in kinks if k > t + KINK_GAP), default=math.inf)

    def hold_at(self, t: float, rest_left: float | None = None) -> tuple[float, float] | None:
        """The absolute span (start, end) of the hold that holds phase t (from its start on, to
        KINK_GAP), or None; a hold of zero length at t counts unless it is ``rest_left``, the one
        the run has just left."""
        for a, b in hold_spans(self.holds, t):
            if a - KINK_GAP <= t < b - KINK_GAP or (a == b and abs(t - a) <= KINK_GAP
                                                     and a != rest_left):
                return a, b
        return None

    def rate_phase(self, t: float, left: bool = False) -> float:
        """The phase at which the rate of the piece holding t is read: t, or at a kink t -+ e (the
        piece before it when ``left``, else the one after it)."""
        if not self.is_kink(t):
            return t
        return t - self.e if left else t + self.e

    def rate_phases(self, ts: np.ndarray, upto: float | None = None) -> np.ndarray:
        """:meth:`rate_phase` of each of ``ts``: at a kink the piece after it, except at ``upto``
        (the end of an interval of the phases: the piece before it)."""
        if not self._k:
            return ts
        out = np.array(ts, float)
        for i, t in enumerate(out.tolist()):
            if self.is_kink(t):
                out[i] = t - self.e if upto is not None and t == upto else t + self.e
        return out

    def curvature_phase(self, t: float, left: bool = False, dt: float = 1e-5) -> float:
        """The centre of a central difference of step ``dt`` [cycles] of the rate near t that stays
        inside the piece holding t (at a kink: the piece before it when ``left``)."""
        if not self._k:
            return t
        kl = self._around(t)
        i = bisect.bisect_left(kl, t - KINK_GAP) if left else bisect.bisect_right(kl, t + KINK_GAP)
        lo = kl[i - 1] if i > 0 else -math.inf
        hi = kl[i] if i < len(kl) else math.inf
        if hi - lo <= 4 * dt:
            return 0.5 * (lo + hi)
        return min(max(t, lo + 2 * dt), hi - 2 * dt)

    def split(self, a: float, b: float) -> list[tuple[float, float]]:
        """[a, b] cut at the input's knots inside it (its kinks, and the knots where a higher
        derivative jumps, such as a half-cosine edge meeting a flat: quadrature panels end
        there)."""
        knots = self._around(a, self._knots) + self._around(b, self._knots)
        inner = [k for k in knots if a + KINK_GAP < k < b - KINK_GAP]
        edges = [a, *sorted(set(inner)), b]
        return list(zip(edges[:-1], edges[1:]))
