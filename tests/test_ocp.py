"""Periodic-gait optimal control: statuses, settings validation and the command line (each shipped
problem file solved, judged and converged in N: tests/test_ocp_problems.py)."""

from dataclasses import replace

import numpy as np
import pytest

from ocp_crawl import Robot
from ocp_crawl import Status
from ocp_crawl.ocp import OCPSettings, optimize_gait

from conftest import COARSE


@pytest.mark.slow
def test_infeasible_speed_requirement_is_a_status():
    res = optimize_gait(Robot.paper(), "physical",
                        OCPSettings(objective="min_cot", speed_min=5.0, nodes=24, harmonic_psi=12,
                                    harmonic_A=2,
                                    # the scan's best member, no local search: the status is
                                    # IPOPT's, whatever the start
                                    starts=1, baselines="harmonic", baseline_samples=0,
                                    baseline_starts=0))
    assert not res.success
    assert res.status == Status.INFEASIBLE, res.message
    assert "infeasible" in res.message and "Infeasible_Problem_Detected" in res.message


@pytest.mark.parametrize("bad,match", [
    (dict(objective="fastest"), "objective must be one of"),
    (dict(nodes=4), "nodes must be >= 8"),
    (dict(direction=0), "direction must be -1 or"),
    (dict(A_max_deg=95), "A_max_deg must be in"),
    (dict(sigma0=(2.0,)), "sigma0 must be"),
    (dict(mu_ratios=(0.9, -1.0)), "mu_ratios must be positive"),
    (dict(max_accel_deg_s2=-1.0), r"max_accel_deg_s2 must be in \[0.01, 1e\+07\]"),
    (dict(max_rate_deg_s=0.0), r"max_rate_deg_s must be in \[0.01, 10000\] \(below 0.01 deg/s"),
    (dict(max_rate_deg_s=1e-300), "max_rate_deg_s must be in"),
    (dict(regularization=1e300), r"regularization must be in \[0, 0.01\] \(a tie-breaker"),
    (dict(nodes=10 ** 400), "nodes must be finite, got 1000"),
    (dict(speed_min=np.float32(20.0)), "speed_min must be in"),
    (dict(replay_tol=0.5), "replay_tol must be in"),
    (dict(friction_tol=0.05), "friction_tol"),
    (dict(mu_ratio_eps=0.9), "mu_ratio_eps must be in"),
    (dict(stage_tol=0.0), "stage_tol must be > 0"),
    (dict(loose_last=True), "loose_last needs stage_tol <= sigma_min"),
    (dict(stage_tol_ratio=0.0), "stage_tol_ratio must be > 0"),
    (dict(stage_tol_ratio=2.0), "stage_tol_ratio must be in"),
    (dict(loose_last=1), "loose_last must be True or False"),
    (dict(warm_barrier="probing"), "warm_barrier must be one of"),
])
def test_settings_validation(bad, match):
    with pytest.raises((ValueError, TypeError), match=match):
        OCPSettings(**bad)


def test_cli_optimize_json_and_outputs(cli_optimize_run):
    import json

    code, stdout, stderr, out, nodes = cli_optimize_run
    data = json.loads(stdout)  # the progress bar never mixes into the JSON on stdout
    assert code == (0 if data["success"] else 1)
    # the bar on stderr counts every IPOPT iteration of the homotopies' calls, over every start
    iterations = sum(start["iterations"] for start in data["starts"])
    assert (sum(stage["iterations"] for stage in data["homotopy"])
            in [s["iterations"] for s in data["starts"]])
    assert f"optimize: {iterations} IPOPT it" in stderr and "polish" in stderr
    for key in ("status", "success", "message", "objective", "S_ocp", "S_replay", "rel_diff_replay",
                "CoT_plus_replay", "best_harmonic", "gain", "solve_time_s",
                "complementarity_residual"):
        assert key in data, key
    assert data["objective"] == "max_speed" and 0 < data["best_harmonic"]["A1_deg"] <= 30.0
    lines = [r for r in (out / "torques.csv").read_text().splitlines() if not r.startswith("#")]
    assert lines[0] == "phase [-],tau1 [N m],tau2 [N m],period [s]" and len(lines) == nodes + 1
    phase = np.array([float(r.split(",")[0]) for r in lines[1:]])
    assert phase[0] == 0.0 and np.all(np.diff(phase) > 0) and phase[-1] < 1.0
    for name in ("arrays.npz", "summary.json", "optimal_gait.png", "optimal_gait.pdf"):
        assert (out / name).stat().st_size > 0


