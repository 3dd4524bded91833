"""A chain of n links in a problem file ([robot] lengths, masses, stiffness): the paper's robot
written as a three-link chain gives the three-link robot's results through every solver and
command that takes a chain; the shipped five-link file simulates, cross-checks, sweeps and
animates; a reversed chain mirrors S; the commands that model the three-link robot only say so
(tests/_bad_input_rows.py)."""
import csv
import json
import tomllib

import numpy as np
import pytest

from ocp_crawl.cli import main
from ocp_crawl.model.chain import Chain
from ocp_crawl.problem import ProblemError, load_problem, problem_from_dict, run_problem
from ocp_crawl.problem.overrides import read_toml

from _bad_input_rows import CHAIN, PAPER

#: the paper's robot (Table I) as a three-link chain: legs l = L / 4, body 2 l, uniform mass
PAPER_AS_CHAIN = """
[robot]
lengths = [0.03, 0.06, 0.03]
masses = [0.013, 0.026, 0.013]
stiffness = [0.1677, 0.1677]
mu = 0.389

[gait]
gamma_deg = 90.0
A_deg = 30.0
psi_deg = 45.0
"""


def _pair(overrides=()):
    three = load_problem(PAPER, list(overrides))
    chain = problem_from_dict(tomllib.loads(PAPER_AS_CHAIN), overrides=list(overrides))
    return three, chain


@pytest.mark.parametrize("overrides", [
    [], ["model.gravity=paper"], ["gait.drive=angles"], ["gait.psi_deg=-30", "robot.mu=0.3"],
    ["simulation.solver=mpcc", "simulation.steps=40"]],
    ids=["event", "paper gravity", "angles", "psi -30", "mpcc"])
def test_the_paper_robot_as_a_chain_is_the_three_link_robot(overrides):
    """Two simulators each (the three-link robot's and the chain's, separate code): the same S, W+,
    CoT+ and events."""
    three, chain = _pair(overrides)
    assert isinstance(chain.robot, Chain) and chain.robot.n == 3
    assert chain.solver == three.solver and chain.drive == three.drive
    a, b = run_problem(three), run_problem(chain)
    assert a.success and b.success, (a.message, b.message)
    # the three-link time-stepping's IPOPT steps carry their tolerance (|dS|/|S| <= 2e-8,
    # docs/guide/simulators.md); the chain's steps are Newton solves of the enumerated modes,
    # exact to the event-driven S
    rel = 2e-8 if three.solver == "mpcc" else 1e-9
    assert b.S == pytest.approx(a.S, rel=rel, abs=1e-15)
    assert b.W_plus == pytest.approx(a.W_plus, rel=rel)
    assert b.CoT_plus == pytest.approx(a.CoT_plus, rel=rel)
    if three.solver == "mpcc":
        exact = run_problem(three.with_values({"simulation.solver": "event"}))
        assert b.S == pytest.approx(exact.S, rel=1e-9)
    ea, eb = a.steady_events(), b.steady_events()
    assert [(e.mode_before, e.mode_after) for e in ea] == [(e.mode_before, e.mode_after)
                                                           for e in eb]
    np.testing.assert_allclose([e.t - b.t0 for e in eb], [e.t - a.t0 for e in ea], atol=1e-9)


def test_a_chain_problem_round_trips_through_its_dict():
    problem = load_problem(CHAIN)
    again = problem_from_dict(problem.to_dict())
    assert again == problem and "beta" not in problem.to_dict()["robot"]
    np.testing.assert_array_equal(again.torque(np.linspace(0, 1, 7)),
                                  problem.torque(np.linspace(0, 1, 7)))
    given = problem_from_dict(problem.given_dict())
    assert given.robot == problem.robot


def _reversed_text() -> dict:
    """problems/five_link_chain.toml read from foot 2: every list reversed, the centres of mass
    measured from the other end, the feet swapped and the joints' phase lead negated."""
    data = read_toml(CHAIN)
    r, g = data["robot"], data["gait"]
    for key in ("lengths", "masses", "stiffness", "rest_deg"):
        r[key] = r[key][::-1]
    r["com"] = [1.0 - c for c in r["com"][::-1]]
    r["mu1"], r["mu2"] = r["mu2"], r["mu1"]
    for key in ("gamma_joints_deg", "A_joints_deg"):
        g[key] = g[key][::-1]
    g["psi_deg"] = -g["psi_deg"]
    return data


@pytest.mark.parametrize("drive", ["torque", "angles"])
def test_the_reversed_chain_mirrors_S(drive):
    problem = load_problem(CHAIN, [f"gait.drive={drive}"])
    mirror = problem_from_dict(_reversed_text(), overrides=[f"gait.drive={drive}"])
    assert mirror.robot == problem.robot.reversed()
    a, b = run_problem(problem), run_problem(mirror)
    assert a.success and b.success, (a.message, b.message)
    assert b.S == pytest.approx(-a.S, rel=1e-9) and abs(a.S) > 1e-3
    assert b.W_plus == pytest.approx(a.W_plus, rel=1e-9)


