r"""Property-based tests (hypothesis) of the problem files, with strategies driven by the schema:
round trips, ``--set`` overrides, invalid and missing keys, and runs with prescribed angles.

The number of examples per property comes from ``OCP_CRAWL_HYPOTHESIS_EXAMPLES`` (default 25, so
that the file runs in well under a minute); a large run::

    OCP_CRAWL_HYPOTHESIS_EXAMPLES=500 python -m pytest -q tests/test_properties_problem_files.py \
        --hypothesis-show-statistics

The statistics list the outcomes (``event``) of the random runs: success, failure status, input
rejected.  Every assertion holds for every example, whatever the seed.
"""
from __future__ import annotations

import json
import math
import re
import tomllib
from dataclasses import fields

import pytest
from hypothesis import assume, event, given
from hypothesis import strategies as st

from ocp_crawl import Robot
from ocp_crawl.sim.angles import simulate_angles
from ocp_crawl.sim.event import HybridOptions
from ocp_crawl.problem import (SCHEMA, SECTIONS, Problem, ProblemError, problem_from_dict,
                               run_problem)
from ocp_crawl.problem.chain_robot import CHAIN_KEYS, JOINT_KEYS
from ocp_crawl.problem.robot_checks import MAX_STIFFNESS_RATIO
from ocp_crawl.problem.keys import Tables

from _properties_common import (BAD_NUMBERS, CHEAP, SIMS, amplitudes, check_outcome, gammas,
                                run_prescribed)

# ============================================================================================
# 3. problem files: strategies driven by the schema
# ============================================================================================
#: physically sensible ranges where the schema's rule alone allows configurations without contact
#: (the rule is still applied on top)
PLAUSIBLE = {
    ("robot", "beta"): st.floats(1.0, 5.0),
    ("gait", "gamma_deg"): st.floats(70.0, 120.0), ("gait", "gamma1_deg"): st.floats(70.0, 120.0),
    ("gait", "gamma2_deg"): st.floats(70.0, 120.0),
    ("gait", "A_deg"): st.floats(0.0, 20.0), ("gait", "A1_deg"): st.floats(0.0, 20.0),
    ("gait", "A2_deg"): st.floats(0.0, 20.0),
}
_NUM = r"(-?[0-9.]+(?:e-?[0-9]+)?)"


def rule_bounds(key):
    """(low, high, low open, high open, listed values) from the rule's text, e.g. "> 0", "in (0,
    0.25]", "-1 or 1"."""
    text = key.valid_text.removeprefix("an array of numbers, each ")
    if m := re.fullmatch(rf"(>=|>) {_NUM}", text):
        return float(m[2]), None, m[1] == ">", False, None
    if m := re.fullmatch(rf"in ([\[(]){_NUM}, {_NUM}([\])])", text):
        return float(m[2]), float(m[3]), m[1] == "(", m[4] == ")", None
    if m := re.fullmatch(rf"{_NUM} or {_NUM}", text):
        return None, None, False, False, [key.type(m[1]), key.type(m[2])]
    if text == "any finite number":
        return None, None, False, False, None
    raise AssertionError(f"the property tests do not know the rule {text!r} of key {key.name}: "
                         "extend rule_bounds")


#: values of the table keys: [[ocp.constraint]] tables (bounds no gait of the runs can miss) and
#: IPOPT options
TABLE_VALUES = {
    ("ocp", "constraint"): [[], [{"quantity": "peak_torque", "max": 10.0}],
                            [{"quantity": "period", "min": 1e-3, "max": 100.0}]],
    ("ocp", "ipopt"): [{}, {"max_iter": 3000}, {"tol": 1e-9, "mu_strategy": "adaptive"}],
}


def valid_values(section: str, key, ranges=None):
    """Values the schema accepts for a key (the key's own rule filters them)."""
    ranges = PLAUSIBLE if ranges is None else ranges
    if key.choices:
        return st.sampled_from(key.choices)
    if (section, key.name) in TABLE_VALUES:
        return st.sampled_from(TABLE_VALUES[(section, key.name)])
    if key.type is list:  # an array of numbers, each within the rule
        lo, hi, lo_open, hi_open, _ = rule_bounds(key)
        entry = st.floats(lo, hi, exclude_min=lo_open, exclude_max=hi_open).filter(key.rule.test)
        return st.lists(entry, min_size=1, max_size=3)
    lo, hi, lo_open, hi_open, listed = rule_bounds(key)
    if listed is not None:
        base = st.sampled_from(listed)
    elif (section, key.name) in ranges:
        base = ranges[(section, key.name)]
    elif key.type is int:
        lo_i = -100 if lo is None else math.floor(lo)
        base = st.integers(lo_i, lo_i + 200 if hi is None else math.ceil(hi))
    else:
        lo_f = -1e3 if lo is None else lo
        hi_f = (abs(lo_f) * 10 + 10 if hi is None else hi)
        base = st.floats(lo_f, hi_f, exclude_min=lo_open, exclude_max=hi_open)
        if key.type is float:
            base = st.one_of(base, base.map(lambda v: v)).filter(math.isfinite)
    return base.filter(lambda v: key.rule is None or key.rule.test(v))


