"""Event-driven hybrid-quasistatic stepper for prescribed torques (paper Section II-B).

The robot is tracked along its equilibrium branch by continuation in the phase t (cycles).
In each contact mode the configuration solves three equations in x = (phi1, phi2, f_t/(M g)):
the joint balance F = 0 and one mode equation (stick-stick: d = d0; slip of foot i with
sign(d') = sigma: f_t = sigma mu_i f_n,i).  Every point is a Newton solve of the compiled
mode system (no integration drift); events are guard functions of the mode, detected by a
sign change between steps, located by Brent's method on the guard of the solved state
(xtol 1e-13 in phase) and applied by a transition table:

=============  ==========================================  ======================
mode           guard (positive inside)                     on zero
=============  ==========================================  ======================
stick-stick    mu_i f_n,i - sigma f_t  (i = 1, 2; +-)        slip of foot i, sign(d') = sigma
slip i, sigma  sigma d'                                     stick-stick (d0 = d)
slip i, sigma  mu_j f_n,j - mu_i f_n,i                       slip of foot j, same sigma
any            f_n,1, f_n,2                                 lift-off (failure status)
any            d                                            feet crossing (failure status)
any            det J (sign of the mode's start)              fold (failure status)
=============  ==========================================  ======================

When mu1 f_n1 = mu2 f_n2 identically (mirror-symmetric gait, equal friction), no single-foot slip
is consistent; the stepper then uses the non-generic slip-slip mode, in which both feet are at
their friction limits and, the split of d' between the feet being statically indeterminate, each
foot takes half of it (the symmetric solution). It leaves slip-slip when the limits separate.

A fold is located exactly by the augmented system G(x, t) = 0, J v = 0, v0.v = 1.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from ocp_crawl.model.inputs import PeriodicSignal, ReferenceTorque, as_signal
from ocp_crawl.model.statics import AUX, Model, fast_ddot2, fast_newton, solve_many, symbolic
from ocp_crawl.sim.quadrature import gauss_nodes
from ocp_crawl.sim.result import STATUS_MESSAGES, CrawlResult, Event, Mode, Status, cost_of_transport, energy_balance

EPS = np.finfo(float).eps
#: phases of the default output grid over the steady cycle (events are added)
DEFAULT_OUTPUT_POINTS = 201
#: largest |mu1 f_n1 - mu2 f_n2|/(M g) for which the slip-slip mode is kept
SYMMETRY_TOL = 1e-8
#: adaptive quadrature of the cycle integrals: tolerance on the Legendre tail of a panel's
#: integrand (relative to the segment's largest value) and the number of halvings allowed
QUAD_TOL = 1e-4
QUAD_DEPTH = 8
#: 5-point Gauss-Legendre nodes and weights on [-1, 1]; Legendre coefficients of the degree-4
#: interpolant through values at the nodes (c = values @ _LEG_FIT) and its values at -1 and 1
_XG, _WG = np.polynomial.legendre.leggauss(5)
_LEG_FIT = np.linalg.inv(np.polynomial.legendre.legvander(_XG, 4)).T
_LEG_ENDS = _LEG_FIT @ np.polynomial.legendre.legvander(np.array([-1.0, 1.0]), 4).T


@dataclass(frozen=True)
class HybridOptions:
    """Options of the event-driven stepper."""

    max_step: float = 1.0 / 64
    """largest continuation step in phase [cycles]"""
    min_step: float = 1e-11
    """smallest continuation step before giving up [cycles]"""
    event_xtol: float = 1e-13
    """tolerance of event location in phase [cycles]"""
    residual_tol: float = 1e-10
    """largest accepted scaled residual |G|_inf of a mode solve"""
    max_cycles: int = 12
    """cycles to run before declaring the gait non-periodic"""
    min_cycles: int = 2
    """cycles always run (the first one is a transient from the released start)"""
    periodic_tol: float = 1e-8
    """periodicity: max |phi change| [rad] and |f_t change|/(M g) over one cycle"""
    max_events_per_cycle: int = 200
    """events allowed in one cycle before the run ends with status ``too_many_events``"""
    resolve_input: bool = True
    """limit the step to 1/8 of the period of the input's fastest significant harmonic (see
    :func:`input_step`), so that fast (chattering) inputs are followed and no event pair hides
    inside a step"""
    trial_step: float = 1e-9
    """phase step used to test the consistency of a mode after a transition"""
    quad_h: float = 1.0 / 32
    """largest Gauss-Legendre panel for the per-cycle integrals [cycles]"""

    def __post_init__(self) -> None:
        for name in ("max_step", "min_step", "event_xtol", "residual_tol", "periodic_tol", "trial_step", "quad_h"):
            v = getattr(self, name)
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"HybridOptions.{name} must be a positive finite number, got {v!r}")
        if self.max_step > 0.25:
            raise ValueError(f"HybridOptions.max_step must be <= 0.25 cycles, got {self.max_step!r}")
        if isinstance(self.max_cycles, bool) or not (isinstance(self.max_cycles, int) and self.max_cycles >= 2):
            raise ValueError(f"HybridOptions.max_cycles must be an integer >= 2, got {self.max_cycles!r}")
        if isinstance(self.min_cycles, bool) or not (isinstance(self.min_cycles, int)
                                                     and 1 <= self.min_cycles <= self.max_cycles):
            raise ValueError(f"HybridOptions.min_cycles must be an integer in [1, max_cycles], got {self.min_cycles!r}")
        if isinstance(self.max_events_per_cycle, bool) or not (isinstance(self.max_events_per_cycle, int)
                                                               and self.max_events_per_cycle >= 1):
            raise ValueError("HybridOptions.max_events_per_cycle must be an integer >= 1, "
                             f"got {self.max_events_per_cycle!r}")
        if not isinstance(self.resolve_input, bool):
            raise ValueError(f"HybridOptions.resolve_input must be True or False, got {self.resolve_input!r}")


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


_S_GRID = np.linspace(0.0, 1.0, 33)[1:-1]
_S_BUMP = (_S_GRID * (1 - _S_GRID)) ** 2


def _cubic_min(g0: float, g1: float, m0: float, m1: float) -> tuple[float, float]:
    """Lowest interior local minimum (s, value) on (0, 1) of the cubic with values g0, g1 and slopes
    m0, m1 (per unit s) at the ends; (nan, inf) if it has none."""
    a = 2 * (g0 - g1) + m0 + m1
    b = 3 * (g1 - g0) - 2 * m0 - m1
    best = (math.nan, math.inf)
    # critical points: 3 a s^2 + 2 b s + m0 = 0; a local minimum where 6 a s + 2 b > 0
    if abs(a) < 1e-300:
        roots = [-m0 / (2 * b)] if b > 0 else []
    else:
        disc = b * b - 3 * a * m0
        if disc < 0:
            return best
        sq = math.sqrt(disc)
        roots = [(-b - sq) / (3 * a), (-b + sq) / (3 * a)]
    for s in roots:
        if 0 < s < 1 and 6 * a * s + 2 * b > 0:
            v = ((a * s + b) * s + m0) * s + g0
            if v < best[1]:
                best = (s, v)
    return best


def hermite(t0, x0, xd0, t1, x1, xd1, t):
    """Cubic Hermite interpolation between (t0, x0, x0') and (t1, x1, x1'); scalars or arrays of phases."""
    h = np.asarray(t1 - t0, float)
    s = np.where(h > 0, (np.asarray(t, float) - t0) / np.where(h > 0, h, 1.0), 0.0)
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * x0 + h10 * h * xd0 + h01 * x1 + h11 * h * xd1


def event_kind(guard: str) -> str:
    """Public event kind of an internal guard name (see :class:`~ocp_crawl.sim.result.Event`)."""
    if guard.startswith("slip_"):
        return f"slip_onset_{guard[5]}"
    if guard.startswith("switch_to_"):
        return "slip_switch"
    return {"stick": "slip_to_stick", "asymmetry": "slip_slip_end"}.get(guard, guard)


def mode_q(mode: Mode, d0: float = 0.0) -> np.ndarray:
    """Mode-parameter vector q = (e_ss, sigma, w, d0) of the compiled mode system."""
    if mode == Mode.STICK:
        return np.array([1.0, 0.0, 0.0, d0])
    return np.array([0.0, float(mode.sigma), {1: 1.0, 2: 0.0, 3: 0.5}[mode.foot], 0.0])


#: q of the "released" start: f_t = 0, d free
Q_RELEASED = np.array([0.0, 0.0, 1.0, 0.0])


@dataclass
class _Point:
    t: float
    x: np.ndarray
    aux: np.ndarray
    rates: dict | None = None
    """guard rates of the point's mode (cached by :meth:`HybridStepper._dips`)"""
    tau: np.ndarray | None = None
    """torque and its derivative at t (kept from the solve)"""
    dtau: np.ndarray | None = None

    @property
    def xdot(self) -> np.ndarray:
        a = self.aux
        return np.array([a[AUX["dphi1"]], a[AUX["dphi2"]], a[AUX["dft"]]])


