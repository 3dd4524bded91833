"""The ocp-crawl command line: outputs, exit codes and one-line errors for bad input."""
import json
import math
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from ocp_crawl.cli.app import COMMANDS, main

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "problems" / "paper_gait.toml"
PAPER_TEXT = PAPER.read_text()

JSON_KEYS = {"status", "success", "message", "S", "W_plus", "CoT_plus", "events", "cycles",
             "problem"}


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def write(tmp_path, text, name="x.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def edit(old, new):
    assert old in PAPER_TEXT, old
    return PAPER_TEXT.replace(old, new, 1)


def test_commands_are_registered():
    assert {"simulate", "demo"} <= set(COMMANDS)


def test_simulate_prints_a_readable_summary(capsys):
    code, out, err = run(capsys, "simulate", PAPER)
    assert code == 0, err
    assert err == ""
    for word in ("status     success", "S          -55.8", "mm per cycle", "W+ ", "mJ", "CoT+",
                 "cycles", "events in the steady cycle: 4", "stick-stick"):
        assert word in out, word


def test_simulate_json(capsys):
    code, out, err = run(capsys, "simulate", PAPER, "--json", "--drive", "angles")
    assert code == 0, err
    assert len(out.strip().splitlines()) == 1
    data = json.loads(out)
    assert JSON_KEYS <= set(data)
    assert data["success"] is True and data["status"] == 0 and data["drive"] == "angles"
    assert data["S"] == pytest.approx(-0.0558, rel=0.01)
    assert data["problem"]["gait"]["drive"] == "angles"
    assert data["problem"]["robot"]["k"] == 0.1677
    assert data["events"] and all({"t", "kind"} <= set(e) for e in data["events"])


def _text_events(text):
    """(title, [(t, phase, kind)]) of the events table of simulate's text summary."""
    lines = text.splitlines()
    i = next(j for j, line in enumerate(lines) if line.startswith("events"))
    rows = [line.split() for line in lines[i + 2:]]
    return lines[i], [(float(r[0]), float(r[1]), r[2]) for r in rows]


@pytest.mark.parametrize("sets", [[], ["gait.psi_deg=0", "gait.gamma_deg=60"]],
                         ids=["success", "fold"])
def test_simulate_json_labels_the_events_the_text_lists(capsys, sets):
    """The JSON labels every event steady (in the steady cycle the text lists) or not (the transient
    before it; every event of a failed run), with the phase the text shows; the text's count is the
    steady ones'."""
    argv = ["simulate", PAPER, *(a for s in sets for a in ("--set", s))]
    _, text, _ = run(capsys, *argv)
    code, out, _ = run(capsys, *argv, "--json")
    data = json.loads(out)
    title, rows = _text_events(text)
    steady = [e for e in data["events"] if e["steady"]]
    assert all(isinstance(e["steady"], bool) for e in data["events"])
    if data["success"]:
        assert title == f"events in the steady cycle: {len(steady)}"
        assert 0 < len(steady) < len(data["events"])
        shown = steady
    else:
        assert code == 1 and not steady and title == f"events: {len(data['events'])}"
        shown = data["events"]
    assert [(round(e["t"], 6), round(e["phase"], 5), e["kind"]) for e in shown] == rows


def test_simulate_reports_the_speed_of_a_problem_with_a_period(capsys):
    """[gait] period gives the mean speed |S| / period (text in mm/s, JSON in m/s); without it the
    speed is "-" and null, and S is the same either way (the quasistatic S per cycle does not depend
    on time)."""
    code, out, err = run(capsys, "simulate", PAPER, "--json")
    plain = json.loads(out)
    assert code == 0, err
    assert plain["period"] is None and plain["speed"] is None and plain["units"]["speed"] == "m/s"
    code, out, err = run(capsys, "simulate", PAPER, "--json", "--set", "gait.period=2.5")
    timed = json.loads(out)
    assert code == 0, err
    assert timed["S"] == plain["S"] and timed["period"] == 2.5 and timed["units"]["period"] == "s"
    assert timed["speed"] == abs(timed["S"]) / 2.5
    _, text, _ = run(capsys, "simulate", PAPER, "--set", "gait.period=2.5")
    assert f"speed      {abs(timed['S']) / 2.5 * 1e3:.3f} mm/s (|S| / period, period 2.5 s)" in text
    _, text, _ = run(capsys, "simulate", PAPER)
    assert "speed      - (no [gait] period)" in text


@pytest.mark.slow
def test_simulate_out_writes_the_files(capsys, tmp_path):
    out_dir = tmp_path / "run" / "deep"
    out_dir.mkdir(parents=True)
    (out_dir / "notes.txt").write_text("mine\n")  # a directory holding other files is fine
    argv = ["simulate", PAPER, "--set", "model.gravity=paper", "--out", out_dir]
    code, out, err = run(capsys, *argv)
    assert code == 0, err
    assert (out_dir / "notes.txt").read_text() == "mine\n"
    (out_dir / "notes.txt").unlink()
    names = {p.name for p in out_dir.iterdir()}
    # no temporary files left
    assert names == {"arrays.npz", "summary.json", "gait.png", "gait.pdf"}
    summary = json.loads((out_dir / "summary.json").read_text())
    assert summary["gravity"] == "paper" and summary["success"] is True
    with np.load(out_dir / "arrays.npz") as arrays:
        assert arrays["phi"].shape == (2,
                                       arrays["t"].size) and arrays["x1"].shape == arrays["t"].shape
    assert (out_dir / "gait.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out_dir / "gait.pdf").read_bytes()[:5] == b"%PDF-"
    refuse_then_force(capsys, argv, out_dir, names, 0)


@pytest.mark.slow
def test_numerical_failure_exits_1_and_still_prints_json(capsys, tmp_path):
    # a stiff robot with a large amplitude: foot 2 lifts off during the first cycle
    code, out, err = run(capsys, "simulate", PAPER, "--set", "robot.k=0.612", "--set",
                         "gait.A_deg=60", "--json", "--out", tmp_path)
    assert code == 1
    data = json.loads(out)
    assert data["success"] is False and data["status_name"] == "lift_off" and data["S"] is None
    assert err.startswith("ocp-crawl: simulation failed: a foot lifts off")
    assert len(err.strip().splitlines()) == 1
    assert (tmp_path / "gait.png").exists()


@pytest.mark.slow
def test_demo(capsys, tmp_path, monkeypatch):
    argv = ["demo", "--out", tmp_path / "demo"]
    code, out, err = run(capsys, *argv)
    assert code == 0, err
    assert "torque drive, physical gravity" in out and "prescribed angles" in out
    assert out.count("success") == 3
    files = {p.name for p in (tmp_path / "demo").iterdir()}
    for case in ("torque_physical", "torque_paper", "angles"):
        assert {f"{case}_gait.png", f"{case}_gait.pdf", f"{case}_summary.json",
                f"{case}_arrays.npz"} <= files
    summary = json.loads((tmp_path / "demo" / "demo_summary.json").read_text())
    # the physical and the printed gravity sign differ by a few percent in S (MODEL_NOTES erratum)
    s_phys, s_paper = summary["torque_physical"]["S"], summary["torque_paper"]["S"]
    assert 0.02 < abs(s_phys - s_paper) / abs(s_phys) < 0.10
    # --out guard: the figures of the --force run are not the point here (and cost most of the time)
    import ocp_crawl.cli.run_commands as cli
    from ocp_crawl.io.files import atomic_write

    def cheap_outputs(out, result, problem, data, stem=""):
        return [atomic_write(out / f"{stem}{name}",
                             lambda fh: fh.write(b"stand-in")) for name in cli.RUN_FILES]

    monkeypatch.setattr(cli, "write_outputs", cheap_outputs)
    refuse_then_force(capsys, argv, tmp_path / "demo", files, 0)


def test_help_and_version(capsys):
    code, out, _ = run(capsys, "--help")
    assert code == 0 and "simulate" in out and "demo" in out
    code, out, _ = run(capsys, "--version")
    assert code == 0 and "ocp-crawl" in out


# ------------------------------------------------------------------------------------------ bad
# input the table of malformed inputs of every command is tests/test_bad_input.py (its rows in
# tests/_bad_input_rows.py and tests/_bad_input_data_rows.py)


@pytest.mark.slow
def test_real_subprocess_bad_input_and_json(tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    bad = write(tmp_path, edit("k = 0.1677", "k = -1.0"))
    proc = subprocess.run([sys.executable, "-m", "ocp_crawl.cli", "simulate", str(bad)],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.strip() == (f"ocp-crawl: error: {bad}: [robot] k = -1.0 is invalid: "
                                   "must be in [1e-12, 1e12] (torsion stiffness, N m/rad): "
                                   "so that M g L, k/(M g L) "
                                   "and their squares stay far inside the floating-point range")
    proc = subprocess.run([sys.executable, "-m", "ocp_crawl", "simulate", str(PAPER), "--json"],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert JSON_KEYS <= set(json.loads(proc.stdout))


# ------------------------------------------------------------------------------------------
# internal errors
def one_line(err: str) -> str:
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize("exc",
                         [ZeroDivisionError("float division by zero"), ValueError("bad shape (2,)"),
                          TypeError("unsupported operand")])
def test_an_internal_error_exits_1_not_2(exc, capsys, monkeypatch):
    import ocp_crawl.cli.run_commands as cli

    def broken(*args, **kwargs):
        raise exc

    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    monkeypatch.setattr(cli, "run_problem", broken)
    code, out, err = run(capsys, "simulate", PAPER)
    assert code == 1
    assert out == ""
    assert one_line(err) == (f"ocp-crawl: internal error: {type(exc).__name__}: {exc} "
                             "(set OCP_CRAWL_TRACEBACK=1 for the traceback)")
    monkeypatch.setenv("OCP_CRAWL_TRACEBACK", "1")
    with pytest.raises(type(exc)):
        main(["simulate", str(PAPER)])


def test_an_internal_error_of_the_optimiser_exits_1(capsys, monkeypatch):
    import ocp_crawl.ocp

    def broken(*args, **kwargs):
        return 1.0 / 0.0

    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    monkeypatch.setattr(ocp_crawl.ocp, "optimize_gait", broken)
    code, out, err = run(capsys, "optimize", REPO / "problems" / "ocp_max_speed.toml")
    assert code == 1
    # the run's estimate (above a minute) is announced as it starts, then the error's one line
    notice, error = err.splitlines()
    assert notice.startswith("ocp-crawl: estimated about ")
    assert one_line(error).startswith("ocp-crawl: internal error: ZeroDivisionError: ")


def test_an_io_error_while_writing_exits_1(capsys, monkeypatch, tmp_path):
    import ocp_crawl.cli.run_commands as cli

    def full(path, *args, **kwargs):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    monkeypatch.setattr(cli, "write_npz", full)
    code, out, err = run(capsys, "simulate", PAPER, "--out", tmp_path / "o")
    assert code == 1
    line = one_line(err)
    assert line.startswith("ocp-crawl: I/O "
                           "error: ") and "No space left on device" in line and "arrays.npz" in line


# ------------------------------------------------------------------------------------------
# no_start
def test_no_start_check_agrees_with_the_solver():
    """check_start (the CLI's pre-check) rejects exactly the problems simulate_torque reports as
    no_start."""
    from ocp_crawl.cli.app import BadInput
    from ocp_crawl.cli.run_commands import check_start
    from ocp_crawl.problem import load_problem, run_problem
    from ocp_crawl.sim.result import Status

    for k, expect_start in ((0.00306, False), (0.0306, True), (0.1677, True)):
        problem = load_problem(PAPER, [f"robot.k={k}"])
        result = run_problem(problem)
        assert (result.status != Status.NO_START) is expect_start, (k, result.message)
        if expect_start:
            check_start(problem)
        else:
            with pytest.raises(BadInput) as info:
                check_start(problem)
            # the same verdict and detail as the solver's result
            assert result.message in str(info.value)
            assert f"k = {k}" in str(info.value)


# ------------------------------------------------------------------------------------------ --out
# and --force
def snapshot(directory: Path) -> dict:
    """name -> (bytes, mtime_ns, inode) of every file under directory."""
    out = {}
    for p in sorted(directory.rglob("*")):
        if p.is_file():
            st = p.stat()
            out[str(p.relative_to(directory))] = (p.read_bytes(), st.st_mtime_ns, st.st_ino)
    return out


#: a cheap optimize: few nodes, the harmonic baseline alone (every family: the shared run of
#: conftest.py)
OCP_CHEAP = ["--set", "ocp.nodes=8", "--set", "ocp.harmonic_psi=4", "--set",
             "ocp.baselines=harmonic",
             "--set", "ocp.baseline_samples=0", "--set", "ocp.baseline_starts=1",
             "--set", "ocp.baseline_evaluations=40"]

#: command -> (arguments after the command, files the run writes in --out); --out DIR is appended
#: (simulate and demo: in test_simulate_out_writes_the_files and test_demo)
FORCE_CASES = {
    "optimize": ([REPO / "problems" / "ocp_max_speed.toml", *OCP_CHEAP],
                 {"torques.csv", "optimal_gait.toml", "arrays.npz", "summary.json",
                  "optimal_gait.png", "optimal_gait.pdf"}),
    "sweep": ([PAPER, "--grid", "gait.psi_deg=45", "--jobs", "1", "--no-progress"],
              {"settings.json", "results.csv", "summary.json"}),
}


def refuse_then_force(capsys, argv, out_dir, files, first_code):
    """After a first run: the same run refuses (exit 2, one line) leaving every file untouched; with
    --force it runs again and rewrites the files."""
    before = snapshot(out_dir)
    assert set(files) <= set(before), set(before)
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    line = one_line(err)
    assert line.startswith(f"ocp-crawl: error: --out {out_dir}: would overwrite earlier results (")
    assert "--force" in line
    assert snapshot(out_dir) == before  # byte-identical, not even touched
    code, _, err = run(capsys, *argv, "--force")
    assert code == first_code, err
    after = snapshot(out_dir)
    assert set(after) == set(before)
    for name in files:  # every file written again (atomically: a new inode)
        assert after[name][2] != before[name][2] or after[name][1] != before[name][1], name


@pytest.mark.slow
@pytest.mark.parametrize("command", list(FORCE_CASES))
def test_out_is_never_overwritten_without_force(command, capsys, tmp_path):
    args, files = FORCE_CASES[command]
    out_dir = tmp_path / "out"
    argv = [command, *args, "--out", out_dir]
    first = run(capsys, *argv)[0]
    # the cheap optimisation may fail its replay; it writes its files either way
    assert first in (0, 1)
    refuse_then_force(capsys, argv, out_dir, files, first)


def test_animate_never_overwrites_a_gif_without_force(capsys, tmp_path):
    gif = tmp_path / "a.gif"
    argv = ["animate", PAPER, "--out", gif, "--cycles", "1", "--frames-per-cycle", "2"]
    code, _, err = run(capsys, *argv)
    assert code == 0, err
    before = snapshot(tmp_path)
    assert gif.read_bytes()[:6] == b"GIF89a"
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert one_line(err).startswith(f"ocp-crawl: error: --out {gif}: "
                                    "would overwrite earlier results (a.gif)")
    assert snapshot(tmp_path) == before
    code, _, err = run(capsys, *argv, "--force")
    assert code == 0, err
    assert gif.stat().st_ino != before["a.gif"][2] or gif.stat().st_mtime_ns != before["a.gif"][1]


def test_reproduce_refuses_before_computing_and_accepts_force_or_resume(capsys, tmp_path,
                                                                        monkeypatch):
    """No full reproduce here: a stand-in records the calls and writes report.md like the real
    one."""
    import ocp_crawl.studies.reproduce as rp

    calls = []

    def fake_reproduce(out_dir, quick=False, gravity="paper", sweep=None, log=None):
        calls.append(sweep.resume)
        report = Path(out_dir) / "report.md"
        report.write_text(f"run {len(calls)}\n")
        return rp.ReproduceResult(Path(out_dir), "quick", gravity, (report,), report, {}, (), 0.0)

    monkeypatch.setattr(rp, "reproduce", fake_reproduce)
    out_dir = tmp_path / "r"
    argv = ["reproduce", "--quick", "--no-progress", "--out", out_dir]
    assert run(capsys, *argv)[0] == 0 and calls == [False]
    before = snapshot(out_dir)
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == "" and calls == [False]  # refused before computing
    line = one_line(err)
    assert f"--out {out_dir}: would overwrite earlier results (report.md)" in line
    assert "--resume" in line and "--force" in line
    assert snapshot(out_dir) == before
    assert run(capsys, *argv, "--resume")[0] == 0 and calls == [False, True]
    assert run(capsys, *argv, "--force")[0] == 0 and calls == [False, True, False]
    assert (out_dir / "report.md").read_text() == "run 3\n"


# ------------------------------------------------------------------------------------------ solvers
@pytest.mark.slow
def test_simulate_with_the_mpcc_solver_from_the_problem_key(capsys):
    """``--set simulation.solver=mpcc`` runs the MPCC time-stepping (200 steps per cycle unless
    ``simulation.steps`` says otherwise); ``--solver``/``--steps`` are shortcuts.

    The event-driven and MPCC values of S agree to within n_events (2 h)^2, h = 1/steps: inside a
    mode the time-stepping is exact, and each of the steady cycle's stick-slip transitions is taken
    up to two steps late, the slip over that window (starting from zero slip rate) being quadratic
    in its length (see ocp_crawl.sim.crosscheck).  The paper gait has 4 events per cycle: 1.6e-3 at
    100 steps.
    """
    from ocp_crawl.problem import load_problem, run_problem

    assert load_problem(PAPER, ["simulation.solver=mpcc"]).to_dict()["simulation"]["steps"] == 200
    steps = 100
    code, out, err = run(capsys, "simulate", PAPER, "--set", "simulation.solver=mpcc", "--set",
                         f"simulation.steps={steps}", "--json")
    assert code == 0, err
    mpcc = json.loads(out)
    assert (mpcc["solver"] == "mpcc" and mpcc["status_name"] == "success"
            and "MPCC" in mpcc["message"])
    assert (mpcc["problem"]["simulation"]["solver"] == "mpcc"
            and mpcc["problem"]["simulation"]["steps"] == steps)
    event = run_problem(load_problem(PAPER))
    n_events, h = len(event.steady_events()), 1 / steps
    assert n_events == 4
    assert abs(mpcc["S"] - event.S) <= n_events * (2 * h) ** 2 * abs(event.S)
    # the shortcuts give the same run
    code, out, err = run(capsys, "simulate", PAPER, "--solver", "mpcc", "--steps", str(steps),
                         "--json")
    assert code == 0, err
    assert json.loads(out)["S"] == mpcc["S"]
    code, out, err = run(capsys, "simulate", PAPER)
    assert code == 0 and "(solver event)" in out


# ------------------------------------------------------------------------------------------ files,
# frames
def test_a_full_disk_names_the_file(capsys, monkeypatch, tmp_path):
    """A real full disk raises OSError(ENOSPC) without a file name (from write or fsync): the one
    line names the file, exit 1 (not bad input), and no temporary file is left."""
    import errno

    import ocp_crawl.io.files as files

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    monkeypatch.setattr(files.os, "fsync", full)
    out_dir = tmp_path / "o"
    code, out, err = run(capsys, "simulate", PAPER, "--out", out_dir)
    assert code == 1
    target = out_dir / "arrays.npz"  # the first file written
    assert one_line(err) == f"ocp-crawl: I/O error: {target}: {os.strerror(errno.ENOSPC)}"
    assert not out_dir.exists()  # all or nothing: the staged set is removed with the directory
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_names_its_target(tmp_path):
    import errno

    from ocp_crawl.io.files import atomic_write

    target = tmp_path / "x.json"
    target.write_text("old")

    def failing(fh):
        fh.write(b"partial")
        raise OSError(errno.EIO, "Input/output error")

    with pytest.raises(OSError) as info:
        atomic_write(target, failing)
    assert info.value.filename == str(target) and info.value.errno == errno.EIO
    assert target.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["x.json"]


def test_animation_frames_are_bounded():
    """frames_of refuses sizes beyond its bounds, and a failed run is shown over its last ``cycles``
    cycles only."""
    from ocp_crawl.problem import load_problem, run_problem
    from ocp_crawl.viz.animate import MAX_CYCLES, MAX_FRAMES_PER_CYCLE, frames_of

    ok = run_problem(load_problem(PAPER))
    assert ok.success
    assert len(frames_of(ok, MAX_CYCLES,
                         MAX_FRAMES_PER_CYCLE).t) == MAX_CYCLES * MAX_FRAMES_PER_CYCLE + 1
    for cycles, per_cycle in ((MAX_CYCLES + 1, 48), (2, MAX_FRAMES_PER_CYCLE + 1), (10**9, 48),
                              (2, 10**9)):
        with pytest.raises(ValueError, match="cycles must be in"):
            frames_of(ok, cycles, per_cycle)
    # a run that failed after 400 cycles (samples of the shape as data): shown over its last cycle,
    # 10 frames + 1
    n = 4001
    failed = SimpleNamespace(success=False, S=math.nan, t=np.linspace(0.0, 400.0, n), t0=0.0,
                             x1=np.zeros(n),
                             x2=np.full(n, 0.05), phi=np.full((2, n), 1.5), theta=np.zeros(n),
                             mode=np.zeros(n, int))
    fr = frames_of(failed, 1, 10)
    assert len(fr.t) == 11 and fr.t[0] == 399.0 and fr.t[-1] == 400.0


def test_input_path_beyond_the_basic_plane(tmp_path, capsys):
    """``--input`` with a character beyond U+FFFF in its path (before, the path became JSON's
    surrogate escapes, which TOML does not read back, and the file was "not found")."""
    table = tmp_path / "t\U0001F600.csv"
    table.write_text("phase [-],tau1 [N m],tau2 [N "
                     "m]\n0.0,-0.29,-0.29\n0.25,-0.25,-0.33\n0.5,-0.29,-0.29\n0.75,-0.33,-0.25\n",
                     encoding="utf-8")
    paper = Path(__file__).resolve().parent.parent / "problems" / "paper_gait.toml"
    code = main(["simulate", str(paper), "--input", str(table), "--json"])
    out, err = capsys.readouterr()
    assert code in (0, 1) and "No such file" not in err, err
    assert json.loads(out)["problem"]["gait"]["file"] == str(table)
