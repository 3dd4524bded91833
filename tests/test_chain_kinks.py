"""Inputs with kinks and holds through the chain's simulators (ocp_crawl.sim.chain_pieces).

Piecewise-linear tables, pulses with straight or half-cosine edges, a square table whose holds end
at a friction tie of the symmetric robot, and an optimal-control profile: the paper's robot
written as a chain must move as the three-link event stepper moves it (its own rules at kinks,
holds and ties); a five-link chain under tables must pass the crosscheck of its event-driven
stepper against its switch-exact steps; reading the chain from the other end mirrors S.
"""
import json

import numpy as np
import pytest

from ocp_crawl import load_problem, simulate
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.inputs import ReferenceTorque
from ocp_crawl.model.robot import Robot
from ocp_crawl.model.sampled import JointLinear, PeriodicLinear
from ocp_crawl.model.statics import Model
from ocp_crawl.problem.shipped import shipped_files
from ocp_crawl.sim.chain_mpcc import simulate_chain_mpcc, step_phases
from ocp_crawl.sim.chain_pieces import ChainPieces
from ocp_crawl.sim.chain_torque import ChainReferenceTorque, simulate_chain_torque
from ocp_crawl.sim.crosscheck import crosscheck
from ocp_crawl.status import Status

ROBOT = Robot.paper()
MODEL = Model(ROBOT, "physical")
CHAIN3 = ChainModel(Chain.from_robot(ROBOT), "physical")
PROBLEMS = shipped_files("problems")
#: relative agreement of S and W+ with the three-link stepper (the same equations, two codes)
RTOL = 1e-9


def _random_table(seed: int) -> ReferenceTorque:
    """Reference angles linear between 8 random knots around the paper's gait."""
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0.0, 1.0, 8))
    t[0] = 0.0
    ref = np.pi / 2 + np.radians(30) * np.vstack([np.sin(2 * np.pi * t + 0.8),
                                                  np.sin(2 * np.pi * t)])
    return ReferenceTorque(PeriodicLinear(t, ref + np.radians(3) * rng.standard_normal((2, 8))),
                           ROBOT.k)


#: each joint steps between 60 and 120 deg and holds, in turn; at t = 0.5 both are up (a friction
#: tie of the symmetric robot at a kink)
SQUARE = ReferenceTorque(PeriodicLinear(
    [0.0, 0.1, 0.4, 0.5, 0.6, 0.9],
    np.pi / 2 + np.radians(30) * np.array([[-1, 1, 1, 1, -1, -1], [-1, -1, -1, 1, 1, 1.0]])),
    ROBOT.k)


def _pulse(ramp: str) -> ReferenceTorque:
    torque = load_problem(PROBLEMS["pulse_gait.toml"], [f'gait.ramp="{ramp}"']).torque
    assert isinstance(torque, ReferenceTorque)
    return torque


def _edges(ramp: str, rise: float, hold: float, psi: float) -> ReferenceTorque:
    over = [f'gait.ramp="{ramp}"', f"gait.rise={rise}", f"gait.hold={hold}", f"gait.psi_deg={psi}"]
    torque = load_problem(PROBLEMS["pulse_gait.toml"], over).torque
    assert isinstance(torque, ReferenceTorque)
    return torque


INPUTS = {"table-1": lambda: _random_table(1), "table-2": lambda: _random_table(2),
          "square": lambda: SQUARE, "trapezoid": lambda: _pulse("linear"),
          "cosine-pulse": lambda: _pulse("cosine"),
          # edges without flats: a slip ends in the cycle's last step
          "rests": lambda: _edges("cosine", 0.5, 0.0, 90.0),
          # a hold whose end leaves a slip mode on another branch (a jump) and stick-stick
          "hold-end": lambda: _edges("cosine", 0.35, 0.1, 45.0)}


