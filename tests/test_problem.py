"""Problem files: loading, schema, overrides and one-line errors for bad input."""
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ocp_crawl.sim.event import HybridOptions
from ocp_crawl.problem import (PAPER_GAIT, SECTIONS, Problem, ProblemError, load_problem,
                               paper_problem,
                               parse_override, problem_from_dict, run_problem, schema_markdown)
from ocp_crawl.sim.result import Status

REPO = Path(__file__).resolve().parent.parent
PROBLEMS = REPO / "problems"


def paper_dict(**changes):
    """The paper problem as a plain dict, with ``section__key=value`` changes (None deletes the
    key)."""
    data = {s: dict(v) for s, v in PAPER_GAIT.items()}
    for name, value in changes.items():
        section, key = name.split("__")
        if value is None:
            data[section].pop(key, None)
        else:
            data.setdefault(section, {})[key] = value
    return data


def test_paper_gait_file_matches_table_one():
    p = load_problem(PROBLEMS / "paper_gait.toml")
    r = p.robot
    assert (r.M, r.L, r.beta, r.k, r.mu1, r.mu2, r.g) == (0.052, 0.120, 2.0, 0.1677, 0.389, 0.389,
                                                          9.81)
    assert p.drive == "torque" and p.gravity == "physical"
    assert p.gait.gamma1 == pytest.approx(math.pi / 2, rel=0, abs=1e-15)
    assert p.gait.A2 == pytest.approx(math.pi / 6, rel=0, abs=1e-15)
    assert p.gait.psi == pytest.approx(math.pi / 4, rel=0, abs=1e-15)
    assert p.hybrid == HybridOptions()
    # the degree values are kept as given, for reporting
    assert p.sections["gait"]["gamma_deg"] == 90.0
    # the problem built in code for the demo is the same problem
    assert p == paper_problem()


def test_other_problem_files():
    p = load_problem(PROBLEMS / "paper_gait_paper_gravity.toml")
    assert p.gravity == "paper" and p.robot == paper_problem().robot
    q = load_problem(PROBLEMS / "unequal_friction.toml")
    assert (q.robot.mu1, q.robot.mu2) == (0.35, 0.43)


def test_every_problem_file_has_a_unit_comment_on_every_key():
    for path in PROBLEMS.glob("*.toml"):
        for line in path.read_text().splitlines():
            if "=" in line and not line.lstrip().startswith("#"):
                assert ("#" in line
                        and "[" in line.split("#", 1)[1]), f"{path.name}: no unit on {line!r}"


def test_defaults_and_ints_for_floats():
    data = paper_dict(robot__beta=None, robot__g=None, robot__M=1, gait__drive=None)
    p = problem_from_dict(data)
    assert p.robot.beta == 2.0 and p.robot.g == 9.81 and p.drive == "torque"
    assert isinstance(p.robot.M, float) and p.robot.M == 1.0


def test_per_joint_gait_keys():
    data = paper_dict(gait__gamma_deg=None, gait__gamma1_deg=95.0, gait__gamma2_deg=85.0,
                      gait__A1_deg=25.0)
    p = problem_from_dict(data)
    assert p.gait.gamma1 == pytest.approx(math.radians(95), rel=1e-15)
    assert p.gait.gamma2 == pytest.approx(math.radians(85), rel=1e-15)
    assert p.gait.A1 == pytest.approx(math.radians(25), rel=1e-15)
    assert p.gait.A2 == pytest.approx(math.radians(30), rel=1e-15)


def test_overrides():
    p = load_problem(PROBLEMS / "paper_gait.toml",
                     ["robot.k=0.05", 'gait.drive="angles"', "model.gravity=paper",
                      "simulation.max_cycles=5"])
    assert (p.robot.k == 0.05 and p.drive == "angles" and p.gravity == "paper"
            and p.hybrid.max_cycles == 5)
    # setting mu replaces mu1/mu2 given in the file, and the other way round
    q = load_problem(PROBLEMS / "unequal_friction.toml", ["robot.mu=0.5"])
    assert (q.robot.mu1, q.robot.mu2) == (0.5, 0.5)
    q = load_problem(PROBLEMS / "paper_gait.toml", ["robot.mu1=0.3", "robot.mu2=0.4"])
    assert (q.robot.mu1, q.robot.mu2) == (0.3, 0.4)
    # a key --set twice to different values is a conflict (before, the last one won silently); twice
    # the same is fine
    with pytest.raises(ProblemError, match=r"robot.k is set twice, to 1 and to 2"):
        load_problem(PROBLEMS / "paper_gait.toml", ["robot.k=1", "robot.k=2"])
    assert load_problem(PROBLEMS / "paper_gait.toml", ["robot.k=2", "robot.k=2"]).robot.k == 2.0


