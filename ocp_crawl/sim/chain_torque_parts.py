"""Parts of the torque-driven stepper of an n-link chain (:mod:`ocp_crawl.sim.chain_torque`): the
mode solves at a phase, the guard functions of each contact mode, the choice of the mode after an
event, the location of events and the cycle integrals and samples of constant-mode segments.

States are ``x = (phi_1 .. phi_m [rad], f_t/(M g) [-])``, phases t in cycles, rates per cycle.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from ocp_crawl.model.chain_compiled import fast_chain_ddot2, fast_chain_newton, newton_columns
from ocp_crawl.model.chain_model import ChainModel, slip_mode, stick_mode
from ocp_crawl.model.chain_statics import aux_names
from ocp_crawl.model.chain_stability import chain_stability_margin
from ocp_crawl.sim.chain_pieces import ChainPieces
from ocp_crawl.sim.event_guards import NEAR_TOUCH, cubic_min
from ocp_crawl.sim.event_locate import NotLocated, guard_root
from ocp_crawl.sim.quadrature import gauss_nodes, sign_split
from ocp_crawl.sim.result import Mode
from ocp_crawl.status import Status

#: largest change of the state from an event to the start of the mode after it that is not a jump
#: (a snap-through): |d phi| [rad], |d f_t|/(M g)/(1 + max k/(M g L)), |d d|/L (the three-link
#: stepper's ``jump_tol``)
JUMP_TOL = 1e-6
#: the modes of a generic gait (one foot slips at a time); slip-slip needs mu1 f_n1 = mu2 f_n2
#: guard values within this of zero [-] are not decided by their sign
GUARD_NOISE = 1e-12

SINGLE_MODES = (Mode.STICK, Mode.SLIP1_POS, Mode.SLIP1_NEG, Mode.SLIP2_POS, Mode.SLIP2_NEG)


def mode_vector(mode: Mode, d0: float = 0.0) -> np.ndarray:
    """The mode vector ``q`` of :mod:`ocp_crawl.model.chain_model` of ``mode`` (stick distance
    ``d0`` [m] for stick-stick)."""
    if mode is Mode.STICK:
        return stick_mode(d0)
    if mode.foot not in (1, 2):
        raise ValueError(f"mode {mode.label} (both feet slipping) is not supported")
    return slip_mode(mode.foot, mode.sigma)


@dataclass
class Point:
    """A solved equilibrium at phase ``t`` [cycles]: state ``x``, outputs ``aux``
    (:meth:`ChainModel.evaluate`, rates per cycle) and the feet positions ``x1``, ``x2`` [m];
    ``left``: at a kink of the input, its rates are those of the piece before it."""

    t: float
    x: np.ndarray
    aux: dict
    x1: float = 0.0
    x2: float = 0.0
    left: bool = False
    jac: np.ndarray | None = field(default=None, repr=False, compare=False)
    """the mode system's Jacobian at the point (n x n)"""
    guards: dict = field(default_factory=dict, repr=False, compare=False)
    """the guards at this point by mode (:meth:`ChainSolver.guards`), once each"""
    rates: dict = field(default_factory=dict, repr=False, compare=False)
    """the guards' rates at this point by mode (:meth:`ChainSolver.guard_rates`), once each"""
    _det: float | None = field(default=None, repr=False, compare=False)

    def det(self) -> float:
        """det of the mode system's Jacobian (its sign tells the equilibrium branch; computed
        when first asked: most solved points, an event's trials, never are)."""
        if self._det is None:
            if self.jac is None:
                raise ValueError("a point without its Jacobian has no det")
            self._det = float(np.linalg.det(self.jac))
        return self._det

    def xdot(self, m: int, Mg: float) -> np.ndarray:
        """Rate of the state along the mode's solution [1/cycle]."""
        a = self.aux
        return np.array([a[k] for k in _rate_names(m)] + [a["dft"] / Mg])


