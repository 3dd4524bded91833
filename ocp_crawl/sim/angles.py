"""Prescribed-angle locomotion (paper Section II-A).

The joint angles phi(t) are imposed, so the configuration, d(t) and the normal forces are known
at every phase. Generically d' != 0, so one foot slips at every instant: the one with the smaller
friction limit mu_i f_n,i (equal friction: the foot with the smaller normal force, sign of Delta in
eq. (delta); for a tie, as in mirror-symmetric gaits, both feet slip symmetrically), in the
direction that changes d; then f_t = mu_s f_n,s sign(d') (eq. (ft)) and the holding torques follow
from the joint balance.  The switching instants (d' = 0: slip direction reverses; mu1 f_n1 = mu2
f_n2: slipping foot changes) are located by Brent's method on the exact kinematics.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ocp_crawl.model.inputs import PeriodicSignal, as_signal
from ocp_crawl.model.statics import KIN, Model, call_mapped, symbolic
from ocp_crawl.sim.quadrature import gauss_nodes, positive_part_integral
from ocp_crawl.sim.assemble import (balance_metrics, default_phases, failure_message, new_result,
                                    output_phases, sample_fields)
from ocp_crawl.sim.result import CrawlResult, Event, Mode
from ocp_crawl.status import Status

if TYPE_CHECKING:  # (the chain's prescribed-angle simulator shares these functions)
    from ocp_crawl.model.chain_model import ChainModel
    from ocp_crawl.sim.chain_angles import ChainGait

    from typing import TypeAlias

    _Gait: TypeAlias = "KinematicGait | ChainGait"
    _AnyModel: TypeAlias = "Model | ChainModel"


class KinematicGait:
    """Vectorised evaluation of the prescribed gait's kinematics and guards at phases t."""

    def __init__(self, model: Model, angles: PeriodicSignal):
        self.model, self.angles = model, angles
        r = model.robot
        self.mu = (r.mu1, r.mu2)
        self.Mg = r.M * r.g

    def __call__(self, t) -> dict[str, np.ndarray]:
        t = np.atleast_1d(np.asarray(t, float))
        phi = self.angles(t).reshape(2, -1)
        dphi = self.angles.derivative(t).reshape(2, -1)
        k = call_mapped(symbolic().kin, phi, self.model.p)
        out = {n: k[i] for n, i in KIN.items()}
        out["phi"], out["dphi"] = phi, dphi
        out["ddot"] = k[KIN["grad_d1"]] * dphi[0] + k[KIN["grad_d2"]] * dphi[1]
        out["h"] = (self.mu[0] * out["fn1"] - self.mu[1] * out["fn2"]) / self.Mg
        return out

    def scalar(self, name: str):
        return lambda t: float(self(t)[name][0])


#: |mu1 f_n1 - mu2 f_n2|/(M g) below which both friction limits are taken as equal (both feet slip)
TIE = 1e-12
#: feet closer than TOUCH * L are taken as meeting (d only touches zero in symmetric folds)
TOUCH = 1e-8
#: largest |phi(1) - phi(0)| [rad] accepted as a periodic input
PERIODIC_TOL = 1e-9


def _classes(name: str, v: np.ndarray) -> np.ndarray:
    """Sign classes of a switching function: -1, 0, +1 (for h, |h| <= TIE is the tie class 0)."""
    if name == "h":
        return np.where(np.abs(v) <= TIE, 0, np.sign(v)).astype(int)
    return np.sign(v).astype(int)


