"""Prescribed-angle locomotion (paper Section II-A).

The joint angles phi(t) are imposed, so the configuration, d(t) and the normal forces are known
at every phase. Generically d' != 0, so one foot slips at every instant: the one with the smaller
friction limit mu_i f_n,i (equal friction: the foot with the smaller normal force, sign of Delta in
eq. (delta); for a tie, as in mirror-symmetric gaits, both feet slip symmetrically), in the direction that changes d; then f_t = mu_s f_n,s sign(d') (eq. (ft)) and the
holding torques follow from the joint balance.  The switching instants (d' = 0: slip direction
reverses; mu1 f_n1 = mu2 f_n2: slipping foot changes) are located by Brent's method on the exact
kinematics.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from .inputs import PeriodicSignal, as_signal
from .model import KIN, Model, call_mapped, symbolic
from .quadrature import gauss_nodes, positive_part_integral
from .result import STATUS_MESSAGES, CrawlResult, Event, Mode, Status, cost_of_transport

class _Kinematic:
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


def simulate_angles(model: Model, angles, t_eval=None, n_scan: int = 512) -> CrawlResult:
    """Prescribed-angle gait over one cycle (it is periodic after one cycle).

    ``angles``: periodic signal of the joint angles [rad] (e.g. :class:`~ocp_crawl.inputs.Harmonic`).
    ``t_eval``: output phases in [0, 1]; by default 201 equally spaced phases plus the switching instants.
    ``n_scan``: phases scanned for sign changes of the switching functions before Brent's method.
    """
    angles = as_signal(angles)
    kin = _Kinematic(model, angles)
    robot = model.robot
    Mg = robot.M * robot.g
    res = CrawlResult(success=False, status=int(Status.SUCCESS), message="", drive="angles", gravity=model.gravity,
                      cycles=1)
    model.check_contact(angles(0.0), where="prescribed configuration at t = 0")

    ts = np.linspace(0.0, 1.0, n_scan + 1)
    K = kin(ts)
    # validity first: the first phase at which the feet cross (d = 0) or a foot lifts off
    # (f_n = 0) ends the run; near d = 0 the normal forces x_c/d M g are singular, so the feet
    # crossing is searched first and the lift-off only before it
    failure = None
    d = K["d"]
    bad_d = np.nonzero(~(d > 0))[0]
    t_cross = None
    if bad_d.size:
        j = bad_d[0]
        t_cross = brentq(kin.scalar("d"), ts[j - 1], ts[j], xtol=1e-14) if j > 0 else 0.0
    # d may also touch zero without changing sign (symmetric legs folding through phi = 0):
    # refine every local minimum of d on the scan
    dmin_f = kin.scalar("d")
    for j in np.nonzero((d[1:-1] <= d[:-2]) & (d[1:-1] <= d[2:]))[0] + 1:
        if t_cross is not None and ts[j - 1] >= t_cross:
            break
        if d[j] > 0.05 * robot.L:
            continue
        opt = minimize_scalar(dmin_f, bounds=(ts[j - 1], ts[j + 1]), method="bounded", options={"xatol": 1e-13})
        if not (opt.fun > TOUCH * robot.L) and (t_cross is None or opt.x < t_cross):
            t_cross = float(opt.x)
            break
    if t_cross is not None:
        failure = (t_cross, Status.FEET_CROSSED, "feet meet or cross", "feet_crossed")
    checks = [(f"fn{i}", Status.LIFT_OFF, f"foot {i} lifts off", f"lift_off_{i}") for i in (1, 2)]
    checks += [(f"zj{i}", Status.JOINT_ON_GROUND, f"joint {i} reaches the ground", f"joint_{i}_on_ground") for i in (1, 2)]
    for name, status, label, kind in checks:
        bad = np.nonzero(~(K[name] > 0))[0]
        if not bad.size or (t_cross is not None and ts[bad[0] - 1] >= t_cross):
            continue
        j = bad[0]
        hi = ts[j] if t_cross is None else min(ts[j], t_cross * (1 - 1e-13))
        f = kin.scalar(name)
        if j == 0:
            tf = 0.0
        elif f(hi) < 0:
            tf = brentq(f, ts[j - 1], hi, xtol=1e-14)
        else:
            continue
        if name.startswith("zj") and abs(f(tf)) > 1e-6 * robot.L:
            # the joint height jumps instead of vanishing: theta changes branch, which happens
            # where the feet meet (d = 0) and the body would flip over
            status, label, kind = Status.FEET_CROSSED, "feet meet or cross", "feet_crossed"
        if failure is None or tf < failure[0]:
            failure = (tf, status, label, kind)
    if failure is not None:
        tf, status, label, kind = failure
        res.status = int(status)
        res.failure_t = tf
        res.message = f"{STATUS_MESSAGES[status]}: {label} at phase t = {tf:.10f} (prescribed angles)"
        res.events = [Event(tf, kind, "", "failure")]
        return res

    events: list[tuple[float, str]] = []
    for name, kind in (("ddot", "slip_reversal"), ("h", "slip_switch")):
        v = np.where(np.abs(K[name]) <= TIE, 0.0, K[name]) if name == "h" else K[name]
        for j in np.nonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)[0]:
            events.append((brentq(kin.scalar(name), ts[j], ts[j + 1], xtol=1e-14, rtol=4 * np.finfo(float).eps), kind))
        # a switching function that is exactly zero on a scan phase, with opposite signs around it
        for j in np.nonzero((v[1:-1] == 0) & (v[:-2] * v[2:] < 0))[0]:
            events.append((ts[j + 1], kind))
    events.sort()
    breaks = [0.0] + [e[0] for e in events] + [1.0]

    def mode_at(tm: float) -> Mode:
        k1 = kin(tm)
        h = k1["h"][0]
        foot = 3 if abs(h) <= TIE else (1 if h < 0 else 2)
        sigma = 1 if k1["ddot"][0] > 0 else -1
        return Mode.slip(foot, sigma)

    # foot positions: the slipping foot follows d, the other stays
    seg_modes = []
    x1, x2 = 0.0, float(K["d"][0])
    anchors = []
    for a, b in zip(breaks[:-1], breaks[1:]):
        if b - a <= 0:
            continue
        m = mode_at(0.5 * (a + b))
        da, db = float(kin(a)["d"][0]), float(kin(b)["d"][0])
        anchors.append((a, b, m, x1, x2))
        if m.foot == 1:
            x1 = x2 - db
        elif m.foot == 2:
            x2 = x1 + db
        else:
            mid = 0.5 * (x1 + x2)
            x1, x2 = mid - 0.5 * db, mid + 0.5 * db
        seg_modes.append(m)
    res.S = x1 - 0.0
    ev_objs = []
    for (t_ev, kind) in events:
        before = mode_at(max(t_ev - 1e-9, 0.0))
        after = mode_at(min(t_ev + 1e-9, 1.0))
        ev_objs.append(Event(float(t_ev), kind, before.label, after.label, float(kin(t_ev)["ddot" if kind == "slip_reversal" else "h"][0])))
    res.events = ev_objs

    def seg_of(t):
        for a, b, m, xa1, xa2 in anchors:
            if a <= t <= b:
                return a, b, m, xa1, xa2
        return anchors[-1]

    # output arrays
    if t_eval is None:
        te = np.unique(np.concatenate([np.linspace(0, 1, 201), [e[0] for e in events]]))
    else:
        te = np.asarray(t_eval, float).ravel()
        if np.any(te < 0) or np.any(te > 1):
            raise ValueError("t_eval must lie in [0, 1]")
    Ko = kin(te)
    modes = np.empty(len(te), int)
    ft = np.empty(len(te))
    x1o = np.empty(len(te))
    x2o = np.empty(len(te))
    mu = (robot.mu1, robot.mu2)
    for j, t in enumerate(te):
        a, b, m, xa1, xa2 = seg_of(t)
        modes[j] = int(m)
        ft[j] = (mu[0] * Ko["fn1"][j] if m.foot in (1, 3) else mu[1] * Ko["fn2"][j]) * m.sigma
        if m.foot == 1:
            x2o[j] = xa2
            x1o[j] = xa2 - Ko["d"][j]
        elif m.foot == 2:
            x1o[j] = xa1
            x2o[j] = xa1 + Ko["d"][j]
        else:
            mid = 0.5 * (xa1 + xa2)
            x1o[j], x2o[j] = mid - 0.5 * Ko["d"][j], mid + 0.5 * Ko["d"][j]
    res.t, res.phi, res.theta, res.d = te, Ko["phi"], Ko["theta"], Ko["d"]
    res.x1, res.x2, res.f_t, res.f_n1, res.f_n2, res.mode = x1o, x2o, ft, Ko["fn1"], Ko["fn2"], modes
    res.tau = model.hold_torque(Ko["phi"], ft)

    # energetics, segment by segment (f_t and the holding torques jump at the switching instants)
    wplus = np.zeros(2)
    w_in = 0.0
    diss = 0.0
    for a, b, m, _, _ in anchors:
        def power(t, i, m=m):
            k1 = kin(t)
            f = (mu[0] * k1["fn1"] if m.foot in (1, 3) else mu[1] * k1["fn2"]) * m.sigma
            tau = model.hold_torque(k1["phi"], f)
            return tau[i] * k1["dphi"][i]

        for i in range(2):
            wplus[i] += positive_part_integral(a, b, lambda t, i=i: power(t, i), lambda t, i=i: float(power(t, i)[0]))
        tq, wq = gauss_nodes(a, b, 1.0 / 64, 5)
        k1 = kin(tq)
        f = (mu[0] * k1["fn1"] if m.foot in (1, 3) else mu[1] * k1["fn2"]) * m.sigma
        tau = model.hold_torque(k1["phi"], f)
        w_in += float(np.sum(wq * np.sum(tau * k1["dphi"], axis=0)))
        diss += float(np.sum(wq * np.abs(f * k1["ddot"])))
    dV = float(model.potential(angles(1.0)) - model.potential(angles(0.0)))
    scale = max(abs(w_in), abs(diss), 1e-300)
    res.energy = {"input_work": w_in, "potential_change": dV, "dissipation": diss,
                  "balance_residual": (w_in - dV - diss) / scale}
    res.W_plus_joint = wplus
    res.W_plus = float(wplus.sum())
    res.CoT_plus = cost_of_transport(res.W_plus, robot, res.S)
    res.periodicity_residual = float(np.max(np.abs(angles(1.0) - angles(0.0))))
    res.success = True
    res.status = int(Status.SUCCESS)
    res.message = f"prescribed-angle gait: {len(events)} switching instants per cycle"
    return res
