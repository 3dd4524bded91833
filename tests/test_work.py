"""The work estimates of ocp_crawl.problem.work: bounds of the runs they size, refusals, notices.

The estimates are counts (steps, cycles, points, rows) times a cost per unit; the unit costs are
machine-dependent and live in scripts/bench.py ``work``, so these tests check the counts: an upper
bound of the steps the solver reports it took, the sizing axis a sweep is charged for, the scaling
with each count, and what the commands do with an estimate (refuse above --max-hours, announce
above a minute).  The refusals of each command are rows of the bad-input matrix.
"""
import math
from dataclasses import replace
from pathlib import Path

import pytest

from ocp_crawl import load_problem, problem_from_dict, run_problem
from ocp_crawl.cli import main
from ocp_crawl.problem.run import ocp_settings
from ocp_crawl.problem.work import (DEFAULT_MAX_HOURS, EVENT_STEPS, EVENT_STEPS_TYPICAL,
                                    TYPICAL_CYCLES, UNIT_COST, Work, WorkLimit, codesign_work,
                                    fit_work, optimize_work, simulation_work, sweep_work)

PROBLEMS = Path(__file__).resolve().parent.parent / "problems"


def problem(name: str, *overrides: str):
    return load_problem(PROBLEMS / name, overrides=list(overrides))


@pytest.mark.slow
@pytest.mark.parametrize("name, overrides, unit", [
    ("paper_gait.toml", (), "event_step"),
    ("pulse_gait.toml", (), "event_step"),
    ("paper_gait.toml", ("simulation.max_step=1e-3",), "event_step"),
    ("paper_gait.toml", ("simulation.solver=mpcc", "simulation.steps=50"), "mpcc_step"),
    ("paper_gait.toml", ("simulation.solver=mujoco", "simulation.period=1"), "mujoco_step"),
])
def test_the_estimate_bounds_the_steps_the_solver_takes(name, overrides, unit):
    p = problem(name, *overrides)
    work = simulation_work(p)
    result = run_problem(p)
    assert result.success, result.message
    setup = UNIT_COST["mpcc_setup"] if unit == "mpcc_step" else 0.0
    steps = (work.seconds - setup) / UNIT_COST[unit]
    assert steps >= result.nsteps and work.typical < work.seconds
    # with every cycle run the bound is reached, so it is not loose by more than the cycles it
    # allows
    assert steps <= p.options.max_cycles * max(result.nsteps / result.cycles, 1000) * 10


def test_a_chains_event_work_grows_with_its_links_and_its_cycles():
    five = problem("five_link_chain.toml")
    three = problem_from_dict({"robot": {"lengths": [0.03, 0.06, 0.03],
                                         "masses": [0.013, 0.026, 0.013],
                                         "stiffness": [0.1677, 0.1677], "mu": 0.389},
                               "gait": {"gamma_deg": 90.0, "A_deg": 30.0, "psi_deg": 45.0}})
    w5, w3 = simulation_work(five), simulation_work(three)
    assert w5.typical / w3.typical == pytest.approx(5 / 3, rel=1e-12)
    assert w5.seconds / w5.typical == pytest.approx(
        five.options.max_cycles * EVENT_STEPS / EVENT_STEPS_TYPICAL / TYPICAL_CYCLES, rel=1e-12)
    longer = simulation_work(five.with_values({"simulation.max_cycles": 24}))
    assert longer.seconds == pytest.approx(2 * w5.seconds, rel=1e-12)
    assert "5 links" in w5.detail and w5.keys == ("simulation.max_cycles",)


def test_mpcc_work_grows_with_steps_times_cycles():
    def mpcc(*overrides):
        return simulation_work(problem("paper_gait.toml", "simulation.solver=mpcc", *overrides))

    base, finer = mpcc("simulation.steps=100"), mpcc("simulation.steps=200")
    more = mpcc("simulation.steps=100", "simulation.max_cycles=24")
    setup = UNIT_COST["mpcc_setup"]
    assert more.seconds - setup > 1.8 * (base.seconds - setup)
    assert finer.seconds - setup == pytest.approx(2 * (base.seconds - setup), rel=0.01)


def test_check_refuses_above_the_limit_and_names_what_sizes_the_work():
    work = Work(3 * 3600.0, "MPCC 10000 steps x 500 cycles",
                ("simulation.steps", "simulation.max_cycles"))
    with pytest.raises(WorkLimit, match=r"about 3 h .*simulation\.steps, simulation\.max_cycles.*"
                                        r"--max-hours 3"):
        work.check()
    assert DEFAULT_MAX_HOURS < 3
    work.check(3.0)
    work.check(math.inf)
    with pytest.raises(WorkLimit, match="limit of 36 s"):
        Work(60.0, "x").check(0.01)


