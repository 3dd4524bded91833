"""Bad-input matrix: every command, malformed problem files and arguments -> exit 2, one line, no traceback.

One table (:data:`ROWS`) of cases; each row runs ``ocp_crawl.cli.app.main`` in-process with every long
computation replaced by a function that fails the test (bad input must be rejected before any
run), and checks: exit code 2, stdout empty, stderr exactly one line ``ocp-crawl: error: ...``
naming the file (for file errors), the key and the value as written, no traceback.  A few rows
also run through a real ``python -m ocp_crawl`` subprocess.
"""
import contextlib
import os
import signal
import subprocess
import sys
import tempfile
import threading
from dataclasses import dataclass, field
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

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "problems" / "paper_gait.toml"
OCP = REPO / "problems" / "ocp_max_speed.toml"
PAPER_TEXT, OCP_TEXT = PAPER.read_text(), OCP.read_text()


def _permissions_ignored() -> bool:
    """True for root (os.geteuid() == 0) unless it runs without CAP_DAC_OVERRIDE: probed, not assumed."""
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
#: k = 0.05 M g L (Table I robot): the springs cannot hold the robot up at t = 0 (status no_start)
SOFT = "robot.k=0.00306"


def edit(old, new, text=PAPER_TEXT):
    assert old in text, old
    return text.replace(old, new, 1)


def ocp_edit(old, new):
    return edit(old, new, OCP_TEXT)


@dataclass(frozen=True)
class Row:
    """One case: a command and its arguments, and the words its one-line message must contain.

    Placeholders in ``argv`` and ``words``: {file} the problem file written from ``text`` (its name
    is x.toml), {paper} / {ocp} the shipped problem files, {tmp} a fresh directory, {blocker} a
    regular file, {dir} a directory, {missing} a file that does not exist, {unreadable} a file
    without read permission, {readonly} a directory without write permission.
    """

    command: str
    argv: tuple
    words: tuple
    text: str | None = None
    files: dict = field(default_factory=dict)
    """files to create under {tmp} first (name -> bytes): earlier results"""
    needs_permissions: bool = False
    """the row relies on file permissions, which root ignores"""
    absent: tuple = ()
    """words the message must not contain (e.g. blaming the gait for the robot's mass, nan for inf)"""


def R(command, argv, words, **kw):
    if "absent" in kw:
        kw["absent"] = tuple(kw["absent"])
    return Row(command, tuple(argv), tuple(words), **kw)


def nested(depth: int) -> str:
    """A TOML array nested ``depth`` deep: [[[...]]]"""
    return "[" * depth + "]" * depth


