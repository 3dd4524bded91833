"""The endgame of the homotopy (ocp/endgame.py): the stages it replaces, its verdict, and the
homotopy that goes on when it is not kept.

The judge of every optimum here is the event-driven replay of its torques (an independent
simulator); the endgame's own record says what it was compared with."""
from dataclasses import replace

import numpy as np
import pytest

from ocp_crawl import Harmonic, Model, ReferenceTorque, Robot
from ocp_crawl.ocp.endgame import Endgame
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.solve import solve_from
from ocp_crawl.ocp.solver import GaitSolver
from ocp_crawl.ocp.transcription import GaitOCP


def endgame(keep=True, solved=True, guess=True) -> Endgame:
    """An endgame of stand-in parts: a guess, a solve and a verdict as given."""
    return Endgame(1e-4, 50, lambda x: x + 1 if guess else None,
                   lambda x, n: (x * 2, [], None, "Solve_Succeeded") if solved
                   else (None, [], "the tightened NLP (Maximum_Iterations_Exceeded)",
                         "Maximum_Iterations_Exceeded"),
                   lambda x, xs, against: (keep, f"replay 2 against {against}'s 1"))


def test_the_endgame_replaces_the_stages_after_its_sigma():
    schedule = (1e-3, 1e-4, 1e-5, 1e-6)
    assert endgame().head(schedule) == (1e-3, 1e-4)
    assert endgame().head((1e-3, 1e-5, 1e-6)) == ()  # its sigma is no stage: the whole homotopy
    assert endgame().head((1e-2, 1e-4)) == ()  # the last stage: nothing to replace


@pytest.mark.parametrize("case, kept", [({}, True), ({"keep": False}, False),
                                        ({"solved": False}, False), ({"guess": False}, False)])
def test_the_endgame_is_kept_only_when_its_judge_says_so(case, kept):
    game = endgame(**case)
    out = game(np.ones(3), [])
    assert (out is not None) == kept
    if kept:
        assert np.array_equal(out[0], np.full(3, 4.0)) and out[1] is None
    assert len(game.outcome) == 1 and ("not kept" not in game.outcome[0]) == kept


def settings(**changes) -> OCPSettings:
    return OCPSettings(objective="max_speed", nodes=16, starts=1, baselines="harmonic", **changes)


def solve(st: OCPSettings):
    robot = Robot.paper()
    signal = ReferenceTorque(Harmonic.from_degrees(90.0, 30.0, 30.0), robot.k)
    return solve_from(GaitSolver(GaitOCP(robot, "physical", st)), [Model(robot)], signal,
                      st.min_period(30.0, 30.0))


@pytest.fixture(scope="module")
def whole():
    """The whole homotopy's optimum, the reference of every path."""
    res = solve(settings())
    assert res.success, res.message
    return res


@pytest.mark.slow
def test_an_endgame_not_kept_gives_the_whole_homotopy_and_a_kept_one_its_replay(whole):
    """With one iteration allowed, the endgame's solve fails and the homotopy goes on from the
    endgame's stage: the same optimum as the whole homotopy's, to round-off.  With the default cap,
    the endgame's optimum is kept only as good as its stage's profile by replay, and the replay
    confirms it."""
    capped = solve(settings(endgame_sigma=1e-4, endgame_max_iter=1))
    assert capped.success, capped.message
    assert "not kept" in capped.path
    assert np.allclose(capped.tau, whole.tau, rtol=0, atol=1e-9 * np.abs(whole.tau).max())
    assert capped.value_replay == pytest.approx(whole.value_replay, rel=1e-9)
    kinds = [h.kind for h in capped.homotopy]
    assert kinds[1] == "endgame"
    assert [k for k in kinds if k != "endgame"] == [h.kind for h in whole.homotopy]

    ended = solve(settings(endgame_sigma=1e-4))
    assert ended.success, ended.message
    assert ended.path.startswith("endgame after sigma = 1e-04 kept (")
    assert [h.kind for h in ended.homotopy][:2] == ["homotopy", "endgame"]
    assert {h.kind for h in ended.homotopy[1:]} == {"endgame"}
    assert abs(ended.value_replay - ended.value_ocp) <= 1e-6 * ended.value_replay
    stage = float(ended.path.split("stage profile's ")[1].split(" mm/s")[0]) * 1e-3
    assert ended.value_replay >= stage


def test_endgame_settings_name_the_schedule():
    with pytest.raises(ValueError, match="endgame_sigma must be one of the homotopy.s stages"):
        settings(endgame_sigma=1e-6)  # the last stage of the default schedule
    with pytest.raises(ValueError, match="endgame_max_iter"):
        settings(endgame_max_iter=0)
    assert replace(settings(), sigma0=(1e-3,), sigma_factor=0.1, sigma_min=1e-6).schedule() == (
        1e-3, 1e-4, 1e-5, 1e-6)


@pytest.mark.slow
def test_always_perturbed_hessian_solves_the_same_problem(whole):
    """perturbation = "always" adds one variable in neither the objective nor the constraints (IPOPT
    then treats the Hessian as degenerate from its first factorisation): the optimum it reaches is a
    complementary point that the replay confirms, within 1 % of the default path's."""
    always = solve(settings(perturbation="always"))
    assert always.success, always.message
    assert abs(always.value_replay - always.value_ocp) <= 1e-6 * always.value_replay
    assert always.value_replay == pytest.approx(whole.value_replay, rel=1e-2)
    with pytest.raises(ValueError, match="perturbation"):
        settings(perturbation="never")


@pytest.mark.slow
@pytest.mark.parametrize("fork", [True, False])
def test_both_paths_keep_the_better_by_replay(fork, monkeypatch, whole):
    """endgame_paths = "both": the endgame and the rest of the homotopy both run (in a forked
    process, or one after the other where none can be forked: the same result), and the better by
    replay is kept, so the optimum is at least the whole homotopy's by replay; both are in the
    records."""
    if not fork:
        from ocp_crawl import workers

        monkeypatch.setattr(workers, "mp_context",
                            lambda: workers.multiprocessing.get_context("spawn"))
    both = solve(settings(endgame_sigma=1e-4, endgame_paths="both"))
    assert both.success, both.message
    assert both.value_replay >= whole.value_replay * (1 - 1e-9)
    kinds = [h.kind for h in both.homotopy]
    assert ("endgame" in kinds
            and [k for k in kinds if k != "endgame"] == [h.kind for h in whole.homotopy])
    assert "against the homotopy's optimum's" in both.path
