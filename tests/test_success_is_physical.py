"""No silent success: a torque-driven run is ``success`` only if every equilibrium it reports is
stable, the state is continuous across its events and the energy balance of its steady cycle closes.

Each verdict is checked against something independent of the code that makes it: the stability
verdicts against short damped (overdamped) dynamics runs built from the model's joint balance only,
the jump against the equilibria on both sides of it, the energy gate against the run's own residual,
the repaired dense output against a run with a finer continuation step.
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ocp_crawl import Model, simulate_torque
from ocp_crawl.model.inputs import CallableSignal, ReferenceTorque
from ocp_crawl.model.stability import stability_margin
from ocp_crawl.problem import paper_problem, problem_from_dict
from ocp_crawl.sim.assemble import balance_metrics, energy_gate, new_result
from ocp_crawl.sim.event import HybridOptions, HybridStepper
from ocp_crawl.sim.event_state import mode_q
from ocp_crawl.sim.result import Mode
from ocp_crawl.sim.timestepping import TimeSteppingOptions, simulate_mpcc
from ocp_crawl.status import STATUS_MESSAGES, Status
from _counterexamples import SNAP_THROUGH


#: two random robots (k/(M g L) about 0.045) whose stick-stick cycle passes close to a fold: the
#: dense output used to land on other roots of the mode equations there (energy residual 3e-5 and
#: 1e-4, W+ off by 9e-4 and 6e-3), which the energy gate caught
NEAR_FOLD = [
    {"robot": {"M": 2.3877886819781526, "L": 0.22648969419138656, "beta": 1.5111820930099082,
               "k": 0.2390059508595425, "g": 9.81, "mu1": 0.7752320555912096,
               "mu2": 0.8851063791543987},
     "gait": {"drive": "torque", "psi_deg": 166.4025944231273, "gamma_deg": 84.4432533600534,
              "A_deg": 35.886000305131084}, "model": {"gravity": "physical"}},
    {"robot": {"M": 1.6769455264706707, "L": 0.2664547636300657, "beta": 0.8083817986291837,
               "k": 0.1914478659632936, "g": 9.81, "mu1": 0.377010542038843,
               "mu2": 0.6549228845061807},
     "gait": {"drive": "torque", "psi_deg": -9.324419770511355, "gamma_deg": 71.6779541432795,
              "A_deg": 22.704663998489718}, "model": {"gravity": "physical"}},
]


def _failure_is_reported(res, status):
    assert res.status == status and not res.success, res.message
    assert (res.message.startswith(STATUS_MESSAGES[status])
            and len(res.message) > len(STATUS_MESSAGES[status]) + 5)
    assert res.failure_t is not None and res.failure_mode
    assert math.isnan(res.S) and math.isnan(res.W_plus) and math.isnan(res.CoT_plus)


# ------------------------------------------------------------------ damped dynamics, from the joint
# balance only
def _stick_flow(model, phi0, tau):
    """Overdamped flow along the stick-stick constraint d(phi) = d(phi0) with the torque held at
    tau: phi' = F(phi, tau, f_t)/(M g L), f_t the multiplier that makes d' = 0, plus a restoring
    term -(d - d0) grad d/|grad d|^2 against drift.  F from ``Model.equilibrium_residual`` (linear
    in f_t)."""
    r = model.robot
    d0 = float(model.kinematics(phi0)["d"])

    def rhs(_t, phi):
        kin = model.kinematics(phi)
        g = np.array([float(kin["grad_d1"]), float(kin["grad_d2"])])
        F0 = model.equilibrium_residual(phi, tau, 0.0)
        c = model.equilibrium_residual(phi, tau, 1.0) - F0
        ft = -(g @ F0) / (g @ c)
        return (F0 + ft * c) / r.MgL - 10.0 * (float(kin["d"]) - d0) * g / (g @ g)

    return rhs


def _stick_growth(model, phi0, tau, T, eps=1e-6):
    """|dphi(T)|/|dphi(0)| of the constrained damped run from phi0 displaced by eps along the
    constraint."""
    kin = model.kinematics(phi0)
    g = np.array([float(kin["grad_d1"]), float(kin["grad_d2"])])
    v = np.array([-g[1], g[0]]) / np.linalg.norm(g)
    sol = solve_ivp(_stick_flow(model, phi0, tau), (0, T), phi0 + eps * v, method="LSODA",
                    rtol=1e-11, atol=1e-15)
    assert sol.success
    return np.linalg.norm(sol.y[:, -1] - phi0) / eps


@pytest.mark.parametrize("values, stable", [({}, True), ({"model.gravity": "paper"}, True),
                                            ({"robot.k": 0.002}, False),
                                            ({"robot.k": 1e-3}, False)])
def test_start_verdict_agrees_with_damped_dynamics(values, stable):
    """The released start (f_t = 0, both feet held) is kept by the simulators iff a damped run along
    the constraint returns to it; the margin only sets the run's length (e^5 of growth or decay)."""
    pr = paper_problem().with_values(values)
    m = pr.model
    st = HybridStepper(m, pr.torque)
    x0 = next(st.released_states(0.0)).x
    margin = stability_margin(m, x0, (1, 0, 0))
    growth = _stick_growth(m, x0[:2], pr.torque(0.0), 5.0 / abs(margin))
    assert (growth < 0.05) if stable else (growth > 20), growth
    res = simulate_torque(m, pr.torque)
    assert res.success == stable, res.message
    if not stable:
        _failure_is_reported(res, Status.NO_START)