ROWS = {
    # ------------------------------------------------------------------ simulate
    "simulate: negative stiffness": R("simulate", ["{file}"], ["x.toml", "[robot] k = -1.0", "must be in [1e-12, 1e12]"],
                                      text=edit("k = 0.1677", "k = -1.0")),
    "simulate: zero mass": R("simulate", ["{file}"], ["x.toml", "[robot] M = 0", "must be in [1e-12, 1e12]"],
                             text=edit("M = 0.052", "M = 0")),
    "simulate: negative length": R("simulate", ["{file}"], ["x.toml", "[robot] L = -0.12", "must be in [1e-12, 1e12]"],
                                   text=edit("L = 0.120", "L = -0.12")),
    "simulate: zero beta": R("simulate", ["{file}"], ["x.toml", "[robot] beta = 0.0", "must be in [0.01, 100]"],
                             text=edit("beta = 2.0", "beta = 0.0")),
    "simulate: zero gravity": R("simulate", ["{file}"], ["x.toml", "[robot] g = 0.0", "must be in [1e-12, 1e12]"],
                                text=edit("g = 9.81", "g = 0.0")),
    "simulate: infinite g": R("simulate", ["{file}"], ["x.toml", "[robot] g = inf", "finite"],
                              text=edit("g = 9.81", "g = inf")),
    "simulate: NaN amplitude": R("simulate", ["{file}"], ["x.toml", "[gait] A_deg = nan", "finite"],
                                 text=edit("A_deg = 30.0", "A_deg = nan")),
    "simulate: negative friction": R("simulate", ["{file}"], ["x.toml", "[robot] mu = -0.2", "in [1e-4, 1e4]"],
                                     text=edit("mu = 0.389", "mu = -0.2")),
    "simulate: bool for a number": R("simulate", ["{file}"], ["x.toml", "[robot] L = true", "expected a number"],
                                     text=edit("L = 0.120", "L = true")),
    "simulate: string for a number": R("simulate", ["{file}"], ["x.toml", '[robot] beta = "2"', "expected a number"],
                                       text=edit("beta = 2.0", 'beta = "2"')),
    "simulate: float for an int": R("simulate", ["{file}"], ["x.toml", "max_cycles = 3.5", "integer"],
                                    text=edit("max_cycles = 12", "max_cycles = 3.5")),
    "simulate: bool for an int": R("simulate", ["{file}"], ["x.toml", "max_cycles = true", "integer"],
                                   text=edit("max_cycles = 12", "max_cycles = true")),
    "simulate: mu with mu1": R("simulate", ["{file}"], ["x.toml", "mu = 0.389", "mu1 = 0.3", "exclusive"],
                               text=edit("mu = 0.389", "mu = 0.389\nmu1 = 0.3")),
    "simulate: missing key": R("simulate", ["{file}"], ["x.toml", "[robot] k", "missing", "required"],
                               text=edit("k = 0.1677", "")),
    "simulate: missing section": R("simulate", ["{file}"], ["x.toml", "section [robot] is missing"],
                                   text=PAPER_TEXT[PAPER_TEXT.index("[gait]"):]),
    "simulate: empty file": R("simulate", ["{file}"], ["x.toml", "[robot]", "missing"], text=""),
    "simulate: key outside a section": R("simulate", ["{file}"], ["x.toml", "top-level key k = 0.1", "section"],
                                         text="k = 0.1\n" + PAPER_TEXT),
    "simulate: unknown key": R("simulate", ["{file}"], ["x.toml", "stiffness = 0.1677", "unknown key"],
                               text=edit("k = 0.1677", "stiffness = 0.1677")),
    "simulate: unknown section": R("simulate", ["{file}"], ["x.toml", "[modle]", "did you mean model?"],
                                   text=edit("[model]", "[modle]")),
    "simulate: bad drive": R("simulate", ["{file}"], ["x.toml", '[gait] drive = "crawl"', '"angles"'],
                             text=edit('drive = "torque"', 'drive = "crawl"')),
    "simulate: bad gravity": R("simulate", ["{file}"], ["x.toml", 'gravity = "real"', '"paper"'],
                               text=edit('gravity = "physical"', 'gravity = "real"')),
    "simulate: malformed TOML": R("simulate", ["{file}"], ["x.toml", "malformed TOML", "line 9", "k 0.1677"],
                                  text=edit("k = 0.1677", "k 0.1677")),
    "simulate: not UTF-8": R("simulate", ["{file}"], ["x.toml", "not UTF-8"], text="\udcff"),
    "simulate: foot off the ground": R("simulate", ["{file}"], ["x.toml", "gamma_deg = 30.0", "foot 1 off the ground"],
                                       text=edit("gamma_deg = 90.0", "gamma_deg = 30.0")),
    "simulate: prescribed lift-off": R("simulate", ["{file}", "--drive", "angles"],
                                       ["x.toml", "A_deg = 75.0", "below the ground"],
                                       text=edit("A_deg = 30.0", "A_deg = 75.0")),
    "simulate: cannot stand (no_start)": R("simulate", ["{paper}", "--set", SOFT],
                                           ["paper_gait.toml", "[robot] k = 0.00306", 'gravity = "physical"',
                                            "gamma_deg = 90.0", "psi_deg = 45.0", "no equilibrium to start from"]),
    "simulate: cannot stand, mpcc": R("simulate", ["{paper}", "--set", SOFT, "--solver", "mpcc"],
                                      ["paper_gait.toml", "[robot] k = 0.00306", "no equilibrium to start from"]),
    "simulate: mpcc with the angles drive": R("simulate", ["{paper}", "--drive", "angles", "--solver", "mpcc"],
                                              ["paper_gait.toml", '[simulation] solver = "mpcc" (from --set)',
                                               'drive = "angles"', "own solver"]),
    "simulate: unknown solver in the file": R("simulate", ["{file}"], ["x.toml", '[simulation] solver = "rk4"',
                                                                      'one of "event", "mpcc"'],
                                              text=edit('solver = "event"', 'solver = "rk4"')),
    "simulate: --set syntax": R("simulate", ["{paper}", "--set", "robot.k"], ["robot.k", "SECTION.KEY=VALUE"]),
    "simulate: --set unknown key": R("simulate", ["{paper}", "--set", "robot.kay=1"], ["robot.kay=1", "did you mean k?"]),
    "simulate: --set string for a number": R("simulate", ["{paper}", "--set", "robot.k=soft"],
                                             ["robot.k=soft", "expected a number"]),
    "simulate: --set negative friction": R("simulate", ["{paper}", "--set", "robot.mu=-1"],
                                           ["paper_gait.toml", "[robot] mu = -1 (from --set)", "in [1e-4, 1e4]"]),
    "simulate: missing file": R("simulate", ["{missing}"], ["nope.toml", "cannot read", "No such file"]),
    "simulate: directory as problem file": R("simulate", ["{dir}"], ["adir", "cannot read", "directory"]),
    "simulate: unreadable file": R("simulate", ["{unreadable}"], ["locked.toml", "cannot read", "Permission denied"],
                                   needs_permissions=True),
    "simulate: --out under a file": R("simulate", ["{paper}", "--out", "{blocker}/run"],
                                      ["--out", "blocker/run", "not writable"]),
    "simulate: --out is a file": R("simulate", ["{paper}", "--out", "{blocker}"], ["--out", "blocker", "not a directory"]),
    "simulate: --out read-only": R("simulate", ["{paper}", "--out", "{readonly}/run"], ["--out", "readonly", "not writable"],
                                   needs_permissions=True),
    "simulate: --out holds results": R("simulate", ["{paper}", "--out", "{tmp}"],
                                       ["--out", "summary.json", "would overwrite", "--force"],
                                       files={"summary.json": b"{}"}),
    "simulate: --steps too small": R("simulate", ["{paper}", "--solver", "mpcc", "--steps", "3"], ["--steps 3", "in [4, 10000]"]),
    "simulate: --steps not an integer": R("simulate", ["{paper}", "--steps", "2.5"], ["--steps 2.5", "integer"]),
    "simulate: unknown option": R("simulate", ["{paper}", "--bogus"], ["unrecognized arguments: --bogus"]),
    "simulate: bad --drive": R("simulate", ["{paper}", "--drive", "walk"], ["--drive", "'walk'"]),
    "simulate: no problem file": R("simulate", [], ["PROBLEM.toml", "required"]),
    # ------------------------------------------------------------------ demo
    "demo: --out under a file": R("demo", ["--out", "{blocker}/d"], ["--out", "blocker/d", "not writable"]),
    "demo: --out read-only": R("demo", ["--out", "{readonly}"], ["--out", "readonly", "not writable"],
                               needs_permissions=True),
    "demo: --out holds results": R("demo", ["--out", "{tmp}"], ["--out", "demo_summary.json", "would overwrite"],
                                   files={"demo_summary.json": b"{}"}),
    "demo: unexpected argument": R("demo", ["{paper}"], ["unrecognized arguments", "paper_gait.toml"]),
    # ------------------------------------------------------------------ warmup
    "warmup: unexpected argument": R("warmup", ["{paper}"], ["unrecognized arguments", "paper_gait.toml"]),
    "warmup: unknown option": R("warmup", ["--jobs", "2"], ["unrecognized arguments", "--jobs 2"]),
    "warmup: --json with a value": R("warmup", ["--json=yes"], ["--json", "ignored explicit argument 'yes'"]),
    "warmup: --out": R("warmup", ["--out", "{tmp}"], ["unrecognized arguments", "--out"]),
    # ------------------------------------------------------------------ sweep
    "sweep: NUM < 1": R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:180:0", "--out", "{tmp}"],
                        ["gait.psi_deg=0:180:0", "NUM must be an integer >= 1, got 0"]),
    "sweep: NUM not an integer": R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:180:2.5", "--out", "{tmp}"],
                                   ["gait.psi_deg=0:180:2.5", "NUM must be an integer", "'2.5'"]),
    "sweep: START:STOP malformed": R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:180", "--out", "{tmp}"],
                                     ["gait.psi_deg=0:180", "START:STOP:NUM", "2 fields"]),
    "sweep: START not a number": R("sweep", ["{paper}", "--grid", "gait.psi_deg=a:180:3", "--out", "{tmp}"],
                                   ["gait.psi_deg=a:180:3", "START and STOP must be numbers", "'a'"]),
    "sweep: unknown grid key": R("sweep", ["{paper}", "--grid", "gait.psi=0:1:2", "--out", "{tmp}"],
                                 ["gait.psi=0:1:2", "did you mean gait.psi_deg"]),
    "sweep: unknown grid section": R("sweep", ["{paper}", "--grid", "gaitt.psi_deg=0:1:2", "--out", "{tmp}"],
                                     ["gaitt.psi_deg=0:1:2", "unknown section [gaitt]"]),
    "sweep: grid value not numeric": R("sweep", ["{paper}", "--grid", "robot.k=soft", "--out", "{tmp}"],
                                       ["robot.k=soft", "'soft' is not a number"]),
    "sweep: empty list": R("sweep", ["{paper}", "--grid", "robot.k=", "--out", "{tmp}"], ["robot.k=", "no values"]),
    "sweep: duplicate axis": R("sweep", ["{paper}", "--grid", "robot.k=0.1", "--grid", "robot.k=0.2", "--out", "{tmp}"],
                               ["robot.k=0.2", "already a grid key"]),
    "sweep: negative stiffness on the grid": R("sweep", ["{paper}", "--grid", "robot.k=-1:1:3", "--out", "{tmp}"],
                                               ["robot.k=-1:1:3", "robot.k = -1.0", "must be in [1e-12, 1e12]"]),
    "sweep: every point invalid": R("sweep", ["{paper}", "--grid", "gait.gamma_deg=20,30", "--out", "{tmp}"],
                                    ["paper_gait.toml", "gamma_deg = 20.0", "every one of the 2 points"]),
    "sweep: --jobs 0": R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--jobs", "0", "--out", "{tmp}"],
                         ["--jobs 0", "in [1, 256]"]),
    "sweep: --jobs not an integer": R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--jobs", "1.5"],
                                      ["--jobs 1.5", "integer"]),
    "sweep: --resume with --force": R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--resume", "--force"],
                                      ["--force", "not allowed with", "--resume"]),
    "sweep: no --grid": R("sweep", ["{paper}", "--out", "{tmp}"], ["--grid", "required"]),
    "sweep: empty --scheduler": R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--scheduler", " "],
                                  ["--scheduler", "is invalid"]),
    "sweep: bad problem file": R("sweep", ["{file}", "--grid", "gait.psi_deg=45", "--out", "{tmp}"],
                                 ["x.toml", "[robot] k = -1.0", "must be in [1e-12, 1e12]"],
                                 text=edit("k = 0.1677", "k = -1.0")),
    "sweep: --out under a file": R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--out", "{blocker}/s"],
                                   ["--out", "blocker/s", "not writable"]),
    "sweep: --out holds a sweep": R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--out", "{tmp}"],
                                    ["--out", "results.csv", "already holds a sweep", "--resume", "--force"],
                                    files={"results.csv": b"x\n"}),
    # ------------------------------------------------------------------ reproduce
    "reproduce: --jobs 0": R("reproduce", ["--jobs", "0", "--out", "{tmp}"], ["--jobs 0", "in [1, 256]"]),
    "reproduce: bad --gravity": R("reproduce", ["--gravity", "real", "--out", "{tmp}"], ["--gravity", "'real'"]),
    "reproduce: --out under a file": R("reproduce", ["--out", "{blocker}/r"], ["--out", "blocker/r", "not writable"]),
    "reproduce: --out holds a run": R("reproduce", ["--out", "{tmp}", "--quick"],
                                      ["--out", "report.md", "would overwrite", "--resume", "--force"],
                                      files={"report.md": b"# report\n"}),
    "reproduce: --out holds a partial run": R("reproduce", ["--out", "{tmp}"], ["--out", "sweeps", "would overwrite"],
                                              files={"sweeps/gait/settings.json": b"{}"}),
    "reproduce: --resume with --force": R("reproduce", ["--resume", "--force", "--out", "{tmp}"],
                                          ["--force", "not allowed with", "--resume"]),
    # ------------------------------------------------------------------ animate
    "animate: --fps 0": R("animate", ["{paper}", "--fps", "0", "--out", "{tmp}/a.gif"], ["--fps 0", "(0, 100]"]),
    "animate: --fps nan": R("animate", ["{paper}", "--fps", "nan", "--out", "{tmp}/a.gif"], ["--fps nan", "(0, 100]"]),
    "animate: --fps too high": R("animate", ["{paper}", "--fps", "1e3", "--out", "{tmp}/a.gif"], ["--fps 1e3", "(0, 100]"]),
    "animate: --cycles 0": R("animate", ["{paper}", "--cycles", "0", "--out", "{tmp}/a.gif"], ["--cycles 0", ">= 1"]),
    "animate: --frames-per-cycle 1": R("animate", ["{paper}", "--frames-per-cycle", "1", "--out", "{tmp}/a.gif"],
                                       ["--frames-per-cycle 1", ">= 2"]),
    "animate: --cycles not an integer": R("animate", ["{paper}", "--cycles", "1.5", "--out", "{tmp}/a.gif"],
                                          ["--cycles 1.5", "integer"]),
    "animate: --out not a GIF": R("animate", ["{paper}", "--out", "{tmp}/a.png"], ["--out", "a.png", ".gif"]),
    "animate: --out under a file": R("animate", ["{paper}", "--out", "{blocker}/a.gif"],
                                     ["--out", "blocker/a.gif", "blocker: exists and is not a directory"]),
    "animate: --out exists": R("animate", ["{paper}", "--out", "{tmp}/a.gif"], ["--out", "a.gif", "would overwrite"],
                               files={"a.gif": b"GIF89a"}),
    "animate: cannot stand (no_start)": R("animate", ["{paper}", "--set", SOFT, "--out", "{tmp}/a.gif"],
                                          ["paper_gait.toml", "k = 0.00306", "no equilibrium to start from"]),
    "animate: missing file": R("animate", ["{missing}", "--out", "{tmp}/a.gif"], ["nope.toml", "cannot read"]),
    # ------------------------------------------------------------------ crosscheck
    "crosscheck: --steps too small": R("crosscheck", ["{paper}", "--steps", "3", "50"], ["--steps 3", "in [4, 10000]"]),
    "crosscheck: one step count": R("crosscheck", ["{paper}", "--steps", "100", "100"],
                                    ["--steps 100 100", "two different"]),
    "crosscheck: angles drive": R("crosscheck", ["{paper}", "--set", "gait.drive=angles"],
                                  ["paper_gait.toml", "torque drive", 'drive = "angles"']),
    "crosscheck: cannot stand (no_start)": R("crosscheck", ["{paper}", "--set", SOFT],
                                             ["paper_gait.toml", "k = 0.00306", "no equilibrium to start from"]),
    "crosscheck: malformed TOML": R("crosscheck", ["{file}"], ["x.toml", "malformed TOML"],
                                    text=edit("[gait]", "[gait")),
    "crosscheck: --set bad value": R("crosscheck", ["{paper}", "--set", "robot.mu=nan"],
                                     ["paper_gait.toml", "[robot] mu = nan (from --set)", "finite"]),
    # ------------------------------------------------------------------ optimize
    "optimize: no [ocp] section": R("optimize", ["{paper}"], ["paper_gait.toml", "no [ocp] section"]),
    "optimize: no [ocp] section, --set ocp.*": R("optimize", ["{paper}", "--set", "ocp.nodes=20"],
                                                ["paper_gait.toml", "no [ocp] section"]),
    "optimize: too few nodes": R("optimize", ["{file}"], ["x.toml", "[ocp] nodes = 4", "in [8, 1000]"],
                                 text=ocp_edit("nodes = 50", "nodes = 4")),
    "optimize: float for int nodes": R("optimize", ["{file}"], ["x.toml", "[ocp] nodes = 10.5", "integer"],
                                       text=ocp_edit("nodes = 50", "nodes = 10.5")),
    "optimize: unknown objective": R("optimize", ["{file}"], ["x.toml", '[ocp] objective = "fastest"', '"min_cot"'],
                                     text=ocp_edit('objective = "max_speed"', 'objective = "fastest"')),
    "optimize: unknown [ocp] key": R("optimize", ["{file}"], ["x.toml", "[ocp] unknown key node = 100"],
                                     text=ocp_edit("nodes = 50", "node = 100")),
    "optimize: A_max_deg too large": R("optimize", ["{file}"], ["x.toml", "[ocp] A_max_deg = 95.0", "(0, 90)"],
                                       text=ocp_edit("A_max_deg = 30.0", "A_max_deg = 95.0")),
    "optimize: envelope outside (0, 180)": R("optimize", ["{ocp}", "--set", "gait.gamma_deg=150", "--set",
                                                          "ocp.A_max_deg=40"],
                                             ["ocp_max_speed.toml", "A_max_deg = 40", "gamma_deg = 150", "(0, 180)"]),
    # rules between the homotopy's keys (each alone is valid): exit 2 naming them, not an internal error
    "optimize: sigma_min above sigma0": R("optimize", ["{ocp}", "--set", "ocp.sigma_min=1e-3"],
                                          ["ocp_max_speed.toml", "[ocp]", "sigma_min < sigma0"]),
    "optimize: too many homotopy stages": R("optimize", ["{ocp}", "--set", "ocp.sigma_factor=0.999"],
                                            ["ocp_max_speed.toml", "[ocp]", "sigma_factor 0.999", "homotopy stages"]),
    # keys of earlier versions: the message names the key, the file and the replacement
    "optimize: removed S_min in a file": R("optimize", ["{file}"], ["x.toml", "[ocp] S_min no longer exists",
                                                                     "speed_min [m/s]", "S_min = 0.04"],
                                           text=ocp_edit("nodes = 50", "nodes = 50\nS_min = 0.04")),
    "optimize: removed rate_limit in a file": R("optimize", ["{file}"], ["x.toml", "[ocp] rate_limit no longer exists",
                                                                          "max_rate_deg_s [deg/s]"],
                                                text=ocp_edit("nodes = 50", 'nodes = 50\nrate_limit = "harmonic"')),
    "optimize: removed curvature_limit in a file": R("optimize", ["{file}"],
                                                     ["x.toml", "[ocp] curvature_limit no longer exists",
                                                      "max_accel_deg_s2 [deg/s^2]"],
                                                     text=ocp_edit("nodes = 50",
                                                                   'nodes = 50\ncurvature_limit = "harmonic"')),
    "optimize: removed tie_margin in a file": R("optimize", ["{file}"], ["x.toml", "[ocp] tie_margin no longer exists",
                                                                          "switch-exact"],
                                                text=ocp_edit("nodes = 50", "nodes = 50\ntie_margin = 0.0005")),
    "optimize: removed max_rate by --set": R("optimize", ["{ocp}", "--set", "ocp.max_rate=2.0"],
                                             ["--set", "[ocp] max_rate no longer exists", "max_rate_deg_s [deg/s]"]),
    "optimize: max_rate_deg_s = 0": R("optimize", ["{ocp}", "--set", "ocp.max_rate_deg_s=0"],
                                      ["ocp_max_speed.toml", "[ocp] max_rate_deg_s = 0", "> 0"]),
    "optimize: zero direction": R("optimize", ["{ocp}", "--set", "ocp.direction=0"],
                                  ["ocp_max_speed.toml", "[ocp] direction = 0 (from --set)", "-1 or 1"]),
    "optimize: bool for a string": R("optimize", ["{ocp}", "--set", "ocp.robust=true"],
                                     ["[ocp] robust = true", "expected a string"]),
    "optimize: mu_ratio_eps = 1": R("optimize", ["{ocp}", "--set", "ocp.mu_ratio_eps=1"],
                                    ["[ocp] mu_ratio_eps = 1", "[0, 1)"]),
    "optimize: cannot stand (no_start)": R("optimize", ["{ocp}", "--set", SOFT],
                                           ["ocp_max_speed.toml", "k = 0.00306", "no equilibrium to start from"]),
    "optimize: --out under a file": R("optimize", ["{ocp}", "--out", "{blocker}/o"], ["--out", "blocker/o", "not writable"]),
    "optimize: --out holds results": R("optimize", ["{ocp}", "--out", "{tmp}"], ["--out", "torques.csv", "would overwrite"],
                                       files={"torques.csv": b"phase,tau1,tau2\n"}),
    # ------------------------------------------------------------------ no command
    "no command": R(None, [], ["COMMAND", "required"]),
    "unknown command": R(None, ["crawl"], ["invalid choice: 'crawl'"]),
}

