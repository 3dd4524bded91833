"""The periodic-gait OCP of n-link chains: the paper robot as a chain of three links has the
three-link robot's optimum, a four-link optimum is confirmed by the chain's own event-driven replay
and beats the best travelling wave (checked against a grid of independent simulations), and the
problem-file layer (the envelope's centres, bad input)."""
import csv
import json
import math
from pathlib import Path

import casadi as cs
import numpy as np
import pytest

from ocp_crawl import Harmonic, ReferenceTorque, Robot
from ocp_crawl.cli import main
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_inputs import ChainReferenceTorque, JointFourier
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.ocp.chain_search import ChainWave
from ocp_crawl.ocp.plant import Plant, joint_torque_bounds
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.solve import optimize_gait
from ocp_crawl.ocp.solver import GaitSolver
from ocp_crawl.ocp.transcription import GaitOCP
from ocp_crawl.problem import ProblemError, load_problem, ocp_settings
from ocp_crawl.sim.chain_torque import simulate_chain_torque

ROBOT = Robot.paper()
THREE = Chain.from_robot(ROBOT)
#: the paper robot's body in two links: four links of 30 mm and 13 g
FOUR = Chain(lengths=(0.03,) * 4, masses=(0.013,) * 4, stiffness=(ROBOT.k,) * 3,
             mu=(ROBOT.mu1, ROBOT.mu2))
CENTRES = (90.0, 170.0, 90.0)
FILE = Path(__file__).resolve().parents[1] / "problems" / "ocp_four_links.toml"


def test_the_paper_robot_as_a_chain_has_the_three_link_nlp_and_optimum():
    """The OCP of the paper robot through the chain's statics (another symbolic model of the same
    robot) is the three-link robot's NLP with its joint heights: the same initial guess, objective,
    constraints and constraint Jacobian at the guess and at the three-link optimum (to 1e-12), the
    heights positive there; and the tightened
    NLP of either started at that optimum ends at one point (to 1e-8, IPOPT's stopping point).
    (Separate homotopies need not agree: round-off differences of 1e-14 in the two models' values
    take a nonconvex NLP to other points along the relaxation path.)"""
    settings = OCPSettings(nodes=16, A_max_deg=27.5)
    start = ReferenceTorque(Harmonic.from_degrees(90, 27.5, 20), ROBOT.k)
    T0 = settings.min_period(27.5, 27.5)
    ocp3, ocpc = (GaitOCP(r, "physical", settings) for r in (ROBOT, THREE))
    x0 = ocp3.initial_guess(start, T0)
    assert np.max(np.abs(ocpc.initial_guess(start, T0) - x0)) < 1e-12
    x3, _, failed, _ = GaitSolver(ocp3).solve(x0)
    assert failed is None and ocpc.n_joints == 2
    # the chain's NLP has the rows of its joint heights too (and joint angles up to 2 pi): the
    # three-link robot's rows compared by name, the heights positive (inactive)
    rows3, rowsc = (np.concatenate([np.arange(o.ng)[sl] for k, sl in o.slices.items()
                                    if k.startswith("g_") and k != "g_height_0"])
                    for o in (ocp3, ocpc))
    assert ocp3.nx == ocpc.nx and rows3.size == ocp3.ng
    for x in (x0, x3):
        assert ocpc.objective(x) == pytest.approx(ocp3.objective(x), rel=1e-12)
        g3, gc = (np.asarray(o._g(x)).ravel() for o in (ocp3, ocpc))
        assert np.max(np.abs(gc[rowsc] - g3[rows3])) <= 1e-12 * max(1.0, np.max(np.abs(g3)))
        assert np.min(gc[ocpc.slices["g_height_0"]]) > 0
        J3, Jc = (cs.Function("J", [o.nlp["x"]], [cs.jacobian(o.nlp["g"], o.nlp["x"])])(x)
                  for o in (ocp3, ocpc))
        J3, Jc = J3[rows3.tolist(), :], Jc[rowsc.tolist(), :]
        assert float(cs.mmax(cs.fabs(Jc - J3))) <= 1e-12 * float(cs.mmax(cs.fabs(J3)))
    # the polished point leaves the cross conditions at sigma_min: solved again it moves within
    # that slack, alike in both NLPs
    (xa, _, fa, _), (xc, _, fc, _) = (GaitSolver(o).solve_tightened(x3) for o in (ocp3, ocpc))
    assert fa is None and fc is None
    u3, uc = ocp3.unpack(xa), ocpc.unpack(xc)
    # to where IPOPT stops (tol 1e-10 on the scaled KKT conditions): S and T 2.5e-9 apart
    assert np.max(np.abs(uc["tau"] - u3["tau"])) <= 1e-8 * np.max(np.abs(u3["tau"]))
    assert uc["scen"][0]["S"] == pytest.approx(u3["scen"][0]["S"], rel=1e-8)
    assert uc["T"] == pytest.approx(u3["T"], rel=1e-8)


