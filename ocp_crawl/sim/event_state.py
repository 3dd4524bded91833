"""State of the event-driven stepper: solved points, constant-mode segments, mode parameters, the
run so far, its outcome and failures.

Shared by the modules of the event-driven stepper (:mod:`ocp_crawl.sim.event` and its parts).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ocp_crawl.model.inputs import TWO_PI, Harmonic, ReferenceTorque
from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.result import Event, Mode
from ocp_crawl.status import Status

_DPHI1, _DPHI2, _DFT = AUX["dphi1"], AUX["dphi2"], AUX["dft"]


def hermite(t0, x0, xd0, t1, x1, xd1, t):
    """Cubic Hermite interpolation between (t0, x0, x0') and (t1, x1, x1'); scalars or arrays of
    phases."""
    h = np.asarray(t1 - t0, float)
    s = np.where(h > 0, (np.asarray(t, float) - t0) / np.where(h > 0, h, 1.0), 0.0)
    s2 = s * s
    s3 = s2 * s
    h00, h10 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s
    h01, h11 = -2 * s3 + 3 * s2, s3 - s2
    return h00 * x0 + h10 * h * xd0 + h01 * x1 + h11 * h * xd1


def torque_pair(signal):
    """A function t -> (tau(t), tau'(t)) [N m, N m/cycle] at one phase t [cycles] of the input
    ``signal``.

    For the common torque input k (phi_ref(t) - pi) of a :class:`~ocp_crawl.model.inputs.Harmonic`
    reference both come from one scalar evaluation in the same arithmetic as the signal's own
    methods (the stepper calls this before every solve); any other signal is called as it is.  The
    function has the attribute ``values``: t -> [tau1, tau2, tau1', tau2'] as a list of floats (the
    same numbers).
    """
    ref = getattr(signal, "reference", None)
    if not (isinstance(signal, ReferenceTorque) and type(ref) is Harmonic):
        def generic(t: float):
            return signal(t), signal.derivative(t)

        generic.values = lambda t: [*np.ravel(signal(t)).tolist(),
                                    *np.ravel(signal.derivative(t)).tolist()]
        return generic
    k, g1, g2, a1, a2, half = signal.k, ref.gamma1, ref.gamma2, ref.A1, ref.A2, ref.psi / 2
    pi, two_pi, sin, cos = math.pi, TWO_PI, math.sin, math.cos

    def values(t: float) -> list:
        w = two_pi * t
        w1, w2 = w + half, w - half
        return [k * ((g1 + a1 * sin(w1)) - pi), k * ((g2 + a2 * sin(w2)) - pi),
                k * (two_pi * a1 * cos(w1)), k * (two_pi * a2 * cos(w2))]

    def pair(t: float):
        v = values(t)
        return np.array(v[:2]), np.array(v[2:])

    def rate(t: float) -> list:
        w = two_pi * t
        return [k * (two_pi * a1 * cos(w + half)), k * (two_pi * a2 * cos(w - half))]

    pair.rate, pair.values = rate, values
    return pair


def torque_curvature(torque_at, t: float, dt: float = 1e-5) -> list:
    """tau''(t) [N m/cycle^2] by central differences of tau' over +-dt [cycles], with ``torque_at``
    from
    :func:`torque_pair` (floats; the same arithmetic as on arrays)."""
    rate = getattr(torque_at, "rate", None)
    if rate is None:
        return ((torque_at(t + dt)[1] - torque_at(t - dt)[1]) / (2 * dt)).tolist()
    a, b = rate(t + dt), rate(t - dt)
    return [(a[0] - b[0]) / (2 * dt), (a[1] - b[1]) / (2 * dt)]


def event_kind(guard: str) -> str:
    """Public event kind of an internal guard name (see :class:`~ocp_crawl.sim.result.Event`)."""
    if guard.startswith("slip_"):
        return f"slip_onset_{guard[5]}"
    if guard.startswith("switch_to_"):
        return "slip_switch"
    return {"stick": "slip_to_stick", "asymmetry": "slip_slip_end"}.get(guard, guard)


def mode_q(mode: Mode, d0: float = 0.0) -> np.ndarray:
    """Mode-parameter vector q = (e_ss, sigma, w, d0) of the compiled mode system (d0: stick
    distance [m])."""
    if mode == Mode.STICK:
        return np.array([1.0, 0.0, 0.0, d0])
    return np.array([0.0, float(mode.sigma), {1: 1.0, 2: 0.0, 3: 0.5}[mode.foot], 0.0])


#: q of the "released" start: f_t = 0, d free
Q_RELEASED = np.array([0.0, 0.0, 1.0, 0.0])


class _Point:
    """A solved equilibrium: phase t [cycles], x = (phi1, phi2 [rad], f_t/(M g)), the compiled
    outputs aux (:data:`~ocp_crawl.model.statics.AUX`), and what the stepper derives from them once
    (kept on the point)."""

    __slots__ = ("t", "x", "aux", "rates", "tau", "dtau", "_xdot", "_a", "q", "extra", "guards",
                 "_xl", "_xdl")
    left = False
    """solved with the input's rate just before t (:class:`_LeftPoint`: the end of a step at a kink
    of the input, see :mod:`ocp_crawl.sim.event_kinks`); else with the rate at t, which at a kink is
    the one after it"""

    def __init__(self, t: float, x: np.ndarray, aux: np.ndarray, rates=None, tau=None, dtau=None,
                 q=None, extra=None, a: list | None = None, xl: list | None = None):
        self.t, self.x, self.aux = t, x, aux
        self._xl = xl
        self._xdl = None
        """x as a list (None until asked for; see :attr:`xl`)"""
        self.q, self.extra = q, extra
        """mode parameters of the solve, and the stability numbers and d'' coefficients computed
        with it (:func:`~ocp_crawl.model.stability.fast_step`; None when the solve did not compute
        them)"""
        self.rates = rates
        """guard rates of the point's mode (kept by
        :meth:`~ocp_crawl.sim.event_guards.Guards.dips`)"""
        self.tau, self.dtau = tau, dtau
        """torque and its derivative at t (kept from the solve)"""
        self._xdot = None
        self._a = a
        """aux as a list (None until asked for; see :attr:`a`)"""
        self.guards = None
        """(mode, guard values of that mode) once computed
        (:meth:`~ocp_crawl.sim.event_guards.Guards.at`)"""

    @property
    def a(self) -> list:
        """aux as a list of Python floats (fast scalar access in the guards)"""
        if self._a is None:
            self._a = self.aux.tolist()
        return self._a

    @property
    def xl(self) -> list:
        """x as a list of Python floats"""
        if self._xl is None:
            self._xl = self.x.tolist()
        return self._xl

    @property
    def xdl(self) -> list:
        """the rate x' [1/cycle] as a list of Python floats"""
        if self._xdl is None:
            a = self.a
            self._xdl = [a[_DPHI1], a[_DPHI2], a[_DFT]]
        return self._xdl

    @property
    def xdot(self) -> np.ndarray:
        if self._xdot is None:
            self._xdot = np.array(self.xdl)
        return self._xdot