#: issue 11: every key and option that sizes the work is bounded, and every bad input is one line (the rows that
#: used to hang or end as internal errors are guarded by HANG_GUARD_S)
ROWS.update({
    # ---- bounds on work
    "simulate: max_step 1e-300 (hung)": R("simulate", ["{file}"], ["x.toml", "[simulation] max_step = 1e-300",
                                                                   "in [1e-4, 0.25]", "continuation steps per cycle"],
                                          text=edit("max_step = 0.0625", "max_step = 1e-300")),
    "simulate: --set max_step 1e-300": R("simulate", ["{paper}", "--set", "simulation.max_step=1e-300"],
                                         ["[simulation] max_step = 1e-300 (from --set)", "in [1e-4, 0.25]"]),
    "simulate: --steps 1e9 (hung)": R("simulate", ["{paper}", "--solver", "mpcc", "--steps", "1000000000"],
                                      ["--steps 1000000000", "in [4, 10000]", "IPOPT solve"]),
    "simulate: steps 1e9 in the file": R("simulate", ["{file}"], ["x.toml", "[simulation] steps = 1000000000",
                                                                  "in [4, 10000]"],
                                         text=edit("steps = 200", "steps = 1000000000")),
    "simulate: k/(M g L) 1.6e13 (no_consistent_mode)": R("simulate", ["{paper}", "--set", "robot.k=1e12"],
                                                         ["[robot] k = 1000000000000.0", "k/(M g L) = 1.63e+13",
                                                          "exceeds 1e+10", "gait.drive"]),
    "sweep: L 1e-12 makes k/(M g L) 3.3e11": R("sweep", ["{paper}", "--grid", "robot.L=1e-12,2e-12", "--out", "{tmp}"],
                                              ["k/(M g L) = 3.29e+11", "exceeds 1e+10"]),
    "simulate: max_cycles 1e5": R("simulate", ["{paper}", "--set", "simulation.max_cycles=100000"],
                                  ["[simulation] max_cycles = 100000 (from --set)", "in [2, 500]"]),
    "simulate: event_xtol 0.5": R("simulate", ["{paper}", "--set", "simulation.event_xtol=0.5"],
                                  ["[simulation] event_xtol = 0.5 (from --set)", "in (0, 1e-6]"]),
    "simulate: /dev/zero (hung)": R("simulate", ["/dev/zero"], ["/dev/zero", "larger than 1048576 bytes (1 MiB)"]),
    "simulate: 2 MiB problem file": R("simulate", ["{file}"], ["x.toml", "larger than 1048576 bytes (1 MiB)"],
                                      text=PAPER_TEXT + ("# padding\n" * 220_000)),
    # ---- bad input that ended as an internal error or with more than one line
    "simulate: TOML nested 5000 deep (RecursionError)": R("simulate", ["{file}"], ["x.toml", "malformed TOML",
                                                                                   "nested too deeply"],
                                                          text=edit("k = 0.1677", "k = " + nested(5000))),
    "simulate: --set nested 5000 deep": R("simulate", ["{paper}", "--set", "robot.k=" + nested(5000)],
                                          ["--set \"robot.k=[[[[", "nested too deeply"]),
    "simulate: array nested 400 deep": R("simulate", ["{file}"], ["x.toml", "[robot] k = [[[[...]]]]",
                                                                  "expected a number"],
                                         text=edit("k = 0.1677", "k = " + nested(400))),
    "simulate: k = 1e308 (RuntimeWarnings)": R("simulate", ["{paper}", "--set", "robot.k=1e308"],
                                               ["[robot] k = 1e+308 (from --set)", "in [1e-12, 1e12]", "N m/rad"]),
    "simulate: M = 1e308 (blamed the gait)": R("simulate", ["{file}"], ["x.toml", "[robot] M = 1e+308",
                                                                        "in [1e-12, 1e12]", "kg"],
                                               text=edit("M = 0.052", "M = 1e308"), absent=["[gait]", "nan"]),
    "simulate: L = 1e-300": R("simulate", ["{paper}", "--set", "robot.L=1e-300"],
                              ["[robot] L = 1e-300 (from --set)", "in [1e-12, 1e12]"]),
    "simulate: g = 1e300": R("simulate", ["{paper}", "--set", "robot.g=1e300"],
                             ["[robot] g = 1e+300 (from --set)", "in [1e-12, 1e12]"]),
    "simulate: beta = 1e6": R("simulate", ["{paper}", "--set", "robot.beta=1e6"],
                              ["[robot] beta = 1000000.0 (from --set)", "in [0.01, 100]", "degenerate"]),
    "simulate: frictionless mu = 0 (no_consistent_mode)": R("simulate", ["{file}"],
                                                            ["x.toml", "[robot] mu = 0", "in [1e-4, 1e4]", "frictionless"],
                                                            text=edit("mu = 0.389", "mu = 0")),
    "simulate: mu = 1e-300": R("simulate", ["{paper}", "--set", "robot.mu=1e-300"],
                               ["[robot] mu = 1e-300 (from --set)", "in [1e-4, 1e4]", "frictionless"]),
    "simulate: one frictionless foot": R("simulate", ["{paper}", "--set", "robot.mu1=0"],
                                         ["[robot] mu1 = 0 (from --set)", "in [1e-4, 1e4]"]),
    "simulate: --out empty (exit 0, wrote nothing)": R("simulate", ["{paper}", "--out", ""], ["--out ''", "empty path"]),
    "demo: --out empty": R("demo", ["--out", ""], ["--out ''", "empty path"]),
    "demo: --out blank": R("demo", ["--out", "  "], ["--out '  '", "empty path"]),
    # ---- sweep
    "sweep: NUM 1e20 (ValueError)": R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:180:99999999999999999999",
                                                "--out", "{tmp}"],
                                      ["gait.psi_deg=0:180:99999999999999999999", "NUM = 99999999999999999999",
                                       "20000 points"]),
    "sweep: STOP inf (said nan)": R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:inf:3", "--out", "{tmp}"],
                                    ["gait.psi_deg=0:inf:3", "must be finite", "STOP = inf"], absent=["nan"]),
    "sweep: START -inf": R("sweep", ["{paper}", "--grid", "gait.psi_deg=-inf:0:3", "--out", "{tmp}"],
                           ["gait.psi_deg=-inf:0:3", "START = -inf"], absent=["nan"]),
    "sweep: inf in a list": R("sweep", ["{paper}", "--grid", "gait.psi_deg=0,inf", "--out", "{tmp}"],
                              ["gait.psi_deg=0,inf", "gait.psi_deg = inf must be finite"], absent=["nan"]),
    "sweep: 1e6 points (hung)": R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:180:1000", "--grid",
                                            "gait.gamma_deg=60:120:1000", "--out", "{tmp}"],
                                  ["1000000 points", "1000 (gait.psi_deg) x 1000 (gait.gamma_deg)", "20000 points"]),
    "sweep: list nested 5000 deep": R("sweep", ["{paper}", "--grid", "robot.k=" + nested(5000), "--out", "{tmp}"],
                                      ["--grid 'robot.k=[[[[", "nested too deeply"]),
    "sweep: k = 1e308 on the grid": R("sweep", ["{paper}", "--grid", "robot.k=0.1,1e308", "--out", "{tmp}"],
                                      ["robot.k=0.1,1e308", "robot.k = 1e+308", "in [1e-12, 1e12]"]),
    "sweep: frictionless on the grid": R("sweep", ["{paper}", "--grid", "robot.mu=0,0.4", "--out", "{tmp}"],
                                         ["robot.mu=0,0.4", "robot.mu = 0", "in [1e-4, 1e4]"]),
    "sweep: --jobs 1e5": R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--jobs", "100000", "--out", "{tmp}"],
                           ["--jobs 100000", "in [1, 256]"]),
    "sweep: --out empty": R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--out", ""], ["--out ''", "empty path"]),
    "reproduce: --out empty": R("reproduce", ["--out", ""], ["--out ''", "empty path"]),
    "reproduce: --jobs 1e5": R("reproduce", ["--jobs", "100000", "--out", "{tmp}"], ["--jobs 100000", "in [1, 256]"]),
    # ---- animate
    "animate: --cycles 1e9 (MemoryError)": R("animate", ["{paper}", "--cycles", "1000000000", "--out", "{tmp}/a.gif"],
                                             ["--cycles 1000000000", "in [1, 10]", "memory"]),
    "animate: --frames-per-cycle 1e9 (MemoryError)": R("animate", ["{paper}", "--frames-per-cycle", "1000000000",
                                                                   "--out", "{tmp}/a.gif"],
                                                       ["--frames-per-cycle 1000000000", "in [2, 100]", "memory"]),
    "animate: --out x.gif/ (wrote x.gif)": R("animate", ["{paper}", "--out", "{tmp}/x.gif/"],
                                             ["--out", "x.gif/", "names a directory", ".gif"]),
    "animate: --out empty": R("animate", ["{paper}", "--out", ""], ["--out ''", "empty path"]),
    "animate: /dev/zero": R("animate", ["/dev/zero", "--out", "{tmp}/a.gif"], ["/dev/zero", "1 MiB"]),
    # ---- crosscheck
    "crosscheck: --steps 1e9": R("crosscheck", ["{paper}", "--steps", "50", "1000000000"],
                                 ["--steps 1000000000", "in [4, 10000]"]),
    "crosscheck: nine step counts": R("crosscheck", ["{paper}", "--steps", *map(str, range(10, 100, 10))],
                                      ["--steps 10 20 30 40 50 60 70 80 90", "at most 8"]),
    "crosscheck: mu = 0": R("crosscheck", ["{paper}", "--set", "robot.mu=0"],
                            ["paper_gait.toml", "[robot] mu = 0 (from --set)", "frictionless"]),
    # ---- optimize
    "optimize: nodes 1e5 (hung)": R("optimize", ["{ocp}", "--set", "ocp.nodes=100000"],
                                    ["ocp_max_speed.toml", "[ocp] nodes = 100000 (from --set)", "in [8, 1000]"]),
    "optimize: harmonic_psi 1e5 (hung)": R("optimize", ["{file}"], ["x.toml", "[ocp] harmonic_psi = 100000",
                                                                    "in [4, 180]"],
                                           text=ocp_edit("nodes = 50", "nodes = 50\nharmonic_psi = 100000")),
    "optimize: fourier_order 1e5 (hung)": R("optimize", ["{ocp}", "--set", "ocp.parametrization=fourier", "--set",
                                                         "ocp.fourier_order=100000"],
                                            ["[ocp] fourier_order = 100000 (from --set)", "in [1, 25]"]),
    "optimize: --out empty": R("optimize", ["{ocp}", "--out", ""], ["--out ''", "empty path"]),
    "optimize: k = 1e308": R("optimize", ["{ocp}", "--set", "robot.k=1e308"],
                             ["[robot] k = 1e+308 (from --set)", "in [1e-12, 1e12]"]),
    # ---- init
    "init: a problem file exists (no --force)": R("init", ["{tmp}"], ["{tmp}/problems/unequal_friction.toml", "exists",
                                                                       "--force", "nothing was written"],
                                                  files={"problems/unequal_friction.toml": b"# mine\n"}),
    "init: DIR is a regular file": R("init", ["{blocker}"], ["DIR {blocker}", "not a directory"]),
    "init: DIR/problems is a regular file": R("init", ["{tmp}"], ["{tmp}/problems", "not a directory"],
                                              files={"problems": b"a file\n"}),
    "init: DIR empty": R("init", [""], ["DIR ''", "empty path"]),
    "init: DIR not writable": R("init", ["{readonly}"], ["DIR {readonly}", "Permission denied"],
                                needs_permissions=True),
    "init: two directories": R("init", ["{tmp}", "{dir}"], ["unrecognized arguments", "{dir}"]),
})

