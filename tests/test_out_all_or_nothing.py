"""The files of ``--out DIR`` are written all or nothing (``ocp_crawl.io.files.write_set``).

An I/O error while the second file is written leaves DIR absent (a new DIR) or with its earlier
complete contents (``--force`` over an earlier run), never a partial set, and the message names the
file; no staging directory is left behind.
"""
import errno
import os
from pathlib import Path

import pytest

from ocp_crawl.cli.app import main
from ocp_crawl.io.files import write_set

REPO = Path(__file__).resolve().parent.parent
PAPER = str(REPO / "problems" / "paper_gait.toml")


def full(path, *args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device", str(path))


def contents(directory: Path) -> dict:
    return {str(p.relative_to(directory)): p.read_bytes()
            for p in sorted(directory.rglob("*")) if p.is_file()}


def no_staging_left(parent: Path) -> None:
    assert not [p for p in parent.rglob("*.tmp")], list(parent.rglob("*.tmp"))


def one_error(capsys, argv, name) -> str:
    assert main([str(a) for a in argv]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("ocp-crawl: I/O error: "), err
    assert name in err and "No space left on device" in err, err
    return err


def test_simulate_new_out_is_absent_after_an_io_error(capsys, monkeypatch, tmp_path):
    import ocp_crawl.cli.run_commands as cli
    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    monkeypatch.setattr(cli, "write_json", full)   # summary.json, the 2nd file (after arrays.npz)
    out = tmp_path / "a" / "run"
    err = one_error(capsys, ["simulate", PAPER, "--json", "--out", out], "summary.json")
    assert str(out / "summary.json") in err   # the file as it would have been, not the staged one
    assert not out.exists()
    no_staging_left(tmp_path)


@pytest.mark.slow
def test_simulate_force_keeps_the_earlier_run_after_an_io_error(capsys, monkeypatch, tmp_path):
    import ocp_crawl.cli.run_commands as cli
    out = tmp_path / "run"
    assert main(["simulate", PAPER, "--json", "--out", str(out)]) == 0
    capsys.readouterr()
    before = contents(out)
    assert set(before) == set(cli.RUN_FILES)
    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    monkeypatch.setattr(cli, "write_json", full)
    one_error(capsys, ["simulate", PAPER, "--set", "gait.A_deg=25", "--json", "--out", out,
                       "--force"], "summary.json")
    assert contents(out) == before
    no_staging_left(tmp_path)


def test_fit_out_is_absent_after_an_io_error(capsys, monkeypatch, tmp_path):
    import ocp_crawl.fit.report as report
    data = tmp_path / "d.csv"
    data.write_text("psi [deg],S [mm],sigma_S [mm]\n30,-40,2\n45,-55,2\n60,-65,2\n")
    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    monkeypatch.setattr(report, "write_json", full)   # fit.json, after fitted_problem.toml
    out = tmp_path / "fit"
    one_error(capsys, ["fit", PAPER, data, "--param", "robot.mu", "--max-nfev", "3", "--no-figure",
                       "--json", "--out", out], "fit.json")
    assert not out.exists()
    no_staging_left(tmp_path)


def test_init_writes_nothing_after_an_io_error(capsys, monkeypatch, tmp_path):
    import ocp_crawl.problem.shipped as shipped
    real = shipped.atomic_write
    calls = []

    def second_fails(path, write):
        calls.append(path)
        if len(calls) == 2:
            full(path)
        return real(path, write)
    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    monkeypatch.setattr(shipped, "atomic_write", second_fails)
    (tmp_path / "mine.txt").write_text("mine")
    one_error(capsys, ["init", tmp_path], calls[1].name if calls else "problems")
    assert not [p for p in tmp_path.rglob("*") if p.is_file() and p.name != "mine.txt"]
    no_staging_left(tmp_path)


@pytest.mark.parametrize("existing", [False, True])
def test_write_set_is_all_or_nothing(tmp_path, existing):
    out = tmp_path / "out"
    if existing:
        out.mkdir()
        (out / "a.txt").write_text("old a")
        (out / "keep.txt").write_text("mine")
    before = contents(out) if existing else None

    def write(d: Path, fail: bool):
        (d / "a.txt").write_text("new a")
        if fail:
            raise OSError(errno.EIO, "Input/output error", str(d / "b.txt"))
        (d / "b.txt").write_text("new b")
        return [d / "a.txt", d / "b.txt"]

    with pytest.raises(OSError) as info:
        write_set(out, lambda d: write(d, True))
    assert info.value.filename == str(out / "b.txt")
    assert (contents(out) == before) if existing else not out.exists()
    files = write_set(out, lambda d: write(d, False))
    assert files == [out / "a.txt", out / "b.txt"]
    new = {"a.txt": b"new a", "b.txt": b"new b"}
    assert contents(out) == (dict(new, **{"keep.txt": b"mine"}) if existing else new)
    assert not list(tmp_path.rglob("*.tmp"))
    if not existing:
        assert os.stat(out).st_mode & 0o777 == 0o755   # not the staging directory's private 0700


def test_write_set_without_overwrite_refuses_a_file_that_appeared(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "a.txt").write_text("theirs")
    with pytest.raises(FileExistsError) as info:
        write_set(out, lambda d: [(d / "a.txt").write_text("mine") and d / "a.txt"],
                  overwrite=False)
    assert info.value.filename == str(out / "a.txt") and (out / "a.txt").read_text() == "theirs"


def test_write_set_into_a_symbolic_link_keeps_the_link(tmp_path):
    target = tmp_path / "target"
    target.mkdir()
    link = tmp_path / "link"
    link.symlink_to(target)
    assert write_set(link,
                     lambda d: [(d / "a.txt").write_text("a") and d / "a.txt"]) == [link / "a.txt"]
    assert link.is_symlink() and (target / "a.txt").read_text() == "a"
