"""The rows of the bad-input matrix (tests/test_bad_input.py): malformed problem files and arguments
of every command, and the bounds on work; the rows of data files and waveforms are in
tests/_bad_input_data_rows.py.

:class:`Row` is one case; its placeholders are filled in by ``materialise`` of
tests/test_bad_input.py.
"""
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "problems" / "paper_gait.toml"
OCP = REPO / "problems" / "ocp_max_speed.toml"
CHAIN = REPO / "problems" / "five_link_chain.toml"
PAPER_TEXT, OCP_TEXT, CHAIN_TEXT = PAPER.read_text(), OCP.read_text(), CHAIN.read_text()
DESIGN_TEXT = (REPO / "problems" / "codesign_stiffness.toml").read_text()

#: k = 0.05 M g L (Table I robot): the springs cannot hold the robot up at t = 0 (status no_start)
SOFT = "robot.k=0.00306"


def edit(old, new, text=PAPER_TEXT):
    assert old in text, old
    return text.replace(old, new, 1)


def ocp_edit(old, new):
    return edit(old, new, OCP_TEXT)


def chain_edit(old, new):
    return edit(old, new, CHAIN_TEXT)


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
    """words the message must not contain (e.g. blaming the gait for the robot's mass, nan for
    inf)"""


def R(command, argv, words, **kw):
    if "absent" in kw:
        kw["absent"] = tuple(kw["absent"])
    return Row(command, tuple(argv), tuple(words), **kw)


def nested(depth: int) -> str:
    """A TOML array nested ``depth`` deep: [[[...]]]"""
    return "[" * depth + "]" * depth


