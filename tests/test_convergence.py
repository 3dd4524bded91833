"""Convergence in N: the observed order on sequences of known order, the warm start from the
previous N, and ``optimize --nodes`` (parsing, bad values, the table's text and JSON)."""
import json
import math
import os
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from ocp_crawl import Robot
from ocp_crawl.nlp.homotopy import observe, observers
from ocp_crawl import workers
from ocp_crawl.ocp import convergence
from ocp_crawl.ocp.convergence import check_nodes, converge_in_nodes, observed_orders
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.solve import OCPResult
from ocp_crawl.status import Status

REPO = Path(__file__).resolve().parents[1]
OCP_FILE = REPO / "problems" / "ocp_max_speed.toml"


@pytest.mark.parametrize("nodes, p", [([50, 100, 200, 400], 2.0), ([50, 100, 200, 400], 1.0),
                                      ([25, 50, 100, 200, 400], 1.5), ([10, 30, 90, 270], 3.0)])
def test_observed_order_of_a_sequence_of_known_order(nodes, p):
    """J(N) = J* + C N^-p: the changes shrink by r^p per refinement by r, so the observed order is p
    exactly (to round-off) at every inner N, undefined (NaN) at the ends."""
    values = [0.0513 - 0.37 * n ** -p for n in nodes]
    orders = observed_orders(nodes, values)
    assert math.isnan(orders[0]) and math.isnan(orders[-1])
    for q in orders[1:-1]:
        assert q == pytest.approx(p, rel=1e-9)


def test_observed_order_is_undefined_where_it_has_no_meaning():
    # the ratio of successive N changes (100/50 != 150/100); a zero change; a missing value
    assert all(math.isnan(q) for q in observed_orders([50, 100, 150, 300], [1.0, 1.5, 1.7, 1.8]))
    assert math.isnan(observed_orders([50, 100, 200], [1.0, 1.0, 2.0])[1])
    assert math.isnan(observed_orders([50, 100, 200], [1.0, math.nan, 2.0])[1])
    # an oscillating sequence still has an order (|changes|): 1, -1/4 -> log2(4) = 2
    assert observed_orders([50, 100, 200], [0.0, 1.0, 0.75])[1] == pytest.approx(2.0, rel=1e-12)


@pytest.mark.parametrize("bad, match", [([], "at least one"), ([50, 50], "increase strictly"),
                                        ([100, 50], "increase strictly"),
                                        ([4], "not an integer in"),
                                        ([50.0], "not an integer in"),
                                        ([True], "not an integer in")])
def test_check_nodes_rejects(bad, match):
    with pytest.raises(ValueError, match=match):
        check_nodes(bad)


def _fake_result(settings, tau, T, value):
    N = tau.shape[1]
    return OCPResult(success=True, status=Status.SUCCESS, message="fake",
                     objective=settings.objective,
                     settings=settings, phase=np.arange(N) / N, tau=tau, T_ocp=T,
                     value_ocp=value * 1.001, value_replay=value, rel_diff_replay=1e-3)


class _FakeOCP:
    prepared = []

    def __init__(self, robot, gravity, settings):
        self.settings = settings

    def prepare(self):
        # the class's record (in the parent)
        self.prepared.append((self.settings.nodes, os.getpid()))
        self.done = True  # this transcription's


def _here(task, meanwhile, forward):
    """workers.overlap without the fork (the fakes record their calls in this process)."""
    other = meanwhile()
    return task(forward), other


def _fake_solvers(monkeypatch, fresh, warm, fork=False) -> None:
    """Replace the cold solve (optimize_gait), the warm one (solve_from), the transcription and its
    solver by fakes (and, unless ``fork``, run every warm solve in this process)."""
    monkeypatch.setattr(convergence, "optimize_gait", fresh)
    monkeypatch.setattr(convergence, "solve_from", warm)
    monkeypatch.setattr(convergence, "GaitOCP", _FakeOCP)
    # the fake transcription solves itself
    monkeypatch.setattr(convergence, "GaitSolver", lambda ocp: ocp)
    if not fork:
        monkeypatch.setattr(convergence, "overlap", _here)