def test_the_joint_bounds_of_a_chain_are_each_joints_own():
    """A joint's torque range keeps its reference angle pi + rest + tau/k inside its own centre
    +- A_max; the three-link robot's is the same for both joints."""
    chain = FOUR.replace(stiffness=(0.1, 0.2, 0.3), rest=(0.0, 0.1, 0.0))
    settings = OCPSettings(A_max_deg=20.0, gamma_joints_deg=CENTRES)
    lo, hi = joint_torque_bounds(settings, chain)
    k, rest = np.array(chain.stiffness), np.array(chain.rest)
    assert np.degrees(math.pi + rest + lo / k) == pytest.approx(np.array(CENTRES) - 20.0)
    assert np.degrees(math.pi + rest + hi / k) == pytest.approx(np.array(CENTRES) + 20.0)
    with pytest.raises(ValueError, match="gamma_joints_deg has 3 angles for a robot of 4 joints"):
        joint_torque_bounds(settings, FOUR.replace(lengths=(0.03,) * 5, masses=(0.013,) * 5,
                                                   stiffness=(ROBOT.k,) * 4, com=(), rest=()))
    with pytest.raises(ValueError, match="gamma_joints_deg is a chain's"):
        joint_torque_bounds(settings, ROBOT)
    lo3, hi3 = joint_torque_bounds(OCPSettings(), ROBOT)
    assert lo3 == pytest.approx(2 * [ROBOT.k * math.radians(60 - 180)])
    assert hi3 == pytest.approx(2 * [ROBOT.k * math.radians(120 - 180)])


def test_optimize_on_the_four_link_file_is_confirmed_and_its_files_replay_it(tmp_path, capsys):
    """``optimize`` on problems/ocp_four_links.toml (three torque profiles) from a small search of
    the harmonic travelling waves (the search's own check is the heavy test below), over the file's
    friction set: success, the chain's event-driven replay within 1e-6 of the OCP (every event of this optimum on a sub-step
    boundary), inside its envelope and bandwidth, better than its start; torques.csv has a column
    per joint and ``simulate`` of the written optimal_gait.toml gives the replay's S."""
    out = tmp_path / "out"
    args = ["optimize", str(FILE), "--json", "--jobs", "1", "--out", str(out)]
    for key in ("nodes=20", "A_max_deg=27.5", "harmonic_A=1", "harmonic_psi=4",
                "baseline_evaluations=8", "baselines=harmonic"):
        args += ["--set", f"ocp.{key}"]
    assert main(args) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["status"] == "success" and res["rel_diff_replay"] <= 1e-6
    assert res["envelope_excess"] <= 1e-9 and res["rate_ratio"] <= 1 + 1e-9
    assert [r["shape"] for r in res["baselines"]] == ["harmonic"]
    assert res["gain"] > res["replay_tol"]
    with open(out / "torques.csv", newline="") as fh:
        header = next(csv.reader(row for row in fh if not row.startswith("#")))
    assert header == ["phase [-]", "tau1 [N m]", "tau2 [N m]", "tau3 [N m]", "period [s]"]
    assert main(["simulate", str(out / "optimal_gait.toml"), "--json"]) == 0
    sim = json.loads(capsys.readouterr().out)
    # optimal_gait.toml drives the file's own robot: the friction set's middle scenario
    [S] = [s["S_replay"] for s in res["scenarios"] if s["mu1_mu2"] == 1]
    assert sim["S"] == pytest.approx(S, rel=1e-9)


