"""Sweeps: rows equal to point-by-point runs, failures as data, resume after a kill, the command
line, Dask (grid parsing: test_sweep_grid.py)."""
import csv
import json
import math
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl.cli.app import main
from ocp_crawl.problem import ProblemError, load_problem, run_problem
from ocp_crawl.sweep import (JOURNAL_FILE, RESULTS_FILE, SETTINGS_FILE, SweepError, SweepResult,
                             grid_from_specs, run_sweep)
from ocp_crawl.sweep.journal import SweepStore

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "problems" / "paper_gait.toml"
NUMBERS = ("S", "W_plus", "CoT_plus")


def same_number(a, b, rtol=1e-12):
    if isinstance(a, float) and math.isnan(a):
        return isinstance(b, float) and math.isnan(b)
    return a == b or (math.isfinite(a) and abs(a - b) <= rtol * abs(b))


def assert_same_rows(rows, ref_rows):
    assert len(rows) == len(ref_rows)
    for row, ref in zip(rows, ref_rows):
        assert row.keys() == ref.keys()
        for col in row:
            if col in NUMBERS or isinstance(ref[col], float):
                assert same_number(row[col], ref[col]), (col, row, ref)
            else:
                assert row[col] == ref[col], (col, row, ref)


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


# --------------------------------------------------------------------------------------------
# rows
# --------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_sweep_equals_point_by_point_runs(tmp_path):
    problem = load_problem(PAPER)
    grid = {"gait.psi_deg": [0.0, 45.0, 135.0], "gait.gamma_deg": [80.0, 100.0]}
    res = run_sweep(problem, grid, out_dir=tmp_path / "s", jobs=2)
    assert res.keys == ("gait.psi_deg", "gait.gamma_deg") and res.shape == (3, 2)
    assert res.computed == 6 and len(res.rows) == 6
    for i, psi in enumerate(grid["gait.psi_deg"]):
        for j, gamma in enumerate(grid["gait.gamma_deg"]):
            ref = run_problem(load_problem(PAPER, [f"gait.psi_deg={psi}",
                                                   f"gait.gamma_deg={gamma}"]))
            row = res.rows[2 * i + j]  # grid order: the last key varies fastest
            assert (row["gait.psi_deg"], row["gait.gamma_deg"]) == (psi, gamma)
            assert row["status"] == ref.status_name and row["message"] == ref.message
            for col in NUMBERS:
                assert same_number(row[col], float(getattr(ref, col))), col
            assert same_number(float(res.array("S")[i, j]),
                               float(ref.S) if ref.success else math.nan)
    assert res.status_array().shape == (3, 2)
    assert res.array("gait.gamma_deg")[:, 1].tolist() == [100.0] * 3
    # the file holds the same rows, in grid order, with the documented columns
    table = read_csv(tmp_path / "s" / RESULTS_FILE)
    # every number with its unit, as in the input tables (ocp_crawl.io.tables); text columns bare
    assert table[0] == ["gait.psi_deg [deg]", "gait.gamma_deg [deg]", "S [m]", "W_plus [J]",
                        "CoT_plus [-]", "status", "message"]
    assert [(float(r[0]), float(r[1])) for r in table[1:]] == [(p, g) for p in grid["gait.psi_deg"]
                                                              for g in grid["gait.gamma_deg"]]
    assert_same_rows(SweepResult.read(tmp_path / "s").rows, res.rows)
    assert not (tmp_path / "s" / JOURNAL_FILE).exists()
    settings = json.loads((tmp_path / "s" / SETTINGS_FILE).read_text())
    assert settings["grid"] == grid and settings["solver"] == "event" and settings["version"]
    assert settings["problem"]["robot"]["k"] == 0.1677
    summary = res.summary()
    assert summary["points"] == 6 and sum(summary["counts"].values()) == 6
    assert summary["best"]["point"]["gait.psi_deg"] == 45.0


def reference_status(overrides):
    """Status of one point run on its own: the result's status name, or bad_input."""
    try:
        problem = load_problem(PAPER, overrides)
    except ProblemError as exc:
        return "bad_input", str(exc)
    result = run_problem(problem)
    return result.status_name, result.message