# ---- fit: measurement files (the CSV convention) and parameters
_FIT_HEAD = b"A [deg],S [mm],sigma_S [mm]\n"
_FIT_ROWS = b"15,-27.7,0.2\n22,-41.1,0.2\n30,-56.0,0.2\n"


def _fit(words, *extra, data=_FIT_HEAD + _FIT_ROWS, params=("robot.k",)):
    argv = ["{paper}", "{tmp}/d.csv", *(a for p in params for a in ("--param", p)), "--out", "{tmp}/out", *extra]
    return R("fit", argv, words, files={"d.csv": data})


ROWS.update({
    "fit: NaN measurement": _fit(["d.csv:3", "'S [mm]'", "not a finite number"],
                                 data=_FIT_HEAD + b"15,-27.7,0.2\n22,nan,0.2\n30,-56.0,0.2\n"),
    "fit: too few points": _fit(["d.csv", "too few points", "2 parameter(s)"], params=("robot.k", "robot.mu"),
                                data=_FIT_HEAD + b"15,-27.7,0.2\n22,-41.1,0.2\n"),
    "fit: unknown parameter": _fit(["--param robot.kk", "unknown parameter", "did you mean robot.k?"],
                                   params=("robot.kk",)),
    "fit: zero uncertainty": _fit(["d.csv:4", "sigma_S", "must be > 0"],
                                  data=_FIT_HEAD + b"15,-27.7,0.2\n22,-41.1,0.2\n30,-56.0,0\n"),
    "fit: negative uncertainty": _fit(["d.csv:2", "sigma_S", "must be > 0"],
                                      data=_FIT_HEAD + b"15,-27.7,-0.2\n22,-41.1,0.2\n30,-56.0,0.2\n"),
    "fit: unit mismatch": _fit(["d.csv:1", "'S'", "[deg] is not a length unit"],
                               data=b"A [deg],S [deg],sigma_S [mm]\n" + _FIT_ROWS),
    "fit: no uncertainty column": _fit(["d.csv", "missing column 'sigma_S'"], data=b"A [deg],S [mm]\n15,-27.7\n22,-4\n"),
    "fit: start outside the bounds": _fit(["--param robot.k", "within bounds"], "--bounds", "robot.k=0.2:0.3"),
    "fit: --max-nfev 0": _fit(["--max-nfev 0", "in [1, 10000]"], "--max-nfev", "0"),
    "fit: unknown pressure constant": _fit(["--pressure pressure.c1", "unknown pressure constant"], "--pressure",
                                           "pressure.c1=0.1"),
})
ROWS["fit: earlier results"] = R("fit", ["{paper}", "{tmp}/d.csv", "--param", "robot.k", "--out", "{tmp}/out"],
                                 ["--out", "would overwrite", "--force"],
                                 files={"d.csv": _FIT_HEAD + _FIT_ROWS, "out/fit.json": b"{}"})


