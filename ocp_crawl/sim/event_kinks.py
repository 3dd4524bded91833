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

A *hold* of the input is a piece between breakpoints on which both rates are exactly zero (the plateaus of
pulses and square-like samples).  A quasistatic state does not move while its input does not, whatever its
mode, so the stepper crosses a hold in one step: every step ends at the next hold's start, the state at the
start is the state at the end, and no guard is located inside it (each is constant there; a guard at zero
stays at zero).  At the hold's end the mode that follows is decided by the rates after it
(:meth:`KinksMixin._leave_hold`): of the modes whose equations hold at the state without a jump, the one whose
guards all stay positive (those at zero grow) over the trial steps after the hold.  Rate independence
makes that choice depend on the direction of the input's motion only, so an edge that starts from rest
(a half-cosine ramp) decides as a straight one does.  This is what decides the friction ties of
step-like inputs: a symmetric robot under a symmetric hold sits with both feet at their friction limits,
and the first motion after the hold tells which foot slips, or that both stick.

:class:`KinksMixin` is a part of :class:`~ocp_crawl.sim.event.HybridStepper`; it uses the stepper's
``torque``, ``torque_at``, ``breakpoints``, ``opt``, ``_solve``, ``_trial_steps``, ``_jump``, ``point_guards``,
``tie_note`` and ``_start_mode``.
"""
from __future__ import annotations

import bisect
import math
from functools import lru_cache

import numpy as np

from ocp_crawl.model.inputs import CallableSignal, PeriodicSignal
from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.event_state import _Failure, _Point, _Run, hermite_point, torque_curvature
from ocp_crawl.sim.result import mode_change_kind
from ocp_crawl.status import Status

#: a knot is a kink when the jump of the slope across it, measured at +-e and +-e/16, does not shrink with e
#: (a C1 input's difference shrinks like e) and exceeds this fraction of the input's largest rate
KINK_RTOL = 1e-9
#: kinks closer than this after a phase [cycles] are not the next step's end (no steps of round-off length)
KINK_GAP = 1e-12
#: a piece of the input is a hold where both rates are below this fraction of the input's largest rate
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
    """:func:`input_step` of ``signal``, remembered for hashable (frozen, value-compared) signals such as
    :class:`~ocp_crawl.model.inputs.Harmonic` references, so that a sweep or a replay building many steppers
    of the same input runs the FFT once; a wrapped callable (which may change) is always sampled anew."""
    if isinstance(signal, CallableSignal):
        return input_step(signal)
    try:
        return _cached_input_step(signal)
    except TypeError:  # unhashable (array fields)
        return input_step(signal)


def linear_pieces(signal, breakpoints: np.ndarray, probes=(0.2, 0.5, 0.8)) -> bool:
    """Whether ``signal`` is linear on every piece between its ``breakpoints`` (phases in [0, 1)): its rates
    at interior points of each piece agree to :data:`HELD_PIECE_RTOL` of its largest rate.  Such an input
    (piecewise-linear samples, trapezoid pulses) has nothing to resolve between its kinks, where steps end
    anyway: its Fourier content above the first harmonics is that of the kinks, and :func:`input_step`
    would shorten every step for it (a harmonic gait sampled at 50 nodes: 2,102 steps instead of 105)."""
    b = np.unique(np.mod(np.asarray(breakpoints, float), 1.0))
    if b.size == 0:
        return False
    ends = np.append(b[1:], b[0] + 1.0)
    t = (b[:, None] + (ends - b)[:, None] * np.asarray(probes)[None, :]).ravel()
    d = np.asarray(signal.derivative(t), float).reshape(-1, b.size, len(probes))
    scale = float(np.max(np.abs(d)))
    return bool(np.all(np.ptp(d, axis=2) <= HELD_PIECE_RTOL * scale)) if scale > 0 else True


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


def input_holds(signal, breakpoints: np.ndarray) -> np.ndarray:
    """The holds of ``signal``: maximal stretches of the pieces between its ``breakpoints`` (phases in [0, 1)) on
    which both rates are zero to HELD_PIECE_RTOL of the input's largest rate (tested at three interior phases of each
    piece, which is exact for the pieces of piecewise-linear samples, pulses and PCHIP plateaus; the tolerance
    takes flats whose samples differ by round-off, as an optimiser's or a CSV's may).

    Returns an array (m, 2) of [start, end) phases [cycles] with start in [0, 1) and start < end < start + 1 (a
    hold across the period's end ends after 1); m = 0 for an input without holds or one held all the time.
    """
    b = np.unique(np.mod(np.asarray(breakpoints, float), 1.0))
    if b.size == 0:
        return np.zeros((0, 2))
    ends = np.append(b[1:], b[0] + 1.0)
    t = b[:, None] + np.array([0.25, 0.5, 0.75])[None, :] * (ends - b)[:, None]
    rate = np.asarray(signal.derivative(t.ravel()), float).reshape(2, b.size, 3)
    scale = float(np.max(np.abs(np.asarray(signal.derivative(np.linspace(0.0, 1.0, 257)), float))))
    tol = HELD_PIECE_RTOL * max(scale, float(np.max(np.abs(rate))))
    held = np.all(np.abs(rate) <= tol, axis=(0, 2))
    if held.all():
        return np.zeros((0, 2))
    # breakpoints where both rates vanish (two half-cosine edges meeting at rest): holds of zero length
    rest = b[np.all(np.abs(np.asarray(signal.derivative(b), float).reshape(2, -1)) <= tol, axis=0)]
    out = [(r, r) for r in rest.tolist() if not (held[np.searchsorted(b, r)] or held[np.searchsorted(b, r) - 1])]
    holds = _runs(b, ends, held) + out
    if not holds:
        return np.zeros((0, 2))
    holds = np.array(holds) - np.floor(np.array(holds)[:, :1])
    return holds[np.argsort(holds[:, 0])]


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
        # the cycles before the last complete one are behind the stepper (and the output's steady
        # cycle): dropped, so that the table holds at most three cycles of kinks however many run
        i = bisect.bisect_left(self._kink_list, cycle - 2.0)
        for tj in self._kink_list[:i]:
            del self._kink_table[tj]
        del self._kink_list[:i]

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

    def _init_holds(self) -> None:
        """Find the input's holds (:func:`input_holds`) and keep them as a list of (start, end) per cycle offset."""
        self.holds = input_holds(self.torque, self.breakpoints)
        self._hold_list = [tuple(h) for h in self.holds.tolist()]
        self._rest_left = None  # (the hold of zero length last left: the stepper is at it, and goes on)

    def _hold_spans(self, t: float):
        """The holds' absolute spans (start, end) [cycles] of the cycles around phase t."""
        c = math.floor(t)
        return [(a + k, b + k) for k in (c - 1, c, c + 1) for a, b in self._hold_list]

    def next_hold(self, t: float) -> float:
        """The start of the first hold after phase t [cycles] (later than t + KINK_GAP); inf without holds."""
        return min((a for a, _ in self._hold_spans(t) if a > t + KINK_GAP), default=math.inf)

    def hold_at(self, t: float) -> tuple[float, float] | None:
        """The absolute span (start, end) [cycles] of the hold that holds phase t (from its start on, to round-off),
        or None."""
        if not self._hold_list:
            return None
        return next(((a, b) for a, b in self._hold_spans(t) if a - KINK_GAP <= t < b - KINK_GAP or
                     (a == b and abs(t - a) <= KINK_GAP and a != self._rest_left)), None)

    def _not_at_hold(self, seg, pt: _Point, new: _Point, crossed: list[str]) -> list[str]:
        """The guards ``crossed`` in the step [pt, new], less all of them when the step ends at a hold's start with
        each of them at zero to round-off there and not negative inside the step (solved at a quarter, half and three
        quarters of it): a guard that reaches zero as the input comes to rest (the slip of a half-cosine edge stops
        with its rate) is decided at the hold's end, by the rates after it."""
        if not crossed or abs(self.next_hold(new.t - 2 * KINK_GAP) - new.t) > KINK_GAP:
            return crossed
        g = self.point_guards(seg.mode, new)
        if any(g[k] < -100 * self.noise for k in crossed):
            return crossed
        for s in (0.25, 0.5, 0.75):
            t = pt.t + s * (new.t - pt.t)
            inside = self._solve(t, hermite_point(pt, new, t), seg.q)
            if inside is None or any(self.point_guards(seg.mode, inside)[k] < -100 * self.noise for k in crossed):
                return crossed
        return []

    def _cross_hold(self, run: _Run, t_end: float) -> bool:
        """If run.pt is at (or inside) a hold of the input, move it to the hold's end (or to t_end, the end of the
        cycle, if that comes first) with the state unchanged, and decide there the mode that follows
        (:meth:`_leave_hold`); returns whether it did."""
        span = self.hold_at(run.pt.t)
        if span is None:
            return False
        seg, tb = run.seg, min(span[1], t_end)
        # the hold's ends at rest (zero rates: the dense output interpolates the constant state between them), then
        # the state at its end with the rates after it; a hold of zero length (a rest of the input) is left once
        ends = [self._solve(t, run.pt.xl, seg.q, step=True, held=True) for t in (run.pt.t, tb) if span[0] < span[1]]
        ends.append(self._solve(tb, run.pt.xl, seg.q, step=True))
        self._rest_left = span[0] if span[0] == span[1] else self._rest_left
        if any(p is None or self._jump(run.pt, p)[0] > self.opt.jump_tol for p in ends):
            raise _Failure(Status.NO_CONVERGENCE, tb, seg.mode, "the mode's state changed across a hold of the "
                           "input (the solve did not return the state it started from)")
        self.nsteps += 1
        seg.points.extend(ends)
        run.pt = end = ends[-1]
        if tb == span[1]:
            self._leave_hold(run, end)
        return True

    def _leave_hold(self, run: _Run, end: _Point) -> None:
        """At the end of a hold (state ``end``, with the rates after it): keep the current mode if its guards stay
        positive after the hold (those at zero grow), else :meth:`_apply_decision` of the modes that continue."""
        start, pending = self._trial_steps(run.seg.mode, end, end.a[AUX["d"]])
        if start is None or pending or self.tie_note(end):  # (at a tie every mode is tried: set_valued if several)
            self._apply_decision(run, end, "at the end of a hold of the input")

    def _apply_decision(self, run: _Run, pt: _Point, where: str) -> None:
        """Continue from pt in the one mode of :meth:`_decide`: the current segment goes on if it is the current
        mode, else a new segment starts (its event's kind from the two modes).  NO_CONSISTENT_MODE if no mode
        continues; SET_VALUED if several do (the statics leave the motion undecided: which foot slips, or whether
        they stick, then depends on what breaks the tie, e.g. mu1 != mu2)."""
        found, seg = self._decide(pt), run.seg
        if len(found) != 1:
            names = ", ".join(m.label for m, _ in found) or "none"
            status = Status.SET_VALUED if found else Status.NO_CONSISTENT_MODE
            raise _Failure(status, pt.t, seg.mode, f"{where} the modes that continue from the state are {names}"
                           f"{self.tie_note(pt)}")
        chosen, start = found[0]
        if chosen != seg.mode:
            self._start_mode(run, pt, pt.t, chosen, start, mode_change_kind(seg.mode, chosen), 0.0, "decided")