COMMAND_ROWS = {
    # ------------------------------------------------------------------ simulate
    "simulate: negative stiffness":
        R("simulate", ["{file}"], ["x.toml", "[robot] k = -1.0", "must be in [1e-12, 1e12]"],
          text=edit("k = 0.1677", "k = -1.0")),
    "simulate: an integer of 400 digits in a file": R(
        "simulate", ["{file}"], ["x.toml", "[robot] M = 1111111111", "too large", "finite"],
        text=edit("M = 0.052", "M = " + "1" * 400)),
    "simulate: an integer of 400 digits by --set": R(
        "simulate", ["{paper}", "--set", "simulation.max_cycles=" + "1" * 400],
        ["[simulation] max_cycles = 1111111111", "too large", "finite"]),
    "sweep: an integer of 400 digits in --grid": R(
        "sweep", ["{paper}", "--grid", "gait.A_deg=20," + "1" * 400, "--out", "{tmp}"],
        ["--grid", "gait.A_deg = 1111111111", "must be finite"]),
    "simulate: zero mass":
        R("simulate", ["{file}"], ["x.toml", "[robot] M = 0", "must be in [1e-12, 1e12]"],
          text=edit("M = 0.052", "M = 0")),
    "simulate: negative length":
        R("simulate", ["{file}"], ["x.toml", "[robot] L = -0.12", "must be in [1e-12, 1e12]"],
          text=edit("L = 0.120", "L = -0.12")),
    "simulate: zero beta":
        R("simulate", ["{file}"], ["x.toml", "[robot] beta = 0.0", "must be in [0.01, 100]"],
          text=edit("beta = 2.0", "beta = 0.0")),
    "simulate: zero gravity":
        R("simulate", ["{file}"], ["x.toml", "[robot] g = 0.0", "must be in [1e-12, 1e12]"],
          text=edit("g = 9.81", "g = 0.0")),
    "simulate: infinite g": R("simulate", ["{file}"], ["x.toml", "[robot] g = inf", "finite"],
                              text=edit("g = 9.81", "g = inf")),
    "simulate: NaN amplitude": R("simulate", ["{file}"], ["x.toml", "[gait] A_deg = nan", "finite"],
                                 text=edit("A_deg = 30.0", "A_deg = nan")),
    "simulate: negative friction":
        R("simulate", ["{file}"], ["x.toml", "[robot] mu = -0.2", "in [1e-4, 1e4]"],
          text=edit("mu = 0.389", "mu = -0.2")),
    "simulate: bool for a number":
        R("simulate", ["{file}"], ["x.toml", "[robot] L = true", "expected a number"],
          text=edit("L = 0.120", "L = true")),
    "simulate: string for a number":
        R("simulate", ["{file}"], ["x.toml", '[robot] beta = "2"', "expected a number"],
          text=edit("beta = 2.0", 'beta = "2"')),
    "simulate: float for an int":
        R("simulate", ["{file}"], ["x.toml", "max_cycles = 3.5", "integer"],
          text=edit("max_cycles = 12", "max_cycles = 3.5")),
    "simulate: bool for an int":
        R("simulate", ["{file}"], ["x.toml", "max_cycles = true", "integer"],
          text=edit("max_cycles = 12", "max_cycles = true")),
    "simulate: mu with mu1":
        R("simulate", ["{file}"], ["x.toml", "mu = 0.389", "mu1 = 0.3", "exclusive"],
          text=edit("mu = 0.389", "mu = 0.389\nmu1 = 0.3")),
    "simulate: missing key":
        R("simulate", ["{file}"], ["x.toml", "[robot] k", "missing", "required"],
          text=edit("k = 0.1677", "")),
    "simulate: missing section": R("simulate", ["{file}"], ["x.toml", "section [robot] is missing"],
                                   text=PAPER_TEXT[PAPER_TEXT.index("[gait]"):]),
    "simulate: empty file": R("simulate", ["{file}"], ["x.toml", "[robot]", "missing"], text=""),
    "simulate: key outside a section":
        R("simulate", ["{file}"], ["x.toml", "top-level key k = 0.1", "section"],
          text="k = 0.1\n" + PAPER_TEXT),
    "simulate: unknown key":
        R("simulate", ["{file}"], ["x.toml", "spring_k = 0.1677", "unknown key"],
          text=edit("k = 0.1677", "spring_k = 0.1677")),
    # a chain ([robot] lengths, masses, stiffness): its lists, and what it cannot take
    "simulate: a chain's stiffness as a number":
        R("simulate", ["{file}"], ["x.toml", "[robot] stiffness = 0.1677", "an array"],
          text=edit("k = 0.1677", "stiffness = 0.1677")),
    "simulate: a chain's masses fewer than its links":
        R("simulate", ["{file}"], ["x.toml", "[robot] masses", "5 entries, got 4"],
          text=chain_edit("masses = [0.013, 0.009, 0.010, 0.008, 0.012]",
                          "masses = [0.013, 0.009, 0.010, 0.008]")),
    "simulate: a chain's joint angles fewer than its joints":
        R("simulate", ["{file}"], ["x.toml", "[gait] gamma_joints_deg", "4 joints"],
          text=chain_edit("gamma_joints_deg = [95.0, 170.0, 175.0, 90.0]",
                          "gamma_joints_deg = [95.0, 170.0, 175.0]")),
    "simulate: a chain's centres of mass as an empty array":
        R("simulate", ["{file}"], ["x.toml", "[robot] com = []", "leave the key out"],
          text=chain_edit("com = [0.45, 0.50, 0.55, 0.50, 0.60]", "com = []")),
    "simulate: a chain with the three-link mass":
        R("simulate", ["{file}"], ["x.toml", "[robot] M = 0.052", "mutually exclusive"],
          text=chain_edit("[robot]\n", "[robot]\nM = 0.052\n")),
    "simulate: a chain with joint 1's angle of the three-link robot":
        R("simulate", ["{file}"], ["x.toml", "[gait] gamma1_deg = 90", "gamma_joints_deg"],
          text=chain_edit("[gait]\n", "[gait]\ngamma1_deg = 90.0\n")),
    "simulate: a chain with another waveform than the harmonic":
        R("simulate", ["{file}"], ["x.toml", '[gait] waveform = "fourier"', "harmonic"],
          text=CHAIN_TEXT[:CHAIN_TEXT.index("[gait]")]
          + '[gait]\nwaveform = "fourier"\ngamma_deg = 90.0\nsin1_deg = [10.0]\n'),
    "simulate: a chain with the MuJoCo solver":
        R("simulate", ["{file}", "--solver", "mujoco"], ["x.toml", "chain", "event, mpcc"],
          text=CHAIN_TEXT),
    "simulate: a chain whose first joint starts below the ground":
        R("simulate", ["{file}"], ["x.toml", "[gait] psi_deg = 20", "gamma_joints_deg = [260",
                                   "joint 1"],
          text=chain_edit("gamma_joints_deg = [95.0, 170.0, 175.0, 90.0]",
                          "gamma_joints_deg = [260.0, 170.0, 175.0, 90.0]")),
    "simulate: a chain's per-joint angles on the three-link robot":
        R("simulate", ["{file}"], ["x.toml", "[gait] gamma_joints_deg = [90.0, 90.0]", "chain"],
          text=edit("gamma_deg = 90.0", "gamma_joints_deg = [90.0, 90.0]")),
    "simulate: a chain with both a common and a per-joint amplitude":
        R("simulate", ["{file}"], ["x.toml", "A_joints_deg", "A_deg = 10", "mutually exclusive"],
          text=chain_edit("[gait]\n", "[gait]\nA_deg = 10.0\n")),
    "simulate: a chain with the time-stepping's error estimate":
        R("simulate", ["{file}", "--solver", "mpcc", "--set", "simulation.s_error_tol=1e-3"],
          ["x.toml", "[simulation] s_error_tol = 0.001", "chain"], text=CHAIN_TEXT),
    "crosscheck: a chain too soft to stand":
        R("crosscheck", ["{file}"], ["x.toml", "released equilibrium", "robot.stiffness"],
          text=chain_edit("stiffness = [0.17, 0.30, 0.25, 0.20]",
                          "stiffness = [0.0001, 0.0001, 0.0001, 0.0001]")),
    "optimize: a chain of prescribed angles":
        R("optimize", ["{file}"], ["x.toml", "joint torques", 'drive = "torque"', '"angles"'],
          text=chain_edit("[model]\n", '[ocp]\nobjective = "max_speed"\n\n[model]\n').replace(
              'drive = "torque"', 'drive = "angles"')),
    "simulate: unknown section":
        R("simulate", ["{file}"], ["x.toml", "[modle]", "did you mean model?"],
          text=edit("[model]", "[modle]")),
    "simulate: bad drive":
        R("simulate", ["{file}"], ["x.toml", '[gait] drive = "crawl"', '"angles"'],
          text=edit('drive = "torque"', 'drive = "crawl"')),
    "simulate: bad gravity": R("simulate", ["{file}"], ["x.toml", 'gravity = "real"', '"paper"'],
                               text=edit('gravity = "physical"', 'gravity = "real"')),
    "simulate: malformed TOML":
        R("simulate", ["{file}"], ["x.toml", "malformed TOML", "line 9", "k 0.1677"],
          text=edit("k = 0.1677", "k 0.1677")),
    "simulate: not UTF-8": R("simulate", ["{file}"], ["x.toml", "not UTF-8"], text="\udcff"),
    "simulate: foot off the ground":
        R("simulate", ["{file}"], ["x.toml", "gamma_deg = 30.0", "foot 1 off the ground"],
          text=edit("gamma_deg = 90.0", "gamma_deg = 30.0")),
    "simulate: prescribed lift-off": R("simulate", ["{file}", "--drive", "angles"],
                                       ["x.toml", "A_deg = 75.0", "below the ground"],
                                       text=edit("A_deg = 30.0", "A_deg = 75.0")),
    "simulate: cannot stand (no_start)":
        R("simulate", ["{paper}", "--set", SOFT],
          ["paper_gait.toml", "[robot] k = 0.00306", 'gravity = "physical"',
           "gamma_deg = 90.0", "psi_deg = 45.0", "no equilibrium to start from"]),
    "simulate: cannot stand, mpcc":
        R("simulate", ["{paper}", "--set", SOFT, "--solver", "mpcc"],
          ["paper_gait.toml", "[robot] k = 0.00306", "no equilibrium to start from"]),
    "simulate: mpcc with the angles drive":
        R("simulate", ["{paper}", "--drive", "angles", "--solver", "mpcc"],
          ["paper_gait.toml", '[simulation] solver = "mpcc" (from --set)',
           'drive = "angles"', "own solver"]),
    "simulate: unknown solver in the file":
        R("simulate", ["{file}"], ["x.toml", '[simulation] solver = "rk4"',
                                  'one of "event", "mpcc"'],
          text=edit('solver = "event"', 'solver = "rk4"')),
    "simulate: --set syntax":
        R("simulate", ["{paper}", "--set", "robot.k"], ["robot.k", "SECTION.KEY=VALUE"]),
    "simulate: --set an entry past the array's end":
        R("simulate", ["{file}", "--set", "robot.stiffness[4]=0.2"],
          ["x.toml", "robot.stiffness[4] = 0.2", "4 entries, indices 0 to 3"], text=CHAIN_TEXT),
    "simulate: --set an entry with a leading zero":
        R("simulate", ["{file}", "--set", "robot.stiffness[01]=0.2"],
          ["robot.stiffness[01]", "SECTION.KEY[i]"], text=CHAIN_TEXT),
    "simulate: --set a whole array that changes an entry set before it":
        R("simulate", ["{file}", "--set", "robot.stiffness[1]=0.4", "--set",
                       "robot.stiffness=[0.2, 0.3, 0.3, 0.2]"],
          ["robot.stiffness = [0.2, 0.3, 0.3, 0.2] changes robot.stiffness[1] = 0.4"],
          text=CHAIN_TEXT),
    "sweep: an axis over an entry of an array the --set gives whole":
        R("sweep", ["{file}", "--set", "robot.stiffness=[0.2, 0.3, 0.3, 0.2]", "--grid",
                    "robot.stiffness[1]=0.3,0.4", "--out", "{tmp}"],
          ["robot.stiffness[1]=0.4 undoes --set", "drop the --set"], text=CHAIN_TEXT,
          absent=["or sweep"]),
    "simulate: --set an entry of a number":
        R("simulate", ["{paper}", "--set", "robot.k[0]=0.2"],
          ["robot.k[0]", "not an array"]),
    "simulate: --set an entry of an array the problem does not give":
        R("simulate", ["{file}", "--set", "robot.com[0]=0.5"],
          ["x.toml", "robot.com[0] = 0.5", "give the whole array"],
          text=chain_edit("com = [0.45, 0.50, 0.55, 0.50, 0.60]", "")),
    "simulate: --set an entry to a value its array refuses":
        R("simulate", ["{file}", "--set", "robot.stiffness[1]=-1"],
          ["x.toml", "[robot] stiffness = [0.17, -1, 0.25, 0.2] (from --set)", "entry 1 = -1"],
          text=CHAIN_TEXT),
    "sweep: an axis over an entry of a number":
        R("sweep", ["{paper}", "--grid", "robot.k[0]=0.1,0.2", "--out", "{tmp}"],
          ["robot.k[0]", "not an array key"]),
    "simulate: --set unknown key":
        R("simulate", ["{paper}", "--set", "robot.kay=1"], ["robot.kay=1", "did you mean k?"]),
    "simulate: --set string for a number": R("simulate", ["{paper}", "--set", "robot.k=soft"],
                                             ["robot.k=soft", "expected a number"]),
    "simulate: --set negative friction":
        R("simulate", ["{paper}", "--set", "robot.mu=-1"],
          ["paper_gait.toml", "[robot] mu = -1 (from --set)", "in [1e-4, 1e4]"]),
    "simulate: missing file":
        R("simulate", ["{missing}"], ["nope.toml", "cannot read", "No such file"]),
    "simulate: directory as problem file":
        R("simulate", ["{dir}"], ["adir", "cannot read", "directory"]),
    "simulate: unreadable file":
        R("simulate", ["{unreadable}"], ["locked.toml", "cannot read", "Permission denied"],
          needs_permissions=True),
    "simulate: --out under a file": R("simulate", ["{paper}", "--out", "{blocker}/run"],
                                      ["--out", "blocker/run", "not writable"]),
    "simulate: --out is a file":
        R("simulate", ["{paper}", "--out", "{blocker}"], ["--out", "blocker", "not a directory"]),
    "simulate: --out read-only":
        R("simulate", ["{paper}", "--out", "{readonly}/run"], ["--out", "readonly", "not writable"],
          needs_permissions=True),
    "simulate: --out holds results": R("simulate", ["{paper}", "--out", "{tmp}"],
                                       ["--out", "summary.json", "would overwrite", "--force"],
                                       files={"summary.json": b"{}"}),
    "simulate: --steps too small":
        R("simulate", ["{paper}", "--solver", "mpcc", "--steps", "3"],
          ["--steps 3", "in [4, 10000]"]),
    "simulate: --steps not an integer":
        R("simulate", ["{paper}", "--steps", "2.5"], ["--steps 2.5", "integer"]),
    "simulate: unknown option":
        R("simulate", ["{paper}", "--bogus"], ["unrecognized arguments: --bogus"]),
    "simulate: bad --drive": R("simulate", ["{paper}", "--drive", "walk"], ["--drive", "'walk'"]),
    "simulate: no problem file": R("simulate", [], ["PROBLEM.toml", "required"]),
    # ------------------------------------------------------------------ demo
    "demo: --out under a file":
        R("demo", ["--out", "{blocker}/d"], ["--out", "blocker/d", "not writable"]),
    "demo: --out read-only":
        R("demo", ["--out", "{readonly}"], ["--out", "readonly", "not writable"],
          needs_permissions=True),
    "demo: --out holds results":
        R("demo", ["--out", "{tmp}"], ["--out", "demo_summary.json", "would overwrite"],
          files={"demo_summary.json": b"{}"}),
    "demo: unexpected argument":
        R("demo", ["{paper}"], ["unrecognized arguments", "paper_gait.toml"]),
    # ------------------------------------------------------------------ warmup
    "warmup: unexpected argument":
        R("warmup", ["{paper}"], ["unrecognized arguments", "paper_gait.toml"]),
    "warmup: unknown option": R("warmup", ["--jobs", "2"], ["unrecognized arguments", "--jobs 2"]),
    "warmup: --json with a value":
        R("warmup", ["--json=yes"], ["--json", "ignored explicit argument 'yes'"]),
    "warmup: --out": R("warmup", ["--out", "{tmp}"], ["unrecognized arguments", "--out"]),
    # ------------------------------------------------------------------ sweep
    "sweep: NUM < 1": R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:180:0", "--out", "{tmp}"],
                        ["gait.psi_deg=0:180:0", "NUM must be an integer >= 1, got 0"]),
    "sweep: NUM not an integer":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:180:2.5", "--out", "{tmp}"],
          ["gait.psi_deg=0:180:2.5", "NUM must be an integer", "'2.5'"]),
    "sweep: START:STOP malformed":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:180", "--out", "{tmp}"],
          ["gait.psi_deg=0:180", "START:STOP:NUM", "2 fields"]),
    "sweep: START not a number":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=a:180:3", "--out", "{tmp}"],
          ["gait.psi_deg=a:180:3", "START and STOP must be numbers", "'a'"]),
    "sweep: unknown grid key": R("sweep", ["{paper}", "--grid", "gait.psi=0:1:2", "--out", "{tmp}"],
                                 ["gait.psi=0:1:2", "did you mean gait.psi_deg"]),
    "sweep: unknown grid section":
        R("sweep", ["{paper}", "--grid", "gaitt.psi_deg=0:1:2", "--out", "{tmp}"],
          ["gaitt.psi_deg=0:1:2", "unknown section [gaitt]"]),
    "sweep: grid value not numeric":
        R("sweep", ["{paper}", "--grid", "robot.k=soft", "--out", "{tmp}"],
          ["robot.k=soft", "'soft' is not a number"]),
    "sweep: empty list":
        R("sweep", ["{paper}", "--grid", "robot.k=", "--out", "{tmp}"], ["robot.k=", "no values"]),
    "sweep: duplicate axis":
        R("sweep", ["{paper}", "--grid", "robot.k=0.1", "--grid", "robot.k=0.2", "--out", "{tmp}"],
          ["robot.k=0.2", "already a grid key"]),
    "sweep: negative stiffness on the grid":
        R("sweep", ["{paper}", "--grid", "robot.k=-1:1:3", "--out", "{tmp}"],
          ["robot.k=-1:1:3", "robot.k = -1.0", "must be in [1e-12, 1e12]"]),
    "sweep: every point invalid":
        R("sweep", ["{paper}", "--grid", "gait.gamma_deg=20,30", "--out", "{tmp}"],
          ["paper_gait.toml", "gamma_deg = 20.0", "every one of the 2 points"]),
    "sweep: --jobs 0":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--jobs", "0", "--out", "{tmp}"],
          ["--jobs 0", "in [1, 256]"]),
    "sweep: --jobs not an integer":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--jobs", "1.5"],
          ["--jobs 1.5", "integer"]),
    "sweep: --resume with --force":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--resume", "--force"],
          ["--force", "not allowed with", "--resume"]),
    "sweep: no --grid": R("sweep", ["{paper}", "--out", "{tmp}"], ["--grid", "required"]),
    "sweep: empty --scheduler":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--scheduler", " "],
          ["--scheduler", "is invalid"]),
    "sweep: bad problem file": R("sweep", ["{file}", "--grid", "gait.psi_deg=45", "--out", "{tmp}"],
                                 ["x.toml", "[robot] k = -1.0", "must be in [1e-12, 1e12]"],
                                 text=edit("k = 0.1677", "k = -1.0")),
    "sweep: --out under a file":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--out", "{blocker}/s"],
          ["--out", "blocker/s", "not writable"]),
    "sweep: --out holds a sweep":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--out", "{tmp}"],
          ["--out", "results.csv", "already holds a sweep", "--resume", "--force"],
          files={"results.csv": b"x\n"}),
    # ------------------------------------------------------------------ reproduce
    "reproduce: --jobs 0":
        R("reproduce", ["--jobs", "0", "--out", "{tmp}"], ["--jobs 0", "in [1, 256]"]),
    "reproduce: bad --gravity":
        R("reproduce", ["--gravity", "real", "--out", "{tmp}"], ["--gravity", "'real'"]),
    "reproduce: --out under a file":
        R("reproduce", ["--out", "{blocker}/r"], ["--out", "blocker/r", "not writable"]),
    "reproduce: --out holds a run":
        R("reproduce", ["--out", "{tmp}", "--quick"],
          ["--out", "report.md", "would overwrite", "--resume", "--force"],
          files={"report.md": b"# report\n"}),
    "reproduce: --out holds a partial run":
        R("reproduce", ["--out", "{tmp}"], ["--out", "sweeps", "would overwrite"],
          files={"sweeps/gait/settings.json": b"{}"}),
    "reproduce: --resume with --force": R("reproduce", ["--resume", "--force", "--out", "{tmp}"],
                                          ["--force", "not allowed with", "--resume"]),
    # ------------------------------------------------------------------ animate
    "animate: --fps 0":
        R("animate", ["{paper}", "--fps", "0", "--out", "{tmp}/a.gif"], ["--fps 0", "[0.01, 100]"]),
    "animate: --fps nan":
        R("animate", ["{paper}", "--fps", "nan", "--out", "{tmp}/a.gif"],
          ["--fps nan", "[0.01, 100]"]),
    "animate: --fps too high":
        R("animate", ["{paper}", "--fps", "1e3", "--out", "{tmp}/a.gif"],
          ["--fps 1e3", "[0.01, 100]"]),
    "animate: --cycles 0":
        R("animate", ["{paper}", "--cycles", "0", "--out", "{tmp}/a.gif"], ["--cycles 0", ">= 1"]),
    "animate: --frames-per-cycle 1":
        R("animate", ["{paper}", "--frames-per-cycle", "1", "--out", "{tmp}/a.gif"],
          ["--frames-per-cycle 1", ">= 2"]),
    "animate: --cycles not an integer":
        R("animate", ["{paper}", "--cycles", "1.5", "--out", "{tmp}/a.gif"],
          ["--cycles 1.5", "integer"]),
    "animate: --out not a GIF":
        R("animate", ["{paper}", "--out", "{tmp}/a.png"], ["--out", "a.png", ".gif"]),
    "animate: --out under a file":
        R("animate", ["{paper}", "--out", "{blocker}/a.gif"],
          ["--out", "blocker/a.gif", "blocker: exists and is not a directory"]),
    "animate: --out exists":
        R("animate", ["{paper}", "--out", "{tmp}/a.gif"], ["--out", "a.gif", "would overwrite"],
          files={"a.gif": b"GIF89a"}),
    "animate: cannot stand (no_start)":
        R("animate", ["{paper}", "--set", SOFT, "--out", "{tmp}/a.gif"],
          ["paper_gait.toml", "k = 0.00306", "no equilibrium to start from"]),
    "animate: missing file":
        R("animate", ["{missing}", "--out", "{tmp}/a.gif"], ["nope.toml", "cannot read"]),
    # ------------------------------------------------------------------ crosscheck
    "crosscheck: --steps too small":
        R("crosscheck", ["{paper}", "--steps", "3", "50"], ["--steps 3", "in [4, 10000]"]),
    "crosscheck: one step count": R("crosscheck", ["{paper}", "--steps", "100", "100"],
                                    ["--steps 100 100", "two different"]),
    "crosscheck: angles drive": R("crosscheck", ["{paper}", "--set", "gait.drive=angles"],
                                  ["paper_gait.toml", "torque drive", 'drive = "angles"']),
    "crosscheck: cannot stand (no_start)":
        R("crosscheck", ["{paper}", "--set", SOFT],
          ["paper_gait.toml", "k = 0.00306", "no equilibrium to start from"]),
    "crosscheck: malformed TOML": R("crosscheck", ["{file}"], ["x.toml", "malformed TOML"],
                                    text=edit("[gait]", "[gait")),
    "crosscheck: --set bad value":
        R("crosscheck", ["{paper}", "--set", "robot.mu=nan"],
          ["paper_gait.toml", "[robot] mu = nan (from --set)", "finite"]),
    # ------------------------------------------------------------------ codesign
    "codesign: no [design] section":
        R("codesign", ["{ocp}"], ["ocp_max_speed.toml", "no [design] section"]),
    "codesign: no bounds in --set either":
        R("codesign", ["{ocp}", "--set", "design.scan=2"],
          ["ocp_max_speed.toml", "no [design] bounds", "stiffness_min"]),
    "codesign: no [ocp] section":
        R("codesign", ["{paper}"], ["paper_gait.toml", "no [ocp] section"]),
    "codesign: bounds without the robot":
        R("codesign", ["{file}", "--set", "design.stiffness_min=[0.5]"],
          ["x.toml", "[design] stiffness[0]", "0.1677", "outside"], text=DESIGN_TEXT),
    "codesign: bounds of the wrong count":
        R("codesign", ["{file}", "--set", "design.stiffness_max=[1, 1, 1]"],
          ["x.toml", "[design] stiffness_max", "3 entries", "one per joint (2)"],
          text=DESIGN_TEXT),
    "codesign: no bounds":
        R("codesign", ["{file}"], ["x.toml", "no [design] bounds", "stiffness_min"],
          text=OCP_TEXT + "\n[design]\nscan = 4\n"),
    "codesign: a lower bound alone":
        R("codesign", ["{file}"], ["x.toml", "stiffness_min", "stiffness_max"],
          text=OCP_TEXT + "\n[design]\nstiffness_min = [0.1]\n"),
    "codesign: no designs scanned":
        R("codesign", ["{file}", "--set", "design.scan=0"], ["x.toml", "[design] scan = 0",
                                                             "in [1, 256]"], text=DESIGN_TEXT),
    "codesign: lengths of a chain whose masses are not uniform":
        R("codesign", ["{file}", "--set", "design.lengths_min=[0.01]", "--set",
                       "design.lengths_max=[0.1]"], ["x.toml", "uniform body"],
          text=CHAIN_TEXT.replace('drive = "angles"', 'drive = "torque"')
          + "\n[ocp]\nnodes = 12\n\n[design]\nscan = 2\n"),
    "codesign: length bounds beyond the chain's ratio":
        R("codesign", ["{file}", "--set", "design.lengths_min=[0.0001]", "--set",
                       "design.lengths_max=[0.1]"],
          ["x.toml", "lengths", "more than 100 times shorter"], text=DESIGN_TEXT),
    "codesign: the angles drive":
        R("codesign", ["{file}", "--set", 'gait.drive="angles"'],
          ["x.toml", "joint torques", 'drive = "torque"'], text=DESIGN_TEXT),
    # ------------------------------------------------------------------ optimize
    "optimize: no [ocp] section":
        R("optimize", ["{paper}"], ["paper_gait.toml", "no [ocp] section"]),
    "optimize: no [ocp] section, --set ocp.*": R("optimize", ["{paper}", "--set", "ocp.nodes=20"],
                                                ["paper_gait.toml", "no [ocp] section"]),
    "optimize: --nodes, too many counts": R("optimize",
                                            ["{ocp}", "--nodes", *map(str, range(8, 1001))],
                                            ["--nodes", "993 numbers of nodes given, at most 6"]),
    "optimize: too few nodes":
        R("optimize", ["{file}"], ["x.toml", "[ocp] nodes = 4", "in [8, 1000]"],
          text=ocp_edit("nodes = 50", "nodes = 4")),
    "optimize: float for int nodes":
        R("optimize", ["{file}"], ["x.toml", "[ocp] nodes = 10.5", "integer"],
          text=ocp_edit("nodes = 50", "nodes = 10.5")),
    "optimize: unknown objective":
        R("optimize", ["{file}"], ["x.toml", '[ocp] objective = "fastest"', '"min_cot"'],
          text=ocp_edit('objective = "max:speed"', 'objective = "fastest"')),
    "optimize: unknown [ocp] key":
        R("optimize", ["{file}"], ["x.toml", "[ocp] unknown key node = 100"],
          text=ocp_edit("nodes = 50", "node = 100")),
    "optimize: A_max_deg too large":
        R("optimize", ["{file}"], ["x.toml", "[ocp] A_max_deg = 95.0", "(0, 90)"],
          text=ocp_edit("A_max_deg = 30.0", "A_max_deg = 95.0")),
    "optimize: envelope outside (0, 180)":
        R("optimize", ["{ocp}", "--set", "gait.gamma_deg=150", "--set",
                       "ocp.A_max_deg=40"],
          ["ocp_max_speed.toml", "A_max_deg = 40", "gamma_deg = 150", "(0, 180)"]),
    # rules between the homotopy's keys (each alone is valid): exit 2 naming them, not an internal
    # error
    "optimize: sigma_min above sigma0": R("optimize", ["{ocp}", "--set", "ocp.sigma_min=1e-3"],
                                          ["ocp_max_speed.toml", "[ocp]", "sigma_min < sigma0"]),
    "optimize: endgame after the last stage":
        R("optimize", ["{ocp}", "--set", "ocp.endgame_sigma=1e-6"],
          ["ocp_max_speed.toml", "[ocp]", "endgame_sigma",
           "stages before the last"]),
    "optimize: endgame without iterations":
        R("optimize", ["{ocp}", "--set", "ocp.endgame_max_iter=0"],
          ["[ocp] endgame_max_iter = 0", "[1, 10000]"]),
    "optimize: an unknown way to solve the starts":
        R("optimize", ["{ocp}", "--set", "ocp.start_solve=fast"],
          ["ocp_max_speed.toml", "start_solve", "tightened"]),
    "optimize: too many homotopy stages":
        R("optimize", ["{ocp}", "--set", "ocp.sigma_factor=0.999"],
          ["ocp_max_speed.toml", "[ocp]", "sigma_factor 0.999", "homotopy stages"]),
    # keys of earlier versions: the message names the key, the file and the replacement
    "optimize: removed S_min in a file":
        R("optimize", ["{file}"], ["x.toml", "[ocp] S_min no longer exists",
                                    "speed_min [m/s]", "S_min = 0.04"],
          text=ocp_edit("nodes = 50", "nodes = 50\nS_min = 0.04")),
    "optimize: removed rate_limit in a file":
        R("optimize", ["{file}"], ["x.toml", "[ocp] rate_limit no longer exists",
                                    "max_rate_deg_s [deg/s]"],
          text=ocp_edit("nodes = 50", 'nodes = 50\nrate_limit = "harmonic"')),
    "optimize: removed curvature_limit in a file":
        R("optimize", ["{file}"],
          ["x.toml", "[ocp] curvature_limit no longer exists",
           "max_accel_deg_s2 [deg/s^2]"],
          text=ocp_edit("nodes = 50",
                        'nodes = 50\ncurvature_limit = "harmonic"')),
    "optimize: removed tie_margin in a file":
        R("optimize", ["{file}"], ["x.toml", "[ocp] tie_margin no longer exists",
                                    "switch-exact"],
          text=ocp_edit("nodes = 50", "nodes = 50\ntie_margin = 0.0005")),
    "optimize: removed friction_tol in a file":
        R("optimize", ["{file}"], ["x.toml", "[ocp] friction_tol no longer exists",
                                    "mu_ratio_eps", "friction_tol = 0.05"],
          text=ocp_edit("nodes = 50", "nodes = 50\nfriction_tol = 0.05")),
    "optimize: removed friction_tol by --set":
        R("optimize", ["{ocp}", "--set", "ocp.friction_tol=0.05"],
          ["--set", "[ocp] friction_tol no longer exists", "robust = \"worst\""]),
    "optimize: removed max_rate by --set":
        R("optimize", ["{ocp}", "--set", "ocp.max_rate=2.0"],
          ["--set", "[ocp] max_rate no longer exists", "max_rate_deg_s [deg/s]"]),
    "optimize: max_rate_deg_s = 0":
        R("optimize", ["{ocp}", "--set", "ocp.max_rate_deg_s=0"],
          ["ocp_max_speed.toml", "[ocp] max_rate_deg_s = 0", "in [0.01, 1e4]"]),
    "optimize: max_rate_deg_s = 1e-300":
        R("optimize", ["{ocp}", "--set", "ocp.max_rate_deg_s=1e-300"],
          ["[ocp] max_rate_deg_s = 1e-300", "cycle of the envelope takes hours"]),
    "optimize: regularization = 1e300":
        R("optimize", ["{ocp}", "--set", "ocp.regularization=1e300"],
          ["[ocp] regularization = 1e+300", "tie-breaker"]),
    "optimize: speed_min = 50 m/s":
        R("optimize", ["{ocp}", "--set", 'ocp.objective="min_cot"', "--set",
                       "ocp.speed_min=50"],
          ["[ocp] speed_min = 50", "in [0, 10]", "quasistatic crawler"]),
    "optimize: replay_tol = 0.5": R("optimize", ["{ocp}", "--set", "ocp.replay_tol=0.5"],
                                    ["[ocp] replay_tol = 0.5", "in [1e-9, 0.1]"]),
    "optimize: max_joint_rate_deg_s = 0": R(
        "optimize", ["{ocp}", "--set", "ocp.max_joint_rate_deg_s=0"],
        ["ocp_max_speed.toml", "[ocp] max_joint_rate_deg_s = 0", "in [0.01, 1e4]"]),
    "optimize: zero direction":
        R("optimize", ["{ocp}", "--set", "ocp.direction=0"],
          ["ocp_max_speed.toml", "[ocp] direction = 0 (from --set)", "-1 or 1"]),
    "optimize: bool for a string":
        R("optimize", ["{ocp}", "--set", "ocp.objective=robust_speed", "--set", "ocp.robust=true"],
          ["[ocp] robust = true", "expected a string"]),
    "optimize: mu_ratio_eps = 1":
        R("optimize", ["{ocp}", "--set", "ocp.objective=robust_speed", "--set",
                        "ocp.mu_ratio_eps=1"],
          ["[ocp] mu_ratio_eps = 1", "in [0, 0.5]", "another robot"]),
    "optimize: cannot stand (no_start)":
        R("optimize", ["{ocp}", "--set", SOFT],
          ["ocp_max_speed.toml", "k = 0.00306", "no equilibrium to start from"]),
    "optimize: --out under a file":
        R("optimize", ["{ocp}", "--out", "{blocker}/o"], ["--out", "blocker/o", "not writable"]),
    "optimize: --out holds results":
        R("optimize", ["{ocp}", "--out", "{tmp}"], ["--out", "torques.csv", "would overwrite"],
          files={"torques.csv": b"phase,tau1,tau2\n"}),
    # ------------------------------------------------------------------ dynamics
    "dynamics: a period of 0 s": R("dynamics", ["{paper}", "--periods", "0"],
                                   ["--periods 0", "(0, 10000]"]),
    "dynamics: too many periods": R("dynamics", ["{paper}", "--periods", *map(str, range(1, 14))],
                                    ["--periods", "13 periods given, at most 12"]),
    "dynamics: a chain": R("dynamics", ["{file}"], ["x.toml", "chain", "three-link robot only"],
                           text=CHAIN_TEXT),
    "dynamics: timestep 0": R("dynamics", ["{paper}", "--set", "simulation.timestep=0"],
                              ["[simulation] timestep = 0", "must be in [1e-6, 0.01]"]),
    "dynamics: the angles drive, paper gravity":
        R("dynamics", ["{paper}", "--set", 'gait.drive="angles"',
                       "--set", 'model.gravity="paper"'],
          ["solver = \"mujoco\"", "physical gravity only"]),
    "dynamics: missing file": R("dynamics", ["{missing}"], ["nope.toml", "cannot read"]),
    # ------------------------------------------------------------------ no command
    "no command": R(None, [], ["COMMAND", "required"]),
    "unknown command": R(None, ["crawl"], ["invalid choice: 'crawl'"]),
}