@pytest.mark.parametrize("text, expected", [
    ("robot.k=0.05", ("robot", "k", 0.05)),
    ("robot.k = 5", ("robot", "k", 5)),
    ('gait.drive="angles"', ("gait", "drive", "angles")),
    ("gait.drive=angles", ("gait", "drive", "angles")),
    ("simulation.max_cycles=8", ("simulation", "max_cycles", 8)),
])
def test_parse_override(text, expected):
    assert parse_override(text) == expected


def test_to_dict_round_trip():
    p = load_problem(PROBLEMS / "unequal_friction.toml", ["gait.A1_deg=20"])
    d = p.to_dict()
    assert (d["robot"]["mu1"] == 0.35 and d["gait"]["A1_deg"] == 20.0
            and d["simulation"]["max_cycles"] == 12)
    assert problem_from_dict(d) == p
    # a Problem built in code reports its objects
    bare = problem_from_dict(Problem(robot=p.robot, gait=p.gait).to_dict())
    assert bare.robot == p.robot
    for name in ("gamma1", "gamma2", "A1", "A2", "psi"):
        assert getattr(bare.gait, name) == pytest.approx(getattr(p.gait, name), rel=1e-15)


def test_problem_is_frozen_and_validated():
    p = paper_problem()
    with pytest.raises(AttributeError):
        p.drive = "angles"
    with pytest.raises(TypeError):
        p.sections["robot"]["k"] = 1.0
    with pytest.raises(ValueError, match="drive"):
        Problem(robot=p.robot, gait=p.gait, drive="walk")
    with pytest.raises(TypeError, match="robot"):
        Problem(robot={"M": 1}, gait=p.gait)


def test_schema_is_one_table_with_units():
    assert [s.name for s in SECTIONS][:4] == ["robot", "gait", "model", "simulation"]
    for section in SECTIONS:
        for key in section.keys:
            assert key.unit and key.help
    table = schema_markdown()
    assert ("`robot.k` | float | N m/rad | required unless `lengths` and `masses` and `stiffness` "
            "given | in [1e-12, 1e12] (so that M g L") in table
    # the documentation shows this table through its generated reference page, and the guide links
    # to it
    guide = (REPO / "docs" / "guide" / "problem_files.md").read_text(encoding="utf-8")
    assert "](../reference/problem_files.md)" in guide


# ------------------------------------------------------------------------------------------ errors
BAD = [
    # (changes to the paper problem, words the one-line message must contain)
    (dict(robot__k=-1.0), ["[robot] k = -1.0", "in [1e-12, 1e12]", "N m/rad"]),
    (dict(robot__M=0), ["[robot] M = 0", "in [1e-12, 1e12]", "kg"]),
    (dict(robot__L=True), ["[robot] L = true", "number", "boolean"]),
    (dict(robot__beta=math.nan), ["[robot] beta = nan", "finite"]),
    (dict(robot__g=math.inf), ["[robot] g = inf", "finite"]),
    (dict(robot__mu=-0.1), ["[robot] mu = -0.1", "in [1e-4, 1e4]"]),
    (dict(robot__mu1=0.3), ["mu = 0.389", "mu1 = 0.3", "mutually exclusive"]),
    (dict(robot__mu=None, robot__mu1=0.3), ["[robot] mu1 = 0.3", "without mu2"]),
    (dict(robot__k=None), ["[robot] k is missing", "required"]),
    (dict(robot__kk=0.2), ["[robot] unknown key kk = 0.2", "did you mean k?"]),
    (dict(gait__drive="walk"), ['[gait] drive = "walk"', '"torque", "angles"']),
    (dict(gait__A_deg=-5), ["[gait] A_deg = -5", ">= 0"]),
    (dict(gait__psi_deg="45"), ['[gait] psi_deg = "45"', "number", "string"]),
    (dict(model__gravity="real"), ['[model] gravity = "real"', '"physical", "paper"']),
    (dict(simulation__max_cycles=2.5), ["[simulation] max_cycles = 2.5", "integer"]),
    (dict(simulation__max_step=1.0), ["[simulation] max_step = 1.0", "in [1e-4, 0.25]"]),
    (dict(gait__gamma_deg=30.0), ["[gait] gamma_deg = 30.0", "foot 1 off the ground"]),
    (dict(gait__drive="angles", gait__A_deg=75.0),
     ["A_deg = 75.0", "angles drive", "below the ground"]),
]


