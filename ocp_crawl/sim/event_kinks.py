"""Kinks of the input in the event-driven stepper: phases where the torque is continuous but its
rate jumps.

A piecewise-linear input (:class:`~ocp_crawl.model.inputs.PeriodicLinear` samples, trapezoid
:class:`~ocp_crawl.model.pulse.Pulse` edges) has a kink at each knot where its slope changes.  The
equilibrium x(t) stays continuous there (it depends on the torque only), but its rate x' and every
guard built on it jump: the slip modes' ``stick`` guard sigma d' can change sign *at* the kink (a
slip stops or reverses exactly at a turning point of a triangle wave), and none of the rate-based
tools (the Hermite dip test, Newton on a guard, the central difference of tau') is valid across it.

The stepper therefore treats the input piece by piece:

* every continuation step ends at the next kink; the point there is solved with the *left* rate (the
  limit of the piece the step is in) and a second time with the *right* rate, which starts the next
  piece;
* a guard that is positive from the left and negative from the right is an event exactly at the
  kink: the state is the one at the kink, and the successor mode is the one consistent with the
  right rates; so is a guard that is zero to round-off at the kink (e.g. the friction limits tie
  exactly at a sample) and negative after it (located by the next step,
  :meth:`~ocp_crawl.sim.event_locate.EventLocator.locate`);
* the curvature tau'' (for the rate of the ``stick`` guard) is differenced inside the point's own
  piece.

An input without kinks (smooth, or C1 at its knots such as splines and PCHIP) leaves all of this
out: the stepper then runs exactly as without this module.

A *hold* of the input is a piece between breakpoints on which both rates are exactly zero (the
plateaus of pulses and square-like samples).  A quasistatic state does not move while its input does
not, whatever its mode, so the stepper crosses a hold in one step: every step ends at the next
hold's start, the state at the start is the state at the end, and no guard is located inside it
(each is constant there; a guard at zero stays at zero).  At the hold's end the mode that follows is
decided by the rates after it (:meth:`~ocp_crawl.sim.event_switch.ModeSwitch.leave_hold`): of the
modes whose equations hold at the state without a jump, the one whose guards all stay positive
(those at zero grow) over the trial steps after the hold.  Rate independence makes that choice
depend on the direction of the input's motion only, so an edge that starts from rest (a half-cosine
ramp) decides as a straight one does.  This is what decides the friction ties of step-like inputs: a
symmetric robot under a symmetric hold sits with both feet at their friction limits, and the first
motion after the hold tells which foot slips, or that both stick.

:class:`InputPieces` holds the kinks and holds of one input and the torque values at the kinks; the
steps that end at them and cross them are taken by :class:`~ocp_crawl.sim.event_switch.ModeSwitch`.
"""
from __future__ import annotations

import bisect
import math
from functools import lru_cache

import numpy as np

from ocp_crawl.model.inputs import CallableSignal, PeriodicSignal
from ocp_crawl.sim.event_state import torque_curvature

#: a knot is a kink when the jump of the slope across it, measured at +-e and +-e/16, does not
#: shrink with e (a C1 input's difference shrinks like e) and exceeds this fraction of the input's
#: largest rate
KINK_RTOL = 1e-9
#: kinks closer than this after a phase [cycles] are not the next step's end (no steps of round-off
#: length)
KINK_GAP = 1e-12
#: a piece of the input is a hold where both rates are below this fraction of the input's largest
#: rate
HELD_PIECE_RTOL = 1e-9