def test_start_skips_an_unstable_released_equilibrium():
    """k = 0.0354 M g L (paper gait, physical gravity): the first released equilibrium found (near
    84, 99 deg) is a maximum along the constraint; a later guess finds a stable one, which the run
    starts from (it used to start from the unstable one).  Both verdicts checked by damped runs."""
    pr = paper_problem()
    r = pr.robot.with_stiffness_ratio(0.035416325837244335)
    m = Model(r)
    torque = ReferenceTorque(pr.gait, r.k)
    st = HybridStepper(m, torque)
    found = list(st.released_states(0.0))
    margins = [stability_margin(m, p.x, (1, 0, 0)) for p in found]
    assert margins[0] < 0 < max(margins)
    start = HybridStepper(m, torque).initial_state(0.0)
    assert stability_margin(m, start.x, (1, 0, 0)) > 0
    for pt, mg in ((found[0], margins[0]), (start, stability_margin(m, start.x, (1, 0, 0)))):
        growth = _stick_growth(m, pt.x[:2], torque(0.0), 5.0 / abs(mg))
        assert (growth > 20) if mg < 0 else (growth < 0.05), growth
    assert simulate_torque(m, torque).success


# ------------------------------------------------------------------ counterexample 2: soft springs,
# heavy robot
@pytest.mark.parametrize("values",
                         [{"robot.k": 0.002}, {"robot.k": 1e-3}, {"robot.k": 1e-6},
                          {"robot.M": 1e9}])
def test_soft_spring_counterexamples_are_no_start_in_both_torque_solvers(values):
    """Gravity dominates the springs: the only released equilibrium is the near-Pi shape, a maximum
    of the potential along the constraint (kappa < 0), so the robot cannot stand there: no_start,
    not success (the event-driven stepper and the MPCC time-stepping share the start and agree)."""
    pr = paper_problem().with_values(values)
    for res in (simulate_torque(pr.model, pr.torque), simulate_mpcc(pr.model, pr.torque, steps=40)):
        _failure_is_reported(res, Status.NO_START)
        assert ("unstable equilibrium" in res.message
                and "reduced stiffness" in res.message), res.message


# ------------------------------------------------------------------ counterexample 1: snap-through
def _slip_K_fd(model, phi, tau, sigma, mu, foot, h=1e-6):
    """Finite-difference Jacobian of -F(phi, tau, f_t(phi)) with f_t = sigma mu f_n,foot(phi) [N
    m/rad]."""

    def force(p):
        fn = model.normal_forces(p)[foot - 1]
        return model.equilibrium_residual(p, tau, sigma * mu * float(fn))

    return -np.stack([(force(phi + h * e) - force(phi - h * e)) / (2 * h) for e in np.eye(2)],
                     axis=1)