def test_failures_are_recorded_with_status_and_message(tmp_path):
    # physical gravity: psi 45 with gamma 30 starts with foot 1 off the ground (bad input), psi 0
    # with gamma 60 folds, psi 45 with A 60 loses a contact
    grid = {"gait.psi_deg": [0.0, 45.0], "gait.gamma_deg": [30.0, 60.0, 90.0],
            "gait.A_deg": [30.0, 60.0]}
    res = run_sweep(PAPER, grid, out_dir=tmp_path / "f", jobs=2,
                    extra_columns=("W_plus_joint", "cycles"))
    status = res.status_array()
    assert status.shape == (2, 3, 2)
    assert status[0, 1, 0] == "fold"
    assert status[1, 0, 0] == "bad_input"
    assert status[1, 2, 0] == "success"
    assert len(set(status.ravel())) >= 4  # success, bad_input, fold and a lost contact at least
    for row in res.rows:
        ref_status, ref_message = reference_status([f"{k}={row[k]}" for k in res.keys])
        assert (row["status"], row["message"]) == (ref_status, ref_message)
        if row["status"] != "success":
            assert all(math.isnan(row[c]) for c in NUMBERS)
    bad = res.rows[6]  # psi 45, gamma 30, A 30
    assert "foot 1 off the ground" in bad["message"] and "gamma_deg = 30.0" in bad["message"]
    s = res.array("S")
    assert np.isnan(s[status != "success"]).all() and np.isfinite(s[status == "success"]).all()
    w = res.array("W_plus_joint")
    assert w.shape == (2, 3, 2, 2)
    ok = res.rows[-2]  # psi 45, gamma 90, A 30
    assert ok["status"] == "success" and ok["cycles"] >= 2
    assert w[1, 2, 0].sum() == pytest.approx(ok["W_plus"], rel=1e-12)
    table = read_csv(tmp_path / "f" / RESULTS_FILE)
    assert len(table) == 1 + 12 and table[0][-2:] == ["W_plus_joint [J]", "cycles [-]"]
    col = table[0].index("status")
    assert [r[col] for r in table[1:]] == list(status.ravel())
    assert_same_rows(SweepResult.read(tmp_path / "f").rows, res.rows)


def test_an_unexpected_exception_is_recorded_as_error(monkeypatch):
    import ocp_crawl.sweep.point as sweep

    def flaky(problem):
        if problem.robot.k > 0.15:
            raise RuntimeError("solver bug")
        return run_problem(problem)

    monkeypatch.setattr(sweep, "run_problem", flaky)
    res = run_sweep(PAPER, {"robot.k": [0.1, 0.2]}, jobs=1)
    assert list(res.status_array()) == ["success", "error"]
    assert res.rows[1]["message"] == "RuntimeError: solver bug" and math.isnan(res.rows[1]["S"])
    assert res.summary()["counts"] == {"error": 1, "success": 1}


def test_bad_extra_columns_and_arguments(tmp_path):
    with pytest.raises(ValueError, match="did you mean 'cycles'"):
        run_sweep(PAPER, {"robot.k": [0.1]}, extra_columns=("cycels",))
    with pytest.raises(ValueError, match="valid"):
        run_sweep(PAPER, {"robot.k": [0.1]}, extra_columns=("phi",))
    with pytest.raises(ValueError, match="jobs"):
        run_sweep(PAPER, {"robot.k": [0.1]}, jobs=0)
    with pytest.raises(ValueError, match="mutually exclusive"):
        run_sweep(PAPER, {"robot.k": [0.1]}, out_dir=tmp_path, resume=True, force=True)