def first_zero(f, ts: np.ndarray, v: np.ndarray, scale: float,
                t_end: float | None = None) -> float | None:
    """First phase in [0, t_end) at which the guard ``f`` (values ``v`` on the scan phases ``ts``)
    reaches zero.

    A sign change on the scan is located by Brent's method.  A guard may also reach zero between two
    scan phases without changing sign on the scan (it touches zero, as d in a symmetric fold, or
    dips below it and back): every local minimum of the scan below 5 % of ``scale`` (cycle ends
    included) is refined by minimisation, and a minimum at or below TOUCH * scale is a zero too.
    """
    from scipy.optimize import brentq, minimize_scalar  # scipy only where used (start-up time)

    limit = 1.0 if t_end is None else t_end
    n = v.size
    found = None
    bad = np.nonzero(~(v > 0))[0]
    if bad.size:
        j = int(bad[0])
        if j == 0:
            return 0.0
        hi = min(ts[j], limit * (1 - 1e-13)) if t_end is not None else ts[j]
        f_hi = f(hi) if ts[j - 1] < hi else math.nan
        if f_hi < 0:
            found = brentq(f, ts[j - 1], hi, xtol=1e-14)
        elif f_hi == 0:
            found = hi
    # at the cycle ends the neighbour on the scan side counts
    left = np.concatenate([[v[1]], v[:-1]])
    right = np.concatenate([v[1:], [v[-2]]])
    for m in np.nonzero((v > 0) & (v < 0.05 * scale) & (v <= left) & (v <= right))[0].tolist():
        lo, hi = ts[max(m - 1, 0)], min(ts[min(m + 1, n - 1)], limit)
        if (found is not None and lo >= found) or lo >= hi:
            break
        opt = minimize_scalar(f, bounds=(lo, hi), method="bounded", options={"xatol": 1e-13})
        if opt.fun > TOUCH * scale:
            continue
        t0 = brentq(f, lo, opt.x, xtol=1e-14) if opt.fun < 0 and f(lo) > 0 else float(opt.x)
        if found is None or t0 < found:
            found = t0
        break
    return found


def simulate_angles(model: Model, angles, t_eval=None, n_scan: int = 512) -> CrawlResult:
    """Prescribed-angle gait over one cycle (it is periodic after one cycle).

    Parameters
    ----------
    model : Model
        The robot and the gravity convention.
    angles : PeriodicSignal or callable
        1-periodic joint angles (phi1, phi2) [rad] of the phase t [cycles], interior angles below
        the body (pi = flat), e.g. :class:`~ocp_crawl.model.inputs.Harmonic`.
    t_eval : array_like of float, optional
        Output phases in [0, 1] [cycles]; by default 201 equally spaced phases plus the switching
        instants.
    n_scan : int
        Phases scanned for sign changes of the switching functions before Brent's method (>= 8).

    Returns
    -------
    CrawlResult
        S [m] (< 0: towards foot 1), W+ [J], CoT+ [-], the events and trajectories of the cycle.

    A loss of contact during the cycle (a foot lifting off, a joint reaching the ground, the feet
    meeting) is returned as a failure status with its phase (``failure_t``) and the contact mode
    just before it (``failure_mode``).  Invalid input raises ValueError (TypeError for a wrong
    type): angles that are not finite or not 1-periodic, bad ``t_eval`` or ``n_scan``, and a start
    configuration (the angles at t = 0) without a valid two-foot contact.
    """
    if not isinstance(model, Model):
        raise TypeError(f"simulate_angles: model must be a Model, got {type(model).__name__}")
    angles = as_signal(angles)
    if isinstance(n_scan, bool) or not isinstance(n_scan, (int, np.integer)) or n_scan < 8:
        raise ValueError(f"simulate_angles: n_scan must be an integer >= 8, got {n_scan!r}")
    te = output_phases(t_eval)
    ts = np.linspace(0.0, 1.0, int(n_scan) + 1)
    _check_angles(model, angles, ts)
    kin = KinematicGait(model, angles)
    K = kin(ts)
    robot = model.robot
    failure = first_failure(kin, ts, K, robot.M * robot.g, robot.L, 2)
    if failure is not None:
        return failure_result(model, kin, *failure)
    switches = switching_instants(kin, ts, K)
    anchors, S = slip_anchors(kin, [0.0] + [e[0] for e in switches] + [1.0], float(K["d"][0]))
    events = [switch_event(kin, t_ev, name) for t_ev, name in switches]
    if te is None:
        te = default_phases([e[0] for e in switches])
    samples = _samples(model, kin(te), te, anchors)
    wplus, w_in, w_abs, diss = _cycle_integrals(model, kin, anchors,
                                                np.asarray(getattr(angles, "t_knots", ()), float))
    dV = float(model.potential(angles(1.0)) - model.potential(angles(0.0)))
    return new_result(model, "angles", Status.SUCCESS,
                      f"prescribed-angle gait: {len(switches)} switching instants per cycle",
                      cycles=1, events=events, **samples,
                      **balance_metrics(model.robot, S, wplus, w_in, dV, diss, w_abs),
                      periodicity_residual=float(np.max(np.abs(angles(1.0) - angles(0.0)))))


