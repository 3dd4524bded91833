"""Nothing lost: every file is written atomically, and a writer killed half-way leaves the previous
file.

The kill-and-resume tests of sweeps and of ``reproduce`` are in test_sweep.py and test_studies.py.
"""
import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl.io import files
from ocp_crawl.io.files import TEMP_RE, atomic_write, remove_stale_temps, write_json, write_npz

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "problems" / "paper_gait.toml"


def temps(directory):
    return sorted(p.name for p in Path(directory).iterdir() if p.name.endswith(".tmp"))


# --------------------------------------------------------------------------------------------
# the writer
# --------------------------------------------------------------------------------------------
def test_a_write_that_fails_half_way_leaves_the_previous_file(tmp_path):
    target = tmp_path / "numbers.json"
    old = b'{"S": -0.05}\n'
    target.write_bytes(old)
    os.chmod(target, 0o640)

    def half(fh):
        fh.write(b'{"S": -0.0')
        fh.flush()
        raise RuntimeError("disk on fire")

    with pytest.raises(RuntimeError, match="disk on fire"):
        atomic_write(target, half)
    assert target.read_bytes() == old
    assert temps(tmp_path) == []
    # a complete write replaces the file and keeps its permissions
    write_json(target, {"S": -0.06})
    assert json.loads(target.read_text()) == {"S": -0.06}
    assert target.stat().st_mode & 0o777 == 0o640
    assert temps(tmp_path) == []


def test_a_failed_rename_leaves_the_previous_file(tmp_path, monkeypatch):
    target = tmp_path / "arrays.npz"
    write_npz(target, {"t": np.arange(3.0)})
    old = target.read_bytes()

    def broken_replace(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files.os, "replace", broken_replace)
    with pytest.raises(OSError, match="No space"):
        write_npz(target, {"t": np.arange(5.0)})
    monkeypatch.undo()
    assert target.read_bytes() == old
    assert temps(tmp_path) == []
    with np.load(target) as z:
        np.testing.assert_array_equal(z["t"], np.arange(3.0))


def test_a_failed_first_write_creates_nothing(tmp_path):
    def fail(fh):
        fh.write(b"x" * 100_000)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(tmp_path / "new.csv", fail)
    assert list(tmp_path.iterdir()) == []


KILLED_WRITER = textwrap.dedent("""
    import os, signal, sys
    from ocp_crawl.io.files import atomic_write

    def write(fh):
        fh.write(b"half of the new ")
        fh.flush()
        os.kill(os.getpid(), signal.SIGKILL)

    atomic_write(sys.argv[1], write)
""")


def test_a_writer_killed_half_way_leaves_the_previous_file_and_its_temporary_is_cleaned(tmp_path):
    """SIGKILL in the middle of a write: the old file intact; the orphaned temporary file is removed
    by the next write of that file, and only temporaries of dead writers on this host are ever
    removed."""
    target = tmp_path / "report.md"
    target.write_bytes(b"the old report\n")
    proc = subprocess.Popen([sys.executable, "-c", KILLED_WRITER, str(target)],
                            stderr=subprocess.PIPE)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == -signal.SIGKILL, err
    assert target.read_bytes() == b"the old report\n"
    (orphan,) = temps(tmp_path)
    m = TEMP_RE.match(orphan)
    assert (m and m["name"] == "report.md" and int(m["pid"]) == proc.pid
            and m["host"] == files.HOST_TAG)
    assert (tmp_path / orphan).read_bytes() == b"half of the new "

    # temporaries that must survive: of this process and of another running one (writers still at
    # work), of another host (its pids mean nothing here), of another file's name, not of this
    # package
    running = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        live = f".report.md.{os.getpid()}-{files.HOST_TAG}.abc123.tmp"
        live_other = f".report.md.{running.pid}-{files.HOST_TAG}.abc123.tmp"
        other_host = (f".report.md.{m['pid']}-"
                      f"{'0' * 8 if files.HOST_TAG != '0' * 8 else '1' * 8}.abc123.tmp")
        other_file = f".summary.json.{m['pid']}-{files.HOST_TAG}.abc123.tmp"
        not_ours = ".report.md.swp.tmp"
        keep = [live, live_other, other_host, not_ours]
        for name in keep + [other_file]:
            (tmp_path / name).write_bytes(b"keep")
        atomic_write(target, lambda fh: fh.write(b"the new report\n"))
        assert target.read_bytes() == b"the new report\n"
        assert temps(tmp_path) == sorted(keep + [other_file])
        # the directory sweep removes the dead writer's temporary of any file, nothing else
        assert remove_stale_temps(tmp_path) == [tmp_path / other_file]
        assert temps(tmp_path) == sorted(keep)
    finally:
        running.kill()
        running.wait()