def test_each_N_is_warm_started_from_the_previous_optimum(monkeypatch):
    """The first N is solved from scratch (optimize_gait), every further N from the previous N's
    node profile (linear in phase: at doubled N the previous nodes exactly, midpoints in between)
    and period; the rows carry the changes and the observed order of the replayed objective."""
    profile = lambda t: np.vstack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t) ** 3])  # noqa: E731
    value = lambda n: 0.05 - 0.4 / n**2  # noqa: E731  (second order)
    seen = []

    def fresh(robot, gravity, s, jobs=None):
        seen.append(("fresh", s.nodes))
        return _fake_result(s, profile(np.arange(s.nodes) / s.nodes), 0.7, value(s.nodes))

    def warm(ocp, models, signal, T, harmonic=None, replay=True, baselines=None):
        N, prev = ocp.settings.nodes, seen[-1][1]
        t = np.arange(N) / N
        got = signal(t)
        # the previous nodes are reproduced, the new ones lie on the chords between them
        np.testing.assert_allclose(got[:, ::N // prev], profile(np.arange(prev) / prev), rtol=0,
                                   atol=1e-15)
        mid = 0.5 * (profile(t[::2]) + profile(t[::2] + 1 / prev))
        np.testing.assert_allclose(got[:, 1::2], mid, rtol=0, atol=1e-15)
        assert T == pytest.approx(0.7 + 0.01 * (len(seen) - 1), rel=1e-12)
        seen.append(("warm", N))
        return _fake_result(ocp.settings, profile(t), T + 0.01, value(N))

    _fake_solvers(monkeypatch, fresh, warm)
    table = converge_in_nodes(Robot.paper(), "physical", OCPSettings(), [50, 100, 200, 400])
    assert seen == [("fresh", 50), ("warm", 100), ("warm", 200), ("warm", 400)]
    assert table.success and [r.nodes for r in table.rows] == [50, 100, 200, 400]
    assert math.isnan(table.rows[0].change)
    assert table.rows[1].change == pytest.approx(value(100) - value(50), rel=1e-12)
    assert [round(r.order, 9) for r in table.rows[1:3]] == [2.0, 2.0]
    data = table.to_dict()
    assert (data["unit"] == "m/s" and data["rows"][1]["status"] == "success"
            and "result" not in data["rows"][1])
    json.dumps(data, allow_nan=False)


def test_a_failed_warm_solve_is_retried_from_the_same_start_with_the_cold_settings(monkeypatch):
    """When the warm solve (small relaxation, monotone barrier) is not judged a success, the same
    start is solved once more with the settings of a cold solve; the row carries the retry's result
    and both messages."""
    settings = OCPSettings()
    profile = lambda t: np.vstack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)])  # noqa: E731
    calls = []

    def fresh(robot, gravity, s, jobs=None):
        return _fake_result(s, profile(np.arange(s.nodes) / s.nodes), 0.7, 0.05)

    def warm(ocp, models, signal, T, harmonic=None, replay=True, baselines=None):
        calls.append((ocp.settings.sigma0, ocp.settings.ipopt, T))
        if len(calls) == 1:
            return OCPResult(success=False, status=Status.INFEASIBLE,
                             message="infeasible: restoration failed",
                             objective=ocp.settings.objective, settings=ocp.settings)
        return _fake_result(ocp.settings,
                            profile(np.arange(ocp.settings.nodes) / ocp.settings.nodes), T, 0.051)

    _fake_solvers(monkeypatch, fresh, warm)
    table = converge_in_nodes(Robot.paper(), "physical", settings, [50, 100])
    assert calls[0][0] == (convergence.WARM_SIGMA0,) and calls[0][1]["mu_strategy"] == "monotone"
    assert calls[1][:2] == (settings.sigma0, settings.ipopt) and calls[1][2] == calls[0][2] == 0.7
    row = table.rows[1]
    assert row.status == Status.SUCCESS and row.value_replay == 0.051
    assert "cold solve's settings" in row.message and "restoration failed" in row.message