def _check_angles(model: Model, angles: PeriodicSignal, ts: np.ndarray) -> None:
    """ValueError unless the angles have shape (2, N), are finite with their derivative on the scan
    phases ``ts``, are 1-periodic and give a two-foot contact at t = 0."""
    phi_scan = np.asarray(angles(ts), float)
    if phi_scan.shape != (2, ts.size):
        raise ValueError("simulate_angles: angles(t) must have shape (2, N) for N phases, "
                         f"got {phi_scan.shape}")
    nonfinite = ~np.all(np.isfinite(phi_scan), axis=0) | ~np.all(np.isfinite(angles.derivative(ts)),
                                                                 axis=0)
    if nonfinite.any():
        raise ValueError("simulate_angles: angles or their derivative not finite at phase t "
                         f"= {ts[np.argmax(nonfinite)]:.6g}")
    gap = float(np.max(np.abs(np.asarray(angles(1.0), float) - np.asarray(angles(0.0), float))))
    if not gap <= PERIODIC_TOL:
        raise ValueError("simulate_angles: angles must be 1-periodic in the phase, got |phi(1) "
                         f"- phi(0)| = {gap:.3g} rad")
    model.check_contact(angles(0.0), where="prescribed configuration at t = 0")


def first_failure(kin: _Gait, ts: np.ndarray, K: dict, Mg: float, L: float,
                  joints: int) -> tuple | None:
    """(phase, status, label, event kind) of the first loss of contact in the cycle, or None: a
    foot lifting off (normal force over ``Mg`` [N]), one of the ``joints`` joints reaching the
    ground (height over ``L`` [m]) or the feet meeting.

    The feet crossing (d = 0) is searched first and the others only before it: near d = 0 the
    normal forces x_c/d M g are singular.
    """
    failure = None
    t_cross = first_zero(kin.scalar("d"), ts, K["d"], L)
    if t_cross is not None:
        failure = (t_cross, Status.FEET_CROSSED, "feet meet or cross", "feet_crossed")
    checks = [(f"fn{i}", Mg, Status.LIFT_OFF, f"foot {i} lifts off",
               f"lift_off_{i}") for i in (1, 2)]
    checks += [(f"zj{i}", L, Status.JOINT_ON_GROUND, f"joint {i} reaches the ground",
                f"joint_{i}_on_ground")
               for i in range(1, joints + 1)]
    for name, scale, status, label, kind in checks:
        f = kin.scalar(name)
        tf = first_zero(f, ts, K[name], scale, t_end=t_cross)
        if tf is None:
            continue
        if name.startswith("zj") and abs(f(tf)) > 1e-6 * L:
            # the joint height jumps instead of vanishing: the body angle changes branch, which
            # happens where the feet meet (d = 0) and the chain would turn over
            status, label, kind = Status.FEET_CROSSED, "feet meet or cross", "feet_crossed"
        if failure is None or tf < failure[0]:
            failure = (tf, status, label, kind)
    return failure


def failure_result(model: _AnyModel, kin: _Gait, tf: float, status: Status, label: str,
                    kind: str) -> CrawlResult:
    """The result of a cycle that loses contact at phase tf, with the mode just before it."""
    k0 = kin(max(tf - 1e-9, 0.0))
    h0 = k0["h"][0]
    mode = Mode.slip(3 if abs(h0) <= TIE else (1 if h0 < 0 else 2), 1 if k0["ddot"][0] > 0 else -1)
    return new_result(model, "angles", status,
                      failure_message(status,
                                      f"{label} at phase t = {tf:.10f} (prescribed angles)"),
                      cycles=1, failure_t=tf, failure_mode=mode.label,
                      events=[Event(tf, kind, "", "failure")])


def switching_instants(kin: _Gait, ts: np.ndarray, K: dict) -> list[tuple[float, str]]:
    """Sorted (phase, function) of the switching instants: d' changes sign (slip reversal) or
    vanishes on a stretch (the input holds still: both feet stick); the smaller friction limit
    changes feet (slip switch), or both are equal on a stretch (|h| <= TIE: both feet slip)."""
    events: list[tuple[float, str]] = []
    for name in ("ddot", "h"):
        f = kin.scalar(name)
        c = _classes(name, K[name])
        starts = np.concatenate([[0], np.nonzero(np.diff(c))[0] + 1])
        runs = list(zip(c[starts], starts, np.concatenate([starts[1:] - 1, [c.size - 1]])))
        k = 0
        while k < len(runs) - 1:
            t_ev, k = _next_switch(f, name, ts, runs, k)
            if t_ev is not None:
                events.append((t_ev, name))
    events.sort()
    return events