def test_cli_optimum_reports_its_s_under_a_friction_asymmetry(cli_optimize_run):
    """In each friction scenario of the file's set, the optimum's S at its mu1/mu2 times 1 -+ 0.5 %
    (geometric mean kept) is that of its own problem file (optimal_gait.toml, a table input) run
    with those coefficients: another path to the same simulation; the middle value is the
    scenario's replayed S, and the gait is off the friction tie."""
    import json
    import math
    from pathlib import Path

    REPO = Path(__file__).resolve().parents[1]

    from ocp_crawl.ocp.asymmetry import ASYMMETRY, ties_decide
    from ocp_crawl.problem import load_problem, ocp_settings, run_problem

    code, stdout, _, out, _ = cli_optimize_run
    data = json.loads(stdout)
    assert data["success"], data["message"]
    d = data["friction_asymmetry"]
    assert d["delta"] == ASYMMETRY and d["messages"] == []
    ratios = ocp_settings(load_problem(REPO / "problems" / "ocp_max_speed.toml")).friction_ratios
    assert len(d["S_m"]) == len(data["S_replay"]) == len(ratios) > 1  # the file's friction set
    robot = load_problem(out / "optimal_gait.toml").robot
    mu = math.sqrt(robot.mu1 * robot.mu2)
    for ratio, (low, mid, high), S_replay in zip(ratios, d["S_m"], data["S_replay"]):
        assert mid == S_replay
        for factor, S in ((1 - ASYMMETRY, low), (1 + ASYMMETRY, high)):
            r = ratio * factor
            res = run_problem(load_problem(out / "optimal_gait.toml",
                                           [f"robot.mu1={mu * math.sqrt(r)!r}",
                                            f"robot.mu2={mu / math.sqrt(r)!r}"]))
            assert res.success and res.S == pytest.approx(S, rel=1e-9, abs=1e-12)
    assert not ties_decide(d) and "a friction tie decides" not in data["message"]


def test_optimize_text_of_a_failed_run_has_no_raw_values():
    """A run that found nothing (no replay, no harmonic gait) reads "-" where a number is missing,
    never None or nan; numbers carry their units."""
    from ocp_crawl.cli.optimize_command import format_optimize
    from ocp_crawl.ocp import OCPResult, OCPSettings
    from ocp_crawl.status import Status

    empty = OCPResult(success=False, status=Status.REPLAY_FAILED, message="the replay failed",
                      objective="max_speed", settings=OCPSettings()).summary()
    text = format_optimize(empty)
    assert "None" not in text and "nan" not in text.lower()
    assert "replay -" in text and "(relative difference -)" in text
    done = dict(empty, S_ocp=-0.0791484, S_replay=-0.0778866, objective_value_replay=0.0778866,
                gain=0.2987, rel_diff_replay=0.01620, solve_time_s=4.1098)
    text = format_optimize(done)
    assert "S           OCP -79.148 mm, replay -77.887 mm" in text
    assert ("+29.9 %" in text and "(relative difference +1.62 %)" in text
            and "time        4.1 s" in text)


def test_optimize_text_counts_its_starts_in_words():
    """One start has no "starts" line (its numbers are the other lines: no "1 starts, 1 converged,
    replayed objective x to x"); several give their count, the converged ones and the range, one
    value when they agree, then a line each; the solve's message says "none converged", not a
    range of missing values."""
    from ocp_crawl.cli.optimize_command import format_optimize
    from ocp_crawl.ocp import OCPResult, OCPSettings
    from ocp_crawl.ocp.judge import spread_text
    from ocp_crawl.status import Status

    base = OCPResult(success=False, status=Status.REPLAY_FAILED, message="-", objective="max_speed",
                     settings=OCPSettings()).summary()

    def starts_line(n, converged, low, high):
        s = dict(base, starts=[{}] * n, starts_converged=converged, objective_value_replay_min=low,
                 objective_value_replay_max=high)
        return [line for line in format_optimize(s).splitlines() if line.startswith("starts")]

    assert starts_line(1, 1, 0.0121, 0.0121) == [] and starts_line(0, 0, None, None) == []
    assert starts_line(4, 3, 0.0121, 0.0129) == [
        "starts      4 starts, 3 converged, replayed objective 12.100 mm/s to 12.900 mm/s"]
    assert starts_line(3, 1, 0.0121, 0.0121) == [
        "starts      3 starts, 1 converged, replayed objective 12.100 mm/s"]
    assert starts_line(2, 0, None, None) == ["starts      2 starts, none converged"]
    # each start on a line of its own, under the count
    records = [{"label": "harmonic baseline", "status": "success", "value_replay": 0.0863,
                "iterations": 696},
               {"label": "triangle baseline, tightened", "status": "solver_failure",
                "value_replay": None, "iterations": 500}]
    text = format_optimize(dict(base, starts=records, starts_converged=1,
                                objective_value_replay_min=0.0863,
                                objective_value_replay_max=0.0863)).splitlines()
    at = next(i for i, line in enumerate(text) if line.startswith("starts"))
    assert text[at + 1:at + 3] == [
        "  harmonic baseline: success, replay 86.300 mm/s, 696 IPOPT iterations",
        "  triangle baseline, tightened: solver_failure, replay -, 500 IPOPT iterations"]
    assert spread_text("max_speed", float("nan"), float("nan"), 0) == "none converged"
    assert spread_text("min_cot", 20.31, 20.31, 2) == "2 converged, replayed objective 20.3"


