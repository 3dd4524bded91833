"""MPCC step (IPOPT), its mode-enumeration oracle and the MPCC time-stepping simulator."""
import math

import numpy as np
import pytest

from ocp_crawl import Mode, Model, Robot, Status, simulate_torque
from ocp_crawl.sim.event import HybridStepper
from ocp_crawl.nlp.ipopt import STEP_IPOPT, ipopt_status
from ocp_crawl.sim.mpcc import MPCCOptions, MPCCStep
from ocp_crawl.sim.step import StepState, mode_from_pairs
from ocp_crawl.sim.oracle import solve_step_enumerate
from ocp_crawl.sim.timestepping import TimeSteppingOptions, simulate_mpcc

from conftest import paper_torque

PHI_TOL = 1e-7
"""agreement of phi_{k+1} between the MPCC step and the oracle [rad] (the issue's requirement)"""

#: gaits sampled for the step comparison: gravity, mu1, mu2, psi [deg]
SAMPLED_GAITS = [("physical", 0.389, 0.389, 45.0), ("physical", 0.30, 0.45, 90.0),
                 ("paper", 0.389, 0.389, 90.0), ("paper", 0.35, 0.43, 45.0)]
#: step lengths used with the sampled states [cycles]
STEP_LENGTHS = (1 / 400, 1 / 100, 1 / 25)


def initial_state(model, torque) -> StepState:
    start = HybridStepper(model, torque).initial_state(0.0)
    return StepState(start.x[:2], 0.0, float(model.kinematics(start.x[:2])["d"]), 0.0)


def sampled_steps(per_gait=80):
    """(model, state, tau, h) for states taken along event-driven trajectories, with the torque one
    step later."""
    out = []
    for gravity, mu1, mu2, psi in SAMPLED_GAITS:
        robot = Robot.paper(mu1=mu1, mu2=mu2)
        model = Model(robot, gravity=gravity)
        torque = paper_torque(robot, psi=psi)
        res = HybridStepper(model, torque).run()
        assert res.success, res.message
        idx = set(np.linspace(0, res.t.size - 1, per_gait).round().astype(int).tolist())
        # the event phases are output samples: include them (states on a friction limit or at d' =
        # 0)
        idx |= {int(np.argmin(np.abs(res.t - e.t))) for e in res.steady_events()}
        for j, k in enumerate(sorted(idx)):
            state = StepState(res.phi[:, k], res.x1[k], res.x2[k], res.f_t[k])
            h = STEP_LENGTHS[j % len(STEP_LENGTHS)]
            out.append((model, state, np.asarray(torque(res.t[k] + h)), h))
    return out


@pytest.fixture(scope="module")
def samples():
    return sampled_steps()


@pytest.fixture(scope="module")
def steppers():
    """One MPCC step per model: the NLP is built once and reused for every sampled state."""
    cache = {}

    def get(model, **options):
        key = (model, tuple(sorted(options.items())))
        if key not in cache:
            cache[key] = MPCCStep(model, MPCCOptions(**options))
        return cache[key]
    return get


# ---------------------------------------------------------------------------------------- IPOPT
# failures (the status table itself and forced IPOPT failures of every kind:
# tests/test_ipopt_status.py)
def test_failing_ipopt_status_fails_the_step(paper_robot):
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    step = MPCCStep(model, MPCCOptions(ipopt={"max_iter": 1}, max_retries=0))
    res = step.solve(initial_state(model, torque), torque(0.01))
    assert not res.success
    assert res.status == "Maximum_Iterations_Exceeded" and ipopt_status(res.status).usable is False
    assert "Maximum_Iterations_Exceeded" in res.message
    assert res.homotopy[-1].return_status == res.status and not res.homotopy[-1].accepted


def _fail_calls(step, which):
    """Let IPOPT calls number ``which`` (1-based) of ``step`` report
    Search_Direction_Becomes_Too_Small."""
    original = step._call
    count = {"n": 0}

    def call(*args, **kwargs):
        sol = original(*args, **kwargs)
        count["n"] += 1
        if count["n"] in which:
            sol.status, sol.accepted = "Search_Direction_Becomes_Too_Small", False
        return sol
    step._call = call