#: every key and option that sizes the work is bounded, and every bad input is one line (the rows
#: that used to hang or end as internal errors are guarded by HANG_GUARD_S)
COMMAND_ROWS.update({
    # ---- bounds on work
    "simulate: max_step 1e-300 (hung)":
        R("simulate", ["{file}"], ["x.toml", "[simulation] max_step = 1e-300",
                                   "in [1e-4, 0.25]", "continuation steps per cycle"],
          text=edit("max_step = 0.0625", "max_step = 1e-300")),
    "simulate: --set max_step 1e-300":
        R("simulate", ["{paper}", "--set", "simulation.max_step=1e-300"],
          ["[simulation] max_step = 1e-300 (from --set)", "in [1e-4, 0.25]"]),
    "simulate: --steps 1e9 (hung)":
        R("simulate", ["{paper}", "--solver", "mpcc", "--steps", "1000000000"],
          ["--steps 1000000000", "in [4, 10000]", "IPOPT solve"]),
    "simulate: steps 1e9 in the file":
        R("simulate", ["{file}"], ["x.toml", "[simulation] steps = 1000000000",
                                   "in [4, 10000]"],
          text=edit("steps = 200", "steps = 1000000000")),
    "simulate: k/(M g L) 1.6e13 (no_consistent_mode)":
        R("simulate", ["{paper}", "--set", "robot.k=1e12"],
          ["[robot] k = 1000000000000.0", "k/(M g L) = 1.63e+13",
           "exceeds 1e+10", "gait.drive"]),
    "sweep: L 1e-12 makes k/(M g L) 3.3e11":
        R("sweep", ["{paper}", "--grid", "robot.L=1e-12,2e-12", "--out", "{tmp}"],
         ["k/(M g L) = 3.29e+11", "exceeds 1e+10"]),
    "simulate: max_cycles 1e5": R("simulate", ["{paper}", "--set", "simulation.max_cycles=100000"],
                                  ["[simulation] max_cycles = 100000 (from --set)", "in [2, 500]"]),
    "simulate: event_xtol 0.5": R("simulate", ["{paper}", "--set", "simulation.event_xtol=0.5"],
                                  ["[simulation] event_xtol = 0.5 (from --set)", "in (0, 1e-6]"]),
    "simulate: /dev/zero (hung)":
        R("simulate", ["/dev/zero"], ["/dev/zero", "larger than 1048576 bytes (1 MiB)"]),
    "simulate: 2 MiB problem file":
        R("simulate", ["{file}"], ["x.toml", "larger than 1048576 bytes (1 MiB)"],
          text=PAPER_TEXT + ("# padding\n" * 220_000)),
    # ---- bad input that ended as an internal error or with more than one line
    "simulate: TOML nested 5000 deep (RecursionError)":
        R("simulate", ["{file}"], ["x.toml", "malformed TOML",
                                   "nested too deeply"],
          text=edit("k = 0.1677", "k = " + nested(5000))),
    "simulate: --set nested 5000 deep":
        R("simulate", ["{paper}", "--set", "robot.k=" + nested(5000)],
          ["--set \"robot.k=[[[[", "nested too deeply"]),
    "simulate: array nested 400 deep":
        R("simulate", ["{file}"], ["x.toml", "[robot] k = [[[[...]]]]",
                                   "expected a number"],
          text=edit("k = 0.1677", "k = " + nested(400))),
    "simulate: k = 1e308 (RuntimeWarnings)":
        R("simulate", ["{paper}", "--set", "robot.k=1e308"],
          ["[robot] k = 1e+308 (from --set)", "in [1e-12, 1e12]", "N m/rad"]),
    "simulate: M = 1e308 (blamed the gait)":
        R("simulate", ["{file}"], ["x.toml", "[robot] M = 1e+308",
                                   "in [1e-12, 1e12]", "kg"],
          text=edit("M = 0.052", "M = 1e308"), absent=["[gait]", "nan"]),
    "simulate: L = 1e-300": R("simulate", ["{paper}", "--set", "robot.L=1e-300"],
                              ["[robot] L = 1e-300 (from --set)", "in [1e-12, 1e12]"]),
    "simulate: g = 1e300": R("simulate", ["{paper}", "--set", "robot.g=1e300"],
                             ["[robot] g = 1e+300 (from --set)", "in [1e-12, 1e12]"]),
    "simulate: beta = 1e6":
        R("simulate", ["{paper}", "--set", "robot.beta=1e6"],
          ["[robot] beta = 1000000.0 (from --set)", "in [0.01, 100]", "degenerate"]),
    "simulate: frictionless mu = 0 (no_consistent_mode)":
        R("simulate", ["{file}"],
          ["x.toml", "[robot] mu = 0", "in [1e-4, 1e4]", "frictionless"],
          text=edit("mu = 0.389", "mu = 0")),
    "simulate: mu = 1e-300":
        R("simulate", ["{paper}", "--set", "robot.mu=1e-300"],
          ["[robot] mu = 1e-300 (from --set)", "in [1e-4, 1e4]", "frictionless"]),
    "simulate: one frictionless foot": R("simulate", ["{paper}", "--set", "robot.mu1=0"],
                                         ["[robot] mu1 = 0 (from --set)", "in [1e-4, 1e4]"]),
    "simulate: --out empty (exit 0, wrote nothing)":
        R("simulate", ["{paper}", "--out", ""], ["--out ''", "empty path"]),
    "demo: --out empty": R("demo", ["--out", ""], ["--out ''", "empty path"]),
    "demo: --out blank": R("demo", ["--out", "  "], ["--out '  '", "empty path"]),
    # ---- sweep
    "sweep: NUM 1e20 (ValueError)":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:180:99999999999999999999",
                    "--out", "{tmp}"],
          ["gait.psi_deg=0:180:99999999999999999999", "NUM = 99999999999999999999",
           "20000 points"]),
    "sweep: STOP inf (said nan)":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:inf:3", "--out", "{tmp}"],
          ["gait.psi_deg=0:inf:3", "must be finite", "STOP = inf"], absent=["nan"]),
    "sweep: START -inf":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=-inf:0:3", "--out", "{tmp}"],
          ["gait.psi_deg=-inf:0:3", "START = -inf"], absent=["nan"]),
    "sweep: inf in a list":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=0,inf", "--out", "{tmp}"],
          ["gait.psi_deg=0,inf", "gait.psi_deg = inf must be finite"], absent=["nan"]),
    "sweep: 1e6 points (hung)":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:180:1000", "--grid",
                    "gait.gamma_deg=60:120:1000", "--out", "{tmp}"],
          ["1000000 points", "1000 (gait.psi_deg) x 1000 (gait.gamma_deg)", "20000 points"]),
    "sweep: list nested 5000 deep":
        R("sweep", ["{paper}", "--grid", "robot.k=" + nested(5000), "--out", "{tmp}"],
          ["--grid 'robot.k=[[[[", "nested too deeply"]),
    "sweep: k = 1e308 on the grid":
        R("sweep", ["{paper}", "--grid", "robot.k=0.1,1e308", "--out", "{tmp}"],
          ["robot.k=0.1,1e308", "robot.k = 1e+308", "in [1e-12, 1e12]"]),
    "sweep: frictionless on the grid":
        R("sweep", ["{paper}", "--grid", "robot.mu=0,0.4", "--out", "{tmp}"],
          ["robot.mu=0,0.4", "robot.mu = 0", "in [1e-4, 1e4]"]),
    "sweep: --jobs 1e5":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--jobs", "100000", "--out", "{tmp}"],
          ["--jobs 100000", "in [1, 256]"]),
    "sweep: --out empty":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=45", "--out", ""],
          ["--out ''", "empty path"]),
    "reproduce: --out empty": R("reproduce", ["--out", ""], ["--out ''", "empty path"]),
    "reproduce: --jobs 1e5":
        R("reproduce", ["--jobs", "100000", "--out", "{tmp}"], ["--jobs 100000", "in [1, 256]"]),
    # ---- animate
    "animate: --cycles 1e9 (MemoryError)":
        R("animate", ["{paper}", "--cycles", "1000000000", "--out", "{tmp}/a.gif"],
          ["--cycles 1000000000", "in [1, 10]", "memory"]),
    "animate: --frames-per-cycle 1e9 (MemoryError)":
        R("animate", ["{paper}", "--frames-per-cycle", "1000000000",
                      "--out", "{tmp}/a.gif"],
          ["--frames-per-cycle 1000000000", "in [2, 100]", "memory"]),
    "animate: --out x.gif/ (wrote x.gif)": R("animate", ["{paper}", "--out", "{tmp}/x.gif/"],
                                             ["--out", "x.gif/", "names a directory", ".gif"]),
    "animate: --out empty": R("animate", ["{paper}", "--out", ""], ["--out ''", "empty path"]),
    "animate: /dev/zero":
        R("animate", ["/dev/zero", "--out", "{tmp}/a.gif"], ["/dev/zero", "1 MiB"]),
    # ---- crosscheck
    "crosscheck: --steps 1e9": R("crosscheck", ["{paper}", "--steps", "50", "1000000000"],
                                 ["--steps 1000000000", "in [4, 10000]"]),
    "crosscheck: nine step counts":
        R("crosscheck", ["{paper}", "--steps", *map(str, range(10, 100, 10))],
          ["--steps 10 20 30 40 50 60 70 80 90", "at most 8"]),
    "crosscheck: mu = 0": R("crosscheck", ["{paper}", "--set", "robot.mu=0"],
                            ["paper_gait.toml", "[robot] mu = 0 (from --set)", "frictionless"]),
    # ---- optimize
    "optimize: nodes 1e5 (hung)":
        R("optimize", ["{ocp}", "--set", "ocp.nodes=100000"],
          ["ocp_max_speed.toml", "[ocp] nodes = 100000 (from --set)", "in [8, 1000]"]),
    "optimize: harmonic_psi 1e5 (hung)":
        R("optimize", ["{file}"], ["x.toml", "[ocp] harmonic_psi = 100000",
                                   "in [4, 180]"],
          text=ocp_edit("nodes = 50", "nodes = 50\nharmonic_psi = 100000")),
    "optimize: fourier_order 1e5 (hung)":
        R("optimize", ["{ocp}", "--set", "ocp.parametrization=fourier", "--set",
                       "ocp.fourier_order=100000"],
          ["[ocp] fourier_order = 100000 (from --set)", "in [1, 25]"]),
    "optimize: --out empty": R("optimize", ["{ocp}", "--out", ""], ["--out ''", "empty path"]),
    "optimize: k = 1e308": R("optimize", ["{ocp}", "--set", "robot.k=1e308"],
                             ["[robot] k = 1e+308 (from --set)", "in [1e-12, 1e12]"]),
    # ---- init
    "init: a problem file exists (no --force)":
        R("init", ["{tmp}"], ["{tmp}/problems/unequal_friction.toml", "exists",
                               "--force", "nothing was written"],
          files={"problems/unequal_friction.toml": b"# mine\n"}),
    "init: DIR is a regular file": R("init", ["{blocker}"], ["DIR {blocker}", "not a directory"]),
    "init: DIR/problems is a regular file":
        R("init", ["{tmp}"], ["{tmp}/problems", "not a directory"],
          files={"problems": b"a file\n"}),
    "init: DIR empty": R("init", [""], ["DIR ''", "empty path"]),
    "init: DIR not writable": R("init", ["{readonly}"], ["DIR {readonly}", "Permission denied"],
                                needs_permissions=True),
    "init: two directories": R("init", ["{tmp}", "{dir}"], ["unrecognized arguments", "{dir}"]),
})

