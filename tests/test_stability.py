"""Stability of quasistatic equilibria, each number checked against something independent:
the paper gait (stable), the issue's soft-spring counterexample (unstable), a finite-difference
second derivative of the potential along the constraint curve, the mode Jacobian's determinant, and
short damped-dynamics runs for the slip criterion."""
import math
import time

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from ocp_crawl import Model, ReferenceTorque, simulate_torque
from ocp_crawl.model.stability import (fast_stability, reduced_stiffness, slip_stiffness, stability,
                                       stability_function, stability_margin, stability_margins)
from ocp_crawl.model.statics import symbolic
from ocp_crawl.problem import paper_problem, problem_from_dict
from ocp_crawl.sim.event import HybridStepper
from ocp_crawl.sim.event_state import mode_q
from ocp_crawl.sim.result import Mode
from _counterexamples import SNAP_THROUGH



def _states(model, res):
    """x = (phi1, phi2, f_t/(M g)) and q of every output sample of a result."""
    r = model.robot
    X = np.vstack([res.phi, res.f_t / (r.M * r.g)])
    Q = np.stack([mode_q(Mode(int(c))) for c in res.mode], axis=1)
    return X, Q


def _run(problem, **kw):
    res = simulate_torque(problem.model, problem.torque, **kw)
    assert res.success, res.message
    return res


def _start(problem):
    """The first released equilibrium the event simulator finds: phi and f_t (= 0) at t = 0 (stable
    or not)."""
    return next(HybridStepper(problem.model, problem.torque).released_states(0.0)).x


# ------------------------------------------------------------------ the paper gait is stable
@pytest.mark.parametrize("gravity", ["physical", "paper"])
def test_paper_gait_start_and_steady_cycle_are_stable(gravity):
    pr = paper_problem().with_values({"model.gravity": gravity})
    m = pr.model
    x0 = _start(pr)
    assert x0[2] == 0.0
    assert stability_margin(m, x0, (1, 0, 0)) > 0.5
    res = _run(pr)
    X, Q = _states(m, res)
    margins = stability_margins(m, X, Q)
    assert set(np.unique(res.mode)) == {Mode.STICK, Mode.SLIP1_NEG, Mode.SLIP2_NEG}
    assert margins.min() > 1.0, margins.min()
    # the batch call agrees with the single-point one
    i = int(np.argmin(margins))
    assert margins[i] == pytest.approx(stability_margin(m, X[:, i], Q[:, i]), rel=1e-12)


# ------------------------------------------------------------------ counterexample 2
@pytest.mark.parametrize("k, expected", [(0.002, -0.0035), (1e-3, -0.0047)])
def test_soft_spring_counterexample_is_a_maximum(k, expected):
    """Paper gait with k = 0.002 (1e-3) N m/rad: the simulator used to report success, stuck in
    stick-stick near the released start; the reduced stiffness there is negative (issue: about
    -0.0035 N m/rad), so the run is now ``no_start`` (the released robot can only settle on a
    maximum of the potential)."""
    pr = paper_problem().with_values({"robot.k": k})
    m = pr.model
    r = m.robot
    x0 = _start(pr)
    kappa = reduced_stiffness(m, x0[:2], 0.0)
    assert kappa == pytest.approx(expected, rel=0.05)
    assert stability_margin(m, x0, (1, 0, 0)) == pytest.approx(kappa / r.MgL, rel=1e-12)
    res = simulate_torque(m, pr.torque)
    assert res.status_name == "no_start" and "unstable equilibrium" in res.message, res.message


# ------------------------------------------------------------------ independent checks of kappa
def _curve_point(model, phi0, d0, s):
    """Point of d(phi) = d0 at tangential offset s from phi0: phi0 + s v0 + n u0, n by Newton."""
    kin = model.kinematics(phi0)
    g0 = np.array([kin["grad_d1"], kin["grad_d2"]])
    u0 = g0 / np.linalg.norm(g0)
    v0 = np.array([-u0[1], u0[0]])
    n = 0.0
    for _ in range(50):
        phi = phi0 + s * v0 + n * u0
        kin = model.kinematics(phi)
        step = (kin["d"] - d0) / (kin["grad_d1"] * u0[0] + kin["grad_d2"] * u0[1])
        n -= step
        if abs(step) < 1e-17:
            break
    return phi0 + s * v0 + n * u0