@pytest.mark.parametrize("changes, words", BAD,
                         ids=[next(iter(c)) + "=" + repr(next(iter(c.values()))) for c, _ in BAD])
def test_bad_values_raise_one_line_problem_error(changes, words):
    with pytest.raises(ProblemError) as info:
        problem_from_dict(paper_dict(**changes), source="problems/x.toml")
    msg = str(info.value)
    assert "\n" not in msg
    assert msg.startswith("problems/x.toml: ")
    for w in words:
        assert w in msg, (w, msg)
    assert isinstance(info.value, ValueError)


def test_unknown_and_missing_sections():
    with pytest.raises(ProblemError, match=r"unknown section \[robto\].*did you mean robot\?"):
        problem_from_dict({"robto": {}, **paper_dict()}, source="f.toml")
    data = paper_dict()
    del data["gait"]
    with pytest.raises(ProblemError, match=r"^f.toml: section \[gait\] is missing"):
        problem_from_dict(data, source="f.toml")
    with pytest.raises(ProblemError, match=r"top-level key k = 1 is not in a section"):
        problem_from_dict({"k": 1, **paper_dict()}, source="f.toml")


def test_file_errors(tmp_path):
    with pytest.raises(ProblemError,
                       match=r"nope.toml: cannot read the problem file: No such file"):
        load_problem(tmp_path / "nope.toml")
    with pytest.raises(ProblemError, match=r"cannot read the problem file"):
        load_problem(tmp_path)
    bad = tmp_path / "bad.toml"
    bad.write_text("[robot]\nM = 0.052\nk 0.1\n")
    with pytest.raises(ProblemError, match=r"bad.toml: malformed TOML: .*line 3.*\"k 0.1\"$"):
        load_problem(bad)
    bad.write_bytes(b"\xff\xfe[robot]")
    with pytest.raises(ProblemError, match="not UTF-8"):
        load_problem(bad)


@pytest.mark.parametrize("text, match", [
    ("robot.k", "expected SECTION.KEY=VALUE"),
    ("robot.k=", "one TOML value"),
    ("k=1", "must be SECTION.KEY"),
    ("robot.kk=1", "unknown key kk in \\[robot\\]; did you mean k\\?"),
    ("robo.k=1", "unknown section \\[robo\\]; did you mean robot\\?"),
    ("robot.k=abc", '"abc" is not a TOML value; expected a number'),
    ("robot.k=1\nrobot.M=2", "one TOML value"),
])
def test_bad_overrides(text, match):
    with pytest.raises(ProblemError, match=match) as info:
        load_problem(PROBLEMS / "paper_gait.toml", [text])
    assert "\n" not in str(info.value) and "paper_gait.toml" in str(info.value)


def test_override_values_are_validated_and_marked():
    with pytest.raises(ProblemError,
                       match=r"\[robot\] k = -1 \(from --set\) is invalid: must be in \[1e-12, "
                             r"1e12\]"):
        load_problem(PROBLEMS / "paper_gait.toml", ["robot.k=-1"])


@settings(max_examples=25, deadline=None)
@given(M=st.floats(1e-3, 10), L=st.floats(1e-2, 2), k=st.floats(1e-3, 10), mu=st.floats(1e-4, 2),
       beta=st.floats(1.5, 4), psi=st.floats(-180, 180))