def test_snap_through_counterexample():
    """Stick-stick reaches foot 2's friction limit (f_t = +mu2 f_n2) at phase 0.2215 of the first
    cycle.  The stick-stick equilibrium is stable there (kappa > 0, no fold), but the slip2+
    continuation is a saddle (det K < 0, so the quasistatic slip would run backwards in time:
    inconsistent), and the only consistent mode, slip2-, lies 8 deg away: the robot snaps through.
    Status snap_through, with the jump; before, the run reported success with a -4.4 % energy
    residual."""
    pr = problem_from_dict(SNAP_THROUGH)
    m, r = pr.model, pr.robot
    res = simulate_torque(m, pr.torque)
    _failure_is_reported(res, Status.SNAP_THROUGH)
    assert res.failure_mode == "stick-stick" and 0.22 < res.failure_t < 0.223
    assert "slip2-" in res.message and "deg" in res.message and "phase" in res.message
    jump = res.extra["jump"]
    assert max(jump["phi"]) > 0.1 and jump["mode_after"] == "slip2-"
    # independent: the last state is an equilibrium at foot 2's limit, stable in stick-stick, with a
    # finite-difference slip2+ stiffness of negative determinant (a saddle)
    phi, ft, tau = res.phi[:, -1], res.f_t[-1], res.tau[:, -1]
    assert np.abs(m.equilibrium_residual(phi, tau, ft)).max() < 1e-9 * r.MgL
    assert ft == pytest.approx(r.mu2 * res.f_n2[-1], rel=1e-9)
    assert stability_margin(m, np.array([*phi, ft / (r.M * r.g)]), (1, 0, 0)) > 0
    assert np.linalg.det(_slip_K_fd(m, phi, tau, +1, r.mu2, 2)) < 0
    # the time-stepping solver does not report success either: it lands on the same slip2- saddle
    mp = simulate_mpcc(m, pr.torque, steps=50)
    _failure_is_reported(mp, Status.UNSTABLE)
    assert mp.failure_mode == "slip2-" and abs(mp.failure_t - res.failure_t) <= 2 / 50


def test_jump_guard_exempts_an_input_discontinuity():
    pr = paper_problem()
    square = CallableSignal(lambda t: np.array([0.01, 0.0]) * (1.0 if (t % 1.0) < 0.5 else -1.0))
    st = HybridStepper(pr.model, square)
    assert st.checks.input_jumps(0.5) and not st.checks.input_jumps(0.25)
    smooth = HybridStepper(pr.model, pr.torque)
    assert not any(smooth.checks.input_jumps(t) for t in np.linspace(0, 1, 17))


# ------------------------------------------------------------------ success means stable samples
@pytest.mark.parametrize("case", ["paper/physical", "paper/paper", "near_fold_0", "near_fold_1"])
def test_success_samples_all_have_positive_margin(case):
    if case.startswith("paper"):
        pr = paper_problem().with_values({"model.gravity": case.split("/")[1]})
    else:
        pr = problem_from_dict(NEAR_FOLD[int(case[-1])])
    m, r = pr.model, pr.robot
    res = simulate_torque(m, pr.torque, t_eval=np.linspace(0, 1, 401))
    assert res.success, res.message
    margins = [stability_margin(m, np.array([*res.phi[:, j], res.f_t[j] / (r.M * r.g)]),
                                mode_q(Mode(int(c))))
               for j, c in enumerate(res.mode)]
    assert min(margins) > 0


@pytest.mark.parametrize("i", [0, 1])
def test_near_fold_dense_output_stays_on_the_branch(i):
    """Regression: the steep stick-stick stretch near a fold.  The energy balance closes and W+
    agrees with a run whose continuation step is 8 times finer (its dense output needs no
    repair)."""
    pr = problem_from_dict(NEAR_FOLD[i])
    res = simulate_torque(pr.model, pr.torque)
    fine = simulate_torque(pr.model, pr.torque, HybridOptions(max_step=1 / 512))
    assert res.success and fine.success, (res.message, fine.message)
    assert abs(res.energy["balance_residual"]) < 1e-9
    assert res.W_plus == pytest.approx(fine.W_plus, rel=1e-8)