def _next_switch(f, name: str, ts: np.ndarray, runs: list, k: int) -> tuple[float | None, int]:
    """The switch between the runs k and k + 1 of sign classes of ``f`` (None for a touch) and the
    next k."""
    from scipy.optimize import brentq  # scipy only where used (start-up time)

    rtol = 4 * np.finfo(float).eps
    (c0, _, e0), (c1, s1, e1) = runs[k], runs[k + 1]
    if c0 and c1:
        return brentq(f, ts[e0], ts[s1], xtol=1e-14, rtol=rtol), k + 1
    if c0 and s1 == e1 and k + 2 < len(runs) and runs[k + 2][0]:
        # zero at a single scan phase: a crossing exactly there, or a touch (no event)
        if runs[k + 2][0] == -c0:
            return brentq(f, ts[e0], ts[runs[k + 2][1]], xtol=1e-14, rtol=rtol), k + 2
        return None, k + 2
    # into or out of a stretch on which the function is zero: bisection on the class
    lo, hi = ts[e0], ts[s1]
    while hi - lo > 1e-14:
        mid = 0.5 * (lo + hi)
        if _classes(name, np.array([f(mid)]))[0] == c0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi), k + 1


def _mode_at(kin: _Gait, tm: float) -> Mode:
    """Contact mode at phase tm: the foot with the smaller friction limit slips along sign(d')."""
    k1 = kin(tm)
    h, dd = k1["h"][0], k1["ddot"][0]
    if dd == 0:
        return Mode.STICK
    return Mode.slip(3 if abs(h) <= TIE else (1 if h < 0 else 2), 1 if dd > 0 else -1)


def slip_anchors(kin: _Gait, breaks: list[float], d_start: float) -> tuple[list, float]:
    """(a, b, mode, x1, x2 at a) of each stretch between switching instants, and x1 at the cycle's
    end [m] (foot 1 starts at 0): the slipping foot follows d, the other stays."""
    x1, x2 = 0.0, d_start
    anchors = []
    for a, b in zip(breaks[:-1], breaks[1:]):
        if b - a <= 0:
            continue
        m = _mode_at(kin, 0.5 * (a + b))
        db = float(kin(b)["d"][0])
        anchors.append((a, b, m, x1, x2))
        if m.foot == 1:
            x1 = x2 - db
        elif m.foot == 2:
            x2 = x1 + db
        elif m.foot == 3:
            mid = 0.5 * (x1 + x2)
            x1, x2 = mid - 0.5 * db, mid + 0.5 * db
        # stick-stick (d' = 0 on a stretch): neither foot moves
    return anchors, x1 - 0.0


def switch_event(kin: _Gait, t_ev: float, name: str) -> Event:
    """The event of a switching instant of the function ``name`` ("ddot" or "h") at phase t_ev."""
    before = _mode_at(kin, max(t_ev - 1e-9, 0.0))
    after = _mode_at(kin, min(t_ev + 1e-9, 1.0))
    if name == "h":
        kind = "slip_switch"
    elif after == Mode.STICK:
        kind = "slip_to_stick"
    elif before == Mode.STICK:
        kind = {1: "slip_onset_1", 2: "slip_onset_2", 3: "slip_onset_both"}[after.foot]
    else:
        kind = "slip_reversal"
    return Event(float(t_ev), kind, before.label, after.label, float(kin(t_ev)[name][0]))


def slip_friction(mu, k1: dict, m: Mode):
    """f_t [N] in mode m: the slipping foot's friction limit along sign(d') (foot 1's in
    slip-slip)."""
    return (mu[0] * k1["fn1"] if m.foot in (1, 3) else mu[1] * k1["fn2"]) * m.sigma


def _samples(model: Model, Ko: dict, te: np.ndarray, anchors: list) -> dict:
    """The output array fields (:func:`~ocp_crawl.sim.assemble.sample_fields`) at the phases te,
    with the kinematics Ko there."""
    n = len(te)
    modes, ft, x1o, x2o = np.empty(n, int), np.empty(n), np.empty(n), np.empty(n)
    mu = (model.robot.mu1, model.robot.mu2)
    for j, t in enumerate(te):
        a, b, m, xa1, xa2 = next((s for s in anchors if s[0] <= t <= s[1]), anchors[-1])
        modes[j] = int(m)
        ft[j] = (mu[0] * Ko["fn1"][j] if m.foot in (1, 3) else mu[1] * Ko["fn2"][j]) * m.sigma
        if m.foot == 1:
            x2o[j] = xa2
            x1o[j] = xa2 - Ko["d"][j]
        elif m.foot == 2:
            x1o[j] = xa1
            x2o[j] = xa1 + Ko["d"][j]
        elif m.foot == 0:
            x1o[j], x2o[j] = xa1, xa2
        else:
            mid = 0.5 * (xa1 + xa2)
            x1o[j], x2o[j] = mid - 0.5 * Ko["d"][j], mid + 0.5 * Ko["d"][j]
    return sample_fields(te, Ko["phi"], Ko["theta"], Ko["d"], x1o, x2o, ft, Ko["fn1"], Ko["fn2"],
                         model.hold_torque(Ko["phi"], ft), modes)