def _fd_kappa(model, phi0, f_t, h=2e-3):
    """Second derivative of Pi - tau.phi along d = d0 at an exact equilibrium (tau = holding
    torque), central differences with one Richardson step [N m/rad]."""
    tau = model.hold_torque(phi0, f_t)
    d0 = model.kinematics(phi0)["d"]

    def energy(s):
        phi = _curve_point(model, phi0, d0, s)
        return float(model.potential(phi)) - float(tau @ phi)

    e0 = energy(0.0)

    def second(hh):
        return (energy(hh) - 2 * e0 + energy(-hh)) / hh**2

    return second(h / 2) + (second(h / 2) - second(h)) / 3


FD_CASES = [
    # (k [N m/rad] or None for the paper's, gravity, phi [deg], f_t [N])
    (None, "physical", (101.8, 78.0), 0.0),
    (None, "physical", (95.0, 70.0), 0.12),
    (None, "paper", (120.0, 85.0), -0.15),
    (0.002, "physical", (84.6, 97.6), 0.0),
    (0.002, "physical", (84.6, 97.6), 0.05),
]


@pytest.mark.parametrize("k, gravity, phi_deg, f_t", FD_CASES)
def test_reduced_stiffness_is_second_derivative_along_constraint(k, gravity, phi_deg, f_t):
    pr = paper_problem().with_values({"model.gravity": gravity, **({"robot.k": k} if k else {})})
    m = pr.model
    phi = np.radians(phi_deg)
    kappa = reduced_stiffness(m, phi, f_t)
    fd = _fd_kappa(m, phi, f_t)
    assert kappa == pytest.approx(fd, rel=1e-6, abs=1e-9 * m.robot.MgL)
    if f_t:  # the constraint-curvature term matters: leaving it out fails the check
        assert abs(reduced_stiffness(m, phi, 0.0) - fd) > 1e-3 * abs(fd)


def test_sign_of_kappa_and_det_K_follow_the_mode_jacobian():
    """det J = -kappa |grad d|^2/(M g L^3) in stick-stick and det K/(M g L)^2 in slip (J from
    statics.system)."""
    rng = np.random.default_rng(11)
    sys = symbolic().system
    for k in (0.1677, 0.002):
        m = paper_problem().with_values({"robot.k": k}).model
        r = m.robot
        for _ in range(10):
            x = np.array([*np.radians(rng.uniform(60, 130, 2)), rng.uniform(-0.3, 0.3)])
            kin = m.kinematics(x[:2])
            g2 = kin["grad_d1"] ** 2 + kin["grad_d2"] ** 2
            J = np.asarray(sys(x, np.zeros(2), np.array([1.0, 0, 0, kin["d"]]), m.p)[1])
            s = stability(m, x, (1, 0, 0))
            assert np.linalg.det(J) == pytest.approx(-s["kappa"] * g2 / r.L**2, rel=1e-9)
            for mode in (Mode.SLIP1_POS, Mode.SLIP1_NEG, Mode.SLIP2_POS, Mode.SLIP2_NEG):
                q = mode_q(mode)
                # on the mode's solution set: f_t at the friction limit (J uses x[2], K the friction
                # law)
                x[2] = q[1] * (q[2] * r.mu1 * kin["fn1"]
                               + (1 - q[2]) * r.mu2 * kin["fn2"]) / (r.M * r.g)
                J = np.asarray(sys(x, np.zeros(2), q, m.p)[1])
                K = slip_stiffness(m, x[:2], q[1], q[2]) / r.MgL
                assert np.linalg.det(J) == pytest.approx(np.linalg.det(K), rel=1e-9)
                assert stability(m, x, q)["detK"] == pytest.approx(np.linalg.det(K), rel=1e-12)
                assert stability(m, x, q)["trK"] == pytest.approx(np.trace(K), rel=1e-12)