@lru_cache(maxsize=None)
def _rate_names(m: int) -> tuple[str, ...]:
    """The outputs' names of the joints' rates of m joints."""
    return tuple(f"dphi{j}" for j in range(1, m + 1))


@dataclass
class Segment:
    """A stretch of constant contact mode from phase ``t0`` [cycles]; ``points`` in phase order."""

    mode: Mode
    q: np.ndarray
    t0: float
    points: list = field(default_factory=list)

    @property
    def t1(self) -> float:
        return self.points[-1].t


class Stop(Exception):
    """The end of a run by a failure status at phase t in a mode."""

    def __init__(self, status: Status, t: float, mode: Mode, detail: str):
        super().__init__(detail)
        self.status, self.t, self.mode, self.detail = status, t, mode, detail


class ChainSolver:
    """Newton solves and guards of an n-link chain under the torque signal ``torque``."""

    def __init__(self, model: ChainModel, torque, residual_tol: float = 1e-10):
        self.model, self.torque = model, torque
        self.chain = model.chain
        self.m = model.chain.n_joints
        self.Mg, self.L, self.mu = model.Mg, model.chain.L, model.chain.mu
        self.residual_tol = residual_tol
        self.nfev = 0
        self.p = model.p
        self.names = aux_names(model.chain.n)
        joints = range(1, self.m + 1)
        self._heights = [(f"joint_{j}_on_ground", f"zj{j}") for j in joints]
        self._height_rates = [(f"joint_{j}_on_ground", f"dzj{j}") for j in joints]
        # compiled (model.chain_compiled): the Newton loop makes thousands of calls per run
        n = model.chain.n
        self._newton, self._ddot2 = fast_chain_newton(n), fast_chain_ddot2(n)
        self.pieces = ChainPieces(torque)
        self._taus: dict = {}
        """the torques and rates at recent phases (a phase is solved again and again: Newton
        solves from several guesses, an event's trials; a signal's evaluation costs tens of us)"""

    def tau(self, t: float, left: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Torques [N m] and their rate [N m/cycle] at phase t (at a kink of the input the rate
        after it, or before it when ``left``)."""
        known = self._taus.get((t, left))
        if known is None:
            if len(self._taus) > 64:
                self._taus.clear()
            known = self._taus[(t, left)] = (
                np.asarray(self.torque(t), float).ravel(),
                np.asarray(self.torque.derivative(self.pieces.rate_phase(t, left)),
                           float).ravel())
        return known

    def rate(self, t: float) -> np.ndarray:
        """The torques' rate [N m/cycle] at phase t (at a kink of the input the rate after it)."""
        return np.asarray(self.torque.derivative(self.pieces.rate_phase(t)), float).ravel()

    def taus(self, ts: np.ndarray, upto: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Torques (m, N) [N m] and rates (m, N) [N m/cycle] at the phases ts (N,) (at a kink the
        rate after it, but at ``upto`` the rate before it)."""
        tau = np.asarray(self.torque(ts), float)
        dtau = np.asarray(self.torque.derivative(self.pieces.rate_phases(ts, upto)), float)
        if tau.shape != (self.m, ts.size) or dtau.shape != tau.shape:
            pairs = [self.tau(float(t), t == upto) for t in ts]
            tau = np.array([p[0] for p in pairs]).T.reshape(self.m, -1)
            dtau = np.array([p[1] for p in pairs]).T.reshape(self.m, -1)
        return tau, dtau

    def solve(self, t: float, x0, q: np.ndarray, left: bool = False) -> Point | None:
        """The mode's equilibrium at phase t by Newton's method from ``x0`` (as
        :meth:`ChainModel.solve`: scaled residual <= 1e-13 or a step <= 1e-14, at most 40 steps,
        :data:`~ocp_crawl.model.chain_compiled.NEWTON_OPTIONS`); None when its residual exceeds
        ``residual_tol``.  At a kink of the input its rates are those after it, or before it when
        ``left``."""
        tau, dtau = self.tau(t, left)
        x, out, J = self._newton(x0, tau, dtau, q, self.p)
        self.nfev += 1
        aux = dict(zip(self.names, out.tolist()))
        if not abs(aux["res"]) <= self.residual_tol or not np.isfinite(x).all():
            return None
        nx = self.m + 1
        return Point(float(t), x, aux, left=left and self.pieces.is_kink(t),
                     jac=J.reshape(nx, nx, order="F"))

    def guess(self, pt: Point, t: float) -> np.ndarray:
        """The tangent predictor from ``pt`` to phase t."""
        return pt.x + (t - pt.t) * pt.xdot(self.m, self.Mg)

    def guards(self, mode: Mode, pt: Point) -> dict[str, float]:
        """Guard functions of ``mode`` at pt (scaled [-], positive while the mode holds), named as
        the guards of :mod:`ocp_crawl.sim.event_guards` (so that its ``transition`` table
        applies); each point's once per mode (the steps read their ends' several times)."""
        known = pt.guards.get(mode)
        if known is None:
            known = pt.guards[mode] = self._guards(mode, pt.aux)
        return known

    def _guards(self, mode: Mode, aux: dict) -> dict[str, float]:
        Mg, L = self.Mg, self.L
        g = {"lift_off_1": aux["fn1"] / Mg, "lift_off_2": aux["fn2"] / Mg,
             "feet_crossed": aux["d"] / L}
        for name, key in self._heights:
            g[name] = aux[key] / L
        ft, lim1, lim2 = aux["ft"], aux["lim1"], aux["lim2"]
        if mode is Mode.STICK:
            g.update({"slip_1+": (lim1 - ft) / Mg, "slip_1-": (lim1 + ft) / Mg,
                      "slip_2+": (lim2 - ft) / Mg, "slip_2-": (lim2 + ft) / Mg})
            return g
        g["stick"] = mode.sigma * aux["ddot"] / L
        if mode.foot == 1:
            g["switch_to_2"] = (lim2 - lim1) / Mg
        else:
            g["switch_to_1"] = (lim1 - lim2) / Mg
        return g

    def guard_rates(self, mode: Mode, pt: Point, q: np.ndarray) -> dict[str, float]:
        """Rates [1/cycle] of :meth:`guards` along the mode's solution at pt (the same keys).  The
        slip modes' sigma d'/L needs d'' (:meth:`ChainModel.ddot2`) and so the torques' second
        rate, taken by central differences of their rate (1e-5 cycles) inside the input's piece
        that holds pt.  Each point's rates in a mode are computed once (the points' state and
        outputs do not change)."""
        known = pt.rates.get(mode)
        if known is not None:
            return known
        pt.rates[mode] = r = self._guard_rates(mode, pt, q)
        return r

    def _guard_rates(self, mode: Mode, pt: Point, q: np.ndarray) -> dict[str, float]:
        a, Mg, L = pt.aux, self.Mg, self.L
        r = {"lift_off_1": a["dfn1"] / Mg, "lift_off_2": a["dfn2"] / Mg,
             "feet_crossed": a["ddot"] / L}
        for name, key in self._height_rates:
            r[name] = a[key] / L
        dft, dlim1, dlim2 = a["dft"], self.mu[0] * a["dfn1"], self.mu[1] * a["dfn2"]
        if mode is Mode.STICK:
            r.update({"slip_1+": (dlim1 - dft) / Mg, "slip_1-": (dlim1 + dft) / Mg,
                      "slip_2+": (dlim2 - dft) / Mg, "slip_2-": (dlim2 + dft) / Mg})
            return r
        tau, dtau = self.tau(pt.t, pt.left)
        tc = self.pieces.curvature_phase(pt.t, pt.left)
        ddtau = (self.rate(tc + 1e-5) - self.rate(tc - 1e-5)) / 2e-5
        ab = self._ddot2(pt.x, tau, dtau, q, self.p)[0]
        r["stick"] = mode.sigma * (ab[0] + float(ab[1:] @ ddtau)) / L
        if mode.foot == 1:
            r["switch_to_2"] = (dlim2 - dlim1) / Mg
        else:
            r["switch_to_1"] = (dlim1 - dlim2) / Mg
        return r

    def dips(self, mode: Mode, q: np.ndarray, p0: Point, p1: Point) -> tuple[list[float], bool]:
        """Phases in (p0.t, p1.t) where the cubic Hermite interpolant of a guard (values and
        rates at both ends) has a local minimum below zero: a guard that may dip below zero and
        back inside the step, unseen by the signs at its ends (below -GUARD_NOISE); earliest
        first; and whether a contact's guard nears zero inside the step
        (:data:`~ocp_crawl.sim.event_guards.NEAR_TOUCH`: the step is to be halved)."""
        h = p1.t - p0.t
        g0, g1 = self.guards(mode, p0), self.guards(mode, p1)
        r0, r1 = self.guard_rates(mode, p0, q), self.guard_rates(mode, p1, q)
        out, near = [], False
        for k in g0:
            a, b, m0, m1 = g0[k], g1[k], h * r0[k], h * r1[k]
            if min(a, b) - 0.15 * (abs(m0) + abs(m1)) >= -GUARD_NOISE:
                continue
            s, v = cubic_min(a, b, m0, m1)
            if v < -GUARD_NOISE:
                out.append(p0.t + s * h)
            elif v < NEAR_TOUCH * min(a, b) and k.startswith(("lift", "feet", "joint")):
                near = True
        return sorted(out), near

    def margin(self, x: np.ndarray, q: np.ndarray) -> float:
        """Stability margin of the equilibrium ``x`` in mode ``q`` (> 0: stable)."""
        return chain_stability_margin(self.model, x, q)

    def jump(self, pt: Point, start: Point) -> float:
        """Size of the change of the state from pt to start (:data:`JUMP_TOL`'s measure)."""
        m = self.m
        ft_scale = 1.0 + max(self.chain.stiffness) / (self.Mg * self.L)
        return max(float(np.max(np.abs(start.x[:m] - pt.x[:m]))),
                   abs(start.x[m] - pt.x[m]) / ft_scale, abs(start.aux["d"] - pt.aux["d"]) / self.L)

    def consistent(self, mode: Mode, pt: Point, dt: float) -> Point | None:
        """The solution of ``mode`` at pt (stick-stick at the distance of pt) when every guard of
        the mode is positive just after pt.t and its equilibrium is stable there; else None.

        The guards are tested at pt.t + dt, then (while the least one is within 1e-12 of zero, as
        a guard that leaves zero quadratically, e.g. the friction margin after d' = 0) at
        100 dt and 10^4 dt."""
        q = mode_vector(mode, pt.aux["d"])
        start = self.solve(pt.t, pt.x, q)
        if start is None:
            return None
        for trial in (dt, 100 * dt, 1e4 * dt):
            after = self.solve(pt.t + trial, self.guess(start, pt.t + trial), q)
            if after is None:
                return None
            low = min(self.guards(mode, after).values())
            if low <= -GUARD_NOISE:
                return None
            if low > GUARD_NOISE:
                return start if self.margin(after.x, q) > 0 else None
        return None


def locate(s: ChainSolver, seg: Segment, pt: Point, new: Point, name: str, g0: float,
           trial_step: float, xtol: float) -> tuple[float, Point]:
    """Phase and solved point of the zero of guard ``name`` of the segment's mode in the step
    (pt.t, new.t] (:func:`~ocp_crawl.sim.event_locate.guard_root`, the guard's exact rate from
    :meth:`ChainSolver.guard_rates`), to ``xtol`` [cycles]; a guard not positive at pt is probed
    ``trial_step`` [cycles] after it (not positive there either: the event is at pt)."""
    # (the ends are known: a re-solve there could differ in the last bits and break the bracket;
    # the step's end carries the rates before a kink that ends it)
    known = {pt.t: pt, new.t: new}

    def point_at(t: float) -> Point:
        p = known.get(t)
        if p is None:
            lam = (t - pt.t) / (new.t - pt.t)
            p = s.solve(t, (1 - lam) * pt.x + lam * new.x, seg.q)
            if p is None:
                raise Stop(Status.NO_CONVERGENCE, t, seg.mode, "mode solve failed locating an "
                           f"event of {name}")
            known[t] = p
        return p

    def value(p: Point) -> float:
        return s.guards(seg.mode, p)[name]

    lo = (pt.t, g0)
    if not g0 > 0:
        t = min(pt.t + trial_step, 0.5 * (pt.t + new.t))
        lo = (t, value(point_at(t)))
        if not lo[1] > 0:
            return pt.t, pt
    try:
        return guard_root(point_at, value, lambda p: s.guard_rates(seg.mode, p, seg.q)[name], lo,
                          (new.t, value(new)), xtol)
    except NotLocated as exc:
        raise Stop(Status.NO_CONVERGENCE, exc.t, seg.mode,
                   f"event {name} not located to {xtol:g}") from None


def solve_columns(solver: ChainSolver, ts: np.ndarray, X0: np.ndarray, q: np.ndarray,
                  upto: float | None = None) -> tuple[np.ndarray, dict]:
    """Newton solves of the mode ``q`` at the phases ``ts`` (N,) from the guesses ``X0`` (m+1, N)
    at once (each column as :meth:`ChainSolver.solve`); returns the states (m+1, N) and the
    outputs (:meth:`ChainModel.evaluate` rows, each (N,); their rates at a kink of the input those
    after it, at ``upto`` those before it).  RuntimeError when a column does not converge."""
    tau, dtau = solver.taus(ts, upto)
    X, out = newton_columns(solver.chain.n)(np.asarray(X0, float), tau, dtau, q, solver.model.p)
    solver.nfev += ts.size
    aux = {k: out[i] for i, k in enumerate(aux_names(solver.chain.n))}
    good = (np.abs(aux["res"]) <= solver.residual_tol) & np.all(np.isfinite(X), axis=0)
    if not good.all():
        raise RuntimeError(f"mode solve failed at t = {ts[int(np.argmin(good))]:.15g}")
    return X, aux


class SegmentEval:
    """The mode's solution of a segment at many phases at once, each Newton solve started from
    the tangent predictor of the segment's nearest stored point (rates at ``upto``, the end of
    an interval, those before it)."""

    def __init__(self, solver: ChainSolver, seg: Segment, upto: float | None = None):
        self.solver, self.seg, self.upto = solver, seg, upto
        self.tp = np.array([p.t for p in seg.points])
        self.Xp = np.array([p.x for p in seg.points]).T
        self.Vp = np.array([p.xdot(solver.m, solver.Mg) for p in seg.points]).T
        self.key, self.value = b"", np.zeros(0)

    def solve(self, t: np.ndarray) -> tuple[np.ndarray, dict]:
        """States (m+1, N) and outputs at the phases t (N,)."""
        return solve_columns(self.solver, t, self._guesses(t), self.seg.q, upto=self.upto)

    def _guesses(self, t: np.ndarray) -> np.ndarray:
        """The Newton guesses (m+1, N) at the phases t (N,): the tangent predictor of the nearest
        stored point."""
        i = np.clip(np.searchsorted(self.tp, t), 0, len(self.tp) - 1)
        j = np.maximum(i - 1, 0)
        near = np.where(np.abs(self.tp[j] - t) < np.abs(self.tp[i] - t), j, i)
        X0 = self.Xp[:, near] + (t - self.tp[near]) * self.Vp[:, near]
        # (inside a hold of the input, crossed in one step, the state is that of the hold's start;
        # the rates at its end are those after it)
        held = np.max(np.abs(self.Xp[:, i] - self.Xp[:, j]), axis=0) <= 1e-14
        return np.where(held, self.Xp[:, j], X0)

    def rows(self, t) -> np.ndarray:
        """(m + 1, N): the joint powers tau_j phi_j' [J/cycle], then f_t d' [J/cycle] at the
        phases t."""
        t = np.atleast_1d(np.asarray(t, float))
        key = t.tobytes()
        if key != self.key:
            m = self.solver.m
            _, a = self.solve(t)
            tau = self.solver.taus(t)[0]
            out = np.empty((m + 1, t.size))
            out[:m] = tau * np.array([a[f"dphi{j}"] for j in range(1, m + 1)])
            out[m] = a["ft"] * a["ddot"]
            self.key, self.value = key, out
        return self.value


def segment_integrals(solver: ChainSolver, seg: Segment, a: float, b: float,
                      h: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Integrals over [a, b] in the segment's mode [J]: W+ per joint (m,), the work per joint (m,)
    and the friction dissipation, by 5-point Gauss-Legendre panels of at most ``h`` cycles split at
    the input's kinks; a joint's positive part split at the sign changes of its power's interpolant
    in a panel, also between the nodes (:func:`~ocp_crawl.sim.quadrature.sign_split`: the panels are
    fixed), the split panels' nodes solved together (one solve for every joint)."""
    m = solver.m
    wp, work, diss = np.zeros(m), np.zeros(m), 0.0
    for lo, hi in solver.pieces.split(a, b):
        if hi <= lo:
            continue
        ev = SegmentEval(solver, seg, upto=hi)
        tq, w = gauss_nodes(lo, hi, h, 5)
        r = ev.rows(tq)
        if not np.all(np.isfinite(r)):   # (a singular Jacobian at a node: rates without a value)
            raise RuntimeError(f"the joints' powers are not finite in [{lo:.15g}, {hi:.15g}]")
        work, diss = work + r[:m] @ w, diss + float(r[m] @ w)
        edges = np.linspace(lo, hi, tq.size // 5 + 1)   # (the panels of gauss_nodes)
        pw = r[:m].reshape(m, -1, 5)
        te, we, joint, _, positive = sign_split(np.column_stack([edges[:-1], edges[1:]]), pw, h,
                                                dips=True)
        wp += np.where(positive[:, :, None], pw * w.reshape(1, -1, 5), 0.0).sum(axis=(1, 2))
        if te.size:
            fp = ev.rows(te)[joint, np.arange(te.size)]
            wp += np.bincount(joint, np.maximum(fp, 0.0) * we, minlength=m)
    return wp, work, diss


def sample_segment(solver: ChainSolver, seg: Segment, ts: np.ndarray) -> dict:
    """The sampled fields at the phases ``ts`` of the segment: phi, tau (m, N), d, x1, x2, f_t,
    f_n1, f_n2, theta (N,) and alpha (n, N)."""
    m, n = solver.m, solver.chain.n
    X, a = SegmentEval(solver, seg).solve(np.asarray(ts, float))
    first, d = seg.points[0], a["d"]
    x1 = first.x2 - d if seg.mode.foot == 1 else np.full(d.shape, first.x1)
    x2 = first.x1 + d if seg.mode.foot == 2 else np.full(d.shape, first.x2)
    return {"phi": X[:m], "tau": solver.taus(np.asarray(ts, float))[0], "d": d, "x1": x1,
            "x2": x2, "f_t": a["ft"], "f_n1": a["fn1"], "f_n2": a["fn2"],
            "theta": a[f"alpha{n // 2 + 1}"],
            "alpha": np.array([a[f"alpha{i}"] for i in range(1, n + 1)])}