# --------------------------------------------------------------------------------------------
# every file the commands write is renamed into place from a temporary file
# --------------------------------------------------------------------------------------------
#: runs CLI commands with an audit hook recording every open for writing and every rename under a
#: directory; audit events come from the interpreter itself (builtins.open, io.open, os.open,
#: os.rename/os.replace), so any Python-level writer is seen: fig.savefig(path), Image.save(path),
#: np.savez(path), Path.write_text, open(path, "w")
MONITOR = textwrap.dedent("""
    import json, os, sys
    from pathlib import Path
    import matplotlib
    matplotlib.use("Agg")

    base, commands, log = Path(sys.argv[1]).resolve(), json.loads(sys.argv[2]), sys.argv[3]
    events, recording = [], [False]
    WRITE = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_TRUNC | os.O_APPEND

    def under(p):
        if isinstance(p, int) or p is None:
            return None
        p = Path(os.path.abspath(os.fsdecode(p)))
        return str(p) if base in p.parents else None

    def hook(event, args):
        if not recording[0]:
            return
        if event == "open":
            path, mode, flags = args
            p = under(path)
            writing = (flags & WRITE) if isinstance(flags, int) and flags >= 0 else \\
                any(c in (mode or "") for c in "wax+")
            if p and writing and not os.path.isdir(p):
                events.append(["write", p])
        elif event == "os.rename":
            src, dst = under(args[0]), under(args[1])
            if src or dst:
                events.append(["rename", src, dst])

    sys.addaudithook(hook)
    from ocp_crawl.cli.app import main
    import matplotlib.pyplot as plt
    import numpy as np

    codes = []
    recording[0] = True
    for argv in commands:
        codes.append(main(argv))
    # writes that are NOT atomic, to show that the monitor catches them
    control = base / "control"
    control.mkdir()
    fig = plt.figure()
    fig.savefig(control / "direct.png")
    np.savez(control / "direct.npz", x=np.zeros(2))
    (control / "direct.txt").write_text("x")
    recording[0] = False
    Path(log).write_text(json.dumps({"codes": codes, "events": events}))
""")

#: written directly by design: the sweep's lock (empty) and its append-only journal (deleted at the
#: end)
DIRECT_OK = {".sweep.lock", "results.partial.csv"}


def _staged(path: str, renamed: dict) -> str | None:
    """Where ``path`` was before the staging of ``files.write_set`` moved it: the file itself
    renamed out of a staging directory (``.<DIR>.<pid>-<host>.<random>.tmp``), or a directory above
    it renamed from one."""
    src = renamed.get(path)
    if src is not None and TEMP_RE.match(Path(src).parent.name):
        return src
    for d in Path(path).parents:
        src = renamed.get(str(d))
        if src is not None and TEMP_RE.match(Path(src).name):
            return str(Path(src) / Path(path).relative_to(d))
    return None


def _atomic(path: str, renamed: dict, written: set) -> bool:
    """``path`` renamed into place from a temporary file of its directory (atomic_write), itself or
    as staged by write_set (all or nothing)."""
    src = renamed.get(path)
    m = TEMP_RE.match(Path(src).name) if src else None
    if (m and m["name"] == Path(path).name and Path(src).parent == Path(path).parent
        and src in written):
        return True
    staged = _staged(path, renamed)
    return staged is not None and staged != path and _atomic(staged, renamed, written)


def non_atomic(events, root):
    """Final files under ``root`` that were not renamed into place from a temporary of the same
    directory (directly, or inside the staging directory of an all-or-nothing set), or that were
    opened for writing directly; and temporary files left behind."""
    written = {e[1] for e in events if e[0] == "write"}
    renamed = {}
    for e in events:
        if e[0] == "rename":
            renamed[e[2]] = e[1]
    problems = []
    for f in sorted(p for p in Path(root).rglob("*") if p.is_file()):
        if f.name.endswith(".tmp") or any(TEMP_RE.match(d.name) for d in f.parents):
            problems.append(f"{f}: temporary file left behind")
        elif f.name in DIRECT_OK:
            continue
        elif str(f) in written:
            problems.append(f"{f}: opened for writing directly")
        elif not _atomic(str(f), renamed, written):
            problems.append(f"{f}: not renamed from a temporary file of its directory "
                            f"(source {renamed.get(str(f))})")
    # files written directly and deleted again are harmless scratch files; the rest was checked
    # above
    return problems