def test_a_sweep_is_charged_for_its_costliest_sizing_axis():
    p = problem("paper_gait.toml")
    grid = {"simulation.solver": ["event", "mpcc"], "gait.psi_deg": [10.0, 20.0, 30.0]}
    mpcc = simulation_work(problem("paper_gait.toml", "simulation.solver=mpcc"))
    for jobs in (1, 2):
        assert sweep_work(p, grid, jobs).seconds == pytest.approx(6 * mpcc.seconds / jobs)
    event_only = sweep_work(p, {"gait.psi_deg": [10.0, 20.0, 30.0]})
    assert event_only.seconds == pytest.approx(3 * simulation_work(p).seconds)


def test_fit_and_optimize_work_scale_with_their_counts():
    p = problem("paper_gait.toml")
    assert fit_work(p, 20, 100, 1).seconds == pytest.approx(2 * fit_work(p, 10, 100, 1).seconds)
    assert fit_work(p, 20, 100, 2).seconds == pytest.approx(1.5 * fit_work(p, 20, 100, 1).seconds)
    ocp = problem("ocp_max_speed.toml")
    settings = ocp_settings(ocp)
    one, two = optimize_work(ocp, settings, [50]), optimize_work(ocp, settings, [50, 100])
    assert one.typical == one.seconds and one.text.startswith("about ")
    assert "N = 50+100" in two.detail
    # the solves' work is linear in the nodes summed over the counts (one baseline search)
    hundred = optimize_work(ocp, settings, [100])
    assert two.seconds - one.seconds == pytest.approx(2 * (hundred.seconds - one.seconds))


@pytest.mark.parametrize("name", ["ocp_max_speed.toml", "ocp_four_links.toml"])
def test_optimize_work_counts_tightened_starts_and_the_families_searched_first(name):
    """With tightened starts every family is searched before the solve (three for the three-link
    robot, a chain's two travelling waves), and there is one start per family: the estimate names
    those counts, the search's part grows by the number of families, and "both" adds tightened
    starts to the homotopy's."""
    from ocp_crawl.ocp.chain_search import family_shapes

    p = problem(name)
    settings = ocp_settings(p)
    shapes = family_shapes(settings, p.is_chain)
    assert len(shapes) == (2 if p.is_chain else 3)
    homotopy, tightened, both = (optimize_work(p, replace(settings, start_solve=how))
                                 for how in ("homotopy", "tightened", "both"))
    assert f"{len(shapes)} starts x" in tightened.detail
    assert f"{len(shapes)} tightened starts" in both.detail
    assert both.seconds > homotopy.seconds
    members = [int(w.detail.split("; ")[-1].split()[0]) for w in (homotopy, tightened)]
    assert members[1] == len(shapes) * members[0]


def test_codesign_work_counts_its_designs_on_the_workers_and_its_rounds():
    from ocp_crawl.problem.codesign import design_of

    p = problem("codesign_stiffness.toml")
    settings, design = ocp_settings(p), design_of(p)

    def seconds(scan, rounds, jobs):
        return codesign_work(p, settings, design, scan, rounds, jobs).seconds
    # the scan: linear in the designs per worker; the rounds: linear in their count
    assert seconds(16, 4, 2) - seconds(8, 4, 2) == pytest.approx(seconds(16, 4, 2)
                                                                  - seconds(16, 4, 4))
    assert seconds(8, 6, 2) - seconds(8, 4, 2) == pytest.approx(seconds(8, 4, 2)
                                                                 - seconds(8, 2, 2))
    # each round moves the two free stiffnesses either way, then solves the co-design NLP
    text = codesign_work(p, settings, design, 8, 4, 2).detail
    assert "8 designs / 2 workers" in text and "23 OCP solves (2 free variables, 4 rounds)" in text


def test_a_long_run_is_announced_before_it_starts(capsys, monkeypatch):
    import ocp_crawl.problem.work as work

    # a typical run of 3 cycles of 10^4 steps, above a threshold of 1 s (a minute by default)
    monkeypatch.setattr(work, "ANNOUNCE_SECONDS", 1.0)
    code = main(["simulate", str(PROBLEMS / "paper_gait.toml"), "--set", "simulation.max_step=1e-4",
                 "--set", "simulation.max_cycles=500", "--json"])
    err = capsys.readouterr().err
    assert code == 0
    assert err.startswith("ocp-crawl: estimated about ") and ", up to " in err
    assert "1e+04 steps x 500 cycles" in err and len(err.splitlines()) == 1