@pytest.mark.slow
def test_cli_optimize_infeasible_exits_1(tmp_path, capsys):
    import json
    from pathlib import Path

    from ocp_crawl.cli.app import main

    problem = Path(__file__).resolve().parents[1] / "problems" / "ocp_min_cot.toml"
    code = main(["optimize", str(problem), "--set", "ocp.nodes=24", "--set", "ocp.harmonic_psi=8",
                 "--set", 'ocp.constraint=[{quantity = "speed", min = 5.0}]', "--set",
                 "ocp.baseline_samples=0", "--set",
                 "ocp.baselines=harmonic", "--set",
                 "ocp.baseline_starts=1", "--set", "ocp.baseline_evaluations=40",
                 "--set", "ocp.start_solve=homotopy", "--json"])
    captured = capsys.readouterr()
    assert code == 1
    assert json.loads(captured.out)["status"] == "infeasible"
    assert "infeasible" in captured.err and "Traceback" not in captured.err


@pytest.mark.slow
def test_figure_of_an_unreplayed_result_says_so(coarse_max_speed):
    """A result without a replay (a failed solve that kept its last iterate) draws panel (d) with a
    note instead of an empty axes and an empty legend; the other panels keep their legends."""
    import warnings

    from ocp_crawl.viz.ocp import plot_optimal_gait

    robot = Robot.paper()
    res = coarse_max_speed
    assert res.tau.size and res.replay
    failed = replace(res, replay=[], status=Status.SOLVER_FAILURE, success=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # matplotlib warns of a legend without artists
        fig = plot_optimal_gait(failed, robot)
    ax_d = fig.axes[3]
    assert ax_d.get_legend() is None and "no replay" in " ".join(t.get_text() for t in ax_d.texts)
    assert all(ax.get_legend() is not None for ax in fig.axes[:3])
    assert any("solver_failure" in t.get_text() for t in fig.texts)  # the title


def test_the_message_names_the_calls_after_the_kept_point_that_ipopt_rejected():
    """After a loose last stage: the polish failed, then the stage solved again tightly failed too;
    the kept point is the loose stage's, and the message names both rejected calls (the last of each
    kind) with IPOPT's words."""
    from ocp_crawl.nlp.homotopy import Stage
    from ocp_crawl.ocp.solve import _not_kept

    def stage(kind, accepted, message):
        return Stage(1e-9, "x", accepted, 10, 1e-9, 0.1, kind=kind, message=message)

    run = [stage("homotopy", True, "ok"), stage("polish", False, "polish A failed"),
           stage("polish", False, "polish B failed"),
           stage("homotopy", False, "maximum iterations")]
    note = _not_kept(run)
    assert "the last stage solved again tightly not kept: IPOPT maximum iterations" in note
    assert "polish not kept: IPOPT polish B failed" in note and "polish A" not in note
    assert _not_kept(run[:1]) == "" and _not_kept([*run, stage("polish", True, "ok")]) == ""


@pytest.mark.slow
def test_the_tightened_nlp_alone_refines_a_coarser_optimum(coarse_max_speed):
    """solve_from(..., tightened=True): no homotopy, only polish calls (the tightened NLP on the
    branches of the coarser optimum's simulated guess at twice the nodes), a complementary point
    that the event-driven replay confirms."""
    from ocp_crawl.model.statics import Model
    from ocp_crawl.ocp.judge import replay_signal
    from ocp_crawl.ocp.solve import solve_from
    from ocp_crawl.ocp.solver import GaitSolver
    from ocp_crawl.ocp.transcription import GaitOCP

    robot = Robot.paper()
    coarse = coarse_max_speed
    assert coarse.success, coarse.message
    fine = replace(COARSE, nodes=32)
    res = solve_from(GaitSolver(GaitOCP(robot, "physical", fine)), [Model(robot)],
                     replay_signal(coarse.phase, coarse.tau),
                     coarse.T_ocp, coarse.harmonic, tightened=True)
    assert res.success, res.message
    assert res.homotopy and {h.kind for h in res.homotopy} == {"polish"}
    assert res.complementarity_residual <= fine.comp_tol and res.tau.shape == (2, 32)
    assert abs(res.value_replay - res.value_ocp) <= fine.replay_tol * abs(res.value_replay)


def test_robust_files_replay_each_friction_scenario(tmp_path, capsys, monkeypatch):
    """robust_speed's files replay every friction scenario: the writer of optimize --out adds one
    problem file per scenario, named by its ratio mu1/mu2, and simulating each gives that scenario's
    replayed S and speed, which summary.json and the text label with the same ratio.  The profile is
    a triangle wave spanning the envelope at the bandwidth's shortest period (an OCP solve of
    robust_speed takes minutes), judged by the optimum's replay (judge_replay) and written by the
    optimum's writers (the figure left out: tests/test_ocp.py draws it)."""
    import json
    import math
    from pathlib import Path

    from ocp_crawl.cli.app import main
    from ocp_crawl.cli.optimize_command import _optimize_data, format_optimize
    from ocp_crawl.io import units
    from ocp_crawl.model.statics import Model
    from ocp_crawl.ocp import OCPResult
    from ocp_crawl.ocp.judge import judge_replay
    from ocp_crawl.problem import load_problem, ocp_settings
    from ocp_crawl.viz import ocp as viz_ocp
    from ocp_crawl.viz.ocp import scenario_files, write_outputs

    problem = load_problem(Path(__file__).resolve().parents[1] / "problems" / "ocp_robust.toml")
    settings = ocp_settings(problem)
    n = 24
    lo, hi = settings.torque_bounds(problem.robot)
    tri = lambda i: lo + (hi - lo) * (1 - np.abs(((i % n) - n / 2) / (n / 2)))  # noqa: E731
    tau = np.vstack([tri(np.arange(n) + n // 2), tri(np.arange(n) + n // 4)])
    T = 4 * settings.A_max_deg / settings.max_rate_deg_s
    v = judge_replay([Model(r, gravity=problem.gravity) for r in settings.scenarios(problem.robot)],
                     settings, tau, T, math.nan)
    assert len(v.replay) == 3 and all(r.success for r in v.replay)
    nodes = [np.zeros((2, n + 1))] * 3
    res = OCPResult(True, Status.SUCCESS, "a triangle wave judged by its replay", "robust_speed",
                    settings,
                    phase=np.arange(n) / n, tau=tau, T_ocp=T, phi=nodes, x1=[np.zeros(n + 1)] * 3,
                    f_t=[np.zeros(n + 1)] * 3, modes=[np.zeros(n, int)] * 3, S_ocp=v.S,
                    v_ocp=v.speed,
                    W_plus_ocp=v.W_plus, CoT_plus_ocp=v.CoT_plus, value_ocp=v.value,
                    replay=v.replay, S_replay=v.S,
                    v_replay=v.speed, W_plus_replay=v.W_plus, CoT_plus_replay=v.CoT_plus,
                    value_replay=v.value)
    names = scenario_files(settings)
    assert names == ["optimal_gait_mu1_mu2_0.9.toml", "optimal_gait_mu1_mu2_1.toml",
                     "optimal_gait_mu1_mu2_1.1.toml"]
    monkeypatch.setattr(viz_ocp, "plot_optimal_gait", lambda result, robot: None)
    monkeypatch.setattr(viz_ocp, "save_figure", lambda fig, path: path)
    write_outputs(res, problem.robot, tmp_path, _optimize_data(res, problem))
    summary = json.loads((tmp_path / "summary.json").read_text())
    text = format_optimize(summary)
    assert [s["label"] for s in summary["scenarios"]] == ["0.9", "1", "1.1"]
    for name, scenario, S in zip(names, summary["scenarios"], v.S):
        assert scenario["S_replay"] == S and scenario["mu1_mu2"] == float(scenario["label"])
        assert main(["simulate", str(tmp_path / name), "--json"]) == 0, name
        data = json.loads(capsys.readouterr().out)
        robot = data["problem"]["robot"]
        assert robot["mu1"] / robot["mu2"] == pytest.approx(scenario["mu1_mu2"], rel=1e-12)
        assert data["S"] == pytest.approx(scenario["S_replay"], rel=1e-9), name
        assert data["speed"] == pytest.approx(abs(scenario["v_replay"]),
                                              rel=1e-9) and data["period"] == T
        label = f"mu1/mu2 = {scenario['label']}"
        assert f"{label}: OCP {units.distance(S)}, replay {units.distance(data['S'])}" in text
        assert (f"{label}: OCP {units.speed(scenario['v_ocp'])}, "
                f"replay {units.speed(data['speed'])}" in text)