#: found by fuzzing the command line: each was an internal error, a hang or a silent choice
COMMAND_ROWS.update({
    "sweep: an array key as an axis (KeyError)":
        R("sweep", ["{paper}", "--grid", "gait.phase=0,0.5", "--out",
                   "{tmp}/s"], ["gait.phase", "array key"]),
    "sweep: range ends overflow (said nan)":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=1e308:-1e308:3", "--out",
                   "{tmp}/s"], ["STOP - START", "overflows"], absent=["nan"]),
    "sweep: unknown scheduler scheme (ValueError)":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=0,1",
                   "--scheduler", "bogus://x", "--out", "{tmp}/s"],
          ["--scheduler bogus://x", "unknown address scheme"]),
    "sweep: --grid and --set of one key":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:90:3", "--set",
                   "gait.psi_deg=10", "--out", "{tmp}/s"],
          ["--grid gait.psi_deg=0.0 undoes --set gait.psi_deg=10"]),
    "sweep: --grid robot.mu drops --set robot.mu1":
        R("sweep", ["{paper}", "--set", "robot.mu1=0.3", "--set",
                   "robot.mu2=0.4", "--grid", "robot.mu=0.2,0.4", "--out",
                   "{tmp}/s"],
          ["--grid robot.mu=0.2 undoes --set robot.mu1=0.3",
           "or sweep robot.mu1"]),
    "animate: --fps below a GIF's slowest frame (OverflowError)":
        R("animate", ["{paper}", "--out", "{tmp}/a.gif",
                     "--fps", "0.001"],
         ["--fps 0.001", "[0.01, 100]"]),
    "simulate: --drive and --set gait.drive":
        R("simulate", ["{paper}", "--set", "gait.drive=angles", "--drive",
                      "torque"],
          ["--drive torque", "--set gait.drive=angles", "give one"]),
    "simulate: --solver and --set simulation.solver":
        R("simulate", ["{paper}", "--solver", "mpcc", "--set",
                      "simulation.solver=event"],
          ["--solver mpcc", "--set simulation.solver=event", "give one"]),
    "simulate: --steps with the event solver": R("simulate", ["{paper}", "--steps", "50"],
                                                 ["--steps 50", 'solver "event"', "--solver mpcc"]),
    "simulate: --force without --out":
        R("simulate", ["{paper}", "--force"], ["--force without --out"]),
    "optimize: --force without --out":
        R("optimize", ["{ocp}", "--force"], ["--force without --out"]),
    "optimize: speed_min with max_speed (ignored)":
        R("optimize", ["{ocp}", "--set", "ocp.speed_min=0.1"],
          ["[ocp] speed_min = 0.1 (from --set)", 'objective = "max:speed"',
           'objective = "min_cot"']),
    "optimize: robust without a friction set":
        R("optimize", ["{file}"],
            ["x.toml", '[ocp] robust = "worst"', "mu_ratio_eps > 0",
             'objective = "robust_speed"'],
            text=ocp_edit("mu_ratio_eps = 0.05", "mu_ratio_eps = 0.0")),
    "optimize: a constraint on an unknown quantity": R(
        "optimize", ["{file}"],
        ["x.toml", "[ocp] constraint", "unknown quantity 'torque'", "peak_torque"],
        text=OCP_TEXT + '\n[[ocp.constraint]]\nquantity = "torque"\nmax = 0.3\n'),
    "optimize: a lower bound on the peak torque": R(
        "optimize", ["{file}"],
        ["x.toml", "[ocp] constraint", "min bound is not available", "upper"],
        text=OCP_TEXT + '\n[[ocp.constraint]]\nquantity = "peak_torque"\nmin = 0.3\n'),
    "optimize: a constraint with min above max": R(
        "optimize", ["{file}"], ["x.toml", "[ocp] constraint", "min 0.05 > max 0.04"],
        text=OCP_TEXT + '\n[[ocp.constraint]]\nquantity = "speed"\nmin = 0.05\nmax = 0.04\n'),
    "optimize: a constraint without a bound": R(
        "optimize", ["{file}"], ["x.toml", "[ocp] constraint", "neither min nor max"],
        text=OCP_TEXT + '\n[[ocp.constraint]]\nquantity = "speed"\n'),
    "optimize: a constraint with an unknown key": R(
        "optimize", ["{file}"],
        ["x.toml", "[ocp] constraint", "keys quantity (required), min, max, over"],
        text=OCP_TEXT + '\n[[ocp.constraint]]\nquantity = "speed"\nmaximum = 0.1\n'),
    "optimize: a constraint that is not a table": R(
        "optimize", ["{ocp}", "--set", "ocp.constraint=0.3"],
        ["[ocp] constraint = 0.3 (from --set)", "an array of tables"]),
    "optimize: a friction level of zero": R(
        "optimize", ["{ocp}", "--set", "ocp.mu_levels=[1.0, 0.0]"],
        ["[ocp] mu_levels", "entry 1 = 0.0", "in [0.001, 10]"]),
    "optimize: an unknown IPOPT option in [ocp.ipopt]": R(
        "optimize", ["{file}"], ["x.toml", "[ocp.ipopt]", "No such IPOPT option: max_itr"],
        text=OCP_TEXT + '\n[ocp.ipopt]\nmax_itr = 3\n'),
    "optimize: an objective not in the vocabulary": R(
        "optimize", ["{ocp}", "--set", 'ocp.objective="min:peak_torque"'],
        ["[ocp] objective = \"min:peak_torque\" (from --set)", '"min:W_plus"', '"min:sum"']),
    "optimize: [ocp.terms] with another objective": R(
        "optimize", ["{file}"], ["x.toml", "[ocp] terms", 'objective = "max:speed"'],
        text=OCP_TEXT + '\n[ocp.terms]\nW_plus = 1.0\n'),
    "optimize: min:sum without [ocp.terms]": R(
        "optimize", ["{ocp}", "--set", 'ocp.objective="min:sum"'],
        ["[ocp] terms is missing", 'objective = "min:sum"', "quantity = weight"]),
    "optimize: a weight that is not a number": R(
        "optimize", ["{ocp}", "--set", 'ocp.objective="min:sum"', "--set",
                     "ocp.terms={W_plus = true}"],
        ["[ocp] terms = {W_plus = true} (from --set)", "the weight of W_plus is a boolean (true)"]),
    "optimize: the peak torque as a term": R(
        "optimize", ["{file}"], ["x.toml", "[ocp] terms", "'peak_torque' cannot be a term",
                                 "[[ocp.constraint]]"],
        text=ocp_edit('objective = "max:speed"', 'objective = "min:sum"')
        + '\n[ocp.terms]\npeak_torque = 1.0\n'),
    "optimize: a negative weight of W+": R(
        "optimize", ["{file}"], ["x.toml", "[ocp] terms", "weight of W_plus must be positive"],
        text=ocp_edit('objective = "max:speed"', 'objective = "min:sum"')
        + '\n[ocp.terms]\nW_plus = -1.0\n'),
    "optimize: the worst of a vocabulary objective": R(
        "optimize",
        ["{ocp}", "--set", 'ocp.objective="min:W_plus"', "--set", "ocp.mu_ratio_eps=0.05",
         "--set", 'ocp.robust="worst"'],
        ["[ocp] robust", "min:W_plus", "max:speed and min:CoT_plus"]),
    "optimize: [ocp.ipopt] not a table": R(
        "optimize", ["{ocp}", "--set", "ocp.ipopt=3"], ["[ocp] ipopt = 3 (from --set)", "a table"]),
    "optimize: --start without a period":
        R("optimize", ["{ocp}", "--start", "{paper}"],
          ["--start", "paper_gait.toml", "[gait] period", "optimal_gait.toml"]),
    "optimize: --start with several --nodes":
        R("optimize", ["{ocp}", "--start", "{ocp}", "--nodes", "20", "40"],
          ["--start with --nodes 20 40", "one N"]),
    "optimize: --verbose with --json": R("optimize", ["{ocp}", "--verbose", "--json"],
                                         ["--verbose with --json", "output_file"]),
    "optimize: a friction level below mu's bound": R(
        "optimize", ["{ocp}", "--set", "robot.mu=0.05", "--set", "ocp.mu_levels=[1.0, 0.001]"],
        ["ocp_max_speed.toml", "friction scenario", "mu1 must be >= 0.0001"]),
    "optimize: the angles drive (torques optimised anyway)":
        R("optimize", ["{ocp}", "--set", "gait.drive=angles"],
          ["ocp_max_speed.toml", "needs [gait] drive", '"angles"']),
    "crosscheck: decreasing --steps": R("crosscheck", ["{paper}", "--steps", "40", "20"],
                                        ["--steps 40 20", "increasing strictly"]),
})