def test_margin_falls_to_zero_at_a_reported_fold():
    """Physical gravity, k = 0.3 M g L: the simulator reports a fold of the slip2- branch (det J =
    0); the margin decreases towards zero along the branch and is still positive before it."""
    pr = paper_problem()
    r = pr.robot.with_stiffness_ratio(0.3)
    m = Model(r)
    res = simulate_torque(m, ReferenceTorque(pr.gait, r.k))
    assert res.status_name == "fold" and res.failure_mode == "slip2-"
    X, Q = _states(m, res)
    margins = stability_margins(m, X, Q)
    tail = margins[res.mode == Mode.SLIP2_NEG][-4:]
    assert np.all(tail > 0) and np.all(np.diff(tail) < 0)
    assert tail[-1] < 0.03 < margins.max()


# ------------------------------------------------------------------ slip criterion vs damped
# dynamics
def _damped_run(model, phi_star, sigma, w, T, eps=1e-7):
    """Overdamped run phi' = F(phi)/(M g L) (identity damping, time in units of damping/(M g L))
    with the torque held at the value that makes phi_star a slip equilibrium, from phi_star + eps
    (0.6, 0.8).

    Uses only the model's residual and normal forces (not the stability module).
    Returns (dphi(0), dphi(T))."""
    r = model.robot

    def ft(phi):
        fn1, fn2 = model.normal_forces(phi)
        return sigma * (w * r.mu1 * fn1 + (1 - w) * r.mu2 * fn2)

    tau = model.hold_torque(phi_star, ft(phi_star))
    assert np.abs(model.equilibrium_residual(phi_star, tau, ft(phi_star))).max() < 1e-14 * r.MgL
    dphi0 = eps * np.array([0.6, 0.8])
    # integrate the perturbation itself (not phi), so that its accuracy is relative to its size
    sol = solve_ivp(lambda t, y: model.equilibrium_residual(phi_star + y, tau, ft(phi_star + y))
                    / r.MgL, (0, T), dphi0, method="LSODA", rtol=1e-10, atol=1e-14 * eps)
    assert sol.success
    return dphi0, sol.y[:, -1]


def _check_against_dynamics(model, phi, q, stable):
    """The margin's sign predicts decay or growth of a damped run,
    and the run follows the linearised flow exp(-K t) dphi0 (K from the stability module)."""
    s = stability(model, np.array([*phi, 0.0]), q)
    assert (s["margin"] > 0) == stable
    K = slip_stiffness(model, phi, q[1], q[2]) / model.robot.MgL
    lam = np.linalg.eigvals(K).real
    T = 7.0 / (lam.min() if stable else -lam.min())  # e^7 on the slowest decay / the fastest growth
    dphi0, dphiT = _damped_run(model, phi, q[1], q[2], T)
    growth = np.linalg.norm(dphiT) / np.linalg.norm(dphi0)
    assert (growth < 1e-2) if stable else (growth > 1e2), growth
    linear = expm(-K * T) @ dphi0
    # nonlinear terms: O(|dphi(T)|)
    assert np.linalg.norm(dphiT - linear) < 1e-3 * np.linalg.norm(linear)
    return s


