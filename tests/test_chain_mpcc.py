"""The incremental step and time-stepping of an n-link chain (ocp_crawl.sim.chain_mpcc).

At n = 3 the chain steps equal the three-link MPCC time-stepping on the paper's gait; a five-link
chain with unequal parameters converges to the event-driven chain simulator as N grows.
"""
import numpy as np
import pytest

import ocp_crawl
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_inputs import JointFourier
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.robot import Robot
from ocp_crawl.model.statics import Model
from ocp_crawl.sim.chain_mpcc import ChainStep, chain_step_nlp, simulate_chain_mpcc
from ocp_crawl.sim.chain_torque import ChainReferenceTorque, simulate_chain_torque
from ocp_crawl.sim.mpcc import MPCCOptions
from ocp_crawl.sim.result import Mode
from ocp_crawl.sim.timestepping import TimeSteppingOptions

FIVE = Chain(lengths=(0.025, 0.02, 0.03, 0.022, 0.027),
             masses=(0.010, 0.008, 0.014, 0.009, 0.011), stiffness=(0.17, 0.2, 0.15, 0.18),
             mu=(0.35, 0.45), com=(0.45, 0.5, 0.55, 0.5, 0.4), rest=(0.05, -0.05, 0.0, 0.03))
FIVE_REF = JointFourier.harmonic(np.radians([110, 160, 160, 110]), np.radians([25, 15, 15, 25]),
                                 np.radians([60, 20, -20, -60]))


def _three_link(steps: int, switch_exact: bool):
    """The paper's gait: the three-link MPCC run (exact complementarity: polished steps) and the
    chain run at the same N."""
    robot = Robot.paper()
    torque = ReferenceTorque(Harmonic.from_degrees(90, 30, 45), robot.k)
    opt = TimeSteppingOptions(mpcc=MPCCOptions(polish="always"), steps=steps,
                              switch_exact=switch_exact, s_error_tol=0.0, periodic_tol=1e-12)
    ref = ocp_crawl.simulate(Model(robot), torque, "mpcc", opt)
    res = simulate_chain_mpcc(ChainModel(Chain.from_robot(robot)), torque, steps=steps,
                              switch_exact=switch_exact)
    return ref, res


def _compare(ref, res) -> None:
    assert ref.success and res.success, (ref.message, res.message)
    assert abs(res.S - ref.S) <= 1e-9 * abs(ref.S)
    assert abs(res.W_plus - ref.W_plus) <= 1e-9 * abs(ref.W_plus)
    assert res.t.shape == ref.t.shape
    np.testing.assert_allclose(res.phi, ref.phi, atol=1e-9)
    np.testing.assert_allclose(res.x1, ref.x1, atol=1e-9 * Robot.paper().L)


def test_three_links_equal_mpcc_steps():
    """n = 3, each step in its end mode: S, W+, phi and x1 of the steady cycle equal the three-link
    MPCC time-stepping's to 1e-9 at the same N (25: no step ends on a phase where both feet
    reach their friction limits at once, where the two solvers may pick different feet)."""
    _compare(*_three_link(25, False))


@pytest.mark.slow
def test_three_links_equal_switch_exact_steps():
    """n = 3 with the steps split at the events: S and W+ equal the three-link's to 1e-9."""
    ref, res = _three_link(50, True)
    assert ref.success and res.success, (ref.message, res.message)
    assert abs(res.S - ref.S) <= 1e-9 * abs(ref.S)
    assert abs(res.W_plus - ref.W_plus) <= 1e-9 * abs(ref.W_plus)


