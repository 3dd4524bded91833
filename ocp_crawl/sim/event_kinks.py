"""Kinks of the input in the event-driven stepper: phases where the torque is continuous but its rate jumps.

A piecewise-linear input (:class:`~ocp_crawl.model.inputs.PeriodicLinear` samples, trapezoid
:class:`~ocp_crawl.model.pulse.Pulse` edges) has a kink at each knot where its slope changes.  The
equilibrium x(t) stays continuous there (it depends on the torque only), but its rate x' and every guard
built on it jump: the slip modes' ``stick`` guard sigma d' can change sign *at* the kink (a slip stops or
reverses exactly at a turning point of a triangle wave), and none of the rate-based tools (the Hermite
dip test, Newton on a guard, the central difference of tau') is valid across it.

The stepper therefore treats the input piece by piece:

* every continuation step ends at the next kink; the point there is solved with the *left* rate (the
  limit of the piece the step is in) and a second time with the *right* rate, which starts the next piece;
* a guard that is positive from the left and negative from the right is an event exactly at the kink:
  the state is the one at the kink, and the successor mode is the one consistent with the right rates; so is a
  guard that is zero to round-off at the kink (e.g. the friction limits tie exactly at a sample) and negative
  after it (located by the next step, :meth:`~ocp_crawl.sim.event_locate.EventsMixin._locate`);
* the curvature tau'' (for the rate of the ``stick`` guard) is differenced inside the point's own piece.

An input without kinks (smooth, or C1 at its knots such as splines and PCHIP) leaves all of this out: the
stepper then runs exactly as without this module.

:class:`KinksMixin` is a part of :class:`~ocp_crawl.sim.event.HybridStepper`; it uses the stepper's
``torque``, ``torque_at`` and ``breakpoints``.
"""
from __future__ import annotations

import bisect
import math

import numpy as np

from ocp_crawl.sim.event_state import torque_curvature

#: a knot is a kink when the jump of the slope across it, measured at +-e and +-e/16, does not shrink with e
#: (a C1 input's difference shrinks like e) and exceeds this fraction of the input's largest rate
KINK_RTOL = 1e-9
#: kinks closer than this after a phase [cycles] are not the next step's end (no steps of round-off length)
KINK_GAP = 1e-12


def one_sided_rates(signal, t: np.ndarray, e: float) -> tuple[np.ndarray, np.ndarray]:
    """Rates tau'(t - e) and tau'(t + e) (2, n) of ``signal`` at the phases t (n,) [cycles]: the left and right
    rates at knots t when e is inside the pieces next to them (exact for piecewise-linear pieces)."""
    n = t.size
    return (np.asarray(signal.derivative(t - e), float).reshape(2, n),
            np.asarray(signal.derivative(t + e), float).reshape(2, n))


def input_kinks(signal, breakpoints: np.ndarray) -> tuple[np.ndarray, float]:
    """The kinks of ``signal`` among its ``breakpoints`` (sorted phases in [0, 1)), and the offset e [cycles] at which
    one-sided rates are evaluated (a quarter of the shortest piece, at most 1e-6).

    Returns (kinks (m,), e); m = 0 for an input whose rate is continuous at every breakpoint.
    """
    b = np.unique(np.asarray(breakpoints, float))
    if b.size == 0:
        return np.zeros(0), 0.0
    gaps = np.diff(np.append(b, b[0] + 1.0))
    e = min(1e-6, 0.25 * float(gaps.min()))
    lo, hi = one_sided_rates(signal, b, e)
    lo16, hi16 = one_sided_rates(signal, b, e / 16)
    grid = np.linspace(0.0, 1.0, 257)
    scale = float(np.max(np.abs(np.asarray(signal.derivative(grid), float)))) + np.finfo(float).tiny
    jump, jump16 = np.max(np.abs(hi - lo), axis=0), np.max(np.abs(hi16 - lo16), axis=0)
    return b[(jump16 > 0.5 * jump) & (jump16 > KINK_RTOL * scale)], e


class KinksMixin:
    """Kinks of the input for :class:`~ocp_crawl.sim.event.HybridStepper` (see the module docstring)."""

    def _init_kinks(self) -> None:
        """Find the input's kinks; the table of their absolute phases starts with cycles -1, 0 and 1.  With kinks, the
        stepper's ``_torque_values`` gives the rate after a kink at the kink's phase."""
        self.kinks, self._kink_e = input_kinks(self.torque, self.breakpoints)
        self._kink_table: dict[float, tuple[list, list]] = {}
        """absolute phase of a kink -> (torque values with the left rate, with the right rate), each as
        ``torque_at.values``: [tau1, tau2, tau1', tau2']"""
        self._kink_list: list[float] = []
        self._kink_upto = -2
        if self.kinks.size:
            self._extend_kinks(1)
            base, table = self._torque_values, self._kink_table

            def values(t: float) -> list:  # (the stepper's torque values: at a kink with the rate after it)
                kv = table.get(t)
                return base(t) if kv is None else kv[1]

            self._torque_values = values

    def _extend_kinks(self, cycle: int) -> None:
        """Add the kinks of the cycles up to ``cycle`` to the table (the torque and both rates at each)."""
        for c in range(self._kink_upto + 1, cycle + 1):
            t = c + self.kinks
            tau = np.asarray(self.torque(t), float).reshape(2, -1)
            left, right = one_sided_rates(self.torque, t, self._kink_e)
            for j, tj in enumerate(t.tolist()):
                self._kink_table[tj] = ([*tau[:, j].tolist(), *left[:, j].tolist()],
                                        [*tau[:, j].tolist(), *right[:, j].tolist()])
            self._kink_list.extend(t.tolist())
        self._kink_upto = max(self._kink_upto, cycle)

    def next_kink(self, t: float) -> float:
        """The first kink after phase t [cycles] (later than t + KINK_GAP); inf for an input without kinks."""
        if not self._kink_list:
            return math.inf
        if math.floor(t) + 1 > self._kink_upto:
            self._extend_kinks(math.floor(t) + 1)
        i = bisect.bisect_right(self._kink_list, t + KINK_GAP)
        return self._kink_list[i] if i < len(self._kink_list) else math.inf

    def kink_values(self, t: float, left: bool) -> list | None:
        """The torque values [tau1, tau2, tau1', tau2'] at the kink t with its left or right rate; None if t is not a
        kink of the table (any phase between kinks, and every phase of an input without kinks)."""
        kv = self._kink_table.get(t)
        return None if kv is None else kv[0 if left else 1]

    def curvature(self, t: float, left: bool = False, dt: float = 1e-5) -> list:
        """tau''(t) [N m/cycle^2] (:func:`~ocp_crawl.sim.event_state.torque_curvature`) differenced inside the piece
        between kinks that holds t (for t at a kink: the piece before it when ``left``, else the one after it)."""
        if self._kink_list:
            if math.floor(t) + 1 > self._kink_upto:
                self._extend_kinks(math.floor(t) + 1)
            kl = self._kink_list
            i = bisect.bisect_left(kl, t) if left else bisect.bisect_right(kl, t)
            lo = kl[i - 1] if i > 0 else -math.inf
            hi = kl[i] if i < len(kl) else math.inf
            if hi - lo <= 4 * dt:
                t = 0.5 * (lo + hi)
            elif t - lo < 2 * dt or hi - t < 2 * dt:
                t = min(max(t, lo + 2 * dt), hi - 2 * dt)
        return torque_curvature(self.torque_at, t, dt)