def gait(lines: str) -> str:
    """The paper problem with its [gait] section's keys replaced by ``lines`` (drive kept)."""
    start = PAPER_TEXT.index("gamma_deg = 90.0")
    return PAPER_TEXT[:start] + lines + "\n\n" + PAPER_TEXT[PAPER_TEXT.index("[model]"):]


#: a table of torques over one cycle (the optimize convention) and rows to break it with
CSV_HEAD = "phase [-],tau1 [N m],tau2 [N m]\n"
CSV_ROWS = "0.0,-0.29,-0.29\n0.25,-0.25,-0.33\n0.5,-0.29,-0.29\n0.75,-0.33,-0.25\n"
SAMPLES = 'waveform = "samples"\nfile = "work/t.csv"'


def csv(text: str) -> dict:
    return {"t.csv": text.encode()}


#: issue 14: non-harmonic waveforms ([gait] waveform) are validated like every other key; files name their line
ROWS.update({
    "simulate: unknown waveform": R("simulate", ["{file}"], ["x.toml", '[gait] waveform = "square"', '"pulse"'],
                                    text=gait('waveform = "square"')),
    "simulate: harmonic key with samples": R("simulate", ["{file}"],
                                             ["x.toml", "[gait] gamma_deg = 90.0", 'waveform = "samples"',
                                              'key of waveform = "harmonic"'],
                                             text=gait(SAMPLES + "\ngamma_deg = 90.0"), files=csv(CSV_HEAD + CSV_ROWS)),
    "simulate: samples file missing": R("simulate", ["{file}"], ["x.toml", "[gait] file", "nope.csv", "No such file"],
                                        text=gait('waveform = "samples"\nfile = "nope.csv"')),
    "simulate: --input missing": R("simulate", ["{paper}", "--input", "{tmp}/nope.csv"],
                                   ["paper_gait.toml", "[gait] file", "nope.csv", "(from --set)", "No such file"]),
    "simulate: samples not periodic": R("simulate", ["{file}"], ["x.toml", "[gait] file", "t.csv:6", "not periodic"],
                                        text=gait(SAMPLES), files=csv(CSV_HEAD + CSV_ROWS + "1.0,-0.3,-0.29\n")),
    "simulate: samples NaN": R("simulate", ["{file}"], ["x.toml", "[gait] file", "t.csv:3", "'tau1 [N m]'",
                                                        "not a finite number"],
                               text=gait(SAMPLES), files=csv(CSV_HEAD + CSV_ROWS.replace("-0.25,", "nan,", 1))),
    "simulate: samples NaN inline": R("simulate", ["{file}"], ["x.toml", "[gait] tau1 = [0.1, nan", "entry 1 = nan",
                                                               "finite"],
                                      text=gait('waveform = "samples"\nphase = [0, 0.5, 0.7]\ntau1 = [0.1, nan, 0.1]\n'
                                                'tau2 = [0.1, 0.2, 0.1]')),
    "simulate: samples unknown column": R("simulate", ["{file}"], ["x.toml", "t.csv:1", "unknown column(s) 'tau3'"],
                                          text=gait(SAMPLES),
                                          files=csv("phase [-],tau1 [N m],tau3 [N m]\n" + CSV_ROWS)),
    "simulate: samples one torque column": R("simulate", ["{file}"], ["x.toml", "t.csv", "'tau2 [N m]'", "header has"],
                                             text=gait(SAMPLES),
                                             files=csv("phase [-],tau1 [N m]\n0.0,0.1\n0.5,0.2\n0.7,0.1\n")),
    "simulate: samples wrong unit": R("simulate", ["{file}"], ["x.toml", "t.csv:1", "[deg] is not a torque unit"],
                                      text=gait(SAMPLES), files=csv(CSV_HEAD.replace("tau1 [N m]", "tau1 [deg]") +
                                                                    CSV_ROWS)),
    "simulate: samples unsorted": R("simulate", ["{file}"], ["x.toml", "t.csv:4", "phase 0.2 after 0.25",
                                                             "sorted and unique"],
                                    text=gait(SAMPLES), files=csv(CSV_HEAD + CSV_ROWS.replace("0.5,", "0.2,", 1))),
    "simulate: samples repeated phase inline": R("simulate", ["{file}"], ["x.toml", "[gait] phase", "entry 2",
                                                                          "sorted and unique"],
                                                 text=gait('waveform = "samples"\nphase = [0, 0.5, 0.5]\n'
                                                           'tau1 = [0.1, 0.2, 0.1]\ntau2 = [0.1, 0.2, 0.1]')),
    "simulate: samples angle outside the geometry": R("simulate", ["{file}"],
                                                      ["x.toml", "t.csv:3", "phi1_ref = 400.0 deg", "(0, 360)"],
                                                      text=gait(SAMPLES), files=csv(
                                                          "phase [-],phi1_ref [deg],phi2_ref [deg]\n0,90,90\n"
                                                          "0.3,400,80\n0.6,90,100\n")),
    "simulate: samples foot off the ground": R("simulate", ["{file}"], ["x.toml", "[gait]", "foot 1 off the ground"],
                                               text=gait('waveform = "samples"\nphase = [0, 0.3, 0.6]\n'
                                                         'phi1_ref_deg = [41.5, 90, 90]\nphi2_ref_deg = [18.5, 90, 90]')),
    "simulate: samples lengths differ": R("simulate", ["{file}"], ["x.toml", "[gait] tau2", "2 entries where phase has 3"],
                                          text=gait('waveform = "samples"\nphase = [0, 0.3, 0.6]\n'
                                                    'tau1 = [0.1, 0.2, 0.1]\ntau2 = [0.1, 0.2]')),
    "simulate: torque samples, angles drive": R("simulate", ["{file}", "--drive", "angles"],
                                                ["x.toml", '[gait] drive = "angles"', "torque samples"],
                                                text=gait(SAMPLES), files=csv(CSV_HEAD + CSV_ROWS)),
    "simulate: pulse edges longer than the cycle": R("simulate", ["{file}"], ["x.toml", "[gait] rise = 0.4",
                                                                              "hold = 0.3", "<= 1"],
                                                     text=gait('waveform = "pulse"\ngamma_deg = 90.0\nA_deg = 20.0\n'
                                                               'psi_deg = 90.0\nrise = 0.4\nhold = 0.3')),
    "simulate: pulse without rise": R("simulate", ["{file}"], ["x.toml", "[gait] rise is missing",
                                                               'waveform = "pulse"'],
                                      text=gait('waveform = "pulse"\ngamma_deg = 90.0\nA_deg = 20.0\n'
                                                'psi_deg = 90.0\nhold = 0.3')),
    "simulate: fourier of 101 harmonics": R("simulate", ["{file}"], ["x.toml", "[gait] cos1_deg", "at most 100"],
                                            text=gait('waveform = "fourier"\ngamma_deg = 90.0\ncos1_deg = [' +
                                                      ", ".join(["0.1"] * 101) + "]")),
    "simulate: fourier coefficient a string": R("simulate", ["{file}"], ["x.toml", "[gait] sin2_deg", "entry 0",
                                                                         "expected a number"],
                                                text=gait('waveform = "fourier"\ngamma_deg = 90.0\nsin2_deg = ["1"]')),
})


