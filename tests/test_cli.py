"""The ocp-crawl command line: outputs, exit codes and one-line errors for bad input."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl.cli import COMMANDS, main

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "problems" / "paper_gait.toml"
PAPER_TEXT = PAPER.read_text()

JSON_KEYS = {"status", "success", "message", "S", "W_plus", "CoT_plus", "events", "cycles", "problem"}


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
    for word in ("status     success", "S          -55.8", "mm per cycle", "W+ ", "mJ", "CoT+", "cycles",
                 "events in the steady cycle: 4", "stick-stick"):
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


def test_simulate_out_writes_the_files(capsys, tmp_path):
    out_dir = tmp_path / "run" / "deep"
    code, out, err = run(capsys, "simulate", PAPER, "--set", "model.gravity=paper", "--out", out_dir)
    assert code == 0, err
    names = {p.name for p in out_dir.iterdir()}
    assert names == {"arrays.npz", "summary.json", "gait.png", "gait.pdf"}  # no temporary files left
    summary = json.loads((out_dir / "summary.json").read_text())
    assert summary["gravity"] == "paper" and summary["success"] is True
    with np.load(out_dir / "arrays.npz") as arrays:
        assert arrays["phi"].shape == (2, arrays["t"].size) and arrays["x1"].shape == arrays["t"].shape
    assert (out_dir / "gait.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out_dir / "gait.pdf").read_bytes()[:5] == b"%PDF-"


def test_numerical_failure_exits_1_and_still_prints_json(capsys, tmp_path):
    # a stiff robot with a large amplitude: foot 2 lifts off during the first cycle
    code, out, err = run(capsys, "simulate", PAPER, "--set", "robot.k=0.612", "--set", "gait.A_deg=60", "--json",
                         "--out", tmp_path)
    assert code == 1
    data = json.loads(out)
    assert data["success"] is False and data["status_name"] == "lift_off" and data["S"] is None
    assert err.startswith("ocp-crawl: simulation failed: a foot lifts off")
    assert len(err.strip().splitlines()) == 1
    assert (tmp_path / "gait.png").exists()


def test_demo(capsys, tmp_path):
    code, out, err = run(capsys, "demo", "--out", tmp_path / "demo")
    assert code == 0, err
    assert "torque drive, physical gravity" in out and "prescribed angles" in out
    assert out.count("success") == 3
    files = {p.name for p in (tmp_path / "demo").iterdir()}
    for case in ("torque_physical", "torque_paper", "angles"):
        assert {f"{case}_gait.png", f"{case}_gait.pdf", f"{case}_summary.json", f"{case}_arrays.npz"} <= files
    summary = json.loads((tmp_path / "demo" / "demo_summary.json").read_text())
    # the physical and the printed gravity sign differ by a few percent in S (MODEL_NOTES erratum)
    s_phys, s_paper = summary["torque_physical"]["S"], summary["torque_paper"]["S"]
    assert 0.02 < abs(s_phys - s_paper) / abs(s_phys) < 0.10


def test_help_and_version(capsys):
    code, out, _ = run(capsys, "--help")
    assert code == 0 and "simulate" in out and "demo" in out
    code, out, _ = run(capsys, "--version")
    assert code == 0 and "ocp-crawl" in out


# ------------------------------------------------------------------------------------------ bad input
# (problem file text or None for the paper file, extra arguments, words the one-line message must name)
BAD_INPUT = {
    "negative stiffness": (edit("k = 0.1677", "k = -1.0"), [], ["[robot] k = -1.0", "must be > 0"]),
    "zero mass": (edit("M = 0.052", "M = 0"), [], ["[robot] M = 0", "must be > 0"]),
    "bool is not a number": (edit("L = 0.120", "L = true"), [], ["[robot] L = true", "expected a number"]),
    "string for a number": (edit("beta = 2.0", 'beta = "2"'), [], ['[robot] beta = "2"', "expected a number"]),
    "infinite": (edit("g = 9.81", "g = inf"), [], ["[robot] g = inf", "finite"]),
    "not a number": (edit("A_deg = 30.0", "A_deg = nan"), [], ["[gait] A_deg = nan", "finite"]),
    "negative friction": (edit("mu = 0.389", "mu = -0.2"), [], ["[robot] mu = -0.2", ">= 0"]),
    "mu with mu1": (edit("mu = 0.389", "mu = 0.389\nmu1 = 0.3"), [], ["mu = 0.389", "mu1 = 0.3", "exclusive"]),
    "missing key": (edit("k = 0.1677", ""), [], ["[robot] k", "missing", "required"]),
    "unknown key": (edit("k = 0.1677", "stiffness = 0.1677"), [], ["stiffness = 0.1677", "unknown key"]),
    "unknown section": (edit("[model]", "[modle]"), [], ["[modle]", "did you mean model?"]),
    "bad drive": (edit('drive = "torque"', 'drive = "crawl"'), [], ['[gait] drive = "crawl"', '"angles"']),
    "bad gravity": (edit('gravity = "physical"', 'gravity = "real"'), [], ['gravity = "real"', '"paper"']),
    "float cycles": (edit("max_cycles = 12", "max_cycles = 3.5"), [], ["max_cycles = 3.5", "integer"]),
    "malformed TOML": (edit("k = 0.1677", "k 0.1677"), [], ["malformed TOML", "line 9", "k 0.1677"]),
    "foot off the ground": (edit("gamma_deg = 90.0", "gamma_deg = 30.0"), [],
                            ["gamma_deg = 30.0", "foot 1 off the ground"]),
    "prescribed lift-off": (edit("A_deg = 30.0", "A_deg = 75.0"), ["--drive", "angles"],
                            ["A_deg = 75.0", "below the ground"]),
    "bad --set syntax": (None, ["--set", "robot.k"], ["robot.k", "SECTION.KEY=VALUE"]),
    "bad --set key": (None, ["--set", "robot.kay=1"], ["robot.kay=1", "did you mean k?"]),
    "bad --set value": (None, ["--set", "robot.k=soft"], ["robot.k=soft", "expected a number"]),
    "bad --set physics": (None, ["--set", "robot.mu=-1"], ["[robot] mu = -1 (from --set)", ">= 0"]),
    "missing file": ("", ["--missing"], ["nope.toml", "cannot read", "No such file"]),
    "out is a file": (None, ["--out", "FILE"], ["--out", "not a directory"]),
    "unknown option": (None, ["--bogus"], ["unrecognized arguments: --bogus"]),
    "bad --drive": (None, ["--drive", "walk"], ["--drive", "'walk'"]),
}


@pytest.mark.parametrize("case", list(BAD_INPUT))
def test_bad_input_exits_2_with_one_line(case, capsys, tmp_path):
    text, extra, words = BAD_INPUT[case]
    path = PAPER if text is None else write(tmp_path, text)
    if "--missing" in extra:
        path, extra = tmp_path / "nope.toml", []
    if "FILE" in extra:
        blocker = write(tmp_path, "", "blocker")
        extra = [str(blocker) if a == "FILE" else a for a in extra]
    code, out, err = run(capsys, "simulate", path, *extra)
    assert code == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("ocp-crawl: error: ")
    assert "Traceback" not in err
    if text is not None or "--missing" in BAD_INPUT[case][1]:
        assert path.name in lines[0]
    for w in words:
        assert w in lines[0], (w, lines[0])
    assert out == ""


def test_real_subprocess_bad_input_and_json(tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    bad = write(tmp_path, edit("k = 0.1677", "k = -1.0"))
    proc = subprocess.run([sys.executable, "-m", "ocp_crawl.cli", "simulate", str(bad)], capture_output=True,
                          text=True, env=env, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.strip() == (f"ocp-crawl: error: {bad}: [robot] k = -1.0 is invalid: must be > 0 "
                                   "(torsion stiffness, N m/rad)")
    proc = subprocess.run([sys.executable, "-m", "ocp_crawl", "simulate", str(PAPER), "--json"],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert JSON_KEYS <= set(json.loads(proc.stdout))