#: tables of a random search that a chain stepper without these rules gets wrong: (mu1, mu2, beta,
#: knots, reference angles [rad]); a hold of both joints over [0.13, 0.6] (a quadrature node inside
#: it solved from the rates after it fails), and a slip that stops at a kink ending a step (its
#: guard located with the rates after the kink does not change sign)
FOUND = {
    "long-hold": (0.4060097645480456, 0.46174861265144945, 2.326709972967004,
                  [0.06, 0.07, 0.13, 0.6, 0.66, 0.72, 0.86],
                  [[2.101252597127504, 2.0957676751264116, 2.0551931441358273, 2.0551931441358273,
                    1.9544931100910494, 2.0056433126959328, 2.106185820435757],
                   [1.6446387571380037, 1.6475923101610725, 1.695016974839499, 1.695016974839499,
                    2.2951090926825377, 2.1846618358388, 1.8673934315231464]]),
    "stop-at-kink": (0.49647346542344895, 0.4929812033160846, 1.9178274036795568,
                     [0.4, 0.6, 0.7, 0.86, 0.9, 0.93, 0.98, 0.99],
                     [[2.593871987734694, 1.9685026024154322, 2.167229070778667,
                       2.167229070778667, 2.552208144440756, 2.578587482663925,
                       2.5948987228830918, 2.593871987734694],
                      [1.6683401730019136, 2.4297162466461777, 2.247878799654595,
                       1.8544606617055905, 1.774628597841384, 1.726653346656105,
                       1.6742796315751458, 1.6683401730019136]]),
}


def _steady(res) -> list[tuple[float, str, str]]:
    return [(e.t - res.t0, e.mode_before, e.mode_after) for e in res.steady_events()]


def _same_run(chain_res, ref) -> None:
    assert chain_res.success and ref.success, (chain_res.message, ref.message)
    assert abs(chain_res.S - ref.S) <= RTOL * abs(ref.S)
    assert abs(chain_res.W_plus - ref.W_plus) <= RTOL * ref.W_plus
    a, b = _steady(chain_res), _steady(ref)
    assert [m for _, *m in a] == [m for _, *m in b]
    np.testing.assert_allclose([t for t, *_ in a], [t for t, *_ in b], atol=1e-8)


@pytest.mark.parametrize("name", INPUTS)
def test_kinked_and_held_inputs_move_the_chain_as_the_three_link_stepper(name):
    """The paper's robot as a chain: S, W+ and the steady cycle's events of the three-link event
    stepper, whose kinks, holds and ties it reads the same way."""
    torque = INPUTS[name]()
    _same_run(simulate_chain_torque(CHAIN3, torque), simulate(MODEL, torque, "event"))


def test_a_tie_held_over_whole_steps_is_a_status_of_the_chains_steps():
    """Mirror-symmetric pulses (psi = 0) on the symmetric robot: its feet's limits tie for whole
    steps, and the three-link robot shares its slips between the feet (S = 0); the chain's
    event-driven stepper and its switch-exact steps, whose slips are one foot's, end with a
    status, whatever the number of steps."""
    torque = _edges("cosine", 0.3, 0.2, 0.0)
    ref = simulate(MODEL, torque, "event")
    assert ref.success and abs(ref.S) <= 1e-15
    assert not simulate_chain_torque(CHAIN3, torque).success
    for n in (40, 200):
        steps = simulate_chain_mpcc(CHAIN3, torque, steps=n)
        assert steps.status == Status.SET_VALUED and "tie over the whole step" in steps.message


@pytest.mark.parametrize("name", FOUND)
def test_tables_a_random_search_found(name):
    """The chain of the three-link robot under the tables of :data:`FOUND`: the three-link
    stepper's S and W+."""
    mu1, mu2, beta, t, v = FOUND[name]
    robot = Robot.paper(mu1=mu1, mu2=mu2, beta=beta)
    torque = ReferenceTorque(PeriodicLinear(t, v), robot.k)
    chain = ChainModel(Chain.from_robot(robot), "physical")
    ref = simulate(Model(robot, "physical"), torque, "event")
    res = simulate_chain_torque(chain, torque)
    assert ref.success and res.success, (ref.message, res.message)
    assert abs(res.S - ref.S) <= RTOL * max(abs(ref.S), 1e-6)
    assert abs(res.W_plus - ref.W_plus) <= RTOL * ref.W_plus