def _cycle_integrals(model: Model, kin: KinematicGait, anchors: list, knots: np.ndarray) -> tuple:
    """(W+ per actuator, input work, gross work, friction dissipation) [J] over the cycle, stretch
    by stretch (f_t and the holding torques jump at the switching instants).

    Sampled inputs (splines, PCHIP, piecewise linear) are smooth only between their ``knots``: the
    quadrature panels end at the knots too, or its error grows from ~1e-12 to ~1e-6.  Within a piece
    the panels are halved until the piece's sums agree to :data:`QUAD_RTOL` (:func:`piece_sums`).
    """
    mu = (model.robot.mu1, model.robot.mu2)
    wplus = np.zeros(2)
    sums = np.zeros(3)
    pieces = []
    for a, b, m, _, _ in anchors:
        inner = knots[(knots > a) & (knots < b)]
        edges = np.concatenate([[a], inner, [b]])
        pieces += [(lo, hi, m) for lo, hi in zip(edges[:-1], edges[1:])]
    for a, b, m in pieces:
        def power(t, i, m=m):
            k1 = kin(t)
            tau = model.hold_torque(k1["phi"], slip_friction(mu, k1, m))
            return tau[i] * k1["dphi"][i]

        piece, h = piece_sums(model, kin, mu, a, b, m)
        sums += piece
        for i in range(2):
            wplus[i] += positive_part_integral(a, b, lambda t, i=i: power(t, i),
                                               lambda t, i=i: float(power(t, i)[0]), h=h)
    w_in, w_abs, diss = (float(x) for x in sums)
    return wplus, w_in, w_abs, diss


#: panels of the cycle integrals [cycles]: the widest, and the narrowest of the doublings
QUAD_PANEL, QUAD_PANEL_MIN = 1.0 / 64, 1.0 / 8192
#: the piece's sums are accepted when doubling the panels changes them by at most this fraction of
#: the piece's gross work plus dissipation: on fast pulse edges one 1/64-cycle panel left the
#: dissipation 4e-6 off (the energy balance 1e-10 J of 0.05 J); converged, it agrees with adaptive
#: quadrature to 1e-15
QUAD_RTOL = 1e-11


def piece_sums(model: _AnyModel, kin: _Gait, mu, a: float, b: float, m) -> tuple:
    """(input work, gross work, dissipation) [J] on [a, b] in mode ``m`` by order-5 Gauss panels of
    at most :data:`QUAD_PANEL`, their number doubled until the input work and the dissipation of two
    counts agree (:data:`QUAD_RTOL`); and the panel width.  (Doubling the count, not halving a
    width: a piece shorter than a width would keep its one panel and seem converged.)"""
    def sums(n: int) -> np.ndarray:
        tq, wq = gauss_nodes(a, b, (b - a) / n, 5)
        k1 = kin(tq)
        f = slip_friction(mu, k1, m)
        p = model.hold_torque(k1["phi"], f) * k1["dphi"]
        return np.array([np.sum(wq * np.sum(p, axis=0)), np.sum(wq * np.sum(np.abs(p), axis=0)),
                         np.sum(wq * np.abs(f * k1["ddot"]))])

    if not b > a:
        return np.zeros(3), QUAD_PANEL
    n = max(1, math.ceil((b - a) / QUAD_PANEL - 1e-12))
    last = sums(n)
    while (b - a) / n > QUAD_PANEL_MIN:
        n *= 2
        new = sums(n)
        # input work and dissipation are smooth on a piece; the gross work's |power| has kinks
        # inside it and converges slowly, but is a scale only
        if np.all(np.abs(new - last)[[0, 2]] <= QUAD_RTOL * (new[1] + new[2]) + 1e-300):
            return new, (b - a) / n
        last = new
    return last, (b - a) / n