def test_five_link_step_solves_mpcc():
    """A five-link step from rest is a solution of the MPCC equations (equations and bounds to
    1e-12, exact complementarity) and moves the feet by the change of d."""
    model = ChainModel(FIVE)
    step = ChainStep(model)
    phi0 = np.radians([110.0, 160.0, 160.0, 110.0])
    d0 = float(model.kinematics(phi0)["d"])
    for scale in (0.0, 0.3, 1.0):
        tau = np.asarray(FIVE.stiffness) * (phi0 - np.pi - np.asarray(FIVE.rest)) \
            + scale * np.array([0.02, -0.01, 0.01, -0.02])
        res = step.solve(phi0, 0.0, d0, tau)
        assert res.success, res.message
        assert res.eq_residual <= 1e-12 and res.comp_residual <= 1e-12
        assert abs((res.x2 - res.x1) - res.d) <= 1e-12
        w = res.extra["w"]
        g_eq = np.asarray(chain_step_nlp(5)(w, step.params(phi0, tau))[0]).ravel()
        assert np.max(np.abs(g_eq)) <= 1e-12
        assert res.mode in (Mode.STICK, Mode.SLIP1_POS, Mode.SLIP1_NEG, Mode.SLIP2_POS,
                            Mode.SLIP2_NEG)


def _five_links():
    model = ChainModel(FIVE)
    torque = ChainReferenceTorque(FIVE_REF, FIVE)
    ev = simulate_chain_torque(model, torque, t_eval=np.array([0.0, 1.0]))
    assert ev.success, ev.message
    return model, torque, ev


@pytest.mark.slow
def test_five_links_equal_the_event_solver():
    """Five unequal links at N = 50: with the steps split at the events S equals the event-driven
    chain simulator's to 1e-9; W+ (the midpoint rule on the steps) is within 2e-3 of it (the
    convergence in N: the heavy test below)."""
    model, torque, ev = _five_links()
    res = simulate_chain_mpcc(model, torque, steps=50)
    assert res.success, res.message
    assert abs(res.S - ev.S) <= 1e-9 * abs(ev.S)
    assert abs(res.W_plus - ev.W_plus) <= 2e-3 * abs(ev.W_plus)


@pytest.mark.slow
@pytest.mark.heavy
def test_five_links_converge_to_event_solver():
    """Five unequal links: with the steps split at the events S equals the event-driven chain
    simulator's to 1e-9 at every N; W+ (midpoint rule) converges, first order or better, to below
    1e-3 relative at N = 200."""
    model, torque, ev = _five_links()
    errs = []
    for N in (50, 100, 200):
        res = simulate_chain_mpcc(model, torque, steps=N)
        assert res.success, res.message
        assert abs(res.S - ev.S) <= 1e-9 * abs(ev.S)
        errs.append(abs(res.W_plus - ev.W_plus) / abs(ev.W_plus))
    assert errs[0] > errs[1] > errs[2] and errs[2] < 1e-3, errs
    assert errs[1] <= 0.55 * errs[0] and errs[2] <= 0.55 * errs[1], errs


def test_a_step_ending_on_an_unstable_equilibrium_stops_the_run():
    """The gate of every step: the slip2+ equilibrium of the snap-through robot (a saddle by the
    three-link stability module and by damped dynamics, tests/test_stability.py) stops a chain run
    as ``unstable``; the paper gait's stick-stick start passes."""
    from _counterexamples import SNAP_THROUGH

    from ocp_crawl.model.stability import stability
    from ocp_crawl.problem import problem_from_dict
    from ocp_crawl.sim.chain_mpcc_checks import RunStop, check_step
    from ocp_crawl.sim.event import HybridStepper
    from ocp_crawl.sim.event_state import mode_q
    from ocp_crawl.status import Status

    pr = problem_from_dict(SNAP_THROUGH)
    pt = HybridStepper(pr.model, pr.torque).solver.solve(
        1.09, np.array([1.0457, 2.7819, 0.0216]), mode_q(Mode.SLIP2_POS))
    assert stability(pr.model, pt.x, mode_q(Mode.SLIP2_POS))["margin"] < 0
    model = ChainModel(Chain.from_robot(pr.model.robot), gravity=pr.model.gravity)
    Mg = model.Mg
    row = (1.09, pt.x[:2], 0.0, 0.0, pt.x[2] * Mg, 0.0, 0.0, 0.0, Mode.SLIP2_POS)
    with pytest.raises(RunStop) as stop:
        check_step(model, row, 1.09)
    assert stop.value.status is Status.UNSTABLE
    paper = ChainModel(Chain.from_robot(Robot.paper()))
    check_step(paper, (0.0, np.deg2rad([90.0, 90.0]), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                        Mode.STICK), 0.0)