@pytest.mark.parametrize("name", ["table-1", "square", "rests", "hold-end"])
def test_the_chains_steps_end_at_the_kinks(name):
    """The chain's switch-exact steps (N = 40) give the event-driven S to 1e-9 and its modes, and
    place the events the stepper locates at the kinks and the holds' ends; the step grid holds
    every kink and hold end."""
    torque = INPUTS[name]()
    pieces = ChainPieces(torque)
    kinks = np.mod(np.concatenate([pieces.kinks, np.ravel(pieces.holds)]), 1.0)
    assert kinks.size >= 2 or name == "rests"
    grid = step_phases(torque, 40)
    assert all(np.min(np.abs(grid - k)) <= 1e-12 for k in kinks)
    ref = simulate_chain_torque(CHAIN3, torque)
    steps = simulate_chain_mpcc(CHAIN3, torque, steps=40)
    assert steps.success and abs(steps.S - ref.S) <= RTOL * abs(ref.S), (steps.S, ref.S)
    # (the modes of the cycle [0, 1): an event at its end is the next cycle's first)
    assert ([m for t, *m in _steady(steps) if t < 1 - 1e-12]
            == [m for t, *m in _steady(ref) if t < 1 - 1e-12])
    at_kinks = [t for t, *_ in _steady(ref) if np.any(np.abs(kinks - t) <= 1e-12)]
    assert at_kinks or name == "rests", "no event of this input at a kink or a hold's end"
    located = [t for t, *_ in _steady(steps)]
    for t in at_kinks:
        assert np.min(np.abs(np.array(located) - t)) <= 1e-12, (t, located)


def test_the_optimum_replayed_through_the_chain(cli_optimize_run):
    """The OCP's optimal torques (linear between the nodes) through the chain's event stepper and
    its steps: the three-link replay's S."""
    code, stdout, _, out, nodes = cli_optimize_run
    assert code == 0, stdout
    arrays = np.load(out / "arrays.npz")
    torque = PeriodicLinear(arrays["phase"], arrays["tau"])
    ref = simulate(MODEL, torque, "event")
    # the file asks a friction set: its middle scenario is the robot's own friction
    [S] = [s["S_replay"] for s in json.loads(stdout)["scenarios"] if s["mu1_mu2"] == 1]
    assert abs(ref.S - S) <= 1e-9 * abs(ref.S)
    _same_run(simulate_chain_torque(CHAIN3, torque), ref)
    steps = simulate_chain_mpcc(CHAIN3, torque, steps=nodes)
    assert steps.success and abs(steps.S - ref.S) <= RTOL * abs(ref.S)


def _five_link():
    problem = load_problem(PROBLEMS["five_link_chain.toml"])
    return problem.model, problem.torque.reference


def _five_link_tables() -> dict:
    """Two tables of the five-link file's joints: its gait sampled at 10 random knots and moved by
    2 deg; the joints stepping by +-20 deg around their means in two groups, as SQUARE's joints,
    every joint holding still over [0.1, 0.4] and [0.6, 0.9]."""
    _, ref = _five_link()
    rng = np.random.default_rng(4)
    t = np.sort(rng.uniform(0.0, 1.0, 10))
    t[0] = 0.0
    mean = np.asarray(ref(np.linspace(0.0, 1.0, 64, endpoint=False))).mean(axis=1)
    first, second = [-1, 1, 1, 1, -1, -1], [-1, -1, -1, 1, 1, 1.0]
    levels = np.array([first, second, second, first])
    return {"random": JointLinear(t, ref(t) + np.radians(2) * rng.standard_normal((4, 10))),
            "steps": JointLinear(SQUARE.reference.t_knots,
                                 mean[:, None] + np.radians(20) * levels)}