@pytest.mark.parametrize("own, sigma0",
                         [(dict(stage_tol_ratio=0.1), 1e-5), (dict(sigma0=1e-3), 1e-5),
                          (dict(sigma_min=1e-8), 1e-5), (dict(sigma_factor=0.1), 1e-5),
                          (dict(sigma0=(1e-3, 1e-6), sigma_min=1e-11), (1e-5, 1e-6)),
                          (dict(sigma0=1e-3, sigma_min=1e-5), 1e-3)])
def test_settings_with_their_own_homotopy_keep_it_in_the_warm_solves(monkeypatch, own, sigma0):
    """A file with its own homotopy (robust_speed's) is warm-started with it and the warm barrier,
    from sigma = 1e-5 where that is below its first sigma and above its last (the previous optimum
    is complementary), not with the warm schedule tuned on the default path, then retried with its
    cold settings; before the homotopy, the tightened NLP alone on the same transcription; the
    default settings are not 'own'."""
    settings = OCPSettings(**own)
    assert convergence.own_homotopy(settings) and not convergence.own_homotopy(OCPSettings())
    profile = lambda t: np.vstack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)])  # noqa: E731
    calls = []

    def fresh(robot, gravity, s, jobs=None):
        return _fake_result(s, profile(np.arange(s.nodes) / s.nodes), 0.7, 0.05)

    def warm(ocp, models, signal, T, harmonic=None, replay=True, tightened=False, baselines=None):
        calls.append((ocp.settings, tightened))
        return OCPResult(success=False, status=Status.INFEASIBLE,
                         message="infeasible: restoration failed",
                         objective=ocp.settings.objective, settings=ocp.settings)

    _fake_solvers(monkeypatch, fresh, warm)
    table = converge_in_nodes(Robot.paper(), "physical", settings, [50, 100])
    cold = replace(settings, nodes=100)
    near = replace(cold, sigma0=sigma0, ipopt={**convergence.WARM_IPOPT, **settings.ipopt})
    assert calls == [(near, True), (near, False), (cold, False)]
    message = table.rows[1].message
    assert table.rows[1].status == Status.INFEASIBLE and "settings' own homotopy" in message
    assert "the tightened NLP on its branches gave: infeasible" in message