@dataclass
class _Segment:
    """A stretch of constant mode: its points, and the foot that stays fixed."""

    mode: Mode
    q: np.ndarray
    x1_fixed: float
    x2_fixed: float
    points: list = field(default_factory=list)

    def foot_positions(self, d):
        d = np.asarray(d, float)
        if self.mode == Mode.STICK:
            return np.full_like(d, self.x1_fixed), np.full_like(d, self.x2_fixed)
        if self.mode.foot == 1:  # foot 2 sticks
            return self.x2_fixed - d, np.full_like(d, self.x2_fixed)
        if self.mode.foot == 2:
            return np.full_like(d, self.x1_fixed), self.x1_fixed + d
        mid = 0.5 * (self.x1_fixed + self.x2_fixed)  # slip-slip: symmetric split about the midpoint
        return mid - 0.5 * d, mid + 0.5 * d


class _Failure(Exception):
    def __init__(self, status: Status, t: float, mode: Mode, detail: str, extra: dict | None = None):
        super().__init__(detail)
        self.status, self.t, self.mode, self.detail, self.extra = status, t, mode, detail, extra or {}


class HybridStepper:
    """Event-driven simulation of the torque-driven crawler.  Build once, call :meth:`run`."""

    def __init__(self, model: Model, torque, options: HybridOptions | None = None):
        self.model = model
        self.torque: PeriodicSignal = as_signal(torque)
        self.opt = options or HybridOptions()
        self.sym = symbolic()
        self.newton = fast_newton()
        self.ddot2 = fast_ddot2()
        self.p = model.p
        self.Mg = model.robot.M * model.robot.g
        self.L = model.robot.L
        self.nfev = 0
        self.nsteps = 0
        # round-off level of the scaled guards: the mode equations are scaled by M g L, so the
        # conditioning (and the noise in f_t) grows with k/(M g L)
        self.noise = 1e-13 * (1.0 + model.robot.k / model.robot.MgL)
        self.mu = (model.robot.mu1, model.robot.mu2)
        self.max_step = self.opt.max_step
        # phases where a sampled input's derivative may have a kink (its knots): quadrature panel edges
        signal = self.torque.reference if isinstance(self.torque, ReferenceTorque) else self.torque
        self.breakpoints = np.sort(np.asarray(getattr(signal, "t_knots", np.zeros(0)), dtype=float) % 1.0)
        if self.opt.resolve_input:
            self.max_step = min(self.max_step, max(input_step(self.torque), self.max_step / 64))

    # ------------------------------------------------------------------ primitive evaluations
    def _solve(self, t: float, x0: np.ndarray, q: np.ndarray) -> _Point | None:
        """Newton solve of the mode q at phase t from x0; None if it does not converge."""
        tau = self.torque(t)
        dtau = self.torque.derivative(t)
        x = x0
        for _ in range(4):
            x, aux = self.newton(x, tau, dtau, q, self.p)
            self.nfev += 1
            res = aux[AUX["res"]]
            if not res <= self.opt.residual_tol:  # also catches NaN
                if not np.isfinite(res) or res > 1e3:
                    return None
                continue
            return _Point(t, x, aux, tau=tau, dtau=dtau)
        return None

    def guards(self, mode: Mode, aux: np.ndarray) -> dict[str, float]:
        """Guard functions of a mode (scaled, positive while the mode is valid)."""
        Mg, L = self.Mg, self.L
        g = {"lift_off_1": aux[AUX["fn1"]] / Mg, "lift_off_2": aux[AUX["fn2"]] / Mg, "feet_crossed": aux[AUX["d"]] / L,
             "joint_1_on_ground": aux[AUX["zj1"]] / L, "joint_2_on_ground": aux[AUX["zj2"]] / L}
        ft = aux[AUX["ft"]]
        lim = {1: aux[AUX["lim1"]], 2: aux[AUX["lim2"]]}
        if mode == Mode.STICK:
            for i in (1, 2):
                for s in (1, -1):
                    g[f"slip_{i}{'+' if s > 0 else '-'}"] = (lim[i] - s * ft) / Mg
        elif mode.foot == 3:
            g["stick"] = mode.sigma * aux[AUX["ddot"]] / L
            g["asymmetry"] = SYMMETRY_TOL - abs(lim[1] - lim[2]) / Mg
        else:
            i = mode.foot
            j = 3 - i
            g["stick"] = mode.sigma * aux[AUX["ddot"]] / L
            g[f"switch_to_{j}"] = (lim[j] - lim[i]) / Mg
        return g

    def guard_rates(self, mode: Mode, pt: _Point, q: np.ndarray) -> dict[str, float]:
        """Time derivatives [1/cycle] of :meth:`guards` along the mode's solution at pt.

        The slip modes' ``stick`` guard sigma d'/L needs d'', which depends on the torque's second
        derivative; that is taken by central differences of the torque's derivative.
        """
        aux = pt.aux
        Mg, L = self.Mg, self.L
        r = {"lift_off_1": aux[AUX["dfn1"]] / Mg, "lift_off_2": aux[AUX["dfn2"]] / Mg,
             "feet_crossed": aux[AUX["ddot"]] / L,
             "joint_1_on_ground": aux[AUX["dzj1"]] / L, "joint_2_on_ground": aux[AUX["dzj2"]] / L}
        dft = aux[AUX["dft"]]
        dlim = {1: self.mu[0] * aux[AUX["dfn1"]], 2: self.mu[1] * aux[AUX["dfn2"]]}
        if mode == Mode.STICK:
            for i in (1, 2):
                for s in (1, -1):
                    r[f"slip_{i}{'+' if s > 0 else '-'}"] = (dlim[i] - s * dft) / Mg
            return r
        if mode.foot == 3:
            r["asymmetry"] = -math.copysign(1.0, aux[AUX["lim1"]] - aux[AUX["lim2"]]) * (dlim[1] - dlim[2]) / Mg
        else:
            i = mode.foot
            j = 3 - i
            r[f"switch_to_{j}"] = (dlim[j] - dlim[i]) / Mg
        t, dt = pt.t, 1e-5
        tau, dtau = (pt.tau, pt.dtau) if pt.tau is not None else (self.torque(t), self.torque.derivative(t))
        ab = self.ddot2(pt.x, tau, dtau, q, self.p)[0]
        dd = np.asarray(self.torque.derivative(np.array([t + dt, t - dt]))).reshape(2, 2)
        ddtau = (dd[:, 0] - dd[:, 1]) / (2 * dt)
        r["stick"] = mode.sigma * (ab[0] + ab[1] * ddtau[0] + ab[2] * ddtau[1]) / L
        return r

    def _dips(self, mode: Mode, q: np.ndarray, p0: _Point, p1: _Point, g0: dict,
              g1: dict) -> tuple[list[tuple[str, float]], bool]:
        """Look inside the step [p0.t, p1.t] for zeros of the guards that a sign test at its ends misses
        (a guard dipping below zero and back: two events closer together than the step).

        Each guard is interpolated by the cubic Hermite polynomial of its values and exact rates at
        the ends.  Returns the guards whose interpolant dips below zero, with the phase of its
        minimum, and whether the step is suspect: the interpolant stays positive but not by more
        than an estimate of its error, E s^2 (1 - s)^2 with E = 6 |g1 - g0 - h (g0' + g1')/2|
        (the trapezoid defect, of order h^3 times the third derivative), so the caller halves the step.
        """
        h = p1.t - p0.t
        for pt in (p0, p1):
            if pt.rates is None:
                pt.rates = self.guard_rates(mode, pt, q)
        r0, r1 = p0.rates, p1.rates
        floor = -100 * self.noise
        out = []
        suspect = False
        for name, rate0 in r0.items():
            a, b, m0, m1 = g0[name], g1[name], h * rate0, h * r1[name]
            err = 6.0 * abs(b - a - 0.5 * (m0 + m1))
            # the Hermite basis bounds the cubic below by min(a, b) - 4/27 (|m0| + |m1|)
            if min(a, b) - 0.15 * (abs(m0) + abs(m1)) - err / 16 >= floor:
                continue
            s, v = _cubic_min(a, b, m0, m1)
            if v < floor:
                out.append((name, p0.t + s * h))
                continue
            c3, c2 = 2 * (a - b) + m0 + m1, 3 * (b - a) - 2 * m0 - m1
            bound = ((c3 * _S_GRID + c2) * _S_GRID + m0) * _S_GRID + a - err * _S_BUMP
            suspect = suspect or bool(np.min(bound) < floor)
        return sorted(out, key=lambda r: r[1]), suspect

    def _transition(self, mode: Mode, kind: str) -> Mode | Status:
        if kind.startswith("lift_off"):
            return Status.LIFT_OFF
        if kind == "feet_crossed":
            return Status.FEET_CROSSED
        if kind.startswith("joint_"):
            return Status.JOINT_ON_GROUND
        if kind.startswith("slip_"):
            return Mode.slip(int(kind[5]), +1 if kind[6] == "+" else -1)
        if kind == "stick":
            return Mode.STICK
        if kind.startswith("switch_to_"):
            return Mode.slip(int(kind[-1]), mode.sigma)
        if kind == "asymmetry":
            return Mode.slip(1, mode.sigma)  # provisional: the consistency search picks the weaker foot
        raise AssertionError(kind)

    @staticmethod
    def _hermite(p0: _Point, p1: _Point, t: float) -> np.ndarray:
        return hermite(p0.t, p0.x, p0.xdot, p1.t, p1.x, p1.xdot, t)

    # ------------------------------------------------------------------ events
    def _locate(self, p0: _Point, p1: _Point, q: np.ndarray, mode: Mode, name: str,
                start: bool = False) -> tuple[float, _Point]:
        """Phase and solved state where guard ``name`` crosses zero in [p0.t, p1.t] (Brent's method).
        ``start``: p0 starts the mode's segment, where the guard that fired the transition is zero."""
        # the ends are known (a re-solve there could differ in the last bits and break the bracket)
        cache: dict[float, _Point] = {p0.t: p0, p1.t: p1}

        def g(t: float) -> float:
            pt = cache.get(t)
            if pt is None:
                pt = self._solve(t, self._hermite(p0, p1, t), q)
                if pt is None:
                    raise _Failure(Status.NO_CONVERGENCE, t, mode, f"mode solve failed while locating event {name}")
                cache[t] = pt
            return self.guards(mode, pt.aux)[name]

        g0, g1 = self.guards(mode, p0.aux)[name], self.guards(mode, p1.aux)[name]
        if g1 == 0.0:
            return p1.t, p1
        ta, tb = p0.t, p1.t
        if g0 <= 0 or (start and g0 <= 100 * self.noise):
            # the guard starts at zero (it fired the transition into this mode, or touches zero
            # there): [p0, p1] holds that zero and the crossing, so bracket the crossing between the
            # first sample where the guard is clearly positive and the next one where it is negative
            hh = p1.t - p0.t
            ta = None
            for frac in (1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.05, *np.linspace(0, 1, 10)[1:-1], 1.0):
                s = p0.t + frac * hh
                v = g1 if frac == 1.0 else g(s)
                if v > 10 * self.noise:
                    ta = s
                elif v < 0 and ta is not None:
                    tb = s
                    break
            if ta is None:
                raise _Failure(Status.NO_CONSISTENT_MODE, p0.t, mode,
                               f"guard {name} does not leave zero after the transition into {mode.label}")
        ts = brentq(g, ta, tb, xtol=self.opt.event_xtol, rtol=4 * EPS)
        pt = cache.get(ts)
        if pt is None:
            pt = self._solve(ts, self._hermite(p0, p1, ts), q)
        return ts, pt

    def _consistent(self, mode: Mode, pt: _Point, d0: float) -> _Point | None:
        """Return the start point of ``mode`` at pt if the mode is consistent going forward, else None.

        Guards that are clearly positive at the event stay positive over a short step.  Guards
        that vanish at the event (the one that fired, seen from the new mode) may grow only
        quadratically (slip -> stick at d' = 0 is tangential), so the trial step is enlarged
        until their sign is resolved above round-off.
        """
        q = mode_q(mode, d0)
        start = self._solve(pt.t, pt.x, q)
        if start is None:
            return None
        g0 = self.guards(mode, start.aux)
        noise = self.noise
        if any(v < -100 * noise for v in g0.values()):
            return None
        pending = {k for k, v in g0.items() if v < 100 * noise}
        for delta in (1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4):
            nxt = self._solve(pt.t + delta, start.x + delta * start.xdot, q)
            if nxt is None:
                return None
            g = self.guards(mode, nxt.aux)
            for k in list(pending):
                if g[k] < -10 * noise:
                    return None
                if g[k] > 10 * noise:
                    pending.discard(k)
            if not pending:
                return start
        return None

    # ------------------------------------------------------------------ folds
    def _locate_fold(self, pt: _Point, q: np.ndarray, t_limit: float) -> tuple[float, np.ndarray, float] | None:
        """Newton on the augmented fold system from pt; returns (t_fold, x_fold, sigma_min/sigma_max)."""
        _, J = self.sym.system(pt.x, self.torque(pt.t), q, self.p)
        J = np.asarray(J)
        _, _, vt = np.linalg.svd(J)
        v0 = vt[-1]
        z = np.concatenate([pt.x, [0.0], v0])
        t0 = pt.t
        for _outer in range(8):
            tau0, dtau0 = self.torque(t0), self.torque.derivative(t0)
            for _ in range(40):
                H, dH = self.sym.fold(z, v0, tau0, dtau0, q, self.p)
                H = np.asarray(H).ravel()
                dH = np.asarray(dH)
                try:
                    dz = np.linalg.solve(dH, -H)
                except np.linalg.LinAlgError:
                    return None
                z = z + dz
                if np.max(np.abs(dz)) < 1e-14 and np.max(np.abs(H)) < 1e-12:
                    break
            else:
                return None
            t0 = t0 + z[3]
            done = abs(z[3]) < 1e-14
            z[3] = 0.0
            if done:
                break
        if not (pt.t - 1e-9 <= t0 <= t_limit + 1e-9):
            return None
        _, J = self.sym.system(z[:3], self.torque(t0), q, self.p)
        s = np.linalg.svd(np.asarray(J), compute_uv=False)
        return t0, z[:3], s[-1] / s[0]

    # ------------------------------------------------------------------ main loop
    def initial_state(self, t0: float = 0.0) -> _Point:
        """Released start: equilibrium with f_t = 0 at phase t0 (raises ValueError if not a valid contact state)."""
        ref = self.torque.reference(t0) if isinstance(self.torque, ReferenceTorque) else \
            math.pi + self.torque(t0) / self.model.robot.k
        guesses = [np.array([ref[0], ref[1], 0.0])]
        for lam in (0.5, 0.25, 0.0):
            guesses.append(np.array([lam * ref[0] + (1 - lam) * math.pi * 0.6, lam * ref[1] + (1 - lam) * math.pi * 0.6, 0.0]))
        for x0 in guesses:
            pt = self._solve(t0, x0, Q_RELEASED)
            if pt is not None:
                break
        else:
            raise ValueError("no equilibrium found for the starting configuration (t = 0, f_t = 0)")
        self.model.check_contact(pt.x[:2], where="starting configuration")
        return pt

    def run(self, t_eval=None) -> CrawlResult:
        """Simulate cycles from a released start until the gait is periodic; report the steady cycle.

        ``t_eval``: optional phases in [0, 1] (relative to the start of the steady cycle) for the
        output arrays; by default 201 equally spaced phases plus the event phases.  A failed run
        reports the accepted steps and events up to the failure.
        """
        self.nfev = 0
        self.nsteps = 0
        opt = self.opt
        try:
            start = self.initial_state(0.0)
        except ValueError as exc:
            return self._build_result([], [], Status.NO_START, str(exc), 0.0, "released start", 0, None, t_eval, {})
        mode = Mode.STICK
        d0 = start.aux[AUX["d"]]
        seg = _Segment(Mode.STICK, mode_q(Mode.STICK, d0), 0.0, d0)
        pt = self._solve(0.0, start.x, seg.q)
        seg.points.append(pt)
        segments = [seg]
        events: list[Event] = []
        cycle_states = [(pt, mode)]
        det_sign = np.sign(pt.aux[AUX["det"]]) or 1.0
        h = self.max_step
        status = Status.SUCCESS
        detail = ""
        fail_t = None
        fail_mode = None
        cycle = 0
        periodic_at = None
        extra: dict = {}
        events_in_cycle = 0
        try:
            while True:
                t_end = float(cycle + 1)
                while pt.t < t_end - 1e-15:
                    t_new = min(pt.t + h, t_end)
                    if t_end - t_new < 1e-12:
                        t_new = t_end
                    hh = t_new - pt.t
                    guess = pt.x + hh * pt.xdot
                    new = self._solve(t_new, guess, seg.q)
                    ok = new is not None
                    if ok:
                        nx, gx, px = new.x, guess, pt.x
                        jump = max(abs(nx[0] - gx[0]), abs(nx[1] - gx[1]))
                        ok = jump <= 0.05 + 0.5 * max(abs(gx[0] - px[0]), abs(gx[1] - px[1])) and \
                            max(abs(nx[0] - px[0]), abs(nx[1] - px[1])) < 0.35
                    if ok and np.sign(new.aux[AUX["det"]]) != det_sign:
                        ok = False  # crossed a fold onto another branch: treat as failure and locate it
                    if not ok:
                        if hh < 1e-3:
                            fold = self._locate_fold(pt, seg.q, t_new)
                            if fold is not None and fold[0] <= t_new + 1e-12 and fold[2] < 1e-6:
                                events.append(Event(fold[0], "fold", seg.mode.label, "failure", fold[2], "det"))
                                raise _Failure(Status.FOLD, fold[0], seg.mode,
                                               f"fold of the {seg.mode.label} equilibrium branch",
                                               {"fold_x": fold[1].tolist(), "fold_sigma_ratio": fold[2]})
                        h = hh / 4
                        if h < opt.min_step:
                            raise _Failure(Status.NO_CONVERGENCE, pt.t, seg.mode,
                                           f"continuation step fell below {opt.min_step:g} cycles")
                        continue
                    self.nsteps += 1
                    g_old = self.guards(seg.mode, pt.aux)
                    g_new = self.guards(seg.mode, new.aux)
                    crossed = [k for k in g_new if g_new[k] < 0 and g_old[k] > -100 * self.noise]
                    # an event inside the step that the sign test at its ends misses (a guard dipping
                    # below zero and back, possibly before another guard's crossing)?
                    dips, refine = self._dips(seg.mode, seg.q, pt, new, g_old, g_new)
                    for name, t_min in dips:
                        pm = self._solve(t_min, self._hermite(pt, new, t_min), seg.q)
                        if pm is None:
                            refine = True
                            break
                        g_min = self.guards(seg.mode, pm.aux)
                        in_dip = [k for k in g_min if g_min[k] < 0 and g_old[k] > -100 * self.noise]
                        if in_dip:
                            new, crossed = pm, in_dip  # the step now ends inside the dip
                            break
                        if g_min[name] > 100 * self.noise:
                            refine = True  # the interpolant was not accurate enough there
                    if refine and not crossed and hh > 1e-5:
                        h = hh / 2
                        continue
                    if not crossed:
                        pt = new
                        seg.points.append(pt)
                        h = min(self.max_step, 2 * h) if hh >= h * 0.999 else h
                        continue
                    located = [(self._locate(pt, new, seg.q, seg.mode, k, start=pt is seg.points[0]), k)
                               for k in crossed]
                    (t_ev, ev_pt), kind = min(located, key=lambda r: r[0][0])
                    if ev_pt is None:
                        raise _Failure(Status.NO_CONVERGENCE, t_ev, seg.mode, "mode solve failed at an event")
                    g_ev = self.guards(seg.mode, ev_pt.aux)[kind]
                    if ev_pt.t > pt.t:
                        seg.points.append(ev_pt)
                    target = self._transition(seg.mode, kind)
                    if isinstance(target, Status):
                        events.append(Event(t_ev, event_kind(kind), seg.mode.label, "failure", g_ev, kind))
                        raise _Failure(target, t_ev, seg.mode, f"{kind.replace('_', ' ')}")
                    new_d0 = ev_pt.aux[AUX["d"]]
                    trial = self._consistent(target, ev_pt, new_d0)
                    chosen = target
                    kind_out = event_kind(kind)
                    if trial is None:
                        # the table's successor is inconsistent: look for any other consistent mode,
                        # the current one included (a grazing event: the guard touches zero and turns back)
                        found = []
                        for m in Mode:
                            if m == target:
                                continue
                            tr = self._consistent(m, ev_pt, new_d0)
                            if tr is not None:
                                found.append((m, tr))
                        if len(found) != 1:
                            raise _Failure(Status.NO_CONSISTENT_MODE, t_ev, seg.mode,
                                           f"after event {kind}: {len(found)} consistent successor modes "
                                           f"(table successor {target.label} is inconsistent)")
                        chosen, trial = found[0]
                        if chosen == seg.mode:
                            kind_out = f"graze_{kind_out}"
                    events.append(Event(t_ev, kind_out, seg.mode.label, chosen.label, g_ev, kind))
                    events_in_cycle += 1
                    if events_in_cycle > opt.max_events_per_cycle:
                        raise _Failure(Status.TOO_MANY_EVENTS, t_ev, chosen,
                                       f"more than {opt.max_events_per_cycle} events in cycle {cycle + 1}")
                    d_now = ev_pt.aux[AUX["d"]]
                    x1, x2 = (a.item() for a in seg.foot_positions(d_now))
                    q_new = mode_q(chosen, new_d0)
                    seg = _Segment(chosen, q_new, x1, x2, [trial])
                    segments.append(seg)
                    pt = trial
                    det_sign = np.sign(pt.aux[AUX["det"]]) or 1.0
                    h = self.max_step
                # end of a cycle
                cycle += 1
                events_in_cycle = 0
                cycle_states.append((pt, seg.mode))
                if cycle >= opt.min_cycles:
                    (pa, ma), (pb, mb) = cycle_states[-2], cycle_states[-1]
                    dev = max(np.max(np.abs(pa.x[:2] - pb.x[:2])), abs(pa.x[2] - pb.x[2]))
                    if dev <= opt.periodic_tol and ma == mb:
                        periodic_at = cycle
                        extra["periodicity_deviation"] = float(dev)
                        break
                if cycle >= opt.max_cycles:
                    (pa, _), (pb, _) = cycle_states[-2], cycle_states[-1]
                    raise _Failure(Status.NOT_PERIODIC, pt.t, seg.mode,
                                   f"not periodic after {cycle} cycles (last change {np.max(np.abs(pa.x - pb.x)):.3g})")
        except _Failure as f:
            status, detail, fail_t, fail_mode = f.status, f.detail, f.t, f.mode.label
            extra.update(f.extra)
        try:
            return self._build_result(segments, events, status, detail, fail_t, fail_mode, cycle, periodic_at,
                                      t_eval, extra)
        except _Failure as f:
            # the output or the cycle integrals need a solve that fails: report it, with the steps so far
            extra.update(f.extra)
            return self._build_result(segments, events, f.status, f"{f.detail} (output of the result)", f.t,
                                      f.mode.label, cycle, None, None, extra)

    # ------------------------------------------------------------------ dense output and metrics
    def _evaluate_many(self, seg: _Segment, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Solve the segment's mode at many phases (guesses by Hermite interpolation of its points).

        Points that the batched Newton does not converge are solved again one by one.
        """
        pts = seg.points
        ts = np.asarray(ts, float)
        n = len(ts)
        if len(pts) > 1:
            tp = np.array([p.t for p in pts])
            X = np.stack([p.x for p in pts], axis=1)
            XD = np.stack([p.xdot for p in pts], axis=1)
            i = np.clip(np.searchsorted(tp, ts, side="right") - 1, 0, len(pts) - 2)
            guesses = hermite(tp[i], X[:, i], XD[:, i], tp[i + 1], X[:, i + 1], XD[:, i + 1], ts)
        else:
            guesses = np.tile(pts[0].x[:, None], (1, n))
        xs, aux = solve_many(guesses, self.torque(ts).reshape(2, n), self.torque.derivative(ts).reshape(2, n),
                             seg.q, self.p)
        self.nfev += n
        for j in np.nonzero(~(aux[AUX["res"]] <= self.opt.residual_tol))[0]:
            pt = self._solve(ts[j], xs[:, j] if np.all(np.isfinite(xs[:, j])) else guesses[:, j], seg.q)
            if pt is None:
                pt = self._continue_to(seg, float(ts[j]))
            if pt is None:
                raise _Failure(Status.NO_CONVERGENCE, float(ts[j]), seg.mode, "dense output solve failed")
            xs[:, j], aux[:, j] = pt.x, pt.aux
        return xs, aux

    def _continue_to(self, seg: _Segment, t: float) -> _Point | None:
        """Solve the segment's mode at t by continuation from the last stored point before t, in 4,
        16, then 64 sub-steps (when the interpolated guess alone does not converge)."""
        pts = seg.points
        i = max(0, int(np.searchsorted([p.t for p in pts], t, side="right")) - 1)
        for n in (4, 16, 64):
            cur = pts[i]
            for s in np.linspace(cur.t, t, n + 1)[1:]:
                cur = self._solve(float(s), cur.x + (s - cur.t) * cur.xdot, seg.q)
                if cur is None:
                    break
            else:
                return cur
        return None

    def _panels(self, seg: _Segment, a: float, b: float):
        """Adaptive Gauss-Legendre panels (5 nodes) on [a, b] of one smooth segment.

        Panels start no longer than ``quad_h``; a panel is halved (up to QUAD_DEPTH times) while the
        two highest Legendre coefficients of the degree-4 interpolant of an integrand (actuator
        powers, friction power) exceed QUAD_TOL times the largest integrand value on the segment, so
        steep stretches (low stiffness, large amplitudes) are resolved.  Returns the panel edges
        (lo, hi), nodes, weights and integrands (power (2, n, 5), friction power (n, 5)).
        """
        xg, wg = _XG, _WG
        n = max(1, int(np.ceil((b - a) / self.opt.quad_h - 1e-12)))
        edges = np.linspace(a, b, n + 1)
        if self.breakpoints.size:
            cuts = (self.breakpoints[None, :] + np.arange(math.floor(a), math.ceil(b) + 1)[:, None]).ravel()
            edges = np.unique(np.concatenate([edges, cuts[(cuts > a + 1e-12) & (cuts < b - 1e-12)]]))
        pending = np.stack([edges[:-1], edges[1:]], axis=1)
        done = []
        scale = 0.0
        for depth in range(QUAD_DEPTH + 1):
            mid = 0.5 * (pending[:, 0] + pending[:, 1])[:, None]
            half = 0.5 * (pending[:, 1] - pending[:, 0])[:, None]
            t = (mid + half * xg).ravel()
            _, aux = self._evaluate_many(seg, t)
            power = (self.torque(t).reshape(2, -1) * aux[[AUX["dphi1"], AUX["dphi2"]]]).reshape(2, -1, 5)
            fric = np.abs(aux[AUX["ft"]] * aux[AUX["ddot"]]).reshape(-1, 5)
            f = np.concatenate([power, fric[None]], axis=0)  # (3, npan, 5)
            scale = max(scale, float(np.max(np.abs(f))))
            tail = np.abs(f.reshape(-1, 5) @ _LEG_FIT[:, 3:]).max(axis=1).reshape(3, -1)
            ok = np.all(tail <= QUAD_TOL * scale, axis=0) | (depth == QUAD_DEPTH)
            w = (half * wg).reshape(-1, 5)
            done.append((pending[ok], t.reshape(-1, 5)[ok], w[ok], power[:, ok], fric[ok]))
            bad = pending[~ok]
            if not bad.size:
                break
            m = 0.5 * (bad[:, 0] + bad[:, 1])
            pending = np.concatenate([np.stack([bad[:, 0], m], 1), np.stack([m, bad[:, 1]], 1)])
        return [np.concatenate(parts, axis=1 if k == 3 else 0) for k, parts in enumerate(zip(*done))]

    def _cycle_integrals(self, segments, ta: float, tb: float, positive: bool) -> dict:
        """Input work, gross work, friction dissipation and per-actuator positive work over [ta, tb].

        Adaptive Gauss-Legendre panels (:meth:`_panels`) on each smooth segment; for W+ a panel on
        which an actuator's power changes sign is split at the roots of its interpolant.
        """
        w_in = 0.0
        w_abs = 0.0
        diss = 0.0
        wplus = np.zeros(2)
        xg = _XG
        for seg in segments:
            a = max(ta, seg.points[0].t)
            b = min(tb, seg.points[-1].t)
            if b <= a:
                continue
            edges, _, ww, pw, fric = self._panels(seg, a, b)
            w_in += float(np.sum(ww[None] * pw))
            w_abs += float(np.sum(ww[None] * np.abs(pw)))
            diss += float(np.sum(ww * fric))
            if not positive:
                continue
            npan = len(edges)
            # values at the panel edges from each panel's degree-4 interpolant, so that a sign
            # change between an edge and the nearest Gauss node is not missed
            ends = (pw.reshape(-1, 5) @ _LEG_ENDS).reshape(2, npan, 2)
            allv = np.concatenate([pw, ends], axis=2)
            positive_panels = np.all(allv >= 0, axis=2)
            wplus += np.sum(np.where(positive_panels[:, :, None], pw * ww[None], 0.0), axis=(1, 2))
            mixed = ~positive_panels & ~np.all(allv <= 0, axis=2)
            extra_t, extra_w, extra_i = [], [], []
            for i, j in zip(*np.nonzero(mixed)):
                # the power changes sign inside the panel: split at the roots of its degree-4 interpolant
                coef = np.polynomial.legendre.legfit(xg, pw[i, j], 4)
                r = np.polynomial.legendre.legroots(coef)
                r = np.sort(r[(np.abs(r.imag) < 1e-9) & (np.abs(r.real) < 1)].real)
                lo, hi = edges[j]
                cuts = np.concatenate([[lo], lo + (r + 1) * (hi - lo) / 2, [hi]])
                for c0, c1 in zip(cuts[:-1], cuts[1:]):
                    if c1 - c0 <= 0:
                        continue
                    tt, w2 = gauss_nodes(c0, c1, self.opt.quad_h, 5)
                    extra_t.append(tt)
                    extra_w.append(w2)
                    extra_i.append(np.full(len(tt), i))
            if extra_t:
                te = np.concatenate(extra_t)
                we = np.concatenate(extra_w)
                ie = np.concatenate(extra_i)
                _, aux2 = self._evaluate_many(seg, te)
                p2 = self.torque(te).reshape(2, -1) * aux2[[AUX["dphi1"], AUX["dphi2"]]]
                pv = p2[ie, np.arange(len(te))]
                for i in range(2):
                    wplus[i] += float(np.sum((we * np.maximum(pv, 0.0))[ie == i]))
        return {"input_work": w_in, "gross_work": w_abs, "dissipation": diss, "W_plus_joint": wplus}

    def _balance(self, ints: dict, dV: float) -> dict:
        return energy_balance(ints["input_work"], dV, ints["dissipation"], ints["gross_work"], self.model.robot)

    def _state_at(self, segments, t: float) -> _Point:
        for seg in reversed(segments):
            if seg.points[0].t <= t <= seg.points[-1].t + 1e-15:
                for p in seg.points:
                    if abs(p.t - t) < 1e-15:
                        return p
                xs, aux = self._evaluate_many(seg, np.array([t]))
                return _Point(t, xs[:, 0], aux[:, 0])
        raise ValueError(t)

    def _build_result(self, segments, events, status, detail, fail_t, fail_mode, cycles, periodic_at, t_eval, extra):
        model = self.model
        res = CrawlResult(success=status == Status.SUCCESS, status=int(status), message="", drive="torque",
                          gravity=model.gravity, events=events, cycles=cycles, failure_t=fail_t,
                          failure_mode=fail_mode, extra=extra)
        if status == Status.SUCCESS:
            t0 = float(periodic_at - 1)
            res.message = f"{STATUS_MESSAGES[status]} after {cycles} cycles; steady cycle t in [{t0:g}, {t0 + 1:g}]"
        elif status == Status.NO_START:
            t0 = 0.0
            res.message = f"{STATUS_MESSAGES[status]}: {detail}"
        else:
            t0 = float(max(0, math.floor(fail_t if fail_t is not None else 0.0)))
            res.message = f"{STATUS_MESSAGES[status]}: {detail} at phase t = {fail_t:.10f} " \
                          f"(cycle {int(math.floor(fail_t)) + 1}, phase {fail_t % 1:.10f}) in mode {fail_mode}"
        res.t0 = t0
        t1 = t0 + 1.0 if status == Status.SUCCESS else (fail_t if fail_t is not None else t0)
        if t_eval is None and status == Status.SUCCESS:
            # default output: a uniform grid plus the event phases of the steady cycle
            t_eval = np.unique(np.concatenate([np.linspace(0.0, 1.0, DEFAULT_OUTPUT_POINTS),
                                               [e.t - t0 for e in events if t0 <= e.t <= t0 + 1]]))
        # output samples: per segment, its phases, solutions, foot positions and mode
        blocks = []  # (t, X, A, x1, x2, mode) arrays
        if t_eval is None:
            for seg in segments:
                pts = [p for p in seg.points if t0 - 1e-15 <= p.t <= t1 + 1e-15]
                if pts:
                    blocks.append((np.array([p.t for p in pts]), np.stack([p.x for p in pts], axis=1),
                                   np.stack([p.aux for p in pts], axis=1), seg))
        else:
            te = t0 + np.asarray(t_eval, dtype=float).ravel()
            if np.any(te < t0 - 1e-12) or np.any(te > t0 + 1 + 1e-12):
                raise ValueError("t_eval must lie in [0, 1] (phase within the steady cycle)")
            free = np.ones(te.size, bool)  # a phase on a segment boundary goes to the earlier segment
            for seg in segments:
                sel = np.nonzero(free & (te >= seg.points[0].t) & (te <= seg.points[-1].t))[0]
                if sel.size:
                    free[sel] = False
                    xs, aux = self._evaluate_many(seg, te[sel])
                    blocks.append((te[sel], xs, aux, seg))
        if blocks:
            t = np.concatenate([blk[0] for blk in blocks])
            X = np.concatenate([blk[1] for blk in blocks], axis=1)
            A = np.concatenate([blk[2] for blk in blocks], axis=1)
            feet = [blk[3].foot_positions(blk[2][AUX["d"]]) for blk in blocks]
            x1 = np.concatenate([f[0] for f in feet])
            x2 = np.concatenate([f[1] for f in feet])
            mode = np.concatenate([np.full(blk[0].size, int(blk[3].mode)) for blk in blocks])
            order = np.argsort(t, kind="stable")
            t, X, A, x1, x2, mode = t[order], X[:, order], A[:, order], x1[order], x2[order], mode[order]
            res.t, res.phi, res.theta, res.d = t, X[:2], A[AUX["theta"]], A[AUX["d"]]
            res.x1, res.x2, res.f_t, res.f_n1, res.f_n2 = x1, x2, A[AUX["ft"]], A[AUX["fn1"]], A[AUX["fn2"]]
            res.tau = self.torque(t).reshape(2, -1)
            res.mode = mode
            res.extra["max_residual_scaled"] = float(np.max(A[AUX["res"]]))
        if status == Status.SUCCESS:
            pa, pb = self._state_at(segments, t0), self._state_at(segments, t0 + 1)
            sa = [s for s in segments if s.points[0].t <= t0 <= s.points[-1].t][-1]
            sb = [s for s in segments if s.points[0].t <= t0 + 1 <= s.points[-1].t][-1]
            x1a = sa.foot_positions(pa.aux[AUX["d"]])[0].item()
            x1b = sb.foot_positions(pb.aux[AUX["d"]])[0].item()
            res.S = x1b - x1a
            ints = self._cycle_integrals(segments, t0, t0 + 1, positive=True)
            Va = model.potential(pa.x[:2])
            Vb = model.potential(pb.x[:2])
            dV = float(Vb - Va)
            res.W_plus_joint = ints["W_plus_joint"]
            res.W_plus = float(np.sum(ints["W_plus_joint"]))
            res.CoT_plus = cost_of_transport(res.W_plus, model.robot, res.S)
            res.energy = self._balance(ints, dV)
            res.periodicity_residual = extra.get("periodicity_deviation", float("nan"))
        res.nfev = self.nfev
        res.nsteps = self.nsteps
        res.extra["segments"] = len(segments)
        self._segments = segments
        return res

    def cycle_energy(self, cycle: int) -> dict:
        """Energy balance of cycle ``cycle`` (0-based) of the last run: input work, potential change, dissipation."""
        segs = self._segments
        ta, tb = float(cycle), float(cycle + 1)
        ints = self._cycle_integrals(segs, ta, tb, positive=False)
        pa, pb = self._state_at(segs, ta), self._state_at(segs, tb)
        dV = float(self.model.potential(pb.x[:2]) - self.model.potential(pa.x[:2]))
        return self._balance(ints, dV)


def simulate_torque(model: Model, torque, options: HybridOptions | None = None, t_eval=None) -> CrawlResult:
    """Event-driven hybrid-quasistatic simulation of a torque-driven gait (see module docstring)."""
    return HybridStepper(model, torque, options).run(t_eval=t_eval)