#: generous time limit of one row: a hang guard, not a timing assertion (every row takes well under a second)
HANG_GUARD_S = 120


def _computed(*args, **kwargs):
    raise AssertionError("a long computation started before the bad input was rejected")


@pytest.fixture
def nothing_computed(monkeypatch):
    """Every solver, sweep and study fails the test if called (bad input must be rejected first)."""
    for module, name in ((ocp_crawl.cli.run_commands, "run_problem"), (ocp_crawl.problem.run, "simulate"),
                         (ocp_crawl.sim.event.HybridStepper, "run"),
                         (ocp_crawl.sim.angles, "simulate_angles"), (ocp_crawl.sim.timestepping, "simulate_mpcc"),
                         (ocp_crawl.cli.study_commands, "run_sweep"), (ocp_crawl.studies.reproduce, "reproduce"),
                         (ocp_crawl.viz.animate, "animate_problem"), (ocp_crawl.sim.crosscheck, "crosscheck"),
                         (ocp_crawl.ocp, "optimize_gait"), (ocp_crawl.sweep.warmup, "warmup"),
                         (ocp_crawl.fit.solve, "fit_measurements")):
        monkeypatch.setattr(module, name, _computed)


class Hang(Exception):
    """A row ran past HANG_GUARD_S."""


@contextlib.contextmanager
def hang_guard(case: str, seconds: int = HANG_GUARD_S):
    """Fail the row (instead of hanging the suite) if it runs longer than ``seconds`` (SIGALRM; POSIX main thread)."""
    if not hasattr(signal, "SIGALRM") or threading.current_thread() is not threading.main_thread():
        yield
        return

    def alarm(signum, frame):
        raise Hang(f"{case}: still running after {seconds} s (a hang: the bad input was not rejected)")

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
    places = {"{paper}": str(PAPER), "{ocp}": str(OCP), "{tmp}": str(work), "{missing}": str(tmp_path / "nope.toml")}
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
SUBPROCESS_ROWS = ("sweep: NUM < 1", "optimize: unknown [ocp] key", "simulate: cannot stand (no_start)",
                   "simulate: k = 1e308 (RuntimeWarnings)", "sweep: STOP inf (said nan)", "simulate: /dev/zero (hung)",
                   "simulate: TOML nested 5000 deep (RecursionError)")


