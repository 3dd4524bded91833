"""Bad-input matrix: every command, malformed problem files and arguments -> exit 2, one line, no
traceback.

One table (:data:`ROWS`; its rows are in tests/_bad_input_rows.py and tests/_bad_input_data_rows.py)
of cases; each row runs ``ocp_crawl.cli.app.main`` in-process with every long computation replaced
by a function that fails the test (bad input must be rejected before any run), and checks: exit code
2, stdout empty, stderr exactly one line ``ocp-crawl: error: ...`` naming the file (for file
errors), the key and the value as written, no traceback.  A few rows also run through a real
``python -m ocp_crawl`` subprocess.
"""
import contextlib
import os
import signal
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

import pytest

import ocp_crawl.viz.animate
import ocp_crawl.cli.app as cli
import ocp_crawl.cli.run_commands
import ocp_crawl.cli.study_commands
import ocp_crawl.cli.fit_commands
import ocp_crawl.fit.solve
import ocp_crawl.problem.run
import ocp_crawl.sim.crosscheck
import ocp_crawl.sim.event
import ocp_crawl.ocp
import ocp_crawl.sim.angles
import ocp_crawl.studies.reproduce
import ocp_crawl.sweep.warmup
import ocp_crawl.sim.timestepping

from _bad_input_data_rows import _FIT_HEAD, _FIT_ROWS, DATA_ROWS
from _bad_input_rows import COMMAND_ROWS, OCP, PAPER, PAPER_TEXT, Row

#: the whole table: the rows of problem files and arguments, then those of data files and waveforms
ROWS = {**COMMAND_ROWS, **DATA_ROWS}


def _permissions_ignored() -> bool:
    """True for root (os.geteuid() == 0) unless it runs without CAP_DAC_OVERRIDE: probed, not
    assumed."""
    if not (hasattr(os, "geteuid") and os.geteuid() == 0):
        return False
    with tempfile.TemporaryDirectory() as d:
        probe = Path(d) / "probe"
        probe.write_text("x")
        probe.chmod(0)
        try:
            probe.read_text()
            return True
        except PermissionError:
            return False


ROOT = _permissions_ignored()


#: generous time limit of one row: a hang guard, not a timing assertion (every row takes well under
#: a second)
HANG_GUARD_S = 120


def _computed(*args, **kwargs):
    raise AssertionError("a long computation started before the bad input was rejected")


@pytest.fixture
def nothing_computed(monkeypatch):
    """Every solver, sweep and study fails the test if called (bad input must be rejected first)."""
    for module, name in ((ocp_crawl.cli.run_commands, "run_problem"),
                         (ocp_crawl.problem.run, "simulate"),
                         (ocp_crawl.sim.event.HybridStepper, "run"),
                         (ocp_crawl.sim.angles, "simulate_angles"),
                         (ocp_crawl.sim.timestepping, "simulate_mpcc"),
                         (ocp_crawl.cli.study_commands, "run_sweep"),
                         (ocp_crawl.studies.reproduce, "reproduce"),
                         (ocp_crawl.viz.animate, "animate_problem"),
                         (ocp_crawl.sim.crosscheck, "crosscheck"),
                         (ocp_crawl.ocp, "optimize_gait"), (ocp_crawl.sweep.warmup, "warmup"),
                         (ocp_crawl.fit.solve, "fit_measurements")):
        monkeypatch.setattr(module, name, _computed)


class Hang(Exception):
    """A row ran past HANG_GUARD_S."""


@contextlib.contextmanager
def hang_guard(case: str, seconds: int = HANG_GUARD_S):
    """Fail the row (instead of hanging the suite) if it runs longer than ``seconds`` (SIGALRM;
    POSIX main thread)."""
    if not hasattr(signal, "SIGALRM") or threading.current_thread() is not threading.main_thread():
        yield
        return

    def alarm(signum, frame):
        raise Hang(f"{case}: still running after {seconds} s (a hang: "
                   "the bad input was not rejected)")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def materialise(row: Row, tmp_path: Path) -> tuple[list[str], list[str]]:
    """The row's argv and words with the placeholders filled in (files created as needed)."""
    work = tmp_path / "work"
    work.mkdir()
    places = {"{paper}": str(PAPER), "{ocp}": str(OCP), "{tmp}": str(work),
              "{missing}": str(tmp_path / "nope.toml")}
    if row.text is not None:
        path = tmp_path / "x.toml"
        path.write_bytes(row.text.encode("utf-8", "surrogateescape"))
        places["{file}"] = str(path)
    blocker = tmp_path / "blocker"
    blocker.write_text("a regular file\n")
    places["{blocker}"] = str(blocker)
    (tmp_path / "adir").mkdir()
    places["{dir}"] = str(tmp_path / "adir")
    locked = tmp_path / "locked.toml"
    locked.write_text(PAPER_TEXT)
    locked.chmod(0)
    places["{unreadable}"] = str(locked)
    readonly = tmp_path / "readonly"
    readonly.mkdir()
    readonly.chmod(0o555)
    places["{readonly}"] = str(readonly)
    for name, data in row.files.items():
        (work / name).parent.mkdir(parents=True, exist_ok=True)
        (work / name).write_bytes(data)

    def fill(s: str) -> str:
        for k, v in places.items():
            s = s.replace(k, v)
        return s

    argv = ([row.command] if row.command else []) + [fill(a) for a in row.argv]
    return argv, [fill(w) for w in row.words]