def test_the_square_table_passes_the_crosscheck_as_a_chain():
    """Its holds and the ties at their ends: the chain's event-driven stepper against its
    switch-exact steps at N = 40 and 80 (S, W+, the modes, the events' lags)."""
    check = crosscheck(CHAIN3, SQUARE, steps=(40, 80))
    assert check.passed, {k: c.text() for k, c in check.checks.items() if not c.passed}
    assert all(r.rel_diff_S <= 1e-9 for r in check.rows)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["random", "steps"])
def test_five_link_tables_pass_the_crosscheck(name):
    """Unequal links, masses, stiffnesses, rest bends and friction under joint tables: the chain's
    event-driven stepper against its switch-exact steps at N = 40 and 80 (S, W+, the modes, the
    events' lags)."""
    model, _ = _five_link()
    torque = ChainReferenceTorque(_five_link_tables()[name], model.chain)
    assert name == "random" or len(ChainPieces(torque).holds) == 2
    check = crosscheck(model, torque, steps=(40, 80))
    assert check.passed, {k: c.text() for k, c in check.checks.items() if not c.passed}
    assert all(r.rel_diff_S <= 1e-9 for r in check.rows)


#: a six-link chain and its table found by a random search: a slip starts in a step with so small
#: a rate that the step's solution 1e-9 of a step after the event is still stick-stick
SIX = dict(lengths=(0.030561, 0.02886, 0.021153, 0.022202, 0.03023, 0.018074),
           masses=(0.012749, 0.012579, 0.010276, 0.009121, 0.008949, 0.008784),
           com=(0.489015, 0.50091, 0.510699, 0.5991, 0.558532, 0.524436),
           stiffness=(0.318123, 0.186602, 0.177236, 0.254132, 0.15747),
           rest=(-0.081039, 0.002599, -0.005898, 0.07281, 0.022554), mu=(0.402824, 0.399375))
SIX_KNOTS = (0.04, 0.09, 0.16, 0.46, 0.61, 0.67, 0.72, 0.79, 0.87, 0.98)
SIX_TABLE = (
    (1.821961, 1.769802, 1.671839, 1.357907, 1.474462, 1.562266, 1.641049, 1.744442, 1.830166,
     1.856768),
    (2.967797, 2.970199, 2.96779, 2.912569, 2.899873, 2.90316, 2.909359, 2.922075, 2.939461,
     2.960725),
    (3.005861, 3.036683, 3.069798, 3.005861, 2.910744, 2.885101, 2.873725, 2.875196, 2.900917,
     2.965712),
    (3.070395, 3.083423, 3.104273, 3.146242, 3.113295, 3.095198, 3.080659, 3.063975, 3.053722,
     3.058841),
    (1.365296, 1.372043, 1.417662, 1.790023, 1.809847, 1.763587, 1.70661, 1.610023, 1.497356,
     1.386834),
)


@pytest.mark.slow
def test_a_six_link_table_passes_the_crosscheck():
    """Every mode change of the steps located at the event-driven phases (lags 1e-3 steps)."""
    chain = Chain(**SIX)
    torque = ChainReferenceTorque(JointLinear(SIX_KNOTS, SIX_TABLE), chain)
    check = crosscheck(ChainModel(chain, "physical"), torque, steps=(40, 80))
    assert check.passed, {k: c.text() for k, c in check.checks.items() if not c.passed}


#: a three-link chain under a table whose slip of foot 2 ends at a kink (t = 0.43324) with the
#: stick's friction guard at 4e-17 there: Brent's method took that round-off for the next slip's
#: zero and the run ended as a snap-through at the kink of the second cycle
KINK_TIE_CHAIN = Chain(lengths=(0.025686364685129096, 0.03733536902880197, 0.04816448726146781),
                       masses=(0.022166092981944184, 0.022905925756199673, 0.01869849545245067),
                       stiffness=(0.3567034686639414, 0.5462805597602385),
                       mu=(0.2655635613098795, 0.29605579316246244),
                       com=(0.3040432222336807, 0.5230593368214322, 0.3666376978825706),
                       rest=(-0.07314738817412669, 0.1986484873307922))