def test_failed_attempts_are_retried(paper_robot):
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    state = initial_state(model, torque)
    ref = solve_step_enumerate(model, state, torque(0.02))

    def sigmas(res, attempt):
        return [s.sigma for s in res.homotopy if s.attempt == attempt and s.kind == "homotopy"]

    # warm start fails at its first IPOPT call: retried from a cold start (monotone schedule)
    warm = MPCCStep(model).solve(state, torque(0.01))
    step = MPCCStep(model)
    _fail_calls(step, {1})
    res = step.solve(state, torque(0.02), warm_start=warm)
    assert res.success and res.attempts == 2, res.message
    assert (res.homotopy[0].attempt == 0
            and res.homotopy[0].return_status == "Search_Direction_Becomes_Too_Small")
    s1 = sigmas(res, 1)
    assert all(b < a for a, b in zip(s1, s1[1:])) and s1[-1] < 1e-9
    np.testing.assert_allclose(res.phi, ref.phi, rtol=0, atol=PHI_TOL)
    # cold start fails: the next attempt runs the non-monotone schedule (sigma goes up first)
    step = MPCCStep(model)
    _fail_calls(step, {1})
    res = step.solve(state, torque(0.02))
    assert res.success and res.attempts == 2, res.message
    s1 = sigmas(res, 1)
    assert s1[1] > s1[0] and s1[-1] < 1e-9
    np.testing.assert_allclose(res.phi, ref.phi, rtol=0, atol=PHI_TOL)
    # no retries allowed: the step fails with the status of the failed call
    step = MPCCStep(model, MPCCOptions(max_retries=0))
    _fail_calls(step, {1})
    res = step.solve(state, torque(0.02))
    assert (not res.success and res.status == "Search_Direction_Becomes_Too_Small"
            and res.attempts == 1)


def test_acceptable_level_is_accepted_with_the_residual_checks(paper_robot):
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    state = initial_state(model, torque)
    opts = {"tol": 1e-30, "acceptable_tol": 1e-3, "acceptable_iter": 1}
    res = MPCCStep(model, MPCCOptions(ipopt=opts, max_retries=0)).solve(state, torque(0.3))
    assert {s.return_status for s in res.homotopy} == {"Solved_To_Acceptable_Level"}
    assert res.success and res.comp_residual <= 1e-8 and res.eq_residual <= 1e-9
    ref = solve_step_enumerate(model, state, torque(0.3))
    np.testing.assert_allclose(res.phi, ref.phi, rtol=0, atol=PHI_TOL)


def test_success_needs_the_complementarity_residual(paper_robot):
    """IPOPT succeeds at every stage, but without the polish the relaxation leaves a residual above
    comp_tol."""
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    state = initial_state(model, torque)
    res = MPCCStep(model,
                   MPCCOptions(polish="never", comp_tol=1e-14,
                               max_retries=0)).solve(state, torque(0.3))
    assert all(s.return_status == "Solve_Succeeded" for s in res.homotopy)
    assert res.homotopy[-1].comp_residual > 1e-14
    assert not res.success and "complementarity residual" in res.message