def check_one_line(code: int, out: str, err: str, words, absent=()) -> str:
    assert code == 2, (code, out, err)
    assert out == ""
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1 and err.endswith("\n"), err
    line = lines[0]
    assert line.startswith("ocp-crawl: error: "), line
    for w in words:
        assert w in line, (w, line)
    for w in absent:
        assert w not in line, (w, line)
    return line


def test_every_command_has_rows():
    covered = {row.command for row in ROWS.values()}
    assert set(cli.COMMANDS) <= covered, set(cli.COMMANDS) - covered
    for name in cli.COMMANDS:  # several malformed inputs per command
        assert sum(row.command == name for row in ROWS.values()) >= 4, name
    assert len(ROWS) >= 30


@pytest.mark.parametrize("case", list(ROWS))
def test_bad_input_matrix(case, tmp_path, capsys, nothing_computed):
    row = ROWS[case]
    if row.needs_permissions and ROOT:
        pytest.skip("root ignores file permissions")
    if any(a == "/dev/zero" for a in row.argv) and not Path("/dev/zero").exists():
        pytest.skip("no /dev/zero here")
    try:
        argv, words = materialise(row, tmp_path)
        before = {p: p.read_bytes() for p in (tmp_path / "work").rglob("*") if p.is_file()}
        with hang_guard(case):
            code = cli.main(argv)
        out, err = capsys.readouterr()
        check_one_line(code, out, err, words, row.absent)
        # the refused run wrote nothing: earlier results are untouched, no new file appeared
        after = {p: p.read_bytes() for p in (tmp_path / "work").rglob("*") if p.is_file()}
        assert after == before
    finally:
        for name in ("locked.toml", "readonly"):
            if (tmp_path / name).exists():
                (tmp_path / name).chmod(0o755)


#: rows run again through a real subprocess: no traceback reaches stderr
SUBPROCESS_ROWS = ("sweep: NUM < 1", "optimize: unknown [ocp] key",
                   "simulate: cannot stand (no_start)",
                   "simulate: k = 1e308 (RuntimeWarnings)", "sweep: STOP inf (said nan)",
                   "simulate: /dev/zero (hung)", "simulate: TOML nested 5000 deep (RecursionError)")


@pytest.mark.slow
@pytest.mark.parametrize("case", SUBPROCESS_ROWS)
def test_bad_input_in_a_real_process(case, tmp_path):
    argv, words = materialise(ROWS[case], tmp_path)
    env = dict(os.environ, MPLBACKEND="Agg")
    env.pop("OCP_CRAWL_TRACEBACK", None)
    proc = subprocess.run([sys.executable, "-m", "ocp_crawl", *argv], capture_output=True,
                          text=True, env=env, timeout=HANG_GUARD_S, cwd=tmp_path)
    check_one_line(proc.returncode, proc.stdout, proc.stderr, words, ROWS[case].absent)


def test_the_guard_catches_a_computation(tmp_path, capsys, nothing_computed, monkeypatch):
    """The matrix's guard is live: valid input reaches a (replaced) solver, which ends as an
    internal error."""
    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    for argv in (["simulate", str(PAPER)],
                 ["sweep", str(PAPER), "--grid", "gait.psi_deg=45", "--out", str(tmp_path / "s")],
                 ["optimize", str(OCP)], ["crosscheck", str(PAPER)],
                 ["reproduce", "--out", str(tmp_path / "r")],
                 ["animate", str(PAPER), "--out", str(tmp_path / "a.gif")],
                 ["demo", "--out", str(tmp_path / "d")], ["warmup"]):
        code = cli.main(argv)
        # a run estimated above a minute is announced as it starts (ocp_crawl.problem.work)
        err = "".join(line for line in capsys.readouterr().err.splitlines(keepends=True)
                      if not line.startswith("ocp-crawl: estimated "))
        assert code == 1, (argv, err)
        assert err.startswith("ocp-crawl: internal error: AssertionError: "
                              "a long computation started"), err