def test_cycle_integrals_resolve_a_near_fold():
    """k = 0.43325 M g L (paper gait, physical gravity), just above a fold at phase 0.75: phi'
    spikes there.  The energy balance closes (8 panel halvings used to leave -9e-6, now caught as
    energy_imbalance) and W+ agrees with 32 times finer panels."""
    pr = paper_problem()
    r = pr.robot.with_stiffness_ratio(0.43325)
    torque = ReferenceTorque(pr.gait, r.k)
    res = simulate_torque(Model(r), torque)
    fine = simulate_torque(Model(r), torque, HybridOptions(quad_h=1 / 1024))
    assert res.success and fine.success, (res.message, fine.message)
    assert abs(res.energy["balance_residual"]) < 1e-9
    assert res.W_plus == pytest.approx(fine.W_plus, rel=1e-9)


# ------------------------------------------------------------------ the energy gate
def test_energy_gate_of_the_event_solver_fires_at_its_tolerance():
    pr = paper_problem()
    res = simulate_torque(pr.model, pr.torque)
    r = abs(res.energy["balance_residual"])
    assert res.success and 0 < r < 1e-12
    tight = simulate_torque(pr.model, pr.torque, HybridOptions(energy_tol=r / 2))
    _failure_is_reported(tight, Status.ENERGY_IMBALANCE)
    assert "HybridOptions.energy_tol" in tight.message and tight.failure_mode == "steady cycle"
    assert tight.energy == res.energy  # kept for the diagnosis
    assert simulate_torque(pr.model, pr.torque, HybridOptions(energy_tol=2 * r)).success


@pytest.mark.slow
def test_energy_gate_of_the_mpcc_solver_scales_with_the_steps():
    """N = 16: residual O(1/N^2) (0.04/N^2 on the paper gait) passes the default 10/N^2, fails a
    tight 0.01/N^2."""
    pr = paper_problem()
    res = simulate_mpcc(pr.model, pr.torque, steps=16)
    assert res.success, res.message
    r = abs(res.energy["balance_residual"])
    assert 1e-3 / 16**2 < r < 10 / 16**2
    tight = simulate_mpcc(pr.model, pr.torque, steps=16,
                          options=TimeSteppingOptions(energy_tol_n2=0.01))
    _failure_is_reported(tight, Status.ENERGY_IMBALANCE)
    assert "energy_tol_n2" in tight.message


def test_energy_gate_on_a_constructed_result():
    m = Model(paper_problem().robot)
    for residual, ok in ((1e-3, False), (1e-8, True)):
        # input work 1 J, potential change 0, dissipation 1 - residual: the balance misses
        # `residual`
        res = new_result(m, "torque", Status.SUCCESS,
                         **balance_metrics(m.robot, -0.05, np.array([0.5, 0.5]), 1.0, 0.0,
                                           1.0 - residual, 1.0))
        res = energy_gate(res, 1e-6, "tol")
        assert res.success == ok and (ok or res.status == Status.ENERGY_IMBALANCE)
        assert res.energy["balance_residual"] == pytest.approx(residual)


@pytest.mark.parametrize("kw", [{"energy_tol": 0.0}, {"energy_tol": -1e-6}, {"jump_tol": math.nan},
                                {"energy_tol": "1e-6"}])
def test_hybrid_options_validate_the_tolerances(kw):
    with pytest.raises((ValueError, TypeError)):
        HybridOptions(**kw)


@pytest.mark.parametrize("value", [0.0, -1.0, math.inf, math.nan])
def test_mpcc_options_validate_energy_tol_n2(value):
    with pytest.raises(ValueError):
        TimeSteppingOptions(energy_tol_n2=value)


