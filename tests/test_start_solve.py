"""How the starts are solved (``OCPSettings.start_solve``): the homotopy, the tightened NLP from
every waveform family's best member, or both.

The judge of every optimum is the event-driven replay of its torques; the families' best members
are simulated by the baselines' search, independently of the OCP."""
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl import Robot
from ocp_crawl.model.chain import Chain
from ocp_crawl.ocp import optimize_gait
from ocp_crawl.ocp.baseline import Baselines
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.starts import family_starts
from ocp_crawl.problem import load_problem, ocp_settings
from ocp_crawl.status import Status

ROOT = Path(__file__).resolve().parents[1]
#: a small search of every family: the test's cost is the OCP's
SMALL = dict(objective="max_speed", nodes=16, starts=1, harmonic_A=2, harmonic_psi=12,
             baseline_samples=8, baseline_starts=1, baseline_evaluations=30)


@pytest.fixture(scope="module")
def both_run():
    """max_speed on the paper robot over mu1/mu2 = 0.95, 1, 1.05 (the worst; at one friction the
    families' best members ride a friction tie), N = 16: the homotopy from the harmonic baseline,
    then the tightened NLP from each family's best member (in a forked process, with the search of
    the families other than the harmonic one); and the IPOPT iterations this process's observers
    were told of (the progress bar)."""
    from ocp_crawl.nlp.homotopy import observe

    seen: list = []
    settings = OCPSettings(**SMALL, start_solve="both", mu_ratio_eps=0.05, robust="worst")
    with observe(lambda stage: seen.append(stage.iterations)):
        res = optimize_gait(Robot.paper(), "physical", settings, jobs=1)
    return res, sum(seen)


@pytest.fixture(scope="module")
def both(both_run):
    return both_run[0]


def _best_success(res) -> float:
    return max(s.value_replay for s in res.starts if s.status == Status.SUCCESS)


@pytest.mark.slow
def test_both_paths_are_at_least_the_homotopy_and_report_every_start(both_run):
    """"both" solves the harmonic baseline by the homotopy, then the tightened NLP from each
    distinct family's best member: the reported optimum is the best of them by replay, so at least
    the homotopy's; every start is in the record, and every start's IPOPT calls reached this
    process's observers (those of the forked process's starts included)."""
    both, observed = both_run
    assert both.success, both.message
    assert observed == sum(s.iterations for s in both.starts) > both.starts[0].iterations
    labels = [s.label for s in both.starts]
    assert labels[:2] == ["harmonic baseline", "harmonic baseline, tightened"]
    assert all(label.endswith(", tightened") for label in labels[1:])
    shapes = [label.split(" ")[0] for label in labels[1:]]
    assert len(set(labels)) == len(labels) and set(shapes) <= {"harmonic", "triangle", "pulse"}
    assert both.starts[0].status == Status.SUCCESS
    assert both.value_replay == _best_success(both) >= both.starts[0].value_replay


@pytest.mark.slow
def test_every_tightened_start_is_judged(both):
    """Each tightened start is a local search around its member's contact pattern: a success is
    confirmed by its replay (within replay_tol of the OCP; the reported one's within 1e-6), a
    failure is a status with a message (over a friction set a member on the set's edge may end at
    a friction tie, which its replay refuses as ambiguous), never a success."""
    assert both.rel_diff_replay <= 1e-6
    tol = both.settings.replay_tol
    for s in both.starts[1:]:
        if s.status == Status.SUCCESS:
            assert abs(s.value_ocp - s.value_replay) <= tol * abs(s.value_replay), s.label
        else:
            assert s.message and not math.isfinite(s.value_replay), s.label