KINK_TIE_TABLE = JointLinear(
    [0.0, 0.08369751592760977, 0.13766316714192994, 0.22020431473995072, 0.27865271766078503,
     0.43324375739575316, 0.5154254917952313],
    [[2.7886878313912025, 3.121228773856811, 3.137149278720934, 3.365332932799556,
      3.2776322037890426, 3.068894592634066, 2.7882427038718043],
     [2.446098254266591, 2.30913790280239, 2.2609222024500797, 2.0608363455200682,
      1.9474809733170746, 1.808602264154351, 1.9387861308727807]])


def test_a_slip_ending_at_a_kink_with_its_next_guard_at_round_off_continues():
    """The event after the stick that starts at the kink is the next slip at its real zero (about
    0.0499 cycles later, in both cycles alike), and the gait is a success as in the chain's
    incremental steps (an independent solver: success, W+ within 0.1 %)."""
    model = ChainModel(KINK_TIE_CHAIN)
    torque = ChainReferenceTorque(KINK_TIE_TABLE, KINK_TIE_CHAIN)
    res = simulate_chain_torque(model, torque)
    assert res.status is Status.SUCCESS, res.message
    onsets = [e.t for e in res.events if e.kind == "slip_onset_2"]
    first = [t for t in onsets if 0.4 < t < 0.5]
    second = [t for t in onsets if 1.4 < t < 1.5]
    assert len(first) == len(second) == 1 and abs(second[0] - 1 - first[0]) <= 1e-9
    steps = simulate_chain_mpcc(model, torque, steps=50)
    assert steps.status is Status.SUCCESS, steps.message
    assert abs(steps.W_plus - res.W_plus) <= 1e-3 * res.W_plus


def test_a_reversed_chain_under_the_reversed_table_mirrors_s():
    """The five-link chain read from its other end, the table's rows reversed: -S, the same W+."""
    model, _ = _five_link()
    table = _five_link_tables()["steps"]
    chain = model.chain
    res = simulate_chain_torque(model, ChainReferenceTorque(table, chain))
    back = chain.reversed()
    # (the configuration phi of the chain is phi[::-1] of the reversed one)
    mirrored = JointLinear(table.t_knots, table.values[::-1])
    rev = simulate_chain_torque(ChainModel(back, model.gravity), ChainReferenceTorque(mirrored,
                                                                                      back))
    assert res.success and rev.success, (res.message, rev.message)
    # (this gait slips foot 1 back and forth: S is zero but for the round-off of the feet's
    # positions, hence the floor of 1e-12 of the chain's length)
    assert abs(rev.S + res.S) <= 1e-9 * abs(res.S) + 1e-12 * chain.L
    assert abs(rev.W_plus - res.W_plus) <= 1e-9 * res.W_plus


def test_joint_tables_of_any_number_of_rows():
    """JointLinear: the two-row PeriodicLinear for two rows, any number of rows >= 1, and its
    shape errors name the class."""
    t = np.array([0.0, 0.3, 0.7])
    v = np.array([[1.0, 2.0, 0.5], [0.0, -1.0, 1.0]])
    a, b = JointLinear(t, v), PeriodicLinear(t, v)
    ts = np.linspace(-1.0, 2.0, 41)
    np.testing.assert_array_equal(a(ts), b(ts))
    np.testing.assert_array_equal(a.derivative(ts), b.derivative(ts))
    four = JointLinear(t, np.vstack([v, 2 * v]))
    assert four(0.15).shape == (4,) and four(ts).shape == (4, ts.size)
    np.testing.assert_allclose(four(0.15), [1.5, -0.5, 3.0, -1.0])
    with pytest.raises(ValueError, match=r"JointLinear: values must have shape \(m, 3\)"):
        JointLinear(t, np.zeros((2, 4)))
    with pytest.raises(ValueError, match=r"PeriodicLinear: values must have shape \(2, 3\)"):
        PeriodicLinear(t, np.zeros((3, 3)))