# --------------------------------------------------------------------------------------------
# output directories: refuse to overwrite, resume, mismatch
# --------------------------------------------------------------------------------------------
def test_existing_output_needs_force_and_resume_checks_settings(tmp_path):
    out = tmp_path / "s"
    grid = {"gait.psi_deg": [30.0, 60.0]}
    first = run_sweep(PAPER, grid, out_dir=out)
    before = (out / RESULTS_FILE).read_bytes()
    with pytest.raises(SweepError, match="already holds a sweep .*--resume.*--force"):
        run_sweep(PAPER, grid, out_dir=out)
    assert (out / RESULTS_FILE).read_bytes() == before
    with pytest.raises(SweepError, match=r"differs .*grid gait.psi_deg: 2 values 30\.\.60 -> "
                                         r"3 values 30\.\.90"):
        run_sweep(PAPER, {"gait.psi_deg": [30.0, 60.0, 90.0]}, out_dir=out, resume=True)
    with pytest.raises(SweepError, match=r"\[robot\] k 0.1677 -> 0.2"):
        run_sweep(load_problem(PAPER, ["robot.k=0.2"]), grid, out_dir=out, resume=True)
    with pytest.raises(SweepError, match="extra columns"):
        run_sweep(PAPER, grid, out_dir=out, resume=True, extra_columns=("cycles",))
    again = run_sweep(PAPER, grid, out_dir=out, resume=True)  # complete: nothing to compute
    assert again.computed == 0 and (out / RESULTS_FILE).read_bytes() == before
    assert_same_rows(again.rows, first.rows)
    forced = run_sweep(PAPER, {"gait.psi_deg": [90.0]}, out_dir=out, force=True)
    assert forced.computed == 1 and len(read_csv(out / RESULTS_FILE)) == 2


def test_resume_from_a_journal_with_a_torn_last_line(tmp_path):
    out = tmp_path / "s"
    grid = {"gait.psi_deg": [0.0, 45.0, 90.0], "gait.A_deg": [30.0, 60.0]}
    ref = run_sweep(PAPER, grid, out_dir=out)
    expected = (out / RESULTS_FILE).read_text()
    # the state of a run killed while writing its fourth row: a journal of three rows and a torn
    # line
    lines = expected.splitlines(keepends=True)
    journal = (["index," + lines[0]] + [f"{i}," + lines[1 + i] for i in (4, 0, 2)]
               + ["1,0.0,60.0,,,,fo"])
    (out / JOURNAL_FILE).write_text("".join(journal))
    (out / RESULTS_FILE).unlink()
    with pytest.raises(SweepError, match="incomplete .3 of 6 points"):
        SweepResult.read(out)
    journal_bytes = (out / JOURNAL_FILE).read_bytes()
    partial = SweepResult.read(out, partial=True)
    assert list(partial.status_array().ravel()).count("missing") == 3
    assert (out / JOURNAL_FILE).read_bytes() == journal_bytes  # a reader never repairs a journal
    res = run_sweep(PAPER, grid, out_dir=out, resume=True)
    assert res.computed == 3
    assert (out / RESULTS_FILE).read_text() == expected
    assert_same_rows(res.rows, ref.rows)


def _journal_rows(journal: Path) -> int:
    try:
        return max(journal.read_bytes().count(b"\n") - 1, 0)
    except FileNotFoundError:
        return 0