@pytest.mark.slow
def test_every_output_file_is_renamed_into_place(tmp_path):
    tmp_path = tmp_path.resolve()  # the monitor compares absolute paths
    out = tmp_path / "runs"
    out.mkdir()
    commands = [
        ["simulate", str(PAPER), "--out", str(out / "simulate")],
        ["demo", "--out", str(out / "demo")],
        ["animate", str(PAPER), "--out", str(out / "animate" / "crawl.gif"), "--cycles", "1",
         "--frames-per-cycle", "4"],
        ["sweep", str(PAPER), "--grid", "gait.psi_deg=0:90:3", "--out", str(out / "sweep"),
         "--jobs", "1", "--no-progress"],
        ["optimize", str(REPO / "problems" / "ocp_max_speed.toml"), "--set", "ocp.nodes=8",
         "--set", "ocp.harmonic_psi=4", "--set", "ocp.baselines=harmonic", "--set",
         "ocp.baseline_samples=0", "--set", "ocp.baseline_starts=1",
         "--set", "ocp.baseline_evaluations=40", "--out", str(out / "optimize")],
    ]
    log = tmp_path / "events.json"
    proc = subprocess.run([sys.executable, "-c", MONITOR, str(tmp_path), json.dumps(commands),
                           str(log)],
                          capture_output=True, text=True, cwd=tmp_path,
                          env=dict(os.environ, MPLBACKEND="Agg"), timeout=300)
    assert proc.returncode == 0, proc.stderr
    data = json.loads(log.read_text())
    # simulate, demo, animate and sweep succeed; optimize may fail its replay (exit 1) but writes
    # its files
    assert data["codes"][:4] == [0, 0, 0, 0] and data["codes"][4] in (0, 1), (data["codes"],
                                                                              proc.stderr)
    expected = {"simulate": {"arrays.npz", "summary.json", "gait.png", "gait.pdf"},
                "animate": {"crawl.gif"},
                "sweep": {"settings.json", "results.csv", "summary.json"},
                "optimize": {"torques.csv", "optimal_gait.toml", "arrays.npz", "summary.json",
                             "optimal_gait.png", "optimal_gait.pdf"}}
    for name, want in expected.items():
        assert want <= {p.name for p in (out / name).iterdir()}, name
    assert (len(list((out / "demo").glob("*_gait.png"))) >= 2
            and (out / "demo" / "demo_summary.json").exists())
    n_files = sum(1 for p in out.rglob("*") if p.is_file())
    assert n_files >= 25
    assert non_atomic(data["events"], out) == []
    # the monitor sees non-atomic writers: fig.savefig(path), np.savez(path), Path.write_text
    flagged = non_atomic(data["events"], tmp_path / "control")
    assert [Path(p.split(":")[0]).name for p in flagged] == ["direct.npz", "direct.png",
                                                             "direct.txt"], flagged


# --------------------------------------------------------------------------------------------
# the compiled-library cache
# --------------------------------------------------------------------------------------------
def test_a_killed_library_build_is_cleaned_up_and_rebuilt(tmp_path, monkeypatch):
    """The C source and the library are built in a private temporary directory and the library
    renamed into the cache: a build killed half-way leaves only that directory, which the next build
    removes."""
    cs = pytest.importorskip("casadi")
    from ocp_crawl.model import compiled

    if compiled._compiler() is None:
        pytest.skip("no C compiler")
    monkeypatch.setenv("OCP_CRAWL_CACHE", str(tmp_path))
    x = cs.SX.sym("x", 2)
    fun = cs.Function("nothing_lost_f", [x], [cs.vertcat(x[0] * x[1], cs.sin(x[0]))])
    lib = compiled.build_library(fun)
    assert lib is not None and lib.parent == tmp_path
    # the state after a build killed by SIGKILL: no library, the dead builder's directory with a
    # partial file
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    lib.unlink()
    stale = tmp_path / f".{lib.name}.{dead.pid}-{files.HOST_TAG}.k1ll3d.tmp"
    stale.mkdir()
    (stale / "f.c").write_text("/* half a source")
    rebuilt = compiled.build_library(fun)
    assert rebuilt == lib and lib.exists() and not stale.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == [lib.name]
    f = compiled.FastFunction(fun)
    assert f.compiled
    np.testing.assert_allclose(f([0.5, 2.0])[0], [1.0, np.sin(0.5)], rtol=1e-15)
