"""``sweep --resume`` over damaged files of a sweep directory: bytes that are not UTF-8 and rows
with an unknown status are bad input like a garbage row (exit 2, one stderr line naming the file and
line), never an internal error, and never counted as results."""
import shutil
from pathlib import Path

import pytest

from ocp_crawl.cli.app import main
from ocp_crawl.sweep import (JOURNAL_FILE, RESULTS_FILE, SETTINGS_FILE, SweepError, SweepResult,
                             run_sweep)

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "problems" / "paper_gait.toml"
GRID = "gait.psi_deg=0,45"


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    """A finished two-point sweep directory (copied by each test before it is damaged)."""
    out = tmp_path_factory.mktemp("finished") / "s"
    run_sweep(PAPER, {"gait.psi_deg": [0.0, 45.0]}, out_dir=out)
    return out


def _copy(finished: Path, tmp_path: Path) -> Path:
    out = tmp_path / "s"
    shutil.copytree(finished, out)
    return out


def _journal_of(out: Path) -> bytes:
    """The journal of a run killed after its last row (results.csv not written yet)."""
    lines = (out / RESULTS_FILE).read_bytes().splitlines(keepends=True)
    (out / RESULTS_FILE).unlink()
    return b"index," + lines[0] + b"".join(b"%d," % i + line for i, line in enumerate(lines[1:]))


def _resume(out: Path, capsys) -> tuple[int, str]:
    code = main(["sweep", str(PAPER), "--grid", GRID, "--out", str(out), "--resume",
                 "--no-progress"])
    return code, capsys.readouterr().err


def _assert_bad_input(code: int, err: str, *words: str) -> None:
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("ocp-crawl: error: "), err
    assert "internal error" not in err and "Traceback" not in err, err
    for word in words:
        assert word in err, (word, err)


def _row_not_utf8(out: Path) -> bytes:
    return (out / RESULTS_FILE).read_bytes().replace(b"success", b"succ\xe9s", 1)


def _journal_not_utf8(out: Path) -> bytes:
    _journal_of(out)
    return b"\xff\xfe\n"


# each case: file, its damaged bytes (a function of the finished directory), words of the message
NOT_UTF8 = {
    "results.csv: two bytes": (RESULTS_FILE, lambda out: b"\xff\xfe",
                               [f"{RESULTS_FILE}:1", "not UTF-8"]),
    "results.csv: a row": (RESULTS_FILE, _row_not_utf8, [f"{RESULTS_FILE}:2", "not UTF-8", "0xe9"]),
    "settings.json": (SETTINGS_FILE, lambda out: b"\xff\xfe", [SETTINGS_FILE, "not UTF-8"]),
    "journal: two bytes": (JOURNAL_FILE, _journal_not_utf8, [f"{JOURNAL_FILE}:1", "not UTF-8"]),
    "journal: a row": (JOURNAL_FILE, lambda out: _journal_of(out).replace(b"success", b"\xff", 1),
                       [f"{JOURNAL_FILE}:2", "not UTF-8", "0xff"]),
}


@pytest.mark.parametrize("case", sorted(NOT_UTF8))
def test_resume_over_bytes_that_are_not_utf8_is_bad_input(finished, tmp_path, capsys, case):
    name, damaged, words = NOT_UTF8[case]
    out = _copy(finished, tmp_path)
    (out / name).write_bytes(damaged(out))
    code, err = _resume(out, capsys)
    _assert_bad_input(code, err, str(out / name), *words)
    with pytest.raises(SweepError, match="not UTF-8"):
        SweepResult.read(out, partial=True)


@pytest.mark.parametrize("journal", [False, True])
def test_resume_over_a_row_with_an_unknown_status_is_bad_input(finished, tmp_path, capsys, journal):
    out = _copy(finished, tmp_path)
    name = JOURNAL_FILE if journal else RESULTS_FILE
    data = _journal_of(out) if journal else (out / name).read_bytes()
    (out / name).write_bytes(data.replace(b",success,", b",bogus,", 1))
    code, err = _resume(out, capsys)
    _assert_bad_input(code, err, f"{out / name}:2", "'bogus'", "status", "success")
    with pytest.raises(SweepError, match="unknown status 'bogus'"):
        SweepResult.read(out, partial=True)


def test_resume_keeps_rows_of_every_known_status(finished, tmp_path, capsys):
    """A valid failure status on disk is data: resumed as it is, counted under its label."""
    out = _copy(finished, tmp_path)
    text = (out / RESULTS_FILE).read_text(encoding="utf-8")
    (out / RESULTS_FILE).write_text(text.replace(",success,", ",lift_off,", 1), encoding="utf-8")
    assert SweepResult.read(out).counts() == {"lift_off": 1, "success": 1}


def test_a_missing_row_is_computed_on_resume(finished, tmp_path, capsys):
    """A row with status ``missing`` (a point not computed, as ``SweepResult.read(partial=True)``
    shows it) is not a result: ``--resume`` computes the point (before, it was counted as finished
    and kept as missing)."""
    out = _copy(finished, tmp_path)
    text = (out / RESULTS_FILE).read_text()
    first_success = text.index("success")
    (out / RESULTS_FILE).write_text(text[:first_success] + "missing"
                                    + text[first_success + len("success"):])
    code = main(["sweep", str(PAPER), "--grid", GRID, "--out", str(out), "--resume",
                 "--no-progress", "--json"])
    assert code == 0, capsys.readouterr().err
    rows = SweepResult.read(out).rows
    assert [r["status"] for r in rows] == [r["status"] for r in SweepResult.read(finished).rows]
    assert "missing" not in (out / RESULTS_FILE).read_text()


@pytest.mark.parametrize("journal", [False, True])
def test_resume_over_a_success_row_without_s_is_bad_input(finished, tmp_path, capsys, journal):
    """A row with status success and an empty S is a damaged file (a success has a stride), not
    a result."""
    out = _copy(finished, tmp_path)
    name = JOURNAL_FILE if journal else RESULTS_FILE
    data = _journal_of(out) if journal else (out / name).read_bytes()
    lines = data.splitlines(keepends=True)
    header = lines[0].decode().rstrip("\n").split(",")
    n = next(j for j, line in enumerate(lines) if b",success," in line)
    cells = lines[n].decode().rstrip("\n").split(",")
    cells[header.index("S [m]")] = ""
    lines[n] = (",".join(cells) + "\n").encode()
    (out / name).write_bytes(b"".join(lines))
    code, err = _resume(out, capsys)
    _assert_bad_input(code, err, f"{out / name}:{n + 1}", "success", "empty S")
    with pytest.raises(SweepError, match="empty S"):
        SweepResult.read(out, partial=True)