def input_step(signal, samples: int = 1024, rel: float = 1e-3) -> float:
    """Largest continuation step [cycles] that resolves a periodic input: 1/(8 f), where f is the
    highest harmonic whose contribution to the input's rate (amplitude times frequency) is at least
    ``rel`` times the largest one; 1/8 for a constant input.  Harmonics above samples/2 alias.
    """
    t = np.arange(samples) / samples
    u = np.asarray(signal(t), dtype=float).reshape(-1, samples)
    rate = np.abs(np.fft.rfft(u, axis=1)).max(axis=0) * np.arange(samples // 2 + 1)
    if not np.all(np.isfinite(rate)) or rate.max() <= 0:
        return 0.125
    return 0.125 / int(np.nonzero(rate >= rel * rate.max())[0].max())


@lru_cache(maxsize=256)
def _cached_input_step(signal: PeriodicSignal) -> float:
    return input_step(signal)


def step_limit(signal: PeriodicSignal) -> float:
    """:func:`input_step` of ``signal``, remembered for hashable (frozen, value-compared) signals
    such as
    :class:`~ocp_crawl.model.inputs.Harmonic` references, so that a sweep or a replay building many
    steppers of the same input runs the FFT once; a wrapped callable (which may change) is always
    sampled anew."""
    if isinstance(signal, CallableSignal):
        return input_step(signal)
    try:
        return _cached_input_step(signal)
    except TypeError:  # unhashable (array fields)
        return input_step(signal)


def linear_pieces(signal, breakpoints: np.ndarray, probes=(0.2, 0.5, 0.8)) -> bool:
    """Whether ``signal`` is linear on every piece between its ``breakpoints`` (phases in [0, 1)):
    its rates at interior points of each piece agree to :data:`HELD_PIECE_RTOL` of its largest rate.
    Such an input (piecewise-linear samples, trapezoid pulses) has nothing to resolve between its
    kinks, where steps end anyway: its Fourier content above the first harmonics is that of the
    kinks, and :func:`input_step` would shorten every step for it (a harmonic gait sampled at 50
    nodes: 2,102 steps instead of 105)."""
    b = np.unique(np.mod(np.asarray(breakpoints, float), 1.0))
    if b.size == 0:
        return False
    ends = np.append(b[1:], b[0] + 1.0)
    t = (b[:, None] + (ends - b)[:, None] * np.asarray(probes)[None, :]).ravel()
    d = np.asarray(signal.derivative(t), float).reshape(-1, b.size, len(probes))
    scale = float(np.max(np.abs(d)))
    return bool(np.all(np.ptp(d, axis=2) <= HELD_PIECE_RTOL * scale)) if scale > 0 else True


def one_sided_rates(signal, t: np.ndarray, e: float) -> tuple[np.ndarray, np.ndarray]:
    """Rates tau'(t - e) and tau'(t + e) (joints, n) of ``signal`` at the phases t (n,) [cycles]:
    the left and right rates at knots t when e is inside the pieces next to them (exact for
    piecewise-linear pieces)."""
    n = t.size
    return (np.asarray(signal.derivative(t - e), float).reshape(-1, n),
            np.asarray(signal.derivative(t + e), float).reshape(-1, n))


def input_kinks(signal, breakpoints: np.ndarray) -> tuple[np.ndarray, float]:
    """The kinks of ``signal`` among its ``breakpoints`` (sorted phases in [0, 1)), and the offset e
    [cycles] at which one-sided rates are evaluated (a quarter of the shortest piece, at most 1e-6).

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


def input_holds(signal, breakpoints: np.ndarray) -> np.ndarray:
    """The holds of ``signal``: maximal stretches of the pieces between its ``breakpoints`` (phases
    in [0, 1)) on which every joint's rate is zero to HELD_PIECE_RTOL of the input's largest rate
    (tested at three interior phases of each piece, which is exact for the pieces of
    piecewise-linear samples, pulses and PCHIP plateaus; the tolerance takes flats whose samples
    differ by round-off, as an optimiser's or a CSV's may).

    Returns an array (m, 2) of [start, end) phases [cycles] with start in [0, 1) and start < end <
    start + 1 (a hold across the period's end ends after 1); m = 0 for an input without holds or one
    held all the time.
    """
    b = np.unique(np.mod(np.asarray(breakpoints, float), 1.0))
    if b.size == 0:
        return np.zeros((0, 2))
    ends = np.append(b[1:], b[0] + 1.0)
    t = b[:, None] + np.array([0.25, 0.5, 0.75])[None, :] * (ends - b)[:, None]
    rate = np.asarray(signal.derivative(t.ravel()), float).reshape(-1, b.size, 3)
    scale = float(np.max(np.abs(np.asarray(signal.derivative(np.linspace(0.0, 1.0, 257)), float))))
    tol = HELD_PIECE_RTOL * max(scale, float(np.max(np.abs(rate))))
    held = np.all(np.abs(rate) <= tol, axis=(0, 2))
    if held.all():
        return np.zeros((0, 2))
    # breakpoints where both rates vanish (two half-cosine edges meeting at rest): holds of zero
    # length
    rest = b[np.all(np.abs(np.asarray(signal.derivative(b), float).reshape(-1, b.size)) <= tol,
                    axis=0)]
    out = [(r, r) for r in rest.tolist()
           if not (held[np.searchsorted(b, r)] or held[np.searchsorted(b, r) - 1])]
    holds = _runs(b, ends, held) + out
    if not holds:
        return np.zeros((0, 2))
    holds = np.array(holds) - np.floor(np.array(holds)[:, :1])
    return holds[np.argsort(holds[:, 0])]


def hold_spans(holds, t: float) -> list[tuple[float, float]]:
    """The absolute spans (start, end) [cycles] of ``holds`` (rows [start, end) of
    :func:`input_holds`) in the cycles around phase t."""
    c = math.floor(t)
    return [(a + k, b + k) for k in (c - 1, c, c + 1) for a, b in holds]


def hold_holding(holds, t: float, rest_left: float | None) -> tuple[float, float] | None:
    """The absolute span (start, end) [cycles] of the hold among ``holds`` (rows [start, end) of
    :func:`input_holds`) that holds phase t, from its start on to round-off; a hold of zero length
    at t (a rest of the input) counts unless it is ``rest_left``, the one the run has just left."""
    return next(((a, b) for a, b in hold_spans(holds, t) if a - KINK_GAP <= t < b - KINK_GAP or
                 (a == b and abs(t - a) <= KINK_GAP and a != rest_left)), None)


def inside_piece(t: float, lo: float, hi: float, dt: float) -> float:
    """The centre of a central difference of step dt near t that stays inside the piece (lo, hi)
    between kinks [cycles]: t, moved inside by 2 dt from an end, or the piece's middle if it is
    shorter than 4 dt."""
    if hi - lo <= 4 * dt:
        return 0.5 * (lo + hi)
    if t - lo < 2 * dt or hi - t < 2 * dt:
        return min(max(t, lo + 2 * dt), hi - 2 * dt)
    return t


def _runs(b: np.ndarray, ends: np.ndarray, held: np.ndarray) -> list[tuple[float, float]]:
    """The maximal runs (start, end) of consecutive held pieces [b_i, ends_i] around the cycle."""
    if not held.any():
        return []
    first = int(np.argmin(held))  # a moving piece: the holds are the runs of held pieces after it
    out, start = [], None
    for j in range(first + 1, first + 1 + b.size):
        i = j % b.size
        lo, hi = b[i] + (j // b.size), ends[i] + (j // b.size)
        if held[i] and start is None:
            start = lo
        if held[i]:
            end = hi
        elif start is not None:
            out.append((start, end))
            start = None
    if start is not None:
        out.append((start, end))
    return out


class InputPieces:
    """The kinks and holds of one input over the cycles of a run (see the module docstring).

    ``torque``: the input signal; ``torque_at``: its :func:`~ocp_crawl.sim.event_state.torque_pair`;
    ``breakpoints``: its knots (phases in [0, 1)).  The table of the kinks' absolute phases covers
    at most three cycles, extended as the run goes on; the hold of zero length last left is
    remembered (:meth:`leave_rest`), so that a run at it goes on.
    """

    def __init__(self, torque, torque_at, breakpoints: np.ndarray):
        self._torque, self._torque_at = torque, torque_at
        self.kinks, self._kink_e = input_kinks(torque, breakpoints)
        self._kink_table: dict[float, tuple[list, list]] = {}
        """absolute phase of a kink -> (torque values with the left rate, with the right rate), each
        as ``torque_at.values``: [tau1, tau2, tau1', tau2']"""
        self._kink_list: list[float] = []
        self._kink_upto = -2
        self.values = torque_at.values
        """t -> [tau1, tau2, tau1', tau2'] as floats; at a kink with the rate after it"""
        if self.kinks.size:
            self._extend_kinks(1)
            base, table = torque_at.values, self._kink_table

            def values(t: float) -> list:  # (at a kink: with the rate after it)
                kv = table.get(t)
                return base(t) if kv is None else kv[1]

            self.values = values
        self.holds = input_holds(torque, breakpoints)
        self._hold_list = [tuple(h) for h in self.holds.tolist()]
        self._rest_left = None
        """the hold of zero length last left: the stepper is at it, and goes on"""

    @property
    def kinked(self) -> bool:
        """whether the input has kinks"""
        return bool(self._kink_list)

    @property
    def held(self) -> bool:
        """whether the input has holds"""
        return bool(self._hold_list)

    def _extend_kinks(self, cycle: int) -> None:
        """Add the kinks of the cycles up to ``cycle`` to the table (the torque and both rates at
        each)."""
        for c in range(self._kink_upto + 1, cycle + 1):
            t = c + self.kinks
            tau = np.asarray(self._torque(t), float).reshape(2, -1)
            left, right = one_sided_rates(self._torque, t, self._kink_e)
            for j, tj in enumerate(t.tolist()):
                self._kink_table[tj] = ([*tau[:, j].tolist(), *left[:, j].tolist()],
                                        [*tau[:, j].tolist(), *right[:, j].tolist()])
            self._kink_list.extend(t.tolist())
        self._kink_upto = max(self._kink_upto, cycle)
        # the cycles before the last complete one are behind the stepper (and the output's steady
        # cycle): dropped, so that the table holds at most three cycles of kinks however many run
        i = bisect.bisect_left(self._kink_list, cycle - 2.0)
        for tj in self._kink_list[:i]:
            del self._kink_table[tj]
        del self._kink_list[:i]

    def next_kink(self, t: float) -> float:
        """The first kink after phase t [cycles] (later than t + KINK_GAP); inf for an input without
        kinks."""
        if not self._kink_list:
            return math.inf
        if math.floor(t) + 1 > self._kink_upto:
            self._extend_kinks(math.floor(t) + 1)
        i = bisect.bisect_right(self._kink_list, t + KINK_GAP)
        return self._kink_list[i] if i < len(self._kink_list) else math.inf

    def kink_values(self, t: float, left: bool) -> list | None:
        """The torque values [tau1, tau2, tau1', tau2'] at the kink t with its left or right rate;
        None if t is not a kink of the table (any phase between kinks, and every phase of an input
        without kinks)."""
        kv = self._kink_table.get(t)
        return None if kv is None else kv[0 if left else 1]

    def curvature(self, t: float, left: bool = False, dt: float = 1e-5) -> list:
        """tau''(t) [N m/cycle^2] (:func:`~ocp_crawl.sim.event_state.torque_curvature`) differenced
        inside the piece between kinks that holds t (for t at a kink: the piece before it when
        ``left``, else the one after it)."""
        if self._kink_list:
            if math.floor(t) + 1 > self._kink_upto:
                self._extend_kinks(math.floor(t) + 1)
            kl = self._kink_list
            i = bisect.bisect_left(kl, t) if left else bisect.bisect_right(kl, t)
            lo = kl[i - 1] if i > 0 else -math.inf
            hi = kl[i] if i < len(kl) else math.inf
            t = inside_piece(t, lo, hi, dt)
        return torque_curvature(self._torque_at, t, dt)

    def _hold_spans(self, t: float):
        return hold_spans(self._hold_list, t)

    def next_hold(self, t: float) -> float:
        """The start of the first hold after phase t [cycles] (later than t + KINK_GAP); inf without
        holds."""
        return min((a for a, _ in self._hold_spans(t) if a > t + KINK_GAP), default=math.inf)

    def hold_at(self, t: float) -> tuple[float, float] | None:
        """The absolute span (start, end) [cycles] of the hold that holds phase t (from its start
        on, to round-off), or None."""
        if not self._hold_list:
            return None
        return hold_holding(self._hold_list, t, self._rest_left)

    def leave_rest(self, span: tuple[float, float]) -> None:
        """Note that the run crosses the hold ``span``: one of zero length (a rest of the input) is
        left once."""
        self._rest_left = span[0] if span[0] == span[1] else self._rest_left