def test_a_start_of_another_robot_is_bad_input(tmp_path, capsys):
    """``optimize --start`` with the three-link robot's gait for a chain of four links: exit 2, one
    line naming the start file and both joint counts."""
    start = tmp_path / "start.toml"
    paper = (FILE.parent / "paper_gait.toml").read_text()
    start.write_text(paper.replace('[gait]\n', '[gait]\nperiod = 0.5\n', 1))
    assert main(["optimize", str(FILE), "--start", str(start), "--jobs", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "start.toml" in err[0] and "3 joints, got 2" in err[0], err


@pytest.mark.heavy
def test_a_four_link_optimum_is_confirmed_by_its_replay_and_beats_every_wave_of_a_grid():
    """max_speed on four links (three torque profiles): success, the chain's event-driven replay
    within 1e-6 of the OCP (every event of this optimum on a sub-step boundary), inside its
    envelope and bandwidth; its harmonic travelling-wave baseline is at least the best of a grid of
    the family simulated here (JointFourier through the chain's torque drive), and the optimum
    beats the best travelling wave of both shapes."""
    settings = OCPSettings(nodes=20, A_max_deg=27.5, gamma_joints_deg=CENTRES, starts=1,
                           harmonic_A=3, harmonic_psi=12, baseline_starts=1,
                           baseline_evaluations=30)
    res = optimize_gait(FOUR, "physical", settings, jobs=1)
    assert res.success, res.message
    assert res.tau.shape == (3, 20) and res.rel_diff_replay <= 1e-6
    assert res.envelope_excess <= 1e-9 and res.rate_ratio <= 1 + 1e-9
    base = res.harmonic
    assert base is not None and base.feasible
    model = ChainModel(FOUR)
    grid = []
    for A in (27.5 / 3, 2 * 27.5 / 3, 27.5):
        for psi in (10.0, 30.0, 60.0):
            lead = np.radians([psi, 0.0, -psi])
            gait = JointFourier.harmonic(np.radians(CENTRES), np.full(3, math.radians(A)), lead)
            run = simulate_chain_torque(model, ChainReferenceTorque(gait, FOUR))
            if run.success:
                grid.append(-run.S / (2 * math.pi * A / settings.max_rate_deg_s))
    assert grid and base.value >= max(grid) - 1e-9
    best = res.baselines.best
    assert set(res.baselines.choices) == {"harmonic", "triangle"} and best.value >= base.value
    assert res.value_replay > best.value * (1 + settings.replay_tol)


def test_a_travelling_wave_is_the_chain_gait_of_the_same_keys():
    """The family's member is the gait a chain's [gait] section of the same centres, amplitude and
    psi describes."""
    settings = OCPSettings(A_max_deg=27.5, gamma_joints_deg=CENTRES)
    wave = ChainWave(20.0, 25.0)
    problem = load_problem(FILE, overrides=[
        "gait.A_joints_deg=[20.0, 20.0, 20.0]", "gait.psi_deg=25.0"])
    t = np.linspace(0, 1, 11)
    assert wave.gait(settings, FOUR)(t) == pytest.approx(problem.gait(t), abs=1e-12)
    assert wave.period(settings) == pytest.approx(2 * math.pi * 20.0 / 180.0)


def test_the_four_link_file_centres_the_envelope_on_its_gait():
    """ocp_settings of a chain: the envelope's centre of each joint is its gait's mean; an envelope
    outside (0, 360) deg and the MuJoCo check are bad input."""
    settings = ocp_settings(load_problem(FILE))
    assert settings.gamma_joints_deg == pytest.approx(CENTRES, abs=1e-9)
    with pytest.raises(ProblemError, match=r"A_max_deg = 80.0 with the \[gait\] centre of "
                                           r"joint 2, 70 deg, is invalid.*\(here -10 to 150\)"):
        ocp_settings(load_problem(FILE, overrides=[
            "ocp.A_max_deg=80.0", "gait.gamma_joints_deg=[120.0, 70.0, 120.0]",
            "gait.A_joints_deg=[5.0, 5.0, 5.0]"]))
    with pytest.raises(ProblemError, match="MuJoCo models the three-link robot only"):
        ocp_settings(load_problem(FILE, overrides=["ocp.dynamic_margin=2.0"]))


def test_a_plant_simulates_with_the_robots_own_stepper():
    """The OCP's Plant of a chain runs the chain's torque stepper, of the three-link robot the
    three-link one: the paper robot both ways gives one S."""
    torque = ReferenceTorque(Harmonic.from_degrees(90, 30, 45), ROBOT.k)
    s3 = Plant(ROBOT).simulate(torque)
    sc = Plant(THREE).simulate(torque)
    assert s3.success and sc.success and sc.S == pytest.approx(s3.S, rel=1e-9)


def test_the_polish_skips_ties_that_would_move_a_margin_far():
    """GaitSolver._polish_candidates: with the ties fixed first and the branches alone second,
    unless fixing the ties moves a variable of the point by more than TIE_GAP (then the branches
    alone); one candidate where both are the same NLP."""
    from ocp_crawl.ocp import solver as solver_module

    x = np.array([0.3, 5e-6, 0.2])
    alone = np.array([np.inf, np.inf, np.inf])
    cases = {"near": np.array([np.inf, 0.0, np.inf]), "far": np.array([0.0, 0.0, np.inf]),
             "same": alone}
    solver = solver_module.GaitSolver.__new__(solver_module.GaitSolver)
    for name, tied in cases.items():
        solver._polish_data = lambda x, ties=True, tied=tied: {"ubx": tied if ties else alone}
        got = [c["ubx"] for c in solver._polish_candidates(x)]
        want = {"near": [tied, alone], "far": [alone], "same": [alone]}[name]
        assert len(got) == len(want) and all(np.array_equal(g, w) for g, w in zip(got, want))
    assert solver_module.TIE_GAP < 0.3 and 5e-6 < solver_module.TIE_GAP


def test_a_chain_start_that_fails_is_a_status_with_a_torque_row_per_joint():
    """solve_from with a start the chain's simulator cannot follow (torques that fold the chain
    onto the ground): NO_INITIAL_GUESS with the simulator's message, its (empty) torques of three
    rows, so that its torques.csv names tau1..tau3."""
    from ocp_crawl.ocp.solve import solve_from
    from ocp_crawl.viz.ocp import torques_csv

    settings = OCPSettings(nodes=8, A_max_deg=27.5, gamma_joints_deg=CENTRES)
    solver = GaitSolver(GaitOCP(FOUR, "physical", settings))
    crushing = ChainReferenceTorque(JointFourier.harmonic(np.radians([90.0, 300.0, 90.0]),
                                                          np.radians([1.0, 1.0, 1.0]),
                                                          np.zeros(3)), FOUR)
    res = solve_from(solver, [Plant(FOUR)], crushing, 0.5)
    assert res.status.label == "no_initial_guess" and "fails in the simulator" in res.message
    assert res.tau.shape == (3, 0)
    assert "tau3 [N m]" in torques_csv(res)