def test_valid_values_load_and_round_trip(M, L, k, mu, beta, psi):
    data = paper_dict(robot__M=M, robot__L=L, robot__k=k, robot__mu=mu, robot__beta=beta,
                      gait__psi_deg=psi, gait__A_deg=10.0)
    p = problem_from_dict(data)
    assert (p.robot.M, p.robot.L, p.robot.k, p.robot.mu1, p.robot.beta) == (M, L, k, mu, beta)
    assert problem_from_dict(tomllib.loads(_to_toml(p.to_dict()))) == p


def _to_toml(d: dict) -> str:
    def val(v):
        return f'"{v}"' if isinstance(v, str) else repr(v)
    return "\n".join(f"[{s}]\n" + "\n".join(f"{k} = {val(v)}" for k, v in keys.items())
                     for s, keys in d.items())


# ------------------------------------------------------------------------------------------ running
def test_run_problem_dispatches_on_the_drive():
    torque = run_problem(paper_problem())
    angles = run_problem(paper_problem(["gait.drive=angles"]))
    assert torque.success and angles.success
    assert torque.drive == "torque" and angles.drive == "angles"
    # the two drives agree closely on the paper's gait (the springs track the reference well)
    assert torque.S == pytest.approx(angles.S, rel=0.01)
    assert torque.S < 0


def test_run_problem_reports_numerical_failure_as_status():
    res = run_problem(paper_problem(["robot.k=0.612", "gait.A_deg=60"]))
    assert not res.success and res.status == Status.LIFT_OFF


def test_run_problem_t_eval():
    res = run_problem(paper_problem(), t_eval=np.linspace(0, 1, 11))
    assert res.success and res.t.shape == (11,)
    with pytest.raises(TypeError, match="Problem"):
        run_problem({"robot": {}})


def test_status_guide_links_the_generated_table_and_names_real_statuses():
    """The status table is generated from STATUS_MESSAGES (docs/reference/statuses.md); the guide
    links to it, and every status its groups name (in backticks) is a status, in its group's range
    of codes."""
    import re

    from ocp_crawl.status import STATUS_MESSAGES

    text = (REPO / "docs" / "guide" / "statuses.md").read_text(encoding="utf-8")
    assert "](../reference/statuses.md)" in text
    codes = {status.name.lower(): int(status) for status in STATUS_MESSAGES}
    section = text.split("## Statuses", 1)[1].split("\n## ", 1)[0]
    groups = re.findall(r"^- ([0-9 ,and-]+): (.*?)(?=^- |^\S|\Z)", section, re.M | re.S)
    assert len(groups) == 4, groups
    for ranges, words in groups:
        allowed = set()
        for part in re.split(r",| and ", ranges):
            low, _, high = part.strip().partition("-")
            allowed |= set(range(int(low), int(high or low) + 1))
        named = re.findall(r"`([a-z_]+)`", words)
        assert named, ranges
        for name in named:
            assert name in codes and codes[name] in allowed, (ranges, name)


@pytest.mark.parametrize("gait, A_max", [
    ({"gamma_deg": 90.0}, 30.0),  # 60 to 120 deg: valid
    # mean 130: 85 to 175, valid
    ({"gamma_deg": 90.0, "gamma1_deg": 120.0, "gamma2_deg": 140.0}, 45.0),
    ({"gamma_deg": 150.0}, 40.0),  # 110 to 190 deg
    ({"gamma_deg": 60.0}, 70.0),  # -10 to 130 deg (the schema alone accepts both values)
    ({"gamma_deg": 90.0, "gamma1_deg": 120.0, "gamma2_deg": 160.0}, 45.0),  # mean 140: 95 to 185
])
def test_ocp_envelope_must_lie_in_0_180(gait, A_max):
    from ocp_crawl.problem import ocp_settings

    data = paper_dict(ocp__A_max_deg=A_max, **{f"gait__{k}": v for k, v in gait.items()})
    problem = problem_from_dict(data, source="p.toml")
    gamma = (gait.get("gamma1_deg", gait["gamma_deg"])
             + gait.get("gamma2_deg", gait["gamma_deg"])) / 2
    if 0 < gamma - A_max and gamma + A_max < 180:
        settings = ocp_settings(problem)
        assert settings.A_max_deg == A_max and settings.gamma_deg == pytest.approx(gamma, abs=1e-12)
        return
    with pytest.raises(ProblemError) as info:
        ocp_settings(problem)
    msg = str(info.value)
    assert msg.startswith(f"p.toml: [ocp] A_max_deg = {A_max!r} with [gait] ") and "(0, 180)" in msg
    assert "\n" not in msg
    for k, v in gait.items():  # the gait keys that set gamma, as given
        assert f"{k} = {v!r}" in msg