#: tables the schema must reject for [[ocp.constraint]]: an unknown quantity, no bound, a key of
#: another name
BAD_TABLES = [[{"quantity": "torque", "max": 1.0}], [{"quantity": "speed"}],
              [{"quantity": "speed", "maximum": 1.0}], [{"quantity": "peak_torque", "min": 0.1}]]


def invalid_values(key):
    """Values the schema must reject for a key: non-finite, outside the rule, wrong type (for an
    array of tables: tables its rule rejects)."""
    wrong_type = st.sampled_from(["1.0", True, False, [1.0], {"x": 1.0}])
    out = [BAD_NUMBERS, wrong_type]
    if key.type is Tables:
        return st.one_of(out + [st.sampled_from(BAD_TABLES)])
    if key.type is int:
        out.append(st.floats(-50.5, 50.5).filter(lambda v: v != int(v)))
    if key.rule is not None:
        lo, hi, lo_open, hi_open, listed = rule_bounds(key)
        if listed is not None:
            out.append(st.integers(-5, 5).filter(lambda v: v not in listed))
        else:
            cands = []
            if lo is not None:
                cands += [lo - 1.0, lo - 1e-6] + ([lo] if lo_open else [])
            if hi is not None:
                cands += [hi + 1.0, hi + 1e-3] + ([hi] if hi_open else [])
            cands = [key.type(c) if key.type is float else int(c) for c in cands
                     if key.type is float or c == int(c)]
            cands = [c for c in cands if not key.rule.test(c)]
            if cands:
                out.append(st.sampled_from(cands))
    return st.one_of(out)


#: a physical robot for the runs (the schema alone admits e.g. L = 1e-302 m, where M g L S
#: underflows)
PHYSICAL = {**PLAUSIBLE, ("robot", "M"): st.floats(0.005, 5.0),
            ("robot", "L"): st.floats(0.02, 1.0),
            ("robot", "k"): st.floats(1e-3, 100.0), ("robot", "g"): st.floats(1.0, 20.0),
            ("robot", "mu"): st.floats(0.05, 2.0), ("robot", "mu1"): st.floats(0.05, 2.0),
            ("robot", "mu2"): st.floats(0.05, 2.0), ("robot", "beta"): st.floats(0.2, 5.0),
            **{("gait", f"gamma{i}_deg"): gammas for i in ("", "1", "2")},
            **{("gait", f"A{i}_deg"): amplitudes for i in ("", "1", "2")}}


@st.composite
def section_values(draw, section, ranges=None):
    """A valid set of keys for one section: required keys, a random choice of optional ones, pairing
    rules kept (the default waveform's keys: the other waveforms have their own tests,
    tests/test_waveforms.py)."""
    keys = section.key_map
    given = set()
    drawn = default_variant_keys(section)
    for key in drawn:
        if key.required:
            # (alternatives among the keys drawn here: not M, L, k's, a chain's)
            if (key.required_unless and set(key.required_unless) <= {k.name for k in drawn}
                    and draw(st.booleans())):
                given |= set(key.required_unless)
                if not key.exclusive_with and draw(st.booleans()):
                    given.add(key.name)
            else:
                given.add(key.name)
        elif draw(st.booleans()):
            given.add(key.name)
    changed = True
    while changed:  # pairing rules: exclusive keys leave, required partners join
        changed = False
        for name in sorted(given):
            key = keys[name]
            if name in given and any(o in given for o in key.exclusive_with):
                drop = set(key.exclusive_with) if key.required else {name}
                given -= drop
                changed = True
            if name in given and any(r not in given for r in key.requires):
                given |= set(key.requires)
                changed = True
    if section.name == "simulation":
        # the solver choice is covered by tests/test_problem.py; here every problem runs the default
        # solver of its drive, with its own keys (an MPCC or MuJoCo run per example would be slow)
        given &= {f.name for f in fields(HybridOptions)}
    return {name: draw(valid_values(section.name, keys[name],
                                    ranges)) for name in (k.name for k in section.keys)
            if name in given}