@pytest.mark.parametrize("tight, homotopy, cold, calls, row_value", [
    # not worse: the row, no homotopy
    (0.0501, 0.0502, None, 1, 0.0501), (0.04992, 0.0502, None, 1, 0.04992),
    # worse: the homotopy, which does better
    (0.0498, 0.0502, None, 2, 0.0502), (0.045, 0.0502, None, 2, 0.0502),
    # worse, but the homotopy fails or does worse
    (0.0498, None, None, 3, 0.0498), (0.0498, 0.0497, None, 2, 0.0498),
    # the homotopy fails, its cold retry succeeds: the row if better than the tightened NLP's, else
    # the tightened one
    (0.0498, None, 0.0502, 3, 0.0502), (0.0498, None, 0.0497, 3, 0.0498),
])
@pytest.mark.parametrize("first", [dict(stage_tol_ratio=0.1), dict(start_solve="tightened")])
def test_the_tightened_nlp_is_kept_unless_worse_than_the_previous_optimum_and_the_homotopy(
        monkeypatch, first, tight, homotopy, cold, calls, row_value):
    """With their own homotopy or tightened starts, the warm solve's first try, the tightened NLP
    on the previous optimum's branches, is the row when the judge accepts it and it is not worse
    than the previous N's optimum beyond WORSE_TOL plus both OCP-replay differences (1e-3 each in
    the fakes: more than 0.21 % below 0.05 is worse); otherwise the homotopy runs (then the cold
    retry if it fails: None), and the worse tightened success stays the row unless the homotopy
    (or its cold retry) does better; the row's result's solve time is that of all the
    attempts."""
    settings = OCPSettings(**first)
    seen = []

    def fresh(robot, gravity, s, jobs=None):
        return _fake_result(s, np.ones((2, s.nodes)), 0.7, 0.05)

    def warm(ocp, models, signal, T, harmonic=None, replay=True, tightened=False, baselines=None):
        seen.append(tightened)
        # the third call: the cold retry
        value = tight if tightened else homotopy if len(seen) == 2 else cold
        if value is not None:
            res = _fake_result(ocp.settings, np.ones((2, ocp.settings.nodes)), T, value)
        else:
            res = OCPResult(success=False, status=Status.SOLVER_FAILURE,
                            message="IPOPT failed: max_iter",
                            objective=ocp.settings.objective, settings=ocp.settings)
        res.solve_time_s = 2.0 ** (len(seen) - 1)  # 1, 2, 4 s: each attempt's own time
        return res

    _fake_solvers(monkeypatch, fresh, warm)
    row = converge_in_nodes(Robot.paper(), "physical", settings, [50, 100]).rows[1]
    assert seen == [True] + [False] * (calls - 1)
    assert row.status == Status.SUCCESS and row.value_replay == row_value
    assert ("the tightened NLP on its branches)" in row.message) == (calls == 1)
    assert ("worse than N = 50" in row.message) == (calls > 1)
    assert ("kept: the homotopy then gave" in row.message) == (calls > 1 and row_value == tight)
    cold_row = row.message.startswith("fake (from the optimum at N = 50 with the cold solve's "
                                      "settings")
    assert cold_row == (cold is not None and row_value == cold)
    # every attempt's time, whichever attempt is the row
    assert row.result.solve_time_s == 2.0 ** calls - 1


@pytest.mark.parametrize("objective, values, flagged", [
    # 300 is no multiple of 200
    ("max_speed", {50: 0.05, 100: 0.049, 200: 0.049, 300: 0.045}, [100]),
    # 0.16 % worse: within WORSE_TOL plus both rows' OCP-replay differences (1e-3 each in the fakes)
    ("max_speed", {50: 0.05, 100: 0.04992, 200: 0.0499199}, []),
    ("min_cot", {50: 14.4, 100: 14.5, 200: 14.3}, [100]),  # CoT+ larger is worse
])
def test_a_finer_n_worse_than_the_previous_optimum_says_so(monkeypatch, objective, values, flagged):
    """The finer N can represent the previous profile when its N is a multiple of the previous one:
    a replayed optimum worse than the previous beyond WORSE_TOL is another local optimum, and its
    row's message says so."""
    profile = lambda t: np.vstack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)])  # noqa: E731

    def fresh(robot, gravity, s, jobs=None):
        return _fake_result(s, profile(np.arange(s.nodes) / s.nodes), 0.7, values[s.nodes])

    def warm(ocp, models, signal, T, harmonic=None, replay=True, baselines=None):
        N = ocp.settings.nodes
        return _fake_result(ocp.settings, profile(np.arange(N) / N), T, values[N])

    _fake_solvers(monkeypatch, fresh, warm)
    settings = OCPSettings(objective=objective,
                           **(dict(speed_min=0.04) if objective == "min_cot" else {}))
    table = converge_in_nodes(Robot.paper(), "physical", settings, sorted(values))
    assert [r.nodes for r in table.rows if "another local optimum" in r.message] == flagged
    for r in table.rows:
        if r.nodes in flagged:
            assert f"{abs(r.rel_change):.2%} worse than the optimum at N = " in r.message