def test_a_partly_valid_grid_is_data_not_bad_input():
    from ocp_crawl.problem import ProblemError, load_problem
    from ocp_crawl.sweep import check_some_point_valid, grid_from_specs

    problem = load_problem(PAPER)
    # gamma 30 with psi 45 starts with foot 1 off the ground; gamma 90 is fine: the sweep records
    # both
    check_some_point_valid(problem, grid_from_specs(["gait.gamma_deg=30,90"]))
    with pytest.raises(ProblemError, match="every one of the 4 points"):
        check_some_point_valid(problem,
                               grid_from_specs(["gait.gamma_deg=20,30", "gait.A_deg=30,40"]))


def test_the_guard_catches_a_fit(tmp_path, capsys, nothing_computed, monkeypatch):
    """Valid fit input reaches the (replaced) fit, which ends as an internal error: the rows above
    are rejected before it."""
    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    (tmp_path / "d.csv").write_bytes(_FIT_HEAD + _FIT_ROWS)
    code = cli.main(["fit", str(PAPER), str(tmp_path / "d.csv"), "--param", "robot.k", "--out",
                     str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 1 and err.startswith("ocp-crawl: internal error: AssertionError: "
                                        "a long computation started"), err


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
@pytest.mark.parametrize("where", ["problem file", "--input"])
def test_a_named_pipe_without_a_writer_does_not_hang(where, tmp_path, capsys, nothing_computed,
                                                     monkeypatch):
    """Opening a FIFO for reading waits for a writer (found by fuzzing: the command hung until
    killed).  The files are opened without waiting; a pipe that gets no data within PIPE_WAIT_S is
    bad input naming the file."""
    import ocp_crawl.io.files

    monkeypatch.setattr(ocp_crawl.io.files, "PIPE_WAIT_S", 0.2)
    fifo = tmp_path / ("p.toml" if where == "problem file" else "p.csv")
    os.mkfifo(fifo)
    argv = ["simulate", str(fifo)] if where == "problem file" else ["simulate", str(PAPER),
                                                                    "--input", str(fifo)]
    with hang_guard(where):
        code = cli.main(argv)
    out, err = capsys.readouterr()
    check_one_line(code, out, err, [fifo.name, "named pipe", "within 0.2 s", "no writer"])


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_a_named_pipe_whose_writer_comes_late_is_read(tmp_path):
    """A writer that opens the pipe after the reader (``mkfifo f; later > f``) is waited for, and
    its data read whole (the first fix read such a pipe as empty and left the writer blocked)."""
    from ocp_crawl.io.files import read_bounded

    fifo = tmp_path / "late.csv"
    os.mkfifo(fifo)
    data = b"phase [-],tau1 [N m],tau2 [N m]\n" * 2000   # more than a pipe's buffer

    def write():
        import time
        time.sleep(0.3)
        with open(fifo, "wb") as fh:
            fh.write(data)

    writer = threading.Thread(target=write)
    writer.start()
    with hang_guard("late writer"):
        got = read_bounded(fifo, 1 << 20)
    writer.join(timeout=10)
    assert got == data and not writer.is_alive()


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
@pytest.mark.parametrize("argv",
                         [["simulate", "{fifo}", "--set", "robot.k=0.2", "--drive", "torque"],
                          ["sweep", "{fifo}", "--grid", "gait.psi_deg=30,45", "--set",
                           "robot.k=0.2", "--out", "{tmp}/s", "--no-progress"]],
                         ids=["simulate", "sweep"])
def test_a_problem_file_on_a_named_pipe_is_read_once(argv, tmp_path, capsys, monkeypatch):
    """The checks of --set against shortcuts and grids read the file's data already read (a second
    read of a named pipe would wait for a writer that has gone)."""
    import ocp_crawl.io.files

    monkeypatch.setattr(ocp_crawl.io.files, "PIPE_WAIT_S", 5.0)
    fifo = tmp_path / "p.toml"
    os.mkfifo(fifo)

    def write():
        with open(fifo, "wb") as fh:
            fh.write(PAPER.read_bytes())

    writer = threading.Thread(target=write)
    writer.start()
    with hang_guard("pipe read once"):
        code = cli.main([a.replace("{fifo}",
                                   str(fifo)).replace("{tmp}", str(tmp_path)) for a in argv])
    writer.join(timeout=10)
    err = capsys.readouterr().err
    assert code == 0, err