# ------------------------------------------------------------------------------------------ solvers
def test_solver_key_chooses_the_registry_solver():
    from ocp_crawl.sim import SOLVERS
    from ocp_crawl.sim.timestepping import TimeSteppingOptions

    p = paper_problem()
    assert p.solver == "event" and p.options == p.hybrid == HybridOptions()
    q = paper_problem(["simulation.solver=mpcc", "simulation.steps=50", "simulation.max_cycles=6"])
    assert q.solver == "mpcc" and isinstance(q.options, SOLVERS["mpcc"].options)
    assert (q.options.steps, q.options.max_cycles) == (50, 6) and q.hybrid.max_cycles == 6
    assert paper_problem(["simulation.solver=mpcc"]).options.steps == TimeSteppingOptions().steps
    assert (problem_from_dict(q.to_dict()) == q
            and q.with_values({"simulation.solver": "event"}).solver == "event")
    a = paper_problem(["gait.drive=angles"])
    assert a.solver == "angles" and problem_from_dict(a.to_dict()) == a
    # built in code: the drive's default solver; a solver of another drive is refused
    assert Problem(robot=p.robot, gait=p.gait, drive="angles").solver == "angles"
    with pytest.raises(ValueError, match="simulates the torque drive"):
        Problem(robot=p.robot, gait=p.gait, drive="angles", solver="mpcc")
    with pytest.raises(TypeError, match="HybridOptions"):
        Problem(robot=p.robot, gait=p.gait, options=TimeSteppingOptions())


def test_mpcc_with_the_angles_drive_is_bad_input_naming_the_key():
    with pytest.raises(ProblemError) as info:
        paper_problem(["gait.drive=angles", "simulation.solver=mpcc"])
    msg = str(info.value)
    assert ('[simulation] solver = "mpcc" (from --set) is invalid with [gait] drive '
            '= "angles"' in msg), msg
    with pytest.raises(ProblemError, match=r"\[simulation\] solver = \"mpcc\""):
        paper_problem().with_values({"gait.drive": "angles", "simulation.solver": "mpcc"})
    with pytest.raises(ProblemError,
                       match=r"\[simulation\] steps = 3 is invalid: must be in \[4, 10000\]"):
        paper_problem().with_values({"simulation.steps": 3})


def test_run_problem_goes_through_the_registry(monkeypatch):
    import ocp_crawl.problem.run as run

    calls = []
    monkeypatch.setattr(run, "simulate", lambda *args: calls.append(args) or "result")
    q = paper_problem(["simulation.solver=mpcc"])
    assert run_problem(q, t_eval=[0.5]) == "result"
    model, signal, solver, options, t_eval = calls[-1]
    assert (model, signal, solver, options, t_eval) == (q.model, q.torque, "mpcc", q.options, [0.5])
    a = paper_problem(["gait.drive=angles"])
    run_problem(a)
    assert calls[-1][1] == a.gait and calls[-1][2] == "angles"


def test_schema_defaults_are_the_dataclass_defaults():
    """Defaults are defined once, on the dataclass fields; the schema reads them from there."""
    from ocp_crawl.model.statics import Robot
    from ocp_crawl.ocp import OCPSettings
    from ocp_crawl.problem import SCHEMA, ocp_settings
    from ocp_crawl.sim.timestepping import TimeSteppingOptions

    robot = SCHEMA["robot"].key_map
    assert (robot["beta"].default, robot["g"].default) == (Robot().beta, Robot().g)
    sim = SCHEMA["simulation"].key_map
    for name in ("max_step", "event_xtol", "max_cycles", "periodic_tol"):
        assert sim[name].default == getattr(HybridOptions(), name)
    assert sim["steps"].default == TimeSteppingOptions().steps and sim["solver"].default == "event"
    assert SCHEMA["model"].key_map["gravity"].default == "physical" == paper_problem().gravity
    # a problem without an [ocp] section gets OCPSettings' own defaults (the envelope centred on its
    # gait)
    assert ocp_settings(paper_problem()) == OCPSettings(gamma_deg=90.0)
    assert ocp_settings(Problem(robot=Robot(),
                                gait=paper_problem().gait)) == OCPSettings(gamma_deg=90.0)