def test_equal_members_give_one_start():
    """A pulse of rise 0.5 is the triangle: the same node profile and period (up to round-off)
    start once; a pulse of another rise, or of a centre 1e-6 deg away, is a start of its own."""
    settings = OCPSettings(**SMALL)
    robot = Robot.paper()
    from ocp_crawl.ocp.search import best_baselines

    base = best_baselines(robot, "physical", settings, ("triangle",), jobs=1)
    tri = base.choices["triangle"]
    twin = Baselines(settings.objective,
                     {"triangle": tri, "pulse": replace(tri, shape="pulse", rise=0.5)}, 0.0)
    starts = family_starts(twin, settings, robot)
    assert [s.label for s in starts] == ["triangle baseline, tightened"]
    other = Baselines(settings.objective,
                      {"triangle": tri, "pulse": replace(tri, shape="pulse", rise=0.3, duty=0.5)},
                      0.0)
    assert [s.family for s in family_starts(other, settings, robot)] == ["triangle", "pulse"]
    # a centre moved by 1e-13 deg is the same gait up to round-off; by 1e-6 deg another one
    for shift, count in ((1e-13, 1), (1e-6, 2)):
        moved = replace(tri, shape="pulse", rise=0.5, gamma1_deg=tri.gamma1_deg + shift)
        starts = family_starts(Baselines(settings.objective, {"triangle": tri, "pulse": moved},
                                         0.0), settings, robot)
        assert len(starts) == count, shift
    phase = np.arange(settings.nodes) / settings.nodes
    nodes = np.asarray(tri.signal_for(robot, settings)(phase)).reshape(2, -1)
    assert np.max(starts[0].tau[0]) == starts[0].tau[0, 0]  # pinned at the largest tau_1
    assert sorted(starts[0].tau.ravel()) == sorted(nodes.ravel())  # the same nodes, shifted


def test_a_member_also_starts_from_its_best_node_phase():
    """With the scenarios' models a member starts also from its best sub-node sampling: a profile
    whose nodes are the member's signal at phases k/N + j/(4N), j > 0 (computed here), pinned,
    whose worst speed over the friction set, simulated here, beats the k/N start's."""
    from ocp_crawl.model.sampled import PeriodicLinear
    from ocp_crawl.ocp.baseline import WaveChoice
    from ocp_crawl.ocp.plant import Plant
    from ocp_crawl.sim.event import simulate_torque

    robot = Robot.paper()
    settings = OCPSettings(**dict(SMALL, nodes=50), mu_ratio_eps=0.05, robust="worst")
    models = [Plant(r, "physical") for r in settings.scenarios(robot)]
    # the best triangle wave of problems/ocp_max_speed.toml over its friction set
    tri = WaveChoice(82.91864402563719, 83.08186189182614, 22.896660587780147,
                     22.89613070117422, 22.271909603966897, 4 * 22.896660587780147 / 180.0, [],
                     [], [], [], 0.0, True, "max_speed", shape="triangle")
    starts = family_starts(Baselines(settings.objective, {"triangle": tri}, 0.0), settings,
                           robot, models=models)
    assert [s.label for s in starts] == ["triangle baseline, tightened",
                                         "triangle baseline, best node phase, tightened"]
    N = settings.nodes
    phase = np.arange(N) / N
    signal = tri.signal_for(robot, settings)
    shifted = [np.asarray(signal(np.mod(phase + j / (4 * N), 1.0)), float).reshape(2, N)
               for j in range(4)]
    assert any(np.allclose(starts[1].tau, np.roll(t, -int(np.argmax(t[0])), axis=1),
                           rtol=0.0, atol=1e-15) for t in shifted[1:])

    def worst(tau):
        return min(-simulate_torque(m.model, PeriodicLinear(phase, tau)).S for m in models)
    assert worst(starts[1].tau) > worst(starts[0].tau)


@pytest.mark.slow
def test_a_chain_solves_its_travelling_waves_tightened():
    """"tightened" on a chain: its families (travelling waves, harmonic and triangle) searched
    before the solve, each best member a tightened start, no homotopy; the optimum the chain's
    replay confirms."""
    robot = Robot.paper()
    chain = Chain(lengths=(0.03,) * 4, masses=(0.013,) * 4, stiffness=(robot.k,) * 3,
                  mu=(robot.mu1, robot.mu2))
    settings = OCPSettings(nodes=12, A_max_deg=27.5, starts=1, harmonic_A=2, harmonic_psi=6,
                           baseline_starts=1, baseline_evaluations=12, start_solve="tightened",
                           gamma_joints_deg=(90.0, 170.0, 90.0))
    res = optimize_gait(chain, "physical", settings, jobs=1)
    assert set(res.baselines.choices) == {"harmonic", "triangle"}
    assert [s.label for s in res.starts][0] == "harmonic baseline, tightened"
    assert all(s.label.endswith(", tightened") for s in res.starts)
    assert not any(h.kind == "homotopy" for h in res.homotopy)
    assert res.success, res.message
    assert res.rel_diff_replay <= 1e-6


def test_start_solve_is_one_of_its_choices():
    with pytest.raises(ValueError, match="start_solve"):
        OCPSettings(start_solve="fast")