# ---------------------------------------------------------------------------------------- options
# and inputs
@pytest.mark.parametrize("kwargs,exc,match", [
    ({"formulation": "smooth"}, ValueError, "formulation"),
    ({"sigma_min": 1e-8}, ValueError, "sigma_min"),
    ({"sigma_factor": 1.5}, ValueError, "sigma_factor"),
    ({"sigma0": -1.0}, ValueError, "sigma0"),
    ({"sigma0_warm": 1e-14}, ValueError, "sigma0_warm"),
    ({"comp_tol": "1e-8"}, TypeError, "comp_tol"),
    ({"max_retries": -1}, ValueError, "max_retries"),
    ({"polish": True}, ValueError, "polish"),
    ({"ipopt": [("tol", 1e-8)]}, TypeError, "ipopt"),
])
def test_bad_options_raise(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        MPCCOptions(**kwargs)


def test_ipopt_options_are_copied_per_instance(paper_robot):
    user = {"max_iter": 77}
    opts = MPCCOptions(ipopt=user)
    user["max_iter"] = 1
    assert opts.ipopt == {"max_iter": 77}
    before = dict(STEP_IPOPT)
    MPCCStep(Model(paper_robot), opts)
    assert STEP_IPOPT == before


def test_homotopy_schedule():
    opts = MPCCOptions(sigma0=1e-2, sigma_factor=1e-2, sigma_min=1e-12)
    sched = opts.schedule(opts.sigma0)
    assert sched[0] == 1e-2 and sched[-1] == 1e-12 < 1e-9
    assert all(b < a for a, b in zip(sched, sched[1:]))


def test_bad_step_inputs_raise(paper_robot):
    model = Model(paper_robot)
    step = MPCCStep(model)
    state = initial_state(model, paper_torque(paper_robot))
    with pytest.raises(ValueError, match="tau"):
        step.solve(state, [0.1, 0.2, 0.3])
    with pytest.raises(TypeError, match="state"):
        step.solve(state.phi, [0.1, 0.2])
    with pytest.raises(ValueError, match="phi"):
        StepState([1.0, np.nan], 0.0, 0.1)
    with pytest.raises(TypeError, match="model"):
        MPCCStep("robot")


def test_ipopt_is_quiet_unless_verbose(paper_robot, capfd):
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    state = initial_state(model, torque)
    assert MPCCStep(model).solve(state, torque(0.01)).success
    assert capfd.readouterr().out == ""
    assert MPCCStep(model, MPCCOptions(verbose=True)).solve(state, torque(0.01)).success
    assert "Ipopt" in capfd.readouterr().out


def test_mode_from_pairs():
    z = np.zeros(4)
    assert mode_from_pairs(z, np.ones(4))[0] == Mode.STICK
    assert mode_from_pairs(np.array([1e-3, 0, 0, 0]),
                           np.array([0, 0.3, 0.1, 0.1]))[0] == Mode.SLIP1_POS
    assert mode_from_pairs(np.array([0, 0, 0, 2e-3]),
                           np.array([0.1, 0.1, 0.3, 0]))[0] == Mode.SLIP2_NEG
    # both feet move apart by comparable amounts at equal limits: slip-slip, opening (d' > 0)
    assert mode_from_pairs(np.array([0, 1e-3, 1e-3, 0]),
                           np.array([0.2, 0, 0, 0.2]))[0] == Mode.SLIP_BOTH_POS
    # a corner s = c = 0 is no slip
    assert mode_from_pairs(np.zeros(4), np.array([0, 0.2, 0.1, 0.1]))[0] == Mode.STICK


# ---------------------------------------------------------------------------------------- step vs
# oracle
@pytest.mark.slow
def test_mpcc_step_agrees_with_mode_enumeration(samples, steppers):
    assert len(samples) >= 300
    compared_modes = 0
    modes_seen = set()
    for model, state, tau, h in samples:
        ref = solve_step_enumerate(model, state, tau)
        assert ref.success, ref.message
        res = steppers(model).solve(state, tau)
        assert res.success, res.message
        assert res.comp_residual <= 1e-8 and res.eq_residual <= 1e-9
        ctx = (model.gravity, model.robot.mu1, model.robot.mu2, state.phi, h, res.mode.label,
               ref.mode.label)
        np.testing.assert_allclose(res.phi, ref.phi, rtol=0, atol=PHI_TOL, err_msg=str(ctx))
        # a unique consistent mode must be found; with several coinciding ones (a friction limit
        # reached exactly at the end of the step) the mode is not defined by the step
        if ref.extra["n_consistent"] == 1:
            assert res.mode == ref.mode, ctx
            compared_modes += 1
        modes_seen.add(ref.mode)
        np.testing.assert_allclose([res.dx1, res.dx2], [ref.dx1, ref.dx2], rtol=0,
                                   atol=PHI_TOL * model.robot.L)
    assert compared_modes >= 0.9 * len(samples)
    assert {Mode.STICK, Mode.SLIP1_POS, Mode.SLIP1_NEG, Mode.SLIP2_NEG} <= modes_seen


@pytest.mark.parametrize("formulation", ["l1_penalty", "fischer_burmeister"])
def test_alternative_formulations_agree_with_mode_enumeration(samples, steppers, formulation):
    for model, state, tau, h in samples[::10]:
        ref = solve_step_enumerate(model, state, tau)
        res = steppers(model, formulation=formulation).solve(state, tau)
        assert res.success, res.message
        np.testing.assert_allclose(res.phi, ref.phi, rtol=0, atol=PHI_TOL)
        if ref.extra["n_consistent"] == 1:
            assert res.mode == ref.mode


@pytest.mark.parametrize("ipopt", [{}, {"tol": 1e-10, "constr_viol_tol": 1e-10}],
                         ids=["default", "loose-tol"])
def test_step_at_equal_limits_and_turning_point(ipopt):
    """Mirror-symmetric configuration (equal friction limits) where the slip also stops (d' = 0):
    the relaxation leaves the pairs near their corners and the polish has to find the branches."""
    robot = Robot.paper(mu1=0.328, mu2=0.328)
    model = Model(robot, gravity="physical")
    torque = paper_torque(robot, gamma=90.5, A=38.8, psi=-142.8)
    N = 200
    step = MPCCStep(model, MPCCOptions(ipopt=ipopt))
    state, prev = initial_state(model, torque), None
    for n in range(1, 53):  # the symmetric phase is t = 0.25 (step 50)
        tau = torque(n / N)
        res = step.solve(state, tau, warm_start=prev)
        assert res.success and res.comp_residual <= 1e-8, (n, res.message)
        if 48 <= n <= 52:
            ref = solve_step_enumerate(model, state, tau)
            np.testing.assert_allclose(res.phi, ref.phi, rtol=0, atol=PHI_TOL)
            assert res.mode == ref.mode or ref.extra["n_consistent"] > 1
        state, prev = res.next_state(), res


@pytest.mark.slow
def test_incremental_step_is_exact_within_a_mode(gravity):
    """Between two step phases without an event, the step solution is the event-driven solution."""
    robot = Robot.paper(mu1=0.33, mu2=0.42)
    model = Model(robot, gravity=gravity)
    torque = paper_torque(robot, psi=60)
    N = 100
    ev = simulate_torque(model, torque, t_eval=np.arange(N + 1) / N)
    assert ev.success, ev.message
    event_phases = np.array([e.t for e in ev.steady_events()])
    step = MPCCStep(model)
    prev = None
    checked = 0
    for j in range(N):
        state = StepState(ev.phi[:, j], ev.x1[j], ev.x2[j], ev.f_t[j])
        tau = torque(ev.t[j + 1])
        res = step.solve(state, tau, warm_start=prev)
        assert res.success, res.message
        prev = res
        if np.any((event_phases > ev.t[j] - 1e-12) & (event_phases <= ev.t[j + 1] + 1e-12)):
            continue
        ref = solve_step_enumerate(model, state, tau)
        # the MPCC's relaxation leaves |min(s_j, c_j)| <= comp_tol = 1e-8 (scaled): about 1e-10 in
        # phi
        for r in (res, ref):
            np.testing.assert_allclose(r.phi, ev.phi[:, j + 1], rtol=0, atol=1e-9)
            np.testing.assert_allclose([r.x1, r.x2], [ev.x1[j + 1], ev.x2[j + 1]], rtol=0,
                                       atol=1e-9 * robot.L)
            assert int(r.mode) == ev.mode[j + 1]
        checked += 1
    assert checked >= N - 2 * len(event_phases)


# ----------------------------------------------------------------------------------------
# time-stepping
@pytest.fixture(scope="module")
def paper_run():
    robot = Robot.paper()
    model = Model(robot)
    torque = paper_torque(robot)
    return model, torque, simulate_mpcc(model, torque, steps=100)


@pytest.mark.slow
def test_time_stepping_result(paper_run):
    model, torque, res = paper_run
    r = model.robot
    N = 100
    assert res.success, res.message
    assert res.status == Status.SUCCESS and res.cycles >= 2
    # the samples are the step phases and the located events of the cycle (switch-exact steps), in
    # order
    events = sorted(e.t for e in res.events if res.t0 < e.t < res.t0 + 1 and not (e.t * N) % 1 == 0)
    assert len(events) == 4  # the paper gait's slip-to-stick and slip onsets
    n = N + 1 + len(events)
    assert res.t.shape == (n,) and res.phi.shape == (2, n) and res.tau.shape == (2, n)
    np.testing.assert_allclose(res.t,
                               np.sort(np.concatenate([res.t0 + np.arange(N + 1) / N, events])),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.x2 - res.x1, res.d, rtol=0, atol=1e-12)
    kin = model.kinematics(res.phi)
    np.testing.assert_allclose(res.d, kin["d"], rtol=0, atol=1e-12)
    for j in range(n):
        F = model.equilibrium_residual(res.phi[:, j], res.tau[:, j], res.f_t[j])
        assert np.max(np.abs(F)) < 1e-9 * r.M * r.g * r.L
    slack = 1e-10 * r.M * r.g
    assert np.all(res.f_n1 > 0) and np.all(res.f_n2 > 0)
    assert np.all(np.abs(res.f_t) <= r.mu1 * res.f_n1 + slack)
    assert np.all(np.abs(res.f_t) <= r.mu2 * res.f_n2 + slack)
    # the feet move only while their mode says so (a sticking pair keeps s_j <= comp_tol = 1e-8
    # scaled)
    creep = 1e-8 * r.L
    dx1, dx2 = np.diff(res.x1), np.diff(res.x2)
    moving1 = np.isin(res.mode[1:], [Mode.SLIP1_POS, Mode.SLIP1_NEG])
    moving2 = np.isin(res.mode[1:], [Mode.SLIP2_POS, Mode.SLIP2_NEG])
    assert np.all(np.abs(dx1[~moving1]) < creep) and np.all(np.abs(dx2[~moving2]) < creep)
    assert (np.all(dx1[res.mode[1:] == Mode.SLIP1_NEG] < 0)
            and np.all(dx2[res.mode[1:] == Mode.SLIP2_NEG] < 0))
    # metrics: displacement of foot 1, CoT+, positive work, dissipation
    assert res.S == pytest.approx(res.x1[-1] - res.x1[0], abs=1e-15) and res.S < 0
    assert res.CoT_plus == pytest.approx(res.W_plus / (r.M * r.g * abs(res.S)), rel=1e-14)
    assert res.W_plus == pytest.approx(res.W_plus_joint.sum(),
                                       rel=1e-14) and np.all(res.W_plus_joint > 0)
    assert res.energy["dissipation"] > 0 and abs(res.energy["balance_residual"]) < 1e-2
    assert res.periodicity_residual < 1e-8
    assert res.extra["max_comp_residual"] <= 1e-8 and res.extra["retried_steps"] == 0


def test_events_are_located_on_step_boundaries(paper_run):
    """Switch-exact steps: every mode change of the samples starts at a located event, which is a
    sample (a step boundary) and agrees with the event-driven stepper's event phase (an independent
    locator)."""
    model, torque, res = paper_run
    changes = [res.t[j - 1] for j in range(1, res.t.size) if res.mode[j] != res.mode[j - 1]]
    steady = [e.t for e in res.steady_events() if e.t > res.t0 + 1e-12]
    np.testing.assert_allclose(steady, changes, rtol=0, atol=1e-12)
    for e in res.events:
        assert e.mode_before != e.mode_after
        assert e.guard_name != "mode_change_between_steps" and abs(e.guard) < 1e-8, e
    ev = simulate_torque(model, torque)
    np.testing.assert_allclose(sorted(e.t - ev.t0 for e in ev.steady_events()),
                               sorted(t - res.t0 for t in steady), rtol=0, atol=1e-8)


@pytest.mark.slow
def test_t_eval_and_fixed_cycles(paper_run):
    model, torque, res = paper_run
    part = simulate_mpcc(model, torque, steps=100, t_eval=[0.0, 0.25, 0.5, 1.0])
    idx = [int(np.argmin(np.abs(res.t - res.t0 - s))) for s in (0.0, 0.25, 0.5, 1.0)]
    np.testing.assert_allclose(res.t[idx] - res.t0, [0.0, 0.25, 0.5, 1.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(part.phi, res.phi[:, idx], rtol=0, atol=1e-12)
    np.testing.assert_allclose(part.x1, res.x1[idx], rtol=0, atol=1e-15)
    assert list(part.mode) == list(res.mode[idx])
    assert part.S == res.S
    with pytest.raises(ValueError, match="t_eval"):
        simulate_mpcc(model, torque, steps=100, cycles=1, t_eval=[1.5])
    one = simulate_mpcc(model, torque, steps=50, cycles=1)
    assert one.success and one.cycles == 1 and one.nsteps == 50 and one.t0 == 0.0


def test_bad_simulation_inputs_raise(paper_robot):
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    with pytest.raises(ValueError, match="steps"):
        simulate_mpcc(model, torque, steps=2)
    with pytest.raises(ValueError, match="cycles"):
        simulate_mpcc(model, torque, steps=50, cycles=0)
    with pytest.raises(TypeError, match="options"):
        simulate_mpcc(model, torque, options={"max_cycles": 3})
    with pytest.raises(ValueError, match="max_dphi"):
        TimeSteppingOptions(max_dphi=0.0)


def _check_failure_names_the_step(res, N):
    assert not res.success and res.failure_t is not None
    n = res.nsteps
    assert res.failure_t == pytest.approx(n / N, abs=1e-12)
    assert f"step {n} " in res.message and f"t = {n / N:.6f}" in res.message
    assert "IPOPT return status" in res.message
    # nothing after the failed step: the output ends at the last solved step
    assert res.t[-1] == pytest.approx((n - 1) / N, abs=1e-12)
    assert math.isnan(res.S)


def test_lift_off_ends_the_run_at_the_failed_step(gravity):
    robot = Robot.paper().with_stiffness_ratio(10.0)
    model = Model(robot, gravity=gravity)
    torque = paper_torque(robot, A=60)  # pulls foot 2 off the ground (see the hybrid tests)
    N = 100
    res = simulate_mpcc(model, torque, steps=N)
    assert res.status == Status.LIFT_OFF, res.message
    # the step after the lift-off cannot be solved; the lift-off is placed inside it, where the
    # event-driven stepper places it, and the message names both
    n = res.nsteps
    assert "foot 2's normal force reaches zero" in res.message
    assert f"then step {n} (t = {n / N:.6f}" in res.message
    assert "IPOPT return status Infeasible_Problem_Detected" in res.message
    assert res.t[-1] == pytest.approx((n - 1) / N, abs=1e-12) and math.isnan(res.S)
    assert np.all(res.f_n2 > 0)
    ev = simulate_torque(model, torque)
    assert ev.status == Status.LIFT_OFF
    assert res.failure_t == pytest.approx(ev.failure_t, abs=1e-8)


def test_fold_ends_the_run_at_the_failed_step():
    robot = Robot.paper().with_stiffness_ratio(0.3)
    model = Model(robot, gravity="physical")
    torque = paper_torque(robot)
    N = 100
    res = simulate_mpcc(model, torque, steps=N)
    assert res.status == Status.FOLD, res.message
    _check_failure_names_the_step(res, N)
    ev = simulate_torque(model, torque)
    assert ev.status == Status.FOLD
    assert res.failure_t - 1 / N < ev.failure_t <= res.failure_t


def test_ipopt_failure_ends_the_run_with_solver_failure(paper_robot):
    model = Model(paper_robot)
    N = 50
    res = simulate_mpcc(model, paper_torque(paper_robot), steps=N,
                        options=MPCCOptions(ipopt={"max_iter": 1}, max_retries=0))
    assert res.status == Status.SOLVER_FAILURE
    assert res.nsteps == 1
    _check_failure_names_the_step(res, N)
    assert "Maximum_Iterations_Exceeded" in res.message
    # requested output phases beyond the failure are not invented
    part = simulate_mpcc(model, paper_torque(paper_robot), steps=N, t_eval=[0.0, 0.5],
                         options=MPCCOptions(ipopt={"max_iter": 1}, max_retries=0))
    assert part.status == Status.SOLVER_FAILURE and list(part.t) == [0.0]


@pytest.mark.slow
def test_switch_exact_event_points_satisfy_their_event_condition():
    """Unequal friction (problems/unequal_friction.toml): at each located event the sample satisfies
    the event's condition recomputed from the model's kinematics: at a change of the slipping foot
    both feet are on their friction limits (mu1 f_n1 = mu2 f_n2 = |f_t|); at a slip onset the new
    foot is on its limit."""
    robot = Robot.paper(mu1=0.35, mu2=0.43)
    model = Model(robot)
    res = simulate_mpcc(model, paper_torque(robot), steps=50)
    assert res.success, res.message
    Mg = robot.M * robot.g
    kinds = []
    for e in res.steady_events():
        j = int(np.argmin(np.abs(res.t - e.t)))
        assert abs(res.t[j] - e.t) < 1e-12
        kin = model.kinematics(res.phi[:, j])
        lim1, lim2 = robot.mu1 * kin["fn1"], robot.mu2 * kin["fn2"]
        ft = abs(res.f_t[j])
        if e.kind == "slip_switch":
            assert abs(lim1 - lim2) < 1e-8 * Mg and abs(ft - lim1) < 1e-8 * Mg
        elif e.kind.startswith("slip_onset_"):
            assert abs(ft - (lim1 if e.kind.endswith("1") else lim2)) < 1e-8 * Mg
        kinds.append(e.kind)
    assert kinds.count("slip_switch") == 2 and "slip_to_stick" in kinds


def test_the_slip_rate_of_the_step_split_is_read_on_one_piece_of_the_input():
    """The slip-rate guard of the step split (sim/step_split.py) on a slip increment with a kink
    at theta = 0.5 (rate 1 before it, -2 after) and one at the step's start: exact on each side,
    one-sided at the kinks and at the step's end, never an average across a kink; a rate that
    turns at a kink at the step's start turns there, a margin only at zero."""
    from types import SimpleNamespace

    from ocp_crawl.sim.step_split import _Guards

    def increment(theta):   # s(theta), kinked at 0 (zero before it) and at 0.5
        return max(theta, 0.0) if theta <= 0.5 else 0.5 - 2.0 * (theta - 0.5)

    g = _Guards(None, None, Mode.SLIP1_POS, lambda th: np.zeros(2), None, kinks=(0.0, 0.5))
    g.solve = lambda theta: SimpleNamespace(x=np.r_[np.zeros(4), increment(theta), np.zeros(7)])
    rates = {0.25: 1.0, 0.4999: 1.0, 0.5: -2.0, 0.5001: -2.0, 0.9995: -2.0, 1.0: -2.0, 0.0: 1.0}
    for theta, rate in rates.items():
        assert g.slip_rate(theta) == pytest.approx(rate, abs=1e-9), theta
    assert g.slip_rate(0.5, left=True) == pytest.approx(1.0, abs=1e-9)
    assert g.slip_rate(0.0, left=True) == pytest.approx(0.0, abs=1e-9)
    assert g.piece(1.0) == (0.5, 1.0) and g.piece(0.5) == (0.5, 1.0)
    assert g.piece(0.5, left=True) == (0.0, 0.5) and g.piece(-0.3) == (-math.inf, 0.0)
    # at the kink at the step's start: a rate turning there (zero just before), a margin at zero
    assert g.turns_at_kink("s1+ slip rate", -2.0)
    assert g.turns_at_kink("s2+ margin", 0.0) and not g.turns_at_kink("s2+ margin", -1e-3)
    assert not _Guards(None, None, Mode.SLIP1_POS, None, None).turns_at_kink("s2+ margin", 0.0)