@pytest.mark.slow
def test_the_five_link_file_through_every_command_that_takes_a_chain(tmp_path, capsys):
    """simulate (text, JSON, --out with its figure), crosscheck PASS at 50 and 100 steps, a sweep
    whose point equals the simulation, an animation."""
    assert main(["simulate", str(CHAIN), "--json", "--out", str(tmp_path / "sim")]) == 0
    sim = json.loads(capsys.readouterr().out)
    assert sim["success"] and sim["S"] < -1e-3 and len(sim["W_plus_joint"]) == 4
    assert {p.name for p in (tmp_path / "sim").iterdir()} >= {"gait.png", "summary.json"}

    assert main(["crosscheck", str(CHAIN), "--steps", "50", "100", "--json"]) == 0
    check = json.loads(capsys.readouterr().out)
    assert check["passed"] is True, check["checks"]
    assert all(r["rel_diff_S"] <= 1e-9 for r in check["per_steps"])

    assert main(["sweep", str(CHAIN), "--grid", "gait.psi_deg=10,20", "--out",
                 str(tmp_path / "sweep"), "--jobs", "1", "--no-progress"]) == 0
    capsys.readouterr()
    with open(tmp_path / "sweep" / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [float(r["gait.psi_deg [deg]"]) for r in rows] == [10.0, 20.0]
    assert float(rows[1]["S [m]"]) == pytest.approx(sim["S"], rel=1e-12)

    for solver in ("event", "mpcc"):   # (the animation samples the steady cycle densely)
        gif = tmp_path / f"crawl_{solver}.gif"
        assert main(["animate", str(CHAIN), "--out", str(gif), "--cycles", "1",
                     "--frames-per-cycle", "4", "--set", f"simulation.solver={solver}",
                     "--set", "simulation.steps=40"]) == 0
        assert gif.read_bytes()[:6] == b"GIF89a"


def test_the_chain_steps_sampled_at_phases_interpolate_the_steps():
    """t_eval of the chain's time-stepping: the step samples interpolated linearly, as the
    three-link time-stepping's; the events it located on the steps, at the event-driven phases."""
    problem = load_problem(CHAIN, ["simulation.solver=mpcc", "simulation.steps=50"])
    steps = run_problem(problem)
    te = np.linspace(0.0, 1.0, 37)
    sampled = run_problem(problem, t_eval=te)
    assert steps.success and sampled.success
    np.testing.assert_allclose(sampled.t - sampled.t0, te, atol=1e-12)
    for j in range(4):
        np.testing.assert_allclose(sampled.phi[j], np.interp(sampled.t, steps.t, steps.phi[j]))
    np.testing.assert_allclose(sampled.x1, np.interp(sampled.t, steps.t, steps.x1))
    assert sampled.S == steps.S
    exact = run_problem(load_problem(CHAIN))
    located = [e for e in steps.steady_events()]
    assert [e.guard_name for e in located] == ["step_split"] * len(located)
    np.testing.assert_allclose([e.t - steps.t0 for e in located],
                               [e.t - exact.t0 for e in exact.steady_events()], atol=1e-8)


def test_an_entry_of_an_array_set_as_the_file_would_set_it():
    """``--set robot.stiffness[1]=0.5`` and ``with_values({"robot.stiffness[1]": 0.5})`` are the
    file with that entry changed; an entry set twice to two values is refused."""
    data = read_toml(CHAIN)
    data["robot"]["stiffness"][1] = 0.5
    edited = problem_from_dict(data, source=str(CHAIN))
    assert load_problem(CHAIN, ["robot.stiffness[1]=0.5"]) == edited
    assert load_problem(CHAIN).with_values({"robot.stiffness[1]": 0.5}) == edited
    assert edited.robot.stiffness == (0.17, 0.5, 0.25, 0.2)
    with pytest.raises(ProblemError, match=r"robot.stiffness\[1\] is set twice"):
        load_problem(CHAIN, ["robot.stiffness[1]=0.5", "robot.stiffness[1]=0.4"])


def test_a_sweep_over_an_entry_gives_the_simulations_of_its_values(tmp_path, capsys):
    values = (0.2, 0.4)
    assert main(["sweep", str(CHAIN), "--grid", "robot.stiffness[1]=0.2,0.4", "--out",
                 str(tmp_path / "sweep"), "--jobs", "1", "--no-progress"]) == 0
    capsys.readouterr()
    with open(tmp_path / "sweep" / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [float(r["robot.stiffness[1] [N m/rad]"]) for r in rows] == list(values)
    for row, value in zip(rows, values):
        alone = run_problem(load_problem(CHAIN, [f"robot.stiffness[1]={value}"]))
        assert float(row["S [m]"]) == pytest.approx(alone.S, rel=1e-12, abs=1e-15)


#: a soft four-link chain whose foot 2 lifts off at phase 0.644 (a guard's event: the two-contact
#: model ends there)
LIFTS = """
[robot]
lengths = [0.03, 0.03, 0.03, 0.03]
masses = [0.013, 0.013, 0.013, 0.013]
stiffness = [0.05, 0.05, 0.05]
mu = 0.389

[gait]
psi_deg = 45.0
gamma_joints_deg = [90.0, 170.0, 90.0]
A_joints_deg = [30.0, 10.0, 30.0]
"""


def test_a_failed_chain_run_is_a_status_in_simulate_and_animate(tmp_path, capsys):
    """The chain's failure carries no samples: animate says so (exit 1) and writes nothing."""
    path = tmp_path / "lifts.toml"
    path.write_text(LIFTS)
    assert main(["simulate", str(path), "--json"]) == 1
    assert json.loads(capsys.readouterr().out)["status_name"] == "lift_off"
    gif = tmp_path / "crawl.gif"
    assert main(["animate", str(path), "--out", str(gif), "--cycles", "1",
                 "--frames-per-cycle", "4"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nothing written" in err and "lifts off" in err
    assert not gif.exists()