#: a five-link chain (of the random property test's family) whose foot 1 lifts off while it slips
LIFTING = (Chain(lengths=(0.03115881579472988, 0.02530651122084284, 0.020716027601762832,
                          0.016078614047633128, 0.022667377615710367),
                 masses=(0.009084732054199986, 0.0054527519390244516, 0.005487577107271681,
                         0.014991761150650713, 0.011523691115879876),
                 stiffness=(0.1360049603627085, 0.15730710223879646, 0.19619152157750763,
                            0.06580075301952358),
                 mu=(0.43583630660427297, 0.4740177004655007),
                 com=(0.4469020403339648, 0.4869895104450284, 0.594837238651851,
                      0.5795355216217097, 0.5688462075217482),
                 rest=(0.005559611692072343, -0.022854839546989848, 0.03796511733349221,
                       -0.043578556268780905)),
           JointFourier.harmonic(np.radians([121.86344718242378, 155.6829631290227,
                                             155.6829631290227, 121.86344718242378]),
                                 np.radians([27.4439093604867, 10.370344353404215,
                                             24.149911346743547, 10.023993671736573]),
                                 np.radians(0.6055137996596045) * np.arange(4)))


def test_a_foot_that_lifts_off_ends_both_simulators_with_lift_off():
    """Where the event-driven chain stops at foot 1's normal force reaching zero, the steps find no
    consistent mode at the next step's end, and the equilibrium of the mode they were in has that
    normal force below zero: ``lift_off``, not ``no_consistent_mode``, placed where the force
    reaches zero inside that step."""
    chain, reference = LIFTING
    model, torque = ChainModel(chain), ChainReferenceTorque(reference, chain)
    ev = simulate_chain_torque(model, torque, t_eval=np.array([0.0, 1.0]))
    steps = simulate_chain_mpcc(model, torque, steps=50)
    assert ev.status_name == steps.status_name == "lift_off", (ev.message, steps.message)
    assert "lift_off_1" in ev.message
    assert "foot 1's normal force reaches zero" in steps.message
    assert steps.failure_t == pytest.approx(ev.failure_t, abs=1e-8)


def test_a_failed_step_is_diagnosed_in_the_mode_it_started_in():
    """The diagnosis of a step without a consistent mode reads the candidate of the mode the step
    started in: its equilibrium with a joint below the ground gives ``joint_on_ground``; another
    mode's candidate there, or positive normal forces with every joint above, leave the step's
    ``no_consistent_mode`` to the caller."""
    from ocp_crawl.sim.chain_mpcc import ChainStepResult
    from ocp_crawl.sim.chain_mpcc_checks import RunStop, check_end, mode_row
    from ocp_crawl.status import Status

    model, nan = ChainModel(FIVE), float("nan")
    step = ChainStep(model)
    low = np.array([3.3, 3.0, 3.0, 3.3])   # joint 1 and 4 just below the ground
    assert model.kinematics(low)["zj1"] < 0 < model.kinematics(low)["zj2"]

    def failed(phi, mode):
        cand = {"mode": mode, "z": np.r_[phi, 0.1], "fn": np.array([0.2, 0.3])}
        return ChainStepResult(False, "no consistent contact mode", np.full(4, nan), nan, nan, nan,
                               np.full(4, nan), nan, nan, nan, Mode.STICK, nan, nan,
                               {"candidates": [None, cand]})

    def diagnose(res, mode):
        end = mode_row(step, res, mode, 0.5)
        if end is not None:
            check_end(step, None, [], end, set(), consistent=False)

    with pytest.raises(RunStop) as stop:
        diagnose(failed(low, Mode.SLIP1_POS), Mode.SLIP1_POS)
    assert stop.value.status is Status.JOINT_ON_GROUND and "joint 1" in stop.value.detail
    assert mode_row(step, failed(low, Mode.SLIP1_POS), Mode.STICK, 0.5) is None
    diagnose(failed(np.array([1.9, 2.9, 2.9, 1.9]), Mode.STICK), Mode.STICK)