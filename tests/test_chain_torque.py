"""The torque-driven stepper of an n-link chain (ocp_crawl.sim.chain_torque).

At n = 3 it must reproduce the three-link event solver (S, W+ and the steady cycle's contact
modes); a fourth joint made stiff tends to the three-link gait; reversing the chain mirrors S; a
five-link gait agrees with a brute-force continuation of tiny fixed steps written here.
"""
import math

import numpy as np
import pytest

import ocp_crawl
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_inputs import JointFourier
from ocp_crawl.model.chain_model import ChainModel, slip_mode, stick_mode
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.robot import Robot
from ocp_crawl.model.statics import Model
from ocp_crawl.sim.chain_torque import ChainReferenceTorque, simulate_chain_torque
from ocp_crawl.sim.result import Mode

#: relative tolerance of S and W+ against the three-link event solver
RTOL = 1e-7
#: output phases of the runs compared (a few: the samples are not what is compared)
T_OUT = np.array([0.0, 0.5, 1.0])


def _three_link_cases() -> list[tuple[Robot, Harmonic]]:
    """The paper's robot and gait, and three seeded robots and harmonic gaits with mu1 != mu2."""
    rng = np.random.default_rng(3)
    cases = [(Robot.paper(), Harmonic.from_degrees(90, 30, 45))]
    while len(cases) < 4:
        robot = Robot.paper(beta=rng.uniform(1.5, 2.5), mu1=rng.uniform(0.3, 0.5),
                            mu2=rng.uniform(0.3, 0.5))
        gait = Harmonic.from_degrees(rng.uniform(80, 100), rng.uniform(20, 35),
                                     rng.uniform(20, 70))
        cases.append((robot, gait))
    return cases


CASES = _three_link_cases()

FIVE = Chain(lengths=(0.025, 0.02, 0.03, 0.022, 0.027),
             masses=(0.010, 0.008, 0.014, 0.009, 0.011), stiffness=(0.17, 0.2, 0.15, 0.18),
             mu=(0.35, 0.45), com=(0.45, 0.5, 0.55, 0.5, 0.4), rest=(0.05, -0.05, 0.0, 0.03))
FIVE_REF = JointFourier.harmonic(np.radians([110, 160, 160, 110]), np.radians([25, 15, 15, 25]),
                                 np.radians([60, 20, -20, -60]))


def _steady_modes(res) -> list[tuple[str, str]]:
    return [(e.mode_before, e.mode_after) for e in res.events if res.t0 <= e.t <= res.t0 + 1]


def _steady_phases(res) -> np.ndarray:
    return np.array([e.t - res.t0 for e in res.events if res.t0 <= e.t <= res.t0 + 1])


@pytest.fixture(scope="module", autouse=True)
def _built_functions():
    """Builds the CasADi functions and mapped evaluations of both solvers for three links once per
    process (a cost of the first call in a process, not of a simulation)."""
    robot = Robot.paper()
    torque = ReferenceTorque(Harmonic(), robot.k)
    ocp_crawl.simulate(Model(robot), torque)
    simulate_chain_torque(ChainModel(Chain.from_robot(robot)), torque, t_eval=T_OUT,
                          cycles_max=1)


@pytest.mark.parametrize("case", range(len(CASES)))
def test_three_links_equal_event_solver(case):
    """n = 3: S and W+ equal those of the event solver to 1e-7 and the steady cycle has the same
    contact modes and event phases."""
    robot, gait = CASES[case]
    torque = ReferenceTorque(gait, robot.k)
    ref = ocp_crawl.simulate(Model(robot), torque)
    res = simulate_chain_torque(ChainModel(Chain.from_robot(robot)), torque, t_eval=T_OUT)
    assert ref.success and res.success, (ref.message, res.message)
    L = robot.L
    assert abs(res.S - ref.S) <= RTOL * max(abs(ref.S), 1e-3 * L)
    assert abs(res.W_plus - ref.W_plus) <= RTOL * abs(ref.W_plus)
    assert _steady_modes(res) == [(e.mode_before, e.mode_after) for e in ref.steady_events()]
    ref_t = np.array([e.t - ref.t0 for e in ref.steady_events()])
    np.testing.assert_allclose(_steady_phases(res), ref_t, atol=1e-9)
    assert abs(res.energy["balance_residual"]) <= 1e-9


@pytest.mark.slow
def test_stiff_extra_joint_tends_to_three_links():
    """A four-link chain whose body is split by a straight joint of growing stiffness (no torque
    on it) tends to the three-link S, the differences decreasing."""
    robot = Robot.paper(mu2=0.45)
    gait = Harmonic.from_degrees(90, 30, 45)
    c3 = Chain.from_robot(robot)
    base = simulate_chain_torque(ChainModel(c3), ReferenceTorque(gait, robot.k), t_eval=T_OUT)
    (l1, lb, l3), (m1, mb, m3) = c3.lengths, c3.masses
    ref4 = JointFourier.harmonic([gait.gamma1, math.pi, gait.gamma2], [gait.A1, 0.0, gait.A2],
                                 [gait.psi / 2, 0.0, -gait.psi / 2])
    diffs = []
    for factor in (1e2, 1e3, 1e4):
        c4 = Chain(lengths=(l1, lb / 2, lb / 2, l3), masses=(m1, mb / 2, mb / 2, m3),
                   stiffness=(robot.k, factor * robot.k, robot.k), mu=c3.mu, g=c3.g)
        res = simulate_chain_torque(ChainModel(c4), ChainReferenceTorque(ref4, c4), t_eval=T_OUT)
        assert res.success, res.message
        assert _steady_modes(res) == _steady_modes(base)
        diffs.append(abs(res.S - base.S))
    assert diffs[0] > diffs[1] > diffs[2]
    assert diffs[2] <= 1e-5 * abs(base.S)


@pytest.mark.slow
def test_reversed_chain_mirrors_s():
    """The chain read from the other end, with the joint torques in reverse order, moves by -S
    with the same W+."""
    robot = Robot.paper(mu1=0.35, mu2=0.45)
    gait = Harmonic.from_degrees(90, 30, 45)
    c3 = Chain.from_robot(robot)
    res = simulate_chain_torque(ChainModel(c3), ReferenceTorque(gait, robot.k), t_eval=T_OUT)
    mirrored = Harmonic(gait.gamma2, gait.gamma1, gait.A2, gait.A1, -gait.psi)
    rev = simulate_chain_torque(ChainModel(c3.reversed()), ReferenceTorque(mirrored, robot.k),
                                t_eval=T_OUT)
    assert res.success and rev.success
    assert abs(rev.S + res.S) <= 1e-10 * abs(res.S)
    assert abs(rev.W_plus - res.W_plus) <= 1e-10 * res.W_plus


@pytest.mark.slow
def test_large_steps_same_gait():
    """The step does not set the accuracy: steps up to half a cycle (guards between the steps'
    ends watched by their Hermite interpolants) give the same S, W+ and events."""
    robot = Robot.paper(mu2=0.45)
    torque = ReferenceTorque(Harmonic.from_degrees(90, 30, 45), robot.k)
    model = ChainModel(Chain.from_robot(robot))
    fine = simulate_chain_torque(model, torque, t_eval=T_OUT)
    coarse = simulate_chain_torque(model, torque, t_eval=T_OUT, max_step=0.5)
    assert fine.success and coarse.success
    assert abs(coarse.S - fine.S) <= 1e-12 * abs(fine.S)
    assert abs(coarse.W_plus - fine.W_plus) <= 1e-12 * fine.W_plus
    np.testing.assert_allclose(_steady_phases(coarse), _steady_phases(fine), atol=1e-12)


@pytest.mark.parametrize("gait", [(90, 60, 45), (60, 40, 90)])
def test_failure_as_event_solver(gait):
    """A joint reaching the ground ends the run with the event solver's status, mode and phase."""
    robot = Robot.paper(mu2=0.45)
    torque = ReferenceTorque(Harmonic.from_degrees(*gait), robot.k)
    ref = ocp_crawl.simulate(Model(robot), torque)
    res = simulate_chain_torque(ChainModel(Chain.from_robot(robot)), torque)
    assert not res.success and res.status == ref.status
    assert res.failure_mode == ref.failure_mode
    assert abs(res.failure_t - ref.failure_t) <= 1e-9
    assert np.isnan(res.S)


def test_bad_input():
    """A model that is not a ChainModel is a TypeError; torques with the wrong number of rows, a
    cycle count below 1 or a step that is not positive a ValueError."""
    robot = Robot.paper()
    torque = ReferenceTorque(Harmonic(), robot.k)
    with pytest.raises(TypeError, match="ChainModel"):
        simulate_chain_torque(Model(robot), torque)
    with pytest.raises(ValueError, match="4 rows"):
        simulate_chain_torque(ChainModel(FIVE), torque)
    model = ChainModel(Chain.from_robot(robot))
    with pytest.raises(ValueError, match="cycles_max"):
        simulate_chain_torque(model, torque, cycles_max=0)
    with pytest.raises(ValueError, match="max_step"):
        simulate_chain_torque(model, torque, max_step=-0.1)