#: found by a second round of fuzzing
_BIG_INT = "1" + "0" * 5000
COMMAND_ROWS.update({
    "simulate: an integer of 5001 digits (ValueError)":
        R("simulate", ["{paper}", "--set", f"robot.k={_BIG_INT}"],
          ["robot.k=", "more than 4300 digits"]),
    "simulate: a key set twice (the last won)":
        R("simulate", ["{paper}", "--set", "robot.k=0.2", "--set",
                      "robot.k=0.3"],
          ["robot.k is set twice, to 0.2 and to 0.3"]),
    "simulate: a key set before another waveform (dropped)":
        R("simulate", ["{paper}", "--set", "gait.psi_deg=10",
                      "--set", "gait.waveform=fourier"],
          ["[gait] psi_deg = 10", 'waveform = "fourier"']),
    "simulate: mu1 and mu2 then mu (dropped)":
        R("simulate", ["{paper}", "--set", "robot.mu1=0.2", "--set",
                      "robot.mu2=0.3", "--set", "robot.mu=0.5"],
          ["robot.mu = 0.5 drops robot.mu1 = 0.2"]),
    "simulate: a Fourier coefficient of 1e9 deg (ValueError)":
        R("simulate", ["{paper}", "--drive", "angles", "--set",
                      "gait.waveform=fourier", "--set",
                      "gait.sin1_deg=[1e9]"],
          ["sin1_deg", "[-360, 360]"]),
    "animate: --cycles in Arabic-Indic digits":
        R("animate", ["{paper}", "--cycles", "\u0663", "--out", "{tmp}/a.gif"],
          ["--cycles", "must be an integer"]),
    "animate: --out a directory named like the GIF":
        R("animate", ["{paper}", "--out", "{tmp}/d.gif", "--force"],
          ["d.gif is a directory"], files={"d.gif/keep": b""}),
    "animate: --out a name of 300 bytes":
        R("animate", ["{paper}", "--out", "{tmp}/" + "a" * 300 + ".gif"],
          ["longer than"]),
    "simulate: --out holding a directory named summary.json":
        R("simulate", ["{paper}", "--out", "{tmp}/o", "--force"],
          ["summary.json is a directory"],
          files={"o/summary.json/keep": b""}),
    "init: a directory where a shipped file goes": R("init", ["{tmp}", "--force"],
                                                     ["paper_gait.toml", "is a directory"],
                                                     files={"problems/paper_gait.toml/keep": b""}),
    "optimize: --nodes and --set ocp.nodes":
        R("optimize", ["{ocp}", "--nodes", "8", "--set", "ocp.nodes=9"],
          ["--nodes 8 and --set ocp.nodes"]),
    "sweep: an [ocp] axis (rows all the same)":
        R("sweep", ["{paper}", "--grid", "ocp.nodes=8,9", "--out", "{tmp}/s"],
          ["--grid ocp.nodes", "optimize only"]),
    "sweep: a gait.period axis (rows all the same)":
        R("sweep", ["{paper}", "--grid", "gait.period=1,2", "--out",
                  "{tmp}/s"], ["--grid gait.period", "does not change"]),
    "sweep: a [pressure] axis of a harmonic gait":
        R("sweep", ["{paper}", "--grid", "pressure.a1=0.1,0.2", "--out",
                   "{tmp}/s"],
          ["--grid pressure.a1", 'waveform = "pressure"']),
    "sweep: simulation.steps with the event solver":
        R("sweep", ["{paper}", "--grid", "simulation.steps=10,20",
                   "--out", "{tmp}/s"],
          ["simulation.steps", "solver event does not read"]),
    "sweep: NUM in Arabic-Indic digits":
        R("sweep", ["{paper}", "--grid", "gait.psi_deg=0:90:\u0663", "--out",
                   "{tmp}/s"], ["NUM must be an integer"]),
})