class _LeftPoint(_Point):
    """A :class:`_Point` at a kink of the input solved with the input's rate just before it."""

    __slots__ = ()
    left = True


def hermite_point(p0: _Point, p1: _Point, t: float) -> list:
    """:func:`hermite` between two points at one phase t in scalar arithmetic (the same formula): a
    list of 3 floats."""
    h = p1.t - p0.t
    s = (t - p0.t) / h if h > 0 else 0.0
    s2 = s * s
    s3 = s2 * s
    h00, h10, h01, h11 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2
    a, b = h10 * h, h11 * h
    x0, x1, d0, d1 = p0.xl, p1.xl, p0.xdl, p1.xdl
    return [h00 * x0[k] + a * d0[k] + h01 * x1[k] + b * d1[k] for k in range(3)]


@dataclass
class _Segment:
    """A stretch of constant mode: its points, and the foot that stays fixed."""

    mode: Mode
    q: np.ndarray
    x1_fixed: float
    x2_fixed: float
    points: list = field(default_factory=list)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Phases (n,), states (3, n) and their rates (3, n) of the stored points (kept until a
        point is added)."""
        cache = getattr(self, "_arrays", None)
        if cache is None or cache[0].size != len(self.points):
            pts = self.points
            cache = (np.array([p.t for p in pts]), np.array([p.xl for p in pts]).T,
                     np.array([p.xdl for p in pts]).T)
            self._arrays = cache
        return cache

    def feet(self, d):
        """Foot positions (x1, x2) [m] at the foot distance d [m] (a float or an array; a fixed foot
        is its float)."""
        if self.mode == Mode.STICK:
            return self.x1_fixed, self.x2_fixed
        if self.mode.foot == 1:  # foot 2 sticks
            return self.x2_fixed - d, self.x2_fixed
        if self.mode.foot == 2:
            return self.x1_fixed, self.x1_fixed + d
        mid = 0.5 * (self.x1_fixed + self.x2_fixed)  # slip-slip: symmetric split about the midpoint
        return mid - 0.5 * d, mid + 0.5 * d

    def foot_positions(self, d):
        """:meth:`feet` as two arrays of the shape of d."""
        d = np.asarray(d, float)
        return tuple(np.full_like(d, v) if np.ndim(v) == 0 else v for v in self.feet(d))


@dataclass(slots=True)
class _Run:
    """What a run has built so far: the segments, the events, the current segment, point and
    step."""

    seg: _Segment
    pt: _Point
    h: float
    """current continuation step [cycles]"""
    det_sign: float
    """sign of the mode Jacobian's determinant at the segment's start (a change is a fold)"""
    segments: list[_Segment] = field(default_factory=list)
    events: list[Event] = field(default_factory=list)
    cycle: int = 0
    events_in_cycle: int = 0
    nsteps: int = 0
    """accepted continuation steps (a hold of the input crossed counts as one)"""
    extra: dict = field(default_factory=dict)


@dataclass(frozen=True)
class _Outcome:
    """How a run ended: its status, and for a failure the reason, the phase [cycles] and the mode's
    label; for a periodic run the number of cycles run when the state repeated."""

    status: Status
    detail: str = ""
    t: float | None = None
    mode: str | None = None
    periodic_at: int | None = None


class _Failure(Exception):
    def __init__(self, status: Status, t: float, mode: Mode, detail: str,
                 extra: dict | None = None):
        super().__init__(detail)
        self.status, self.t, self.mode, self.detail = status, t, mode, detail
        self.extra = extra or {}


def phase_owners(segments, te: np.ndarray) -> list:
    """The phases ``te`` on each segment: a phase on a boundary goes to the earlier segment, a phase
    on none to none.

    Sorted phases on consecutive segments (the default output) are assigned by one search for all
    segments (the phases of segment k are those in its span after the ones of the segments before);
    others one segment at a time.

    Parameters
    ----------
    segments : list of _Segment
        The run's segments, in the order of the run.
    te : ndarray, shape (n,)
        Phases [cycles].

    Returns
    -------
    list of (_Segment, ndarray)
        Each segment that holds phases, with its phases in the order of ``te``.
    """
    starts = np.array([seg.points[0].t for seg in segments])
    ends = np.array([seg.points[-1].t for seg in segments])
    if te.size and len(segments) and np.all(te[1:] >= te[:-1]) and np.all(starts[1:] >= ends[:-1]):
        lo, hi = np.searchsorted(te, starts, side="left"), np.searchsorted(te, ends, side="right")
        lo = np.maximum(lo, np.maximum.accumulate(np.concatenate([[0], hi[:-1]])))
        return [(seg, te[a:b]) for seg, a, b in zip(segments, lo.tolist(), hi.tolist()) if b > a]
    requests = []
    free = np.ones(te.size, bool)
    for seg in segments:
        sel = np.nonzero(free & (te >= seg.points[0].t) & (te <= seg.points[-1].t))[0]
        if sel.size:
            free[sel] = False
            requests.append((seg, te[sel]))
    return requests
