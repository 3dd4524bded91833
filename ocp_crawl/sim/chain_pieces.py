"""Kinks and holds of an n-link chain's torque input, as its event-driven stepper reads them.

A piecewise-linear input (:class:`~ocp_crawl.model.sampled.JointLinear` tables, trapezoid pulses,
the optimal-control profiles) has kinks, knots where its rate jumps, and may hold still over
pieces.  The chain's stepper (:mod:`ocp_crawl.sim.chain_torque`) follows the rules of the
three-link stepper (:mod:`ocp_crawl.sim.event_kinks`, whose detection and helpers it shares):

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
Phases are located among the kinks by bisection (a table may have thousands of knots).
"""
from __future__ import annotations

import bisect
import math

import numpy as np

from ocp_crawl.model.inputs import input_knots
from ocp_crawl.sim.event_kinks import (KINK_GAP, hold_holding, hold_spans, input_holds,
                                       input_kinks, inside_piece)


class ChainPieces:
    """The kinks (phases in [0, 1)) and holds (rows [start, end)) of ``torque``, and the offset
    ``e`` [cycles] at which one-sided rates are read (:func:`input_kinks`)."""

    def __init__(self, torque):
        knots = input_knots(torque)
        self.kinks, self.e = input_kinks(torque, knots)
        self.holds = [tuple(h) for h in input_holds(torque, knots).tolist()]
        self.knots = knots
        """the input's knots (:func:`input_knots`), phases in [0, 1)"""
        self._k = sorted(self.kinks.tolist())
        self._knots = sorted(knots.tolist())

    def _neighbours(self, t: float, phases: list[float]) -> tuple[float, float]:
        """The absolute phases of the last of ``phases`` (in [0, 1), sorted, nonempty) at or
        before t and the first after it [cycles]."""
        c = math.floor(t)
        i = bisect.bisect_right(phases, t - c)
        before = c + phases[i - 1] if i > 0 else c - 1 + phases[-1]
        after = c + phases[i] if i < len(phases) else c + 1 + phases[0]
        return before, after

    def is_kink(self, t: float) -> bool:
        """Whether phase t [cycles] is a kink (to KINK_GAP)."""
        if not self._k:
            return False
        before, after = self._neighbours(t, self._k)
        return t - before <= KINK_GAP or after - t <= KINK_GAP

    def next_break(self, t: float) -> float:
        """The first kink or hold start after phase t (later than t + KINK_GAP); inf if none."""
        nxt = self._neighbours(t + KINK_GAP, self._k)[1] if self._k else math.inf
        starts = (a for a, _ in hold_spans(self.holds, t) if a > t + KINK_GAP)
        return min(nxt, min(starts, default=math.inf))

    def hold_at(self, t: float, rest_left: float | None = None) -> tuple[float, float] | None:
        """The absolute span (start, end) of the hold that holds phase t (from its start on, to
        KINK_GAP), or None; a hold of zero length at t counts unless it is ``rest_left``, the one
        the run has just left."""
        return hold_holding(self.holds, t, rest_left) if self.holds else None

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
        ts = np.asarray(ts, float)
        k = np.asarray(self._k)
        f = ts - np.floor(ts)
        i = np.searchsorted(k, f)
        gap = np.minimum(np.abs(f - np.append(k, k[0] + 1.0)[i]),
                         np.abs(f - np.insert(k, 0, k[-1] - 1.0)[i]))
        at_kink = gap <= KINK_GAP
        left = at_kink & (ts == upto) if upto is not None else np.zeros(ts.shape, bool)
        return np.where(left, ts - self.e, np.where(at_kink, ts + self.e, ts))

    def curvature_phase(self, t: float, left: bool = False, dt: float = 1e-5) -> float:
        """The centre of a central difference of step ``dt`` [cycles] of the rate near t that stays
        inside the piece holding t (at a kink: the piece before it when ``left``), as the
        three-link stepper's (:func:`inside_piece`)."""
        if not self._k:
            return t
        if self.is_kink(t) and left:
            lo, hi = self._neighbours(t - KINK_GAP, self._k)[0], t
        elif self.is_kink(t):
            lo, hi = t, self._neighbours(t + KINK_GAP, self._k)[1]
        else:
            lo, hi = self._neighbours(t, self._k)
        return inside_piece(t, lo, hi, dt)

    def split(self, a: float, b: float) -> list[tuple[float, float]]:
        """[a, b] cut at the input's knots inside it (its kinks, and the knots where a higher
        derivative jumps, such as a half-cosine edge meeting a flat: quadrature panels end
        there)."""
        inner = [k + c for c in range(math.floor(a), math.floor(b) + 1) for k in self._knots
                 if a + KINK_GAP < k + c < b - KINK_GAP]
        edges = [a, *sorted(inner), b]
        return list(zip(edges[:-1], edges[1:]))