@pytest.mark.parametrize("case", SUBPROCESS_ROWS)
def test_bad_input_in_a_real_process(case, tmp_path):
    argv, words = materialise(ROWS[case], tmp_path)
    env = dict(os.environ, MPLBACKEND="Agg")
    env.pop("OCP_CRAWL_TRACEBACK", None)
    proc = subprocess.run([sys.executable, "-m", "ocp_crawl", *argv], capture_output=True, text=True, env=env,
                          timeout=HANG_GUARD_S, cwd=tmp_path)
    check_one_line(proc.returncode, proc.stdout, proc.stderr, words, ROWS[case].absent)


def test_the_guard_catches_a_computation(tmp_path, capsys, nothing_computed, monkeypatch):
    """The matrix's guard is live: valid input reaches a (replaced) solver, which ends as an internal error."""
    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    for argv in (["simulate", str(PAPER)], ["sweep", str(PAPER), "--grid", "gait.psi_deg=45", "--out", str(tmp_path / "s")],
                 ["optimize", str(OCP)], ["crosscheck", str(PAPER)], ["reproduce", "--out", str(tmp_path / "r")],
                 ["animate", str(PAPER), "--out", str(tmp_path / "a.gif")], ["demo", "--out", str(tmp_path / "d")],
                 ["warmup"]):
        code = cli.main(argv)
        err = capsys.readouterr().err
        assert code == 1, (argv, err)
        assert err.startswith("ocp-crawl: internal error: AssertionError: a long computation started"), err


def test_a_partly_valid_grid_is_data_not_bad_input():
    from ocp_crawl.problem import ProblemError, load_problem
    from ocp_crawl.sweep import check_some_point_valid, grid_from_specs

    problem = load_problem(PAPER)
    # gamma 30 with psi 45 starts with foot 1 off the ground; gamma 90 is fine: the sweep records both
    check_some_point_valid(problem, grid_from_specs(["gait.gamma_deg=30,90"]))
    with pytest.raises(ProblemError, match="every one of the 4 points"):
        check_some_point_valid(problem, grid_from_specs(["gait.gamma_deg=20,30", "gait.A_deg=30,40"]))


def test_the_guard_catches_a_fit(tmp_path, capsys, nothing_computed, monkeypatch):
    """Valid fit input reaches the (replaced) fit, which ends as an internal error: the rows above are rejected
    before it."""
    monkeypatch.delenv("OCP_CRAWL_TRACEBACK", raising=False)
    (tmp_path / "d.csv").write_bytes(_FIT_HEAD + _FIT_ROWS)
    code = cli.main(["fit", str(PAPER), str(tmp_path / "d.csv"), "--param", "robot.k", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 1 and err.startswith("ocp-crawl: internal error: AssertionError: a long computation started"), err