# ------------------------------------------------------------------------------------------ bounds
def test_problem_file_size_is_bounded(tmp_path):
    """A problem file is read up to MAX_PROBLEM_BYTES: one byte more is bad input naming the file
    and the limit."""
    from ocp_crawl.problem.overrides import MAX_PROBLEM_BYTES

    text = (PROBLEMS / "paper_gait.toml").read_text()
    path = tmp_path / "big.toml"
    path.write_text(text + "#" * (MAX_PROBLEM_BYTES - len(text.encode())))
    assert load_problem(path).robot.k == 0.1677
    path.write_text(text + "#" * (MAX_PROBLEM_BYTES - len(text.encode()) + 1))
    with pytest.raises(ProblemError,
                       match=r"big.toml: cannot read the problem file: "
                             rf"larger than {MAX_PROBLEM_BYTES}"):
        load_problem(path)


def test_deep_nesting_is_one_line(tmp_path):
    from ocp_crawl.problem import format_value

    assert format_value([[[[[[1]]]]]]) == "[[[[...]]]]"
    assert len(format_value([list(range(100))] * 100)) <= 60
    path = tmp_path / "deep.toml"
    path.write_text("[robot]\nk = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(ProblemError,
                       match="deep.toml: malformed TOML: arrays or tables nested too deeply"):
        load_problem(path)


@pytest.mark.parametrize("name, low, high",
                         [("nodes", 8, 1000), ("fourier_order", 1, 25), ("harmonic_psi", 4, 180),
                          ("harmonic_A", 1, 20)])
def test_ocp_settings_sizes_are_bounded(name, low, high):
    """The bounds of the [ocp] keys hold in the API too (OCPSettings), and the schema states the
    same ones."""
    from ocp_crawl.ocp import OCPSettings
    from ocp_crawl.problem import SCHEMA

    for ok in (low, high):
        assert getattr(OCPSettings(**{name: ok}), name) == ok
    for bad in (low - 1, high + 1):
        with pytest.raises(ValueError, match=f"OCPSettings.{name} must be"):
            OCPSettings(**{name: bad})
    if name in SCHEMA["ocp"].key_map:
        assert SCHEMA["ocp"].key_map[name].valid_text == f"in [{low}, {high}]"


def test_every_robot_key_and_work_key_is_bounded_on_both_sides():
    """The robot's parameters and every [simulation]/[ocp] key that sizes the work have an upper and
    a lower bound, with a stated reason."""
    from ocp_crawl.problem import SCHEMA

    sized = {"robot": ("M", "L", "beta", "k", "mu", "mu1", "mu2", "g"),
             "simulation": ("max_step", "event_xtol", "max_cycles", "steps"),
             "ocp": ("nodes", "fourier_order", "harmonic_psi")}
    for section, names in sized.items():
        for name in names:
            rule = SCHEMA[section].key_map[name].rule
            assert rule.text.startswith("in ") and rule.why, (section, name, rule)


def test_readme_and_docs_tables_are_rectangular():
    """Every markdown table of the README, of the docs pages and of the generated key reference
    (:func:`schema_markdown`) has as many cells in each row as in its header (a '|' inside a cell,
    e.g. a schema help text with |x|, splits the row)."""
    from conftest import markdown_table_shapes

    pages = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md")),
             *sorted((REPO / "docs" / "guide").glob("*.md"))]
    texts = {str(page.relative_to(REPO)): page.read_text(encoding="utf-8") for page in pages}
    texts["schema_markdown()"] = schema_markdown()
    shapes = {name: markdown_table_shapes(text) for name, text in texts.items()}
    assert sum(len(s) for s in shapes.values()) >= 5
    for name, tables in shapes.items():
        for header, rows in tables:
            assert all(n == header for n in rows), (name, header, rows)