def test_chain_reference_torque():
    """tau_j = k_j (phi_ref_j - pi - rest_j), its rate k_j phi_ref_j', for one and many phases."""
    torque = ChainReferenceTorque(FIVE_REF, FIVE)
    t = np.array([0.1, 0.7])
    k, rest = np.array(FIVE.stiffness), np.array(FIVE.rest)
    np.testing.assert_allclose(torque(t), k[:, None] * (FIVE_REF(t) - math.pi - rest[:, None]))
    np.testing.assert_allclose(torque(0.1), torque(t)[:, 0])
    np.testing.assert_allclose(torque.derivative(t), k[:, None] * FIVE_REF.derivative(t))


def _guards(model: ChainModel, mode: Mode, aux: dict) -> float:
    """The smallest guard of ``mode`` at a solution (positive while the mode holds)."""
    Mg, L = model.Mg, model.chain.L
    g = [aux["fn1"] / Mg, aux["fn2"] / Mg, aux["d"] / L]
    g += [aux[f"zj{j}"] / L for j in range(1, model.chain.n)]
    ft, lim1, lim2 = aux["ft"], aux["lim1"], aux["lim2"]
    if mode is Mode.STICK:
        g += [(lim1 - ft) / Mg, (lim1 + ft) / Mg, (lim2 - ft) / Mg, (lim2 + ft) / Mg]
    else:
        g += [mode.sigma * aux["ddot"] / L,
              ((lim2 - lim1) if mode.foot == 1 else (lim1 - lim2)) / Mg]
    return min(g)


def _brute_force_cycle(model: ChainModel, torque, t0: float, x: np.ndarray, mode: Mode,
                       steps: int) -> float:
    """Displacement of foot 1 [m] over the cycle [t0, t0 + 1] by fixed steps of 1/steps cycles from
    the state x in ``mode``.

    At each step the current mode is kept while its solution has all guards positive, else the
    first mode (stick-stick at the last distance, then each slip) that has, or the one whose least
    guard is largest (a friction margin that leaves zero quadratically after d' = 0 is within the
    steps' error of zero).  Where the slipping foot changes inside a step, the change of d is
    split between the feet at the zero of the linear interpolant of mu1 f_n1 - mu2 f_n2 (else
    the error would be of the order of the step)."""
    modes = (Mode.STICK, Mode.SLIP1_POS, Mode.SLIP1_NEG, Mode.SLIP2_POS, Mode.SLIP2_NEG)
    aux = model.kinematics(x[:-1])
    x1, x2 = 0.0, aux["d"]
    for k in range(1, steps + 1):
        t = t0 + k / steps
        tau, dtau = torque(t), torque.derivative(t)
        tried = {}
        for cand in (mode,) + tuple(m for m in modes if m is not mode):
            q = stick_mode(aux["d"]) if cand is Mode.STICK else slip_mode(cand.foot, cand.sigma)
            sol = model.solve(x, tau, q, dtau=dtau)
            tried[cand] = (_guards(model, cand, sol.aux) if sol.converged else -math.inf, sol)
            if tried[cand][0] > 0:
                break
        new = max(tried, key=lambda m: tried[m][0])
        sol = tried[new][1]
        assert tried[new][0] > -math.inf, f"no mode solves at t = {t}"
        d_old, d_new = aux["d"], sol.aux["d"]
        if {mode.foot, new.foot} == {1, 2} and tried[mode][0] > -math.inf:
            g0 = aux["lim1"] - aux["lim2"]
            g1 = tried[mode][1].aux["lim1"] - tried[mode][1].aux["lim2"]
            d_sw = d_old + g0 / (g0 - g1) * (tried[mode][1].aux["d"] - d_old)
            x1, x2 = (x2 - d_sw, x2) if mode.foot == 1 else (x1, x1 + d_sw)
        mode, x, aux = new, sol.x, sol.aux
        if mode.foot == 1:
            x1 = x2 - d_new
        elif mode.foot == 2:
            x2 = x1 + d_new
    return x1


@pytest.mark.slow
def test_five_links_against_brute_force():
    """A five-link chain with unequal links, joints and feet: success, and S of the steady cycle
    equal to that of a fixed-step continuation of 1,000 steps (mode decided at each step) from the
    cycle's start to 1e-4."""
    model = ChainModel(FIVE)
    torque = ChainReferenceTorque(FIVE_REF, FIVE)
    res = simulate_chain_torque(model, torque, t_eval=T_OUT)
    assert res.success, res.message
    assert res.phi.shape == (4, T_OUT.size)
    assert {e.mode_after for e in res.events} >= {"stick-stick", "slip1+", "slip2-"}
    x = np.append(res.phi[:, 0], res.f_t[0] / model.Mg)
    S = _brute_force_cycle(model, torque, res.t0, x, Mode(int(res.mode[0])), 1000)
    assert abs(S - res.S) <= 1e-4 * abs(res.S)