@pytest.mark.heavy
def test_min_cot_over_a_friction_set_converges_from_tightened_starts():
    """min_cot over mu1/mu2 in {0.95, 1, 1.05} (the worst; the shipped file, 2
    to 5 min on 2 cores), where the homotopy does not converge: success from tightened starts, each
    scenario's replay within replay_tol of speed_min or faster, and the worst CoT+ at most the best
    family member's over the same set."""
    problem = load_problem(ROOT / "problems" / "ocp_min_cot.toml")
    settings = ocp_settings(problem)
    res = optimize_gait(problem.robot, problem.gravity, settings)
    assert res.success, res.message
    tol = settings.replay_tol
    assert min(res.v_replay) >= settings.speed_min * (1 - tol)
    assert res.value_replay == max(res.CoT_plus_replay)
    best = res.baselines.best
    assert best is not None and best.feasible and res.value_replay <= best.value


@pytest.mark.slow
def test_tightened_starts_in_parallel_are_those_one_after_the_other(monkeypatch):
    """The tightened starts are solved two at a time (the second half in a forked process, with more
    than one job); where no process can be forked they run one after the other here: the same
    starts, statuses and values to the last digit.  Either way every start's IPOPT calls reach
    this process's observers (the progress bar)."""
    from ocp_crawl import workers
    from ocp_crawl.nlp.homotopy import observe

    settings = OCPSettings(**dict(SMALL, nodes=12), start_solve="tightened")

    def observed() -> tuple:
        seen: list = []
        with observe(lambda stage: seen.append(stage.iterations)):
            res = optimize_gait(Robot.paper(), "physical", settings, jobs=2)
        return res, sum(seen)
    forked, seen_forked = observed()
    monkeypatch.setattr(workers, "mp_context",
                        lambda: workers.multiprocessing.get_context("spawn"))
    here, seen_here = observed()
    assert len(forked.starts) >= 2
    assert ([(s.label, s.status, s.value_replay) for s in forked.starts]
            == [(s.label, s.status, s.value_replay) for s in here.starts])
    assert np.array_equal(forked.tau, here.tau)
    assert seen_forked == seen_here == sum(s.iterations for s in here.starts) > 0


def test_a_tightened_start_at_its_cap_fails_with_what_to_try():
    """Each tightened start stops at ``endgame_max_iter`` IPOPT iterations a candidate: with 3, no
    start converges, each within 2 x 3 iterations (two candidates at most), and the failure says
    which setting to raise or which path to add."""
    settings = OCPSettings(**dict(SMALL, nodes=12), start_solve="tightened", endgame_max_iter=3)
    res = optimize_gait(Robot.paper(), "physical", settings, jobs=1)
    assert not res.success and len(res.starts) >= 2
    for s in res.starts:
        assert s.status == Status.SOLVER_FAILURE and 0 < s.iterations <= 6
        assert "endgame_max_iter" in s.message and 'start_solve = "both"' in s.message


def test_the_cap_hint_is_for_the_cap_alone():
    """The advice names the cap only where IPOPT stopped at it, and the homotopy only where it is
    not run already."""
    from types import SimpleNamespace

    from ocp_crawl.ocp.solve import _cap_hint

    def calls(*statuses):
        return [SimpleNamespace(return_status=status) for status in statuses]
    capped = calls("Restoration_Failed", "Maximum_Iterations_Exceeded")
    assert "endgame_max_iter, or add the homotopy" in _cap_hint(capped, 500, "tightened")
    assert _cap_hint(capped, 500, "both").endswith("raise [ocp] endgame_max_iter")
    assert _cap_hint(calls("Infeasible_Problem_Detected"), 500, "tightened") == ""
    assert _cap_hint(capped, None, "tightened") == "" and _cap_hint([], 500, "tightened") == ""



@pytest.mark.slow
def test_a_given_start_with_tightened_starts_keeps_every_family():
    """``start`` replaces the harmonic baseline as the first start; with tightened starts the
    harmonic family's best member is then a start of its own, after it."""
    from ocp_crawl.model.inputs import Harmonic, ReferenceTorque

    robot = Robot.paper()
    settings = OCPSettings(**dict(SMALL, nodes=12), start_solve="tightened")
    given = ReferenceTorque(Harmonic.from_degrees(95.0, 25.0, 30.0), robot.k)
    res = optimize_gait(robot, "physical", settings, jobs=1,
                        start=(given, settings.min_period(25.0, 25.0)))
    labels = [s.label for s in res.starts]
    assert labels[0] == "given start, tightened" and "harmonic baseline, tightened" in labels
    assert "triangle baseline, tightened" in labels