def _slip_sample(problem, mode, phase=None):
    """A sample of the steady cycle in ``mode`` (the middle one, or the one nearest ``phase``)."""
    res = simulate_torque(problem.model, problem.torque, t_eval=np.linspace(0, 1, 401))
    idx = np.flatnonzero(res.mode == mode)
    assert idx.size
    i = idx[idx.size // 2] if phase is None else idx[np.argmin(abs(res.t[idx] - res.t0 - phase))]
    return res.phi[:, i]


@pytest.mark.slow
def test_slip_stable_on_the_paper_gait_perturbation_decays():
    pr = paper_problem()
    m = pr.model
    for mode in (Mode.SLIP1_NEG, Mode.SLIP2_NEG):
        s = _check_against_dynamics(m, _slip_sample(pr, mode), mode_q(mode), stable=True)
        assert s["margin"] > 1.0


def test_slip_saddle_on_the_snap_through_robot_perturbation_grows():
    """The issue's snap-through robot: its slip2+ stretch has det K < 0 (a saddle): a perturbation
    grows."""
    pr = problem_from_dict(SNAP_THROUGH)
    # the run now ends as snap_through before its slip2+ stretch: solve the slip2+ equilibrium at
    # phase 0.09 from a guess near the one the simulator used to report there
    st = HybridStepper(pr.model, pr.torque)
    pt = st.solver.solve(1.09, np.array([1.0457, 2.7819, 0.0216]), mode_q(Mode.SLIP2_POS))
    phi = pt.x[:2]
    s = _check_against_dynamics(pr.model, phi, mode_q(Mode.SLIP2_POS), stable=False)
    assert s["detK"] < 0


@pytest.mark.parametrize("mode", [Mode.SLIP1_POS, Mode.SLIP1_NEG])
def test_slip_unstable_at_the_soft_spring_start_perturbation_grows(mode):
    """k = 0.002 N m/rad, the released start's configuration held at foot 1's friction limit: both
    eigenvalues of K have negative real parts (slip1-: real; slip1+: a complex pair): the
    perturbation grows."""
    pr = paper_problem().with_values({"robot.k": 0.002})
    phi = _start(pr)[:2]
    pr.model.check_contact(phi)
    s = _check_against_dynamics(pr.model, phi, mode_q(mode), stable=False)
    assert s["trK"] < 0 and s["detK"] > 0


# ------------------------------------------------------------------ API and cost
def test_margin_accepts_short_and_full_q_and_rejects_bad_input():
    m = paper_problem().model
    x = np.array([math.radians(100), math.radians(80), 0.05])
    assert stability_margin(m, x, (0, -1, 1)) == stability_margin(m, x, (0, -1, 1, 0.07))
    assert (stability_margin(m, x, (1, 0, 0))
            == reduced_stiffness(m, x[:2], x[2] * m.robot.M * m.robot.g) / m.robot.MgL)
    with pytest.raises(ValueError):
        stability_margin(m, x[:2], (1, 0, 0))
    with pytest.raises(ValueError):
        stability_margin(m, x, (1, 0))
    with pytest.raises(ValueError):
        stability_margin(m, np.array([np.nan, 1.0, 0.0]), (1, 0, 0))


def test_margin_is_scale_invariant():
    """Nondimensional: L, M, g scaled with k consistently (k/(M g L) fixed) give the same margin."""
    pr = paper_problem()
    m = pr.model
    r = m.robot
    x = np.array([math.radians(100), math.radians(80), 0.05])
    for f in (1e-3, 1e3):
        r2 = r.replace(L=r.L * f, M=r.M * f, g=r.g / f).with_stiffness_ratio(r.k / r.MgL)
        m2 = Model(r2, gravity=m.gravity)
        for q in ((1, 0, 0), (0, -1, 1), (0, 1, 0)):
            assert stability_margin(m2, x, q) == pytest.approx(stability_margin(m, x, q), rel=1e-10)


def test_cost_of_one_evaluation():
    """Reports the time of one call (CasADi VM, compiled, batch); no timing assertion beyond a hang
    guard.  The compiled function gives the VM's numbers."""
    f = stability_function()
    fast = fast_stability()
    m = paper_problem().model
    x = np.array([1.7, 1.4, 0.05])
    q = np.array([1.0, 0.0, 0.0, 0.0])
    p = m.p
    assert np.allclose(fast(x, q, p)[0], np.asarray(f(x, q, p)).ravel(), rtol=1e-13, atol=0)
    X = np.tile(x[:, None], (1, 201))
    stability_margins(m, X, q)
    n = 2000
    times = {}
    for name, call in (("casadi VM", lambda: f(x, q, p)), ("compiled", lambda: fast(x, q, p)),
                       ("stability_margin", lambda: stability_margin(m, x, q))):
        t0 = time.perf_counter()
        for _ in range(n):
            call()
        times[name] = (time.perf_counter() - t0) / n * 1e6
    t0 = time.perf_counter()
    for _ in range(20):
        stability_margins(m, X, q)
    times["batch, per point"] = (time.perf_counter() - t0) / 20 / X.shape[1] * 1e6
    print("stability cost [us per call]: " + ", ".join(f"{k} {v:.1f}" for k, v in times.items()))
    assert max(times.values()) < 1e4