#: requests whose every count is in range but whose product is hours: refused before they start,
#: naming the settings that size them and --max-hours (ocp_crawl.problem.work)
COMMAND_ROWS.update({
    "simulate: MPCC steps x cycles, hours":
        R("simulate", ["{paper}", "--solver", "mpcc", "--steps", "10000",
                      "--set", "simulation.max_cycles=500", "--set",
                      "simulation.periodic_tol=1e-300"],
          ["estimated about", "up to", "MPCC 10000 steps x 500 cycles",
           "above the limit of 2 h", "simulation.steps",
           "simulation.max_cycles", "--max-hours"]),
    "simulate: event solver under a small --max-hours":
        R("simulate", ["{paper}", "--set",
                       "simulation.max_step=1e-4", "--max-hours",
                       "0.001"],
          ["above the limit of 4 s", "simulation.max_step"]),
    "animate: MPCC steps x cycles, hours":
        R("animate", ["{paper}", "--set", "simulation.solver=mpcc",
                     "--set", "simulation.steps=10000", "--set",
                     "simulation.max_cycles=300", "--out",
                     "{tmp}/a.gif"],
         ["estimated about", "2 x (MPCC 10000 steps x 300 cycles",
          "simulation.steps", "--max-hours"]),
    "simulate: --max-hours 0": R("simulate", ["{paper}", "--max-hours", "0"],
                                 ["--max-hours 0", "(0, 10000]"]),
    "crosscheck: steps x cycles, hours":
        R("crosscheck", ["{paper}", "--steps", "5000", "10000", "--set",
                         "simulation.max_cycles=100"],
          ["estimated about", "MPCC at steps 5000 10000", "--steps",
           "simulation.max_cycles"]),
    "sweep: points x MPCC steps, hours":
        R("sweep", ["{paper}", "--grid", "simulation.solver=event,mpcc",
                    "--grid", "gait.psi_deg=0:180:500", "--grid",
                    "simulation.steps=1000,2000", "--jobs", "2", "--out",
                    "{tmp}/s"],
          ["2000 points / 2 workers", "simulation.steps", "--grid"]),
    "optimize: nodes x counts over --max-hours": R("optimize", ["{ocp}", "--nodes", "200", "400",
                                                                "--max-hours", "0.1"],
                                                   ["N = 200+400", "ocp.nodes", "--nodes",
                                                    "above the limit of 6 min"]),
    "codesign: designs x rounds over --max-hours":
        R("codesign", ["{file}", "--set", "design.scan=64", "--set", "design.search_rounds=12",
                       "--max-hours", "0.1"],
          ["64 designs", "design.scan", "design.search_rounds", "above the limit of 6 min"],
          text=DESIGN_TEXT),
    "dynamics: periods x timestep over --max-hours":
        R("dynamics", ["{paper}", "--periods", "50", "100",
                       "--set", "simulation.timestep=1e-4",
                       "--max-hours", "0.1"],
          ["MuJoCo at T = 50 + 100 s", "simulation.timestep",
           "--periods"]),
})

#: found by the review of the second round
COMMAND_ROWS.update({
    "sweep: --set gait.waveform with a waveform axis":
        R("sweep", ["{paper}", "--set", "gait.waveform=fourier",
                   "--grid", "gait.waveform=harmonic,fourier", "--out",
                   "{tmp}/s"],
          ["--set gait.waveform=fourier", "drop the --set"]),
    "sweep: --set robot.mu1 equal to L, then a mu axis":
        R("sweep", ["{paper}", "--set", "robot.mu1=0.12", "--set",
                   "robot.mu2=0.4", "--grid", "robot.mu=0.3,0.4",
                   "--out", "{tmp}/s"],
          ["undoes --set robot.mu1=0.12"]),
})