# (a fuzz of kill moments; the default suite kills at fixed points: test_workers)
@pytest.mark.heavy
def test_resume_after_the_sweep_process_is_killed_at_random_moments(tmp_path):
    """SIGKILL to the CLI's process group at random (seeded) moments, each run resuming the last,
    then --resume to the end: the same file as an uninterrupted run, and nothing left behind."""
    rng = random.Random(20240611)
    specs = ["gait.psi_deg=0:180:40", "gait.gamma_deg=80:100:4"]
    n_points = 160
    # ~40 ms per point (500 continuation steps per cycle), 160 points sent in chunks of ~50 ms of
    # work: four kills after at most a few rows each can never reach the end of the sweep (the first
    # kill may come after ~1 s of rows)
    args = ["--set", "simulation.max_step=0.002"]
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "ocp_crawl", "sweep", str(PAPER),
           *[a for s in specs for a in ("--grid", s)],
           *args, "--jobs", "2", "--out", str(out), "--no-progress"]
    journal = out / JOURNAL_FILE
    n_done = 0
    # the first kill while the process starts (before or while it opens the sweep's files), then
    # kills after a random number of further rows plus a random delay (between and during writes)
    for kill in range(4):
        proc = subprocess.Popen(cmd + (["--resume"] if kill else []), cwd=tmp_path,
                                start_new_session=True,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        try:
            if kill == 0:
                time.sleep(rng.uniform(0.2, 1.0))
            else:
                target = n_done + rng.randint(1, 5)
                deadline = time.monotonic() + 60
                while (time.monotonic() < deadline and proc.poll() is None
                       and _journal_rows(journal) < target):
                    time.sleep(0.002)
                time.sleep(rng.uniform(0.0, 0.05))
        finally:
            os.killpg(proc.pid, signal.SIGKILL)
            _, err = proc.communicate()
        assert proc.returncode == -signal.SIGKILL, \
            f"run {kill} ended before it could be killed: {err}"
        assert not (out / RESULTS_FILE).exists()
        if (out / SETTINGS_FILE).exists():
            # a torn journal line is not a finished point
            finished = SweepResult.read(out, partial=True)
            done_now = int((finished.status_array() != "missing").sum())
            assert n_done <= done_now < n_points
            n_done = done_now
    assert n_done >= 3

    code = main(cmd[3:] + ["--resume", "--json"])
    assert code == 0
    ref = run_sweep(load_problem(PAPER, ["simulation.max_step=0.002"]), grid_from_specs(specs),
                    out_dir=tmp_path / "ref", jobs=2)
    got, want = read_csv(out / RESULTS_FILE), read_csv(tmp_path / "ref" / RESULTS_FILE)
    assert got[0] == want[0] and len(got) == len(want) == n_points + 1
    keys = [tuple(r[:2]) for r in got[1:]]
    assert len(set(keys)) == n_points and keys == [tuple(r[:2]) for r in want[1:]]
    assert_same_rows(SweepResult.read(out).rows, ref.rows)
    assert (out / RESULTS_FILE).read_bytes() == (tmp_path / "ref" / RESULTS_FILE).read_bytes()
    assert not journal.exists()
    assert sorted(p.name for p in out.iterdir()) == sorted([".sweep.lock", SETTINGS_FILE,
                                                            RESULTS_FILE, "summary.json"])


def test_resume_after_a_kill_while_the_journal_header_was_written(tmp_path, monkeypatch):
    """A run killed before its journal's header was complete leaves an empty (or torn) journal: the
    resumed run writes the header, so that a second kill and resume still work."""
    out = tmp_path / "s"
    grid = {"gait.psi_deg": [0.0, 45.0, 90.0]}
    ref = run_sweep(PAPER, grid, out_dir=out)
    expected = (out / RESULTS_FILE).read_text()
    append = SweepStore.append
    for torn in ("", "index,gait.ps"):
        (out / RESULTS_FILE).unlink(missing_ok=True)
        (out / JOURNAL_FILE).write_text(torn)
        rows = []

        def killed_at_the_second_row(self, settings, index, row):
            rows.append(index)
            if len(rows) == 2:
                raise KeyboardInterrupt
            append(self, settings, index, row)

        monkeypatch.setattr(SweepStore, "append", killed_at_the_second_row)
        with pytest.raises(KeyboardInterrupt):
            run_sweep(PAPER, grid, out_dir=out, resume=True)
        monkeypatch.undo()
        assert (out / JOURNAL_FILE).read_text().startswith("index [-],gait.psi_deg [deg],")
        res = run_sweep(PAPER, grid, out_dir=out, resume=True)
        assert res.computed == 2
        assert (out / RESULTS_FILE).read_text() == expected
        assert_same_rows(res.rows, ref.rows)


def test_files_without_units_in_the_header_are_read_and_other_units_refused(tmp_path):
    """results.csv and the journal of an earlier version (bare column names) are read as they
    are, and a resume writes results.csv with the units; a header whose unit differs is refused
    naming the column."""
    out = tmp_path / "s"
    grid = {"gait.psi_deg": [0.0, 45.0], "model.gravity": ["physical"]}
    ref = run_sweep(PAPER, grid, out_dir=out, extra_columns=("cycles",))
    expected = (out / RESULTS_FILE).read_text()
    assert expected.startswith("gait.psi_deg [deg],model.gravity,S [m],W_plus [J],CoT_plus [-],"
                               "status,message,cycles [-]\n")
    lines = expected.splitlines(keepends=True)
    bare = "gait.psi_deg,model.gravity,S,W_plus,CoT_plus,status,message,cycles\n"
    (out / RESULTS_FILE).write_text(bare + "".join(lines[1:]))
    assert_same_rows(SweepResult.read(out).rows, ref.rows)
    # an earlier version's journal of the first point: resumed, and the file written with the units
    (out / RESULTS_FILE).unlink()
    (out / JOURNAL_FILE).write_text("index," + bare + "0," + lines[1])
    res = run_sweep(PAPER, grid, out_dir=out, resume=True, extra_columns=("cycles",))
    assert res.computed == 1 and (out / RESULTS_FILE).read_text() == expected
    (out / RESULTS_FILE).write_text(expected.replace("S [m]", "S [mm]", 1))
    with pytest.raises(SweepError, match=r"results.csv: columns differ from settings.json "
                                         r"\(column 3 is 'S \[mm\]', expected 'S \[m\]'\); "
                                         r"start again with --force"):
        SweepResult.read(out)
    with pytest.raises(SweepError, match=r"column 3 is 'S \[mm\]'"):
        run_sweep(PAPER, grid, out_dir=out, resume=True, extra_columns=("cycles",))


# --------------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------------
def test_cli_sweep_json_and_summary(tmp_path, capsys):
    out = tmp_path / "c"
    code = main(["sweep", str(PAPER), "--grid", "gait.A_deg=30,60", "--set", "robot.k=0.15",
                 "--jobs", "1", "--out", str(out), "--json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    data = json.loads(captured.out)
    # A 60 loses a contact
    assert data["points"] == 2 and data["successes"] == 1 and data["failures"] == 1
    assert (data["out_dir"] == str(out) and data["elapsed_s"] > 0
            and data["best"]["point"] == {"gait.A_deg": 30.0})
    code = main(["sweep", str(PAPER), "--grid", "gait.A_deg=30,60", "--set", "robot.k=0.15",
                 "--out", str(out), "--resume"])
    captured = capsys.readouterr()
    assert code == 0
    assert "2 points" in captured.out and "success 1" in captured.out and "best S" in captured.out


def test_cli_sweep_echoes_the_resolved_values(tmp_path, capsys):
    """Every value of every axis is echoed, in the text summary and in --json (the step form
    included)."""
    argv = ["sweep", str(PAPER), "--grid", "gait.psi_deg=30:60:step=15", "--grid",
            "robot.k=0.1,0.2", "--jobs", "1"]
    assert main(argv + ["--out", str(tmp_path / "a"), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["grid"] == {"gait.psi_deg": [30.0, 45.0, 60.0], "robot.k": [0.1, 0.2]}
    assert data["units"] == {"gait.psi_deg": "deg", "robot.k": "N m/rad", "S": "m", "W_plus": "J",
                             "CoT_plus": "-", "elapsed_s": "s"}
    assert main(argv + ["--out", str(tmp_path / "b")]) == 0
    out = capsys.readouterr().out
    assert "  gait.psi_deg = 30, 45, 60 (3 values, step 15)" in out.splitlines()
    assert "  robot.k = 0.1, 0.2 (2 values)" in out.splitlines()
    # a long axis: its ends, its length and its step
    assert main(["sweep", str(PAPER), "--grid", "gait.psi_deg=0:44:step=2", "--set", "robot.k=0.5",
                 "--jobs", "1", "--out", str(tmp_path / "c")]) == 0
    assert ("  gait.psi_deg = 0, 2, 4, 6, ..., 42, 44 (23 values, "
            "step 2)" in capsys.readouterr().out.splitlines())


def test_cli_sweep_shows_decimal_values_and_counts_in_words(tmp_path, capsys):
    """Range values are their decimals in the text, the JSON and results.csv (0.1, not
    0.09999999999999999); one point is "1 point", a lowest-CoT+ line naming the best point again is
    left out, and a resume that computes nothing says so instead of timing it."""
    argv = ["sweep", str(PAPER), "--grid", "gait.psi_deg=0:0.3:step=0.1", "--jobs", "1",
            "--no-progress"]
    assert main(argv + ["--out", str(tmp_path / "a"), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["grid"] == {"gait.psi_deg": [0.0, 0.1, 0.2, 0.3]}
    assert data["best"]["point"] == {"gait.psi_deg": 0.1}
    cells = [r[0] for r in read_csv(tmp_path / "a" / RESULTS_FILE)[1:]]
    assert cells == ["0.0", "0.1", "0.2", "0.3"]
    assert main(argv + ["--out", str(tmp_path / "b")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "  gait.psi_deg = 0, 0.1, 0.2, 0.3 (4 values, step 0.1)" in lines
    assert any(line.startswith("best S ") and " at gait.psi_deg = 0.1 (" in line for line in lines)
    # the best point's CoT+ is the lowest: no second line for it
    assert not any(line.startswith("lowest CoT+") for line in lines)
    one = ["sweep", str(PAPER), "--grid", "gait.psi_deg=45", "--jobs", "1",
           "--out", str(tmp_path / "c")]
    assert main(one) == 0
    text = capsys.readouterr().out
    assert ": 1 point\n" in text and "(1 point computed)" in text and "points" not in text
    assert main(one + ["--resume"]) == 0
    text = capsys.readouterr().out
    assert "time       nothing computed: 1 point from the previous run" in text.splitlines()


def test_sweep_over_one_foot_expands_mu(tmp_path, capsys):
    """A file giving mu swept over robot.mu1 (or mu2): the other foot keeps mu.  Each row equals the
    run of the file with both feet set explicitly, through the command line as through run_sweep."""
    values = [0.3, 0.35]
    for key, other in (("mu1", "mu2"), ("mu2", "mu1")):
        res = run_sweep(load_problem(PAPER), {f"robot.{key}": values}, jobs=1)
        for row, v in zip(res.rows, values):
            ref = run_problem(load_problem(PAPER, [f"robot.{key}={v}", f"robot.{other}=0.389"]))
            assert ref.success and row["status"] == "success"
            assert row["S"] == ref.S and row["W_plus"] == ref.W_plus
        # the two feet are not the same: friction on one foot changes S differently than on the
        # other
        assert res.array("S")[0] != run_problem(load_problem(PAPER, ["robot.mu=0.3"])).S
    for extra in ([], ["--set", "robot.mu2=0.389"]):
        out = tmp_path / f"cli{len(extra)}"
        assert main(["sweep", str(PAPER), "--grid", "robot.mu1=0.3,0.35", *extra, "--jobs", "1",
                     "--out", str(out), "--json"]) == 0
        data = json.loads(capsys.readouterr().out)
        assert data["successes"] == 2
        rows = SweepResult.read(out).rows
        ref = run_problem(load_problem(PAPER, ["robot.mu1=0.35", "robot.mu2=0.389"]))
        assert rows[1]["S"] == ref.S


def test_to_pandas_keeps_rows_and_units(tmp_path):
    pd = pytest.importorskip("pandas")
    res = run_sweep(load_problem(PAPER), {"gait.psi_deg": [30.0, 45.0], "robot.mu": [0.3, 0.389]},
                    out_dir=tmp_path / "p", jobs=1)
    df = res.to_pandas()
    assert isinstance(df, pd.DataFrame) and list(df.columns) == list(res.columns) and len(df) == 4
    for i, row in enumerate(res.rows):
        for col in res.columns:
            assert df[col].iloc[i] == row[col] or (isinstance(row[col], float)
                                                   and math.isnan(row[col]))
    # units from the schema (grid keys) and SI units of the results, as results.csv holds them
    assert df.attrs["units"] == {"gait.psi_deg": "deg", "robot.mu": "-", "S": "m", "W_plus": "J",
                                 "CoT_plus": "-"}
    assert df.attrs["grid"] == {"gait.psi_deg": [30.0, 45.0], "robot.mu": [0.3, 0.389]}
    # the same frame from the directory, and S in mm by the unit it carries
    again = SweepResult.read(tmp_path / "p").to_pandas()
    assert again.equals(df) and again.attrs["units"] == df.attrs["units"]
    ref = run_problem(load_problem(PAPER, ["gait.psi_deg=45", "robot.mu=0.389"])).S
    assert df.loc[(df["gait.psi_deg"] == 45.0) & (df["robot.mu"] == 0.389), "S"].item() == ref


def test_cli_default_output_directory(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", str(PAPER), "--grid", "gait.psi_deg=45", "--jobs", "1"]) == 0
    assert (tmp_path / "sweep_paper_gait" / RESULTS_FILE).exists()
    capsys.readouterr()


@pytest.mark.parametrize("argv, match", [
    (["--grid", "gait.psi=0:1:2"], "did you mean gait.psi_deg"),
    ([], "--grid"),
    (["--grid", "gait.psi_deg=45", "--resume", "--force"], "not allowed with"),
    (["--grid", "gait.psi_deg=45", "--jobs", "0"], "--jobs 0 is invalid"),
    (["--grid", "gait.psi_deg=45", "--set", "robot.k=-1"], "k = -1"),
])
def test_cli_sweep_bad_input(tmp_path, capsys, argv, match):
    code = main(["sweep", str(PAPER), "--out", str(tmp_path / "b"), *argv])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and err.startswith("ocp-crawl: error:")
    assert match in err


def test_cli_refuses_existing_output(tmp_path, capsys):
    argv = ["sweep", str(PAPER), "--grid", "gait.psi_deg=45", "--jobs", "1", "--out", str(tmp_path)]
    assert main(argv) == 0
    before = (tmp_path / RESULTS_FILE).read_bytes()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert ("holds a sweep" in err and "--resume" in err and "--force" in err
            and "Traceback" not in err)
    assert (tmp_path / RESULTS_FILE).read_bytes() == before
    assert main(argv + ["--force"]) == 0


# --------------------------------------------------------------------------------------------
# Dask
# --------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_dask_local_cluster_gives_the_same_rows(tmp_path):
    distributed = pytest.importorskip("distributed",
                                      reason="the [cluster] extra (dask.distributed) "
                                             "is not installed")
    grid = {"gait.psi_deg": [0.0, 45.0, 90.0], "gait.A_deg": [30.0, 60.0]}
    pool = run_sweep(PAPER, grid, out_dir=tmp_path / "pool", jobs=2)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        res = run_sweep(PAPER, grid, out_dir=tmp_path / "dask", scheduler=cluster.scheduler_address)
    assert res.computed == 6
    assert_same_rows(res.rows, pool.rows)
    assert ((tmp_path / "dask" / RESULTS_FILE).read_text()
            == (tmp_path / "pool" / RESULTS_FILE).read_text())


@pytest.mark.slow
def test_cli_sweep_over_the_solver(tmp_path, capsys):
    """``--grid simulation.solver=event,mpcc``: both simulators in one sweep, S agreeing to n_events
    (2 h)^2 relative (h = 1/steps: each stick-slip transition is taken up to two MPCC steps late,
    the slip over that window being quadratic in its length; 4 events per cycle, 100 steps:
    1.6e-3)."""
    out, steps = tmp_path / "solvers", 100
    code = main(["sweep", str(PAPER), "--grid", "simulation.solver=event,mpcc", "--grid",
                 "gait.psi_deg=30,45", "--set", f"simulation.steps={steps}", "--out", str(out),
                 "--jobs", "1", "--no-progress"])
    capsys.readouterr()
    assert code == 0
    res = SweepResult.read(out)
    assert res.keys == ("simulation.solver", "gait.psi_deg") and res.shape == (2, 2)
    assert (res.status_array() == "success").all()
    S = res.array("S")
    assert np.all(np.abs(S[1] - S[0]) <= 4 * (2 / steps) ** 2 * np.abs(S[0]))
    # the event row is the run_problem of the point
    assert S[0, 1] == run_problem(load_problem(PAPER, ["gait.psi_deg=45"])).S
    settings = json.loads((out / SETTINGS_FILE).read_text())
    assert settings["problem"]["simulation"]["solver"] == "event"
    assert settings["problem"]["simulation"]["steps"] == steps


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(signal, "SIGXFSZ"), reason="file size limits are POSIX")
def test_an_io_error_of_a_sweep_names_the_file(tmp_path):
    """A journal the file system refuses (here a file size limit, as a full disk) is named in the
    one line: the failed flush when the journal is closed is not a second, anonymous error."""
    import resource

    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (3072, 3072))

    out = tmp_path / "s"
    path = os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])
    env = dict(os.environ, PYTHONPATH=path)
    env.pop("OCP_CRAWL_TRACEBACK", None)
    argv = [sys.executable, "-m", "ocp_crawl", "sweep", str(PAPER), "--grid",
            "gait.psi_deg=0:90:40", "--out", str(out), "--no-progress", "--jobs", "1"]
    proc = subprocess.run(argv, capture_output=True, text=True, env=env, cwd=tmp_path,
                          preexec_fn=limit, timeout=300)
    assert proc.returncode == 1
    assert proc.stderr == f"ocp-crawl: I/O error: {out / JOURNAL_FILE}: File too large\n"