#: random robots near the boundary of success (a random search): joint 2 under the ground by 1e-9 m
#: at most and foot 1 lifting off, both for a stretch shorter than a step, which the steps' ends do
#: not see; and foot 2 lifting off where the step after it cannot be solved (IPOPT: infeasible)
SHORT_LOSSES = {
    "joint": ("joint_on_ground", dict(M=0.12171649372120791, beta=2.2917058589221817,
                                      mu1=0.880530460495349, mu2=0.6304321993783866),
              0.8869625670102979, (1.3838592493289394, 3.033187223371901, 0.4193276707412855,
                                   0.49395855124234744, 2.7045499770065615)),
    "lift-off": ("lift_off", dict(M=0.15429816144175532, beta=1.628521367952375,
                                  mu1=0.35693883377975344, mu2=0.8667957832690099),
                 1.0208798375529244, (2.0166402940394152, 1.1112741690743078,
                                      0.7530896877004707, 0.604280022596627, 2.4361972125527793)),
    "lift-off, step unsolved": (
        "lift_off", dict(M=0.06693044992826896, beta=1.7481950611919117, mu1=1.1599871153685541,
                         mu2=0.4841858050872737), 0.8719901384012985,
        (1.404094844511471, 1.5137198264939513, 0.42151772499449086, 0.34721082979599205,
         0.39263666781644235)),
}


@pytest.mark.parametrize("case", sorted(SHORT_LOSSES))
def test_a_contact_lost_between_the_steps_ends_the_steps_where_the_event_stepper_ends(case):
    """The MPCC steps look between their ends for a contact lost there (a cubic of each contact
    guard's values and rates at the ends, the steps' own solutions inside): the same status at
    the same phase as the event-driven stepper, at any step count."""
    from ocp_crawl.model.inputs import Harmonic
    from ocp_crawl.model.robot import Robot

    status, kw, ratio, ref = SHORT_LOSSES[case]
    robot = Robot.paper(**kw).with_stiffness_ratio(ratio)
    model, torque = Model(robot), ReferenceTorque(Harmonic(*ref), robot.k)
    event = simulate_torque(model, torque)
    assert event.status_name == status, event.message
    for steps in (25, 100):
        res = simulate_mpcc(model, torque, steps=steps)
        assert res.status_name == status, (steps, res.message)
        assert res.failure_t == pytest.approx(event.failure_t, abs=1e-8), steps


#: random robots 1e-7 past the boundary of success: a joint 4e-8 to 9e-8 m under the ground in the
#: first cycle, inside a continuation step of 1/16 cycle whose interpolant of the joint's height
#: stays above zero within its error estimate
NEAR_TOUCHES = [
    (dict(M=0.05658347793573139, beta=1.350084009093285, mu1=0.765441012084144,
          mu2=0.7634861458758879), 1.7554971657836789,
     (2.5587015015808765, 2.1460515457822247, 0.683602732339226, 0.6589063103914271,
      0.6093918834035593)),
    (dict(M=0.07017823580145748, beta=2.932065461760244, mu1=0.5901850674849958,
          mu2=0.7797524373450846), 1.6527048975261305,
     (2.390525089771767, 1.5124045042932726, 1.0223683859363828, 0.2506526609539727,
      0.7148917698630484)),
]


@pytest.mark.parametrize("kw, ratio, ref", NEAR_TOUCHES)
def test_a_joint_that_only_touches_the_ground_in_a_long_step_ends_the_run_there(kw, ratio, ref):
    """The event-driven stepper at its default largest step finds the first touch where it does
    with steps of 1/1000 cycle, and where the MPCC steps (solved inside their steps) find it."""
    from ocp_crawl.model.inputs import Harmonic
    from ocp_crawl.model.robot import Robot
    from ocp_crawl.sim.event import HybridOptions

    robot = Robot.paper(**kw).with_stiffness_ratio(ratio)
    model, torque = Model(robot), ReferenceTorque(Harmonic(*ref), robot.k)
    res = simulate_torque(model, torque)
    fine = simulate_torque(model, torque, HybridOptions(max_step=1e-3))
    steps = simulate_mpcc(model, torque, steps=50)
    assert res.status_name == fine.status_name == steps.status_name == "joint_on_ground"
    assert fine.failure_t < 1
    assert res.failure_t == pytest.approx(fine.failure_t, abs=1e-8)
    assert steps.failure_t == pytest.approx(fine.failure_t, abs=1e-8)