@st.composite
def problem_dicts(draw, ranges=None):
    data = {}
    for section in SECTIONS:
        if section.required or draw(st.booleans()):
            data[section.name] = draw(section_values(section, ranges))
    ocp = data.get("ocp", {})
    if ocp.get("robust") == "worst" and not ocp.get("mu_ratio_eps", 0) > 0:  # the worst needs a set
        ocp["mu_ratio_eps"] = draw(st.sampled_from([0.01, 0.1, 0.5]))
    return data


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf
                                            else repr(v))
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + "}"
    return repr(v)


def to_toml(data: dict) -> str:
    return "\n".join(f"[{s}]\n" + "\n".join(f"{k} = {toml_value(v)}" for k, v in keys.items())
                     for s, keys in data.items())


def load_or_contact_error(data: dict, source: str = "<dict>", overrides=()):
    """The problem, or None when the only fault is a gait without contact (then the message says
    so)."""
    try:
        return problem_from_dict(data, source=source, overrides=overrides)
    except ProblemError as exc:
        msg = str(exc)
        if msg.startswith(f"{source}: [robot] k = ") and "k/(M g L)" in msg and not overrides:
            # the torque drive's documented bound on the nondimensional stiffness, recomputed from
            # the data
            r = data["robot"]
            assert (r["k"] / (r["M"] * r.get("g", Robot.paper().g) * r["L"])
                    > MAX_STIFFNESS_RATIO), msg
            assert "\n" not in msg
            return None
        assert "\n" not in msg and msg.startswith(f"{source}: "
                                                  "[gait] ") and " are invalid" in msg, msg
        return None


def edited(data: dict, section: str, name: str, value) -> dict:
    """The dict edit that ``--set section.name=value`` documents: set the key; mu and mu1/mu2
    replace each other, and one foot's friction set on a robot given one mu leaves the other foot at
    mu."""
    out = {s: dict(v) for s, v in data.items()}
    sec = out.setdefault(section, {})
    key = SCHEMA[section].key_map[name]
    for other in key.exclusive_with:
        sec.pop(other, None)
    if section == "robot" and name in ("mu1", "mu2") and "mu" in sec:
        sec.setdefault("mu2" if name == "mu1" else "mu1", sec["mu"])
    for k in SCHEMA[section].keys:
        if name in k.exclusive_with:
            sec.pop(k.name, None)
    sec[name] = value
    return out


def default_variant_keys(section):
    """The keys of a section with its selector (``[gait] waveform``) at its default, the selector
    left out, for the three-link robot (a chain's keys, ``[robot] lengths, ...`` and its joints'
    lists, have their own tests: tests/test_chain_problems.py and the bad-input matrix)."""
    chain = set(CHAIN_KEYS) | set(JOINT_KEYS)
    keys = [k for k in section.keys if section.name not in ("robot", "gait") or k.name not in chain]
    if section.selector is None:
        return keys
    default = section.key_map[section.selector].default
    return [k for k in keys if k.name != section.selector and section.applies(k, default)]


def schema_keys(numeric_only=False):
    return [(s.name, k) for s in SECTIONS for k in default_variant_keys(s)
            if not numeric_only or k.type in (int, float)]


@pytest.mark.slow
@CHEAP
@given(data=problem_dicts())
def test_problem_round_trip(data):
    """problem_from_dict(p.to_dict()) == p, directly and through TOML text; the values are the ones
    given."""
    p = load_or_contact_error(data)
    assume(p is not None)
    assert problem_from_dict(p.to_dict()) == p
    assert problem_from_dict(tomllib.loads(to_toml(p.to_dict()))) == p
    assert problem_from_dict(p.to_dict()).to_dict() == p.to_dict()
    r = data["robot"]
    assert (p.robot.M, p.robot.L, p.robot.k) == (r["M"], r["L"], r["k"])
    assert (p.robot.mu1, p.robot.mu2) == ((r["mu"], r["mu"]) if "mu" in r else (r["mu1"], r["mu2"]))
    g = data["gait"]
    assert p.gait.psi == math.radians(g["psi_deg"])
    assert p.gait.gamma1 == math.radians(g.get("gamma1_deg", g.get("gamma_deg")))
    assert p.gait.A2 == math.radians(g.get("A2_deg", g.get("A_deg")))
    assert (p.drive == g.get("drive", "torque")
            and p.gravity == data.get("model", {}).get("gravity", "physical"))
    for name, value in data.get("simulation", {}).items():
        assert getattr(p.hybrid, name) == value
    for section, keys in data.items():
        for name, value in keys.items():
            assert p.sections[section][name] == value