# ------------------------------------------------------------------ the command line
def run(capsys, *argv):
    from ocp_crawl.cli.app import main

    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("argv, words", [
    (["--nodes", "4"], ["--nodes 4 is invalid", "in [8, 1000]"]),
    (["--nodes", "50", "abc"], ["--nodes abc is invalid", "integer"]),
    (["--nodes", "100", "2000"], ["--nodes 2000 is invalid"]),
    (["--nodes"], ["--nodes", "expected at least one argument"]),
    (["--nodes", "100", "50"], ["--nodes 100 50 is invalid", "increase strictly"]),
    (["--nodes", "50", "50"], ["--nodes 50 50 is invalid", "increase strictly"]),
    (["--jobs", "0"], ["--jobs 0 is invalid", "worker processes"]),
])
def test_optimize_bad_nodes_exit_2_with_one_line(capsys, argv, words):
    code, out, err = run(capsys, "optimize", OCP_FILE, *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("ocp-crawl: error:"), err
    for w in words:
        assert w in err, (w, err)


def test_optimize_nodes_is_parsed_as_a_list():
    from ocp_crawl.cli.app import build_parser

    args = build_parser().parse_args(["optimize", str(OCP_FILE), "--nodes", "50", "100", "200",
                                      "400"])
    assert args.nodes == [50, 100, 200, 400]
    assert build_parser().parse_args(["optimize", str(OCP_FILE)]).nodes is None


def _fake_table(settings, nodes):
    rows = []
    for n in nodes:
        res = _fake_result(OCPSettings(nodes=n), np.zeros((2, n)), 0.5236, 0.0452 - 0.3 / n**2)
        rows.append(convergence.ConvergenceRow(n, Status.SUCCESS, "fake", 0.5236, res.value_ocp,
                                               res.value_replay,
                                               1e-3, solve_time_s=1.5, result=res))
    convergence._changes(rows, settings.objective)
    return convergence.ConvergenceTable(settings.objective, rows, settings.objective_unit)


def test_optimize_nodes_prints_the_table_with_units(capsys, monkeypatch):
    seen = {}

    def fake(robot, gravity, settings, nodes, log=None, jobs=None):
        seen["nodes"], seen["N0"] = nodes, settings.nodes
        return _fake_table(settings, nodes)
    monkeypatch.setattr(convergence, "converge_in_nodes", fake)
    code, out, err = run(capsys, "optimize", OCP_FILE, "--nodes", "50", "100", "200")
    assert code == 0, err
    assert seen == {"nodes": [50, 100, 200], "N0": 50}
    lines = out.splitlines()
    assert lines[0].startswith("convergence in N: max_speed")
    assert lines[1].split() == ["N", "status", "T", "OCP", "replay", "diff", "change", "change",
                                "p", "time"]
    row100 = lines[3].split()
    # 0.0452 - 0.3/100^2 = 0.04517 m/s; change from N = 50: 0.3 (1/50^2 - 1/100^2) = 9e-5 m/s; p = 2
    assert row100[:2] == ["100",
                          "success"] and "45.17000" in lines[3] and "0.09000 mm/s" in lines[3]
    assert row100[-3:] == ["2.00", "1.5", "s"]
    assert "finest N = 200:" in out and "period T 0.524 s" in out
    code, out, err = run(capsys, "optimize", OCP_FILE, "--nodes", "50", "100", "200", "--json")
    data = json.loads(out)
    assert (code == 0 and data["unit"] == "m/s"
            and [r["nodes"] for r in data["rows"]] == [50, 100, 200])
    assert data["units"]["change"] == "m/s" and data["units"]["T"] == "s"
    assert (data["rows"][1]["order"] == pytest.approx(2.0, rel=1e-9)
            and data["finest"]["nodes"] == 200)


def test_no_warm_start_from_a_profile_the_replay_could_not_follow(monkeypatch):
    """An N whose optimum failed in the replay does not seed the next N: that one starts afresh from
    the baseline (optimize_gait), and the first replayed optimum seeds the rest."""
    seen = []

    def fresh(robot, gravity, s, jobs=None):
        seen.append(("fresh", s.nodes))
        res = _fake_result(s, np.ones((2, s.nodes)), 0.7, 0.05)
        if s.nodes == 50:
            res.status, res.success, res.value_replay = Status.REPLAY_FAILED, False, math.nan
        return res

    def warm(ocp, models, signal, T, harmonic=None, replay=True, baselines=None):
        seen.append(("warm", ocp.settings.nodes))
        return _fake_result(ocp.settings, np.ones((2, ocp.settings.nodes)), T, 0.05)

    monkeypatch.setattr(convergence, "optimize_gait", fresh)
    monkeypatch.setattr(convergence, "solve_from", warm)
    monkeypatch.setattr(convergence, "GaitOCP",
                        lambda robot, gravity, settings: SimpleNamespace(settings=settings))
    monkeypatch.setattr(convergence, "GaitSolver", lambda ocp: ocp)
    table = converge_in_nodes(Robot.paper(), "physical", OCPSettings(), [50, 100, 200])
    assert seen == [("fresh", 50), ("fresh", 100), ("warm", 200)]
    assert not table.success and table.rows[0].status == Status.REPLAY_FAILED



def test_a_warm_solve_with_a_finer_n_after_it_runs_in_a_fork_while_the_next_n_is_built(monkeypatch):
    """Every warm row but the last solves in a forked process (its records reach this process's
    observers, in order) while this process builds the next N's transcription, which the next row
    then uses; the table is the one of the same solves run here."""
    parent = os.getpid()

    def fresh(robot, gravity, s, jobs=None):
        return _fake_result(s, np.ones((2, s.nodes)), 0.7, 0.05)

    def warm(ocp, models, signal, T, harmonic=None, replay=True, baselines=None):
        for callback in observers():
            callback(("stage", ocp.settings.nodes, os.getpid()))
        res = _fake_result(ocp.settings, np.ones((2, ocp.settings.nodes)), T,
                           0.05 + 1e-3 * ocp.settings.nodes)
        res.message = f"pid {os.getpid()}, prepared {getattr(ocp, 'done', False)}"
        return res

    tables, seen = [], []
    for fork in (True, False):
        _FakeOCP.prepared = []
        _fake_solvers(monkeypatch, fresh, warm, fork=fork)
        with observe(seen.append):
            tables.append(converge_in_nodes(Robot.paper(), "physical", OCPSettings(),
                                            [50, 100, 200, 400]))
        assert _FakeOCP.prepared == [(200, parent), (400, parent)]  # built here, meanwhile
    pids = [int(r.message.split()[1].rstrip(",")) for r in tables[0].rows[1:]]
    if workers.mp_context().get_start_method() == "fork":
        assert pids[0] != parent and pids[1] != parent and pids[0] != pids[1] and pids[2] == parent
    # another thread runs in this process (e.g. Dask's, left by an earlier test): every solve here
    else:
        assert pids == [parent] * 3
    assert [(n, pid) for _, n, pid in seen[:3]] == [(100, pids[0]), (200, pids[1]), (400, parent)]
    assert ([n for _, n, pid in seen[3:]] == [100, 200, 400]
            and {pid for *_, pid in seen[3:]} == {parent})
    assert [r.value_replay for r in tables[0].rows] == [r.value_replay for r in tables[1].rows]
    # N = 200, 400 on the built ones
    assert all("prepared True" in r.message for r in tables[0].rows[2:])
    assert "prepared False" in tables[0].rows[1].message  # N = 100: none was built before it


def test_every_row_reports_its_friction_asymmetry():
    """The warm rows (solved by the warm path, not by ``optimize_gait``) carry the same report as
    the first: each confirmed row's S at mu1/mu2 moved by -+0.5 %, its middle value the row's
    replay."""
    from dataclasses import replace

    from conftest import COARSE

    table = converge_in_nodes(Robot.paper(), "physical", replace(COARSE, nodes=12), [12, 16],
                              jobs=1)
    assert len(table.rows) == 2
    for row in table.rows:
        res = row.result
        assert res is not None and res.success, row.message
        d = res.friction_asymmetry
        assert d is not None and d["S_m"][0][1] == res.S_replay[0] and d["messages"] == []