def test_first_loss_finds_what_later_overrides_undo():
    """An override undone by a later one is found (the same key to another value, an alternative
    key, another waveform), and the documented carry-over of one mu to the other foot is not a
    loss."""
    from ocp_crawl.problem.overrides import first_loss

    data = {"robot": {"mu": 0.389}, "gait": {"waveform": "harmonic", "psi_deg": 45.0}}
    assert first_loss(data, [("gait", "psi_deg", 10.0)], [("gait", "psi_deg", 10.0)]) is None
    assert first_loss(data, [("gait", "psi_deg", 10.0)],
                      [("robot", "k", 1.0), ("gait", "psi_deg", 20.0)]) == \
        (1, "gait.psi_deg")
    assert first_loss(data, [("robot", "mu1", 0.3), ("robot", "mu2", 0.4)],
                      [("robot", "mu", 0.2)]) == \
        (0, "robot.mu1")
    # foot 2 keeps mu
    assert first_loss(data, [("robot", "mu", 0.3)], [("robot", "mu1", 0.2)]) is None
    assert first_loss(data, [("gait", "waveform", "samples"), ("gait", "file", "t.csv")],
                      [("gait", "interpolation", "linear")]) is None
    assert first_loss(data, [("gait", "waveform", "samples"), ("gait", "file", "t.csv")],
                      [("gait", "phase", [0.0, 0.5])]) == (0, "gait.file")
    assert first_loss(data, [("gait", "waveform", "samples"), ("gait", "file", "t.csv")],
                      [("gait", "waveform", "harmonic")]) == (0, "gait.waveform")
    # a value that only coincides with another key's (L = 0.12) is not carried: the later mu drops
    # mu1
    robot = {"robot": {"mu": 0.389, "L": 0.12}}
    assert first_loss(robot, [("robot", "mu1", 0.12), ("robot", "mu2", 0.4)],
                      [("robot", "mu", 0.3)]) == \
        (0, "robot.mu1")


def test_problem_files_are_written_by_tomli_w_and_load_back_to_the_same_values():
    """toml_text (optimal_gait.toml, fitted_problem.toml) is tomli-w's text after the comment lines:
    numpy arrays and scalars, non-finite floats, strings with quotes, backslashes and control
    characters and a key that needs quotes load back (tomllib) to the same values; no hand-written
    serialiser is left."""
    import inspect
    import tomli_w
    from ocp_crawl.problem import overrides
    from ocp_crawl.problem.overrides import toml_string, toml_text

    name = 'a "b"\\c\t.csv'
    sections = {"robot": {"k": np.float64(0.1677), "mu": 0.1 + 0.2, "L": 0.12},
                "gait": {"phase": np.linspace(0.0, 0.75, 4), "tau1": [-0.5, math.inf],
                         "file": name},
                "simulation": {"max_cycles": np.int64(12), "odd key": float("-inf")}}
    text = toml_text(sections, comments=["written by a test", "second line"])
    assert text.startswith("# written by a test\n# second line\n\n")
    assert text.split("\n\n", 1)[1] == tomli_w.dumps(overrides._plain_value(sections))
    back = tomllib.loads(text)
    assert back["robot"] == {"k": 0.1677, "mu": 0.30000000000000004, "L": 0.12}
    assert back["gait"] == {"phase": [0.0, 0.25, 0.5, 0.75], "tau1": [-0.5, math.inf], "file": name}
    assert back["simulation"] == {"max_cycles": 12, "odd key": -math.inf}
    assert tomllib.loads(toml_text({"robot": {"k": 1.0}})) == {"robot": {"k": 1.0}}
    path = 'x"y\\z\n'
    assert tomllib.loads("v = " + toml_string(path))["v"] == path
    assert not hasattr(overrides, "_toml_value")
    assert "tomli_w" in inspect.getsource(overrides.toml_string)


@pytest.mark.parametrize("data, words", [({5: {}}, "a section is named 5 (int)"),
                                         ({"robot": {5: 1}}, "a key of [robot] is named 5 (int)")])
def test_a_dict_with_names_that_are_not_strings_is_bad_input(data, words):
    from ocp_crawl.problem import ProblemError, problem_from_dict
    with pytest.raises(ProblemError) as info:
        problem_from_dict(data)
    assert words in str(info.value)