#: a soft five-link chain whose slip of foot 1 ends at a fold of its equilibrium branch (phase
#: 0.6104)
FOLDING = (
    Chain(lengths=(0.03115881579472988, 0.02530651122084284, 0.020716027601762832,
                   0.016078614047633128, 0.022667377615710367),
          masses=(0.009084732054199986, 0.0054527519390244516, 0.005487577107271681,
                  0.014991761150650713, 0.011523691115879876),
          stiffness=(0.01543944424992457, 0.021317258883181246, 0.05077418893108724,
                     0.04489167277586377),
          mu=(0.4688462075217482, 0.3784809328669556),
          com=(0.4986046037463485, 0.5353378703662132, 0.4121605425916112, 0.5111192233841447,
               0.45429032090602034),
          rest=(0.03796511733349221, -0.043578556268780905, 0.017918153302136502,
                0.03700885023275034)),
    JointFourier([2.126918391163502, 2.71718029586238, 2.71718029586238, 2.126918391163502],
                 [[0.0], [0.0019127749421292163], [0.008908241448756668], [0.005545849232583677]],
                 [[0.4789865779593843], [0.1809865461353047], [0.421401319398719],
                  [0.1748637718613802]]))

#: a stiff six-link chain whose joint 1 dips below the ground and back (phase 0.7468) inside a
#: continuation step at whose end the slip's stick guard crosses zero
DIPPING = (
    Chain(lengths=(0.02556982290340406, 0.030273004796038522, 0.031233855340192143,
                   0.025204577104014476, 0.03058679344795575, 0.030922266089200897),
          masses=(0.010947550043408676, 0.009085780468959439, 0.011712764398047977,
                  0.011274678298535875, 0.013400823557331746, 0.012241634885127677),
          stiffness=(92.72679227822066, 508.5549813775502, 73.25177732340771, 279.55260046101864,
                     345.53995888355223),
          mu=(0.4259685865306201, 0.30938232875636607),
          com=(0.4109774633975296, 0.42397598178572254, 0.5404618932128279, 0.40881511654760416,
               0.5400413576206442, 0.4839750872371758),
          rest=(-0.013062824426984719, -0.03460748651849539, -0.03936286870031459,
                -0.037461042074025536, 0.027781029308913435)),
    JointFourier([2.029675009069385, 2.694167018842314, 2.694167018842314, 2.694167018842314,
                  2.029675009069385],
                 [[-0.0], [-0.00514618678579096], [-0.014693108062187366], [-0.01317757641175845],
                  [-0.010769740583359083]],
                 [[0.4195338426905596], [0.35701769904936476], [0.5095627043441332],
                  [0.3045634471603551], [0.18659412550908724]]))


def test_a_fold_ends_the_run_where_the_incremental_steps_find_no_mode_either():
    """The event-driven stepper's fold against the independent incremental steps, which cannot
    continue past it (their first step after it has no consistent mode)."""
    from ocp_crawl.sim.chain_mpcc import simulate_chain_mpcc

    chain, reference = FOLDING
    model, torque = ChainModel(chain), ChainReferenceTorque(reference, chain)
    res = simulate_chain_torque(model, torque)
    assert res.status_name == "fold" and res.failure_mode == "slip1+", res.message
    steps = simulate_chain_mpcc(model, torque, steps=50)
    assert not steps.success and res.failure_t < steps.failure_t <= res.failure_t + 1 / 50


def test_a_guard_dipping_before_another_crosses_at_the_step_end_is_the_event():
    """Joint 1 touches the ground inside a step whose end has the stick guard negative: the run
    ends there (joint_on_ground), before the slip's end, at any largest step."""
    chain, reference = DIPPING
    for max_step in (1 / 16, 1 / 64):
        res = simulate_chain_torque(ChainModel(chain), ChainReferenceTorque(reference, chain),
                                    max_step=max_step)
        assert res.status_name == "joint_on_ground", (max_step, res.message)
        assert res.failure_t == pytest.approx(0.74685, abs=1e-4)


@pytest.mark.parametrize("steps", [50, 100])
def test_the_incremental_steps_find_the_joint_under_the_ground_between_their_ends(steps):
    """The same dip through the independent incremental steps: at 50 steps a cycle joint 1 is above
    the ground at every step's end (0.74 and 0.76) and below it in between; at 100 steps below it
    at 0.75.  Either way the run ends where the event-driven stepper's does."""
    from ocp_crawl.sim.chain_mpcc import simulate_chain_mpcc

    chain, reference = DIPPING
    model, torque = ChainModel(chain), ChainReferenceTorque(reference, chain)
    event = simulate_chain_torque(model, torque)
    res = simulate_chain_mpcc(model, torque, steps=steps)
    assert res.status_name == "joint_on_ground", res.message
    assert res.failure_t == pytest.approx(event.failure_t, abs=1e-9)