@pytest.mark.slow
@CHEAP
@given(data=problem_dicts(), st_key=st.sampled_from(schema_keys()), st_data=st.data())
def test_set_override_equals_dict_edit(data, st_key, st_data):
    """--set SECTION.KEY=VALUE gives the same problem as editing the dict, or the same error (marked
    "from --set")."""
    section, key = st_key
    value = st_data.draw(st.one_of(valid_values(section, key), invalid_values(key))
                         if key.type is not str
                         else st.one_of(valid_values(section, key),
                                        st.sampled_from(["walk", "", "Physical"])))
    text = f"{section}.{key.name}={toml_value(value)}"
    try:
        via_set = problem_from_dict(data, source="f.toml", overrides=[text])
    except ProblemError as exc:
        via_set = exc
    try:
        via_dict = problem_from_dict(edited(data, section, key.name, value), source="f.toml")
    except ProblemError as exc:
        via_dict = exc
    if isinstance(via_dict, Problem):
        assert via_set == via_dict
    else:
        assert isinstance(via_set, ProblemError), via_set
        assert str(via_set).replace(" (from --set)", "") == str(via_dict)
        event("both rejected")
    # a bare word is accepted for string keys
    if key.type is str and re.fullmatch(r"[A-Za-z_]+", value) and value not in ("true", "false",
                                                                                "inf", "nan"):
        try:
            bare = problem_from_dict(data, source="f.toml",
                                     overrides=[f"{section}.{key.name}={value}"])
        except ProblemError as exc:
            bare = exc
        assert str(bare) == str(via_set) if isinstance(bare, ProblemError) else bare == via_set


@pytest.mark.slow
@CHEAP
@given(data=problem_dicts(), st_key=st.sampled_from(schema_keys(numeric_only=True)),
       st_data=st.data())
def test_invalid_numeric_values_name_the_key_and_value(data, st_key, st_data):
    """Every numeric key of the schema rejects NaN, infinities, values outside its rule and wrong
    types with a one-line ProblemError naming the file, the key and the value; from --set too."""
    section, key = st_key
    value = st_data.draw(invalid_values(key))
    assume(not (isinstance(value, (int, float)) and not isinstance(value, bool)
                and math.isfinite(value)
                and key.rule is not None and key.rule.test(value)
                and not (key.type is int and value != int(value))))
    bad = edited(data, section, key.name, value)
    with pytest.raises(ProblemError) as info:
        problem_from_dict(bad, source="problems/x.toml")
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith("problems/x.toml: ")
    assert f"[{section}] {key.name} = {toml_value(value)} is invalid" in msg, msg
    with pytest.raises(ProblemError) as info:
        problem_from_dict(data, source="problems/x.toml",
                          overrides=[f"{section}.{key.name}={toml_value(value)}"])
    assert (f"[{section}] {key.name} = {toml_value(value)} (from --set) "
            "is invalid" in str(info.value)), str(info.value)
    assert isinstance(info.value, ValueError)


@pytest.mark.slow
@CHEAP
@given(data=problem_dicts(), st_key=st.sampled_from([(s.name, k) for s in SECTIONS if s.required
                                                     for k in default_variant_keys(s)
                                                     if k.required]))
def test_missing_required_key_is_named(data, st_key):
    section, key = st_key
    bad = {s: dict(v) for s, v in data.items()}
    bad[section].pop(key.name, None)
    for alt in key.required_unless:  # the alternatives would stand in for the key
        bad[section].pop(alt, None)
    for k in SCHEMA[section].keys:  # so would keys that need it
        if key.name in k.requires:
            bad[section].pop(k.name, None)
    with pytest.raises(ProblemError) as info:
        problem_from_dict(bad, source="p.toml")
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith("p.toml: ")
    assert f"[{section}] {key.name} is missing" in msg, msg


@pytest.mark.slow
@SIMS
@given(data=problem_dicts(PHYSICAL), model_gravity=st.sampled_from(["physical", "paper"]))
def test_run_problem_with_prescribed_angles(data, model_gravity):
    """gait.drive = "angles" through the problem layer: the same result as simulate_angles; a gait
    rejected for losing contact does lose it (the simulator cannot succeed on it)."""
    data = edited(data, "gait", "drive", "angles")
    data = edited(data, "model", "gravity", model_gravity)
    p = load_or_contact_error(data)
    if p is None:
        event("rejected as bad input")
        try:  # the torque drive checks the start configuration only
            q = problem_from_dict(edited(data, "gait", "drive", "torque"))
        except ProblemError:
            # no contact at phase 0: simulate_angles rejects it as well (test_prescribed_random_...)
            return
        res = run_prescribed(q.model, q.gait)
        assert res is not None and not res.success
        return
    res = run_problem(p)
    assert res.drive == "angles" and res.gravity == model_gravity
    direct = simulate_angles(p.model, p.gait)
    assert res.status == direct.status and (not res.success or res.S == direct.S)
    check_outcome(p.model, p.gait, res)
