"""Problem files: a TOML description of a robot, a gait and the simulation settings.

One schema table (:data:`SECTIONS`) lists every section and key with its type, unit, whether it
is required, its default and its validator; loading, ``--set`` overrides, error messages and the
README's key table are all driven by it.  To add a section (e.g. ``[ocp]``, ``[sweep]``), append a
:class:`Section` to :data:`SECTIONS`; its validated values (defaults filled in) appear in
``Problem.sections[name]`` without any other change here.

Every bad input raises :class:`ProblemError` with a one-line message that names the file, the
``[section] key``, the value given and what is valid, for example::

    problems/x.toml: [robot] k = -1.0 is invalid: must be > 0 (torsion stiffness, N m/rad)
"""
from __future__ import annotations

import difflib
import json
import math
import re
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path
from types import MappingProxyType
from typing import Iterable, Any, Callable, Literal, Mapping, Sequence

import numpy as np

from ocp_crawl.sim.event import HybridOptions, simulate_torque
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.statics import GRAVITY_CONVENTIONS, GravityConvention, Model, Robot
from ocp_crawl.sim.angles import simulate_angles
from ocp_crawl.sim.result import CrawlResult

Drive = Literal["torque", "angles"]
DRIVES = ("torque", "angles")

#: phases at which a prescribed-angle gait is checked for contact validity before simulating
CONTACT_GRID = 721


class ProblemError(ValueError):
    """Bad problem input. The message is a single line naming the file, key, value and what is valid."""

    def __init__(self, message: str):
        # one line whatever the user typed (file names, string values)
        super().__init__(" ".join(str(message).split("\n")))


# --------------------------------------------------------------------------------------------
# the schema
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Rule:
    """A value constraint: ``test(value)`` must hold; ``text`` says what is valid (e.g. "> 0")."""

    test: Callable[[Any], bool]
    text: str


GT0 = Rule(lambda v: v > 0, "> 0")
GE0 = Rule(lambda v: v >= 0, ">= 0")
ANGLE = Rule(lambda v: 0 < v < 360, "in (0, 360)")
PHASE = Rule(lambda v: -360 <= v <= 360, "in [-360, 360]")
MAX_STEP = Rule(lambda v: 0 < v <= 0.25, "in (0, 0.25]")
CYCLES = Rule(lambda v: v >= 2, ">= 2")

_TYPE_WORDS = {float: "a number", int: "an integer", str: "a string"}


@dataclass(frozen=True)
class Key:
    """One key of a section: type, unit, description, default, validator and cross-key rules."""

    name: str
    type: type
    """float, int or str (ints are accepted for floats; bools are never numbers)"""
    unit: str
    help: str
    required: bool = False
    default: Any = None
    """value used when the key is absent (None: absent stays absent)"""
    rule: Rule | None = None
    choices: tuple[str, ...] = ()
    required_unless: tuple[str, ...] = ()
    """the key is not required when all of these keys are given"""
    exclusive_with: tuple[str, ...] = ()
    requires: tuple[str, ...] = ()
    """keys that must be given together with this one"""

    def __post_init__(self) -> None:
        if self.type not in _TYPE_WORDS:
            raise TypeError(f"Key {self.name}: type must be one of float, int, str, got {self.type!r}")

    @property
    def what(self) -> str:
        """Description with unit, used at the end of error messages."""
        return f"{self.help}, {self.unit}" if self.unit and self.unit != "-" else self.help

    @property
    def valid_text(self) -> str:
        """What is valid, in words (README table and error messages)."""
        if self.choices:
            return "one of " + ", ".join(json.dumps(c) for c in self.choices)
        if self.rule is not None:
            return self.rule.text
        return "any finite number" if self.type in (float, int) else "any string"


@dataclass(frozen=True)
class Section:
    """A ``[section]`` of a problem file and its keys."""

    name: str
    help: str
    keys: tuple[Key, ...]
    required: bool = False

    @property
    def key_map(self) -> dict[str, Key]:
        return {k.name: k for k in self.keys}


def _hybrid_default(name: str):
    return next(f.default for f in fields(HybridOptions) if f.name == name)


def _robot_default(name: str):
    return next(f.default for f in fields(Robot) if f.name == name)


#: The schema: every section and key of a problem file, in the order they are validated and reported.
SECTIONS: tuple[Section, ...] = (
    Section("robot", "physical parameters (paper Table I)", required=True, keys=(
        Key("M", float, "kg", "total mass", required=True, rule=GT0),
        Key("L", float, "m", "total length", required=True, rule=GT0),
        Key("beta", float, "-", "body-to-leg length ratio", default=_robot_default("beta"), rule=GT0),
        Key("k", float, "N m/rad", "torsion stiffness", required=True, rule=GT0),
        Key("mu", float, "-", "friction coefficient of both feet", required=True, rule=GE0,
            required_unless=("mu1", "mu2"), exclusive_with=("mu1", "mu2")),
        Key("mu1", float, "-", "friction coefficient of foot 1 (left)", rule=GE0, requires=("mu2",)),
        Key("mu2", float, "-", "friction coefficient of foot 2 (right)", rule=GE0, requires=("mu1",)),
        Key("g", float, "m/s^2", "gravitational acceleration", default=_robot_default("g"), rule=GT0),
    )),
    Section("gait", "harmonic reference angles, eq. (ref)", required=True, keys=(
        Key("drive", str, "-", "actuation: spring torque tau = k (phi_ref - pi), or prescribed angles",
            default="torque", choices=DRIVES),
        Key("gamma_deg", float, "deg", "nominal joint angle", required=True, rule=ANGLE,
            required_unless=("gamma1_deg", "gamma2_deg")),
        Key("A_deg", float, "deg", "amplitude", required=True, rule=GE0, required_unless=("A1_deg", "A2_deg")),
        Key("psi_deg", float, "deg", "phase lead of joint 1 over joint 2", required=True, rule=PHASE),
        Key("gamma1_deg", float, "deg", "nominal angle of joint 1 (overrides gamma_deg)", rule=ANGLE),
        Key("gamma2_deg", float, "deg", "nominal angle of joint 2 (overrides gamma_deg)", rule=ANGLE),
        Key("A1_deg", float, "deg", "amplitude of joint 1 (overrides A_deg)", rule=GE0),
        Key("A2_deg", float, "deg", "amplitude of joint 2 (overrides A_deg)", rule=GE0),
    )),
    Section("model", "model conventions", keys=(
        Key("gravity", str, "-", "sign of the gravity term: physical (virtual work) or paper (as printed)",
            default="physical", choices=GRAVITY_CONVENTIONS),
    )),
    Section("simulation", "event-driven solver options (torque drive)", keys=(
        Key("max_step", float, "cycles", "largest continuation step", default=_hybrid_default("max_step"),
            rule=MAX_STEP),
        Key("event_xtol", float, "cycles", "event location tolerance", default=_hybrid_default("event_xtol"),
            rule=GT0),
        Key("max_cycles", int, "-", "cycles before the gait is declared non-periodic",
            default=_hybrid_default("max_cycles"), rule=CYCLES),
        Key("periodic_tol", float, "rad", "periodicity tolerance (angles; f_t/(M g) likewise)",
            default=_hybrid_default("periodic_tol"), rule=GT0),
    )),
)

SECTIONS += (
    Section("ocp", "periodic-gait optimal control (ocp-crawl optimize)", keys=(
        Key("objective", str, "-", "what to optimise", default="max_speed",
            choices=("max_speed", "min_cot", "robust_speed")),
        Key("nodes", int, "-", "steps per cycle of the transcription", default=100, rule=Rule(lambda v: v >= 8, ">= 8")),
        Key("direction", int, "-", "sign of S to pursue (-1: towards foot 1, as psi > 0 gaits)", default=-1,
            rule=Rule(lambda v: v in (-1, 1), "-1 or 1")),
        Key("A_max_deg", float, "deg", "half-width of the reference-angle envelope around gait.gamma_deg",
            default=30.0, rule=Rule(lambda v: 0 < v < 90, "in (0, 90)")),
        Key("parametrization", str, "-", "torques free at every node or a Fourier series", default="free",
            choices=("free", "fourier")),
        Key("fourier_order", int, "-", "order of the Fourier series", default=4, rule=Rule(lambda v: v >= 1, ">= 1")),
        Key("rate_limit", str, "-", "torque rate limit: the harmonic envelope's peak rate, none, or max_rate",
            default="harmonic", choices=("harmonic", "none", "max_rate")),
        Key("max_rate", float, "N m/cycle", "largest |d tau/dt| when rate_limit = \"max_rate\"", rule=GT0),
        Key("curvature_limit", str, "-", "limit on d^2 tau/dt^2: 4 x the harmonic envelope's peak, or none",
            default="harmonic", choices=("harmonic", "none")),
        Key("regularization", float, "-", "weight of the torque-change regularisation", default=1e-5, rule=GE0),
        Key("tie_margin", float, "-", "friction-limit margin (fraction of M g) required for a foot to slip",
            default=0.0005, rule=GE0),
        Key("S_min", float, "m", "min_cot: smallest progress direction * S per cycle", default=0.0, rule=GE0),
        Key("mu_ratio_eps", float, "-", "robust_speed: scenarios mu1/mu2 in {1 - eps, 1, 1 + eps}", default=0.1,
            rule=Rule(lambda v: 0 <= v < 1, "in [0, 1)")),
        Key("robust", str, "-", "robust_speed: maximise the mean or the worst S", default="mean",
            choices=("mean", "worst")),
        Key("harmonic_psi", int, "-", "psi values of the harmonic sweep (initial guess, comparison)", default=36,
            rule=Rule(lambda v: v >= 4, ">= 4")),
    )),
)

SCHEMA: Mapping[str, Section] = MappingProxyType({s.name: s for s in SECTIONS})


def ocp_settings(problem: "Problem"):
    """OCPSettings from the problem's ``[ocp]`` section (defaults when absent) and its gait's gamma."""
    from ocp_crawl.ocp import OCPSettings

    sec = dict(problem.sections.get("ocp", {}))
    if not sec:
        sec = {k.name: k.default for k in SCHEMA["ocp"].keys if k.default is not None}
    if sec.get("rate_limit") == "max_rate" and sec.get("max_rate") is None:
        raise ProblemError(f"{problem.source}: [ocp] rate_limit = \"max_rate\" needs [ocp] max_rate (N m/cycle)")
    rate = {"harmonic": "harmonic", "none": None}.get(sec.get("rate_limit"), sec.get("max_rate"))
    eps = sec["mu_ratio_eps"]
    gamma = math.degrees(0.5 * (problem.gait.gamma1 + problem.gait.gamma2))
    if not (0 < gamma - sec["A_max_deg"] and gamma + sec["A_max_deg"] < 180):
        gait = problem.sections.get("gait", {})
        given = ", ".join(f"{k} = {_fmt(gait[k])}" for k in ("gamma_deg", "gamma1_deg", "gamma2_deg") if k in gait)
        raise ProblemError(f"{problem.source}: [ocp] A_max_deg = {_fmt(sec['A_max_deg'])} with [gait] "
                           f"{given or f'gamma = {gamma:g} deg'} is invalid: the envelope gamma +- A_max_deg must "
                           f"lie in (0, 180) deg (here {gamma - sec['A_max_deg']:g} to {gamma + sec['A_max_deg']:g})")
    return OCPSettings(objective=sec["objective"], nodes=sec["nodes"], direction=sec["direction"],
                       gamma_deg=gamma,
                       A_max_deg=sec["A_max_deg"], parametrization=sec["parametrization"],
                       fourier_order=sec["fourier_order"], rate_limit=rate,
                       curvature_limit=None if sec["curvature_limit"] == "none" else "harmonic",
                       regularization=sec["regularization"],
                       tie_margin=sec["tie_margin"], S_min=sec["S_min"],
                       mu_ratios=(1 - eps, 1.0, 1 + eps) if eps > 0 else (1.0,), robust=sec["robust"],
                       harmonic_psi=sec["harmonic_psi"])


def schema_markdown() -> str:
    """The schema as a Markdown table (section, key, type, unit, required/default, valid values, meaning)."""
    rows = ["| key | type | unit | required / default | valid | meaning |", "|---|---|---|---|---|---|"]
    for sec in SECTIONS:
        for k in sec.keys:
            if k.required and k.required_unless:
                req = "required unless " + " and ".join(f"`{u}`" for u in k.required_unless) + " given"
            elif k.required:
                req = "required"
            elif k.requires:
                req = "optional, with " + ", ".join(f"`{r}`" for r in k.requires)
            elif k.default is None:
                req = "optional"
            else:
                req = f"default `{_fmt(k.default)}`"
            if k.exclusive_with:
                req += "; not with " + ", ".join(f"`{e}`" for e in k.exclusive_with)
            kind = {float: "float", int: "int", str: "string"}[k.type]
            rows.append(f"| `{sec.name}.{k.name}` | {kind} | {k.unit} | {req} | {k.valid_text} | {k.help} |")
    return "\n".join(rows)


# --------------------------------------------------------------------------------------------
# the problem
# --------------------------------------------------------------------------------------------
def _freeze(d: Mapping) -> Mapping:
    return MappingProxyType({k: _freeze(v) if isinstance(v, Mapping) else v for k, v in d.items()})


def _thaw(d: Mapping) -> dict:
    return {k: _thaw(v) if isinstance(v, Mapping) else v for k, v in d.items()}


@dataclass(frozen=True)
class Problem:
    """A validated simulation problem: robot, gait, drive, gravity convention and solver options."""

    robot: Robot
    """physical parameters (SI units)"""
    gait: Harmonic
    """reference angles [rad]; the degree values as given are in ``sections["gait"]``"""
    drive: Drive = "torque"
    """actuation: "torque" (tau = k (phi_ref - pi), event-driven solver) or "angles" (phi = phi_ref prescribed)"""
    gravity: GravityConvention = "physical"
    """sign convention of the gravity term (see MODEL_NOTES erratum)"""
    hybrid: HybridOptions = field(default_factory=HybridOptions)
    """options of the event-driven solver (torque drive only)"""
    sections: Mapping[str, Mapping[str, Any]] = field(default_factory=dict, hash=False)
    """validated values of every section as given, defaults filled in (degrees for the gait)"""
    source: str = field(default="<dict>", compare=False)
    """where the problem came from (file name or "<dict>")"""

    def __post_init__(self) -> None:
        for name, cls in (("robot", Robot), ("gait", Harmonic), ("hybrid", HybridOptions)):
            if not isinstance(getattr(self, name), cls):
                raise TypeError(f"Problem.{name} must be a {cls.__name__}, got {type(getattr(self, name)).__name__}")
        if self.drive not in DRIVES:
            raise ValueError(f"Problem.drive must be one of {DRIVES}, got {self.drive!r}")
        if self.gravity not in GRAVITY_CONVENTIONS:
            raise ValueError(f"Problem.gravity must be one of {GRAVITY_CONVENTIONS}, got {self.gravity!r}")
        object.__setattr__(self, "sections", _freeze(self.sections))

    @property
    def model(self) -> Model:
        return Model(self.robot, gravity=self.gravity)

    @property
    def torque(self) -> ReferenceTorque:
        """The torque input tau = k (phi_ref - pi) of eq. (tau) [N m]."""
        return ReferenceTorque(self.gait, self.robot.k)

    def with_values(self, values: Mapping[str, Any]) -> "Problem":
        """A new problem with typed values set: ``problem.with_values({"robot.mu1": 0.35, "gait.psi_deg": 30.0})``.

        Keys are ``SECTION.KEY`` of the schema (units as in the problem files); the new problem is
        validated as a whole, so a bad value raises ProblemError naming the key.  No text round trip.
        """
        if not isinstance(values, Mapping):
            raise TypeError(f"Problem.with_values needs a mapping of SECTION.KEY to values, got {type(values).__name__}")
        items = [(*split_key(k, f"{self.source}: {k}"), v) for k, v in values.items()]
        data, done = set_values(self.to_dict(), items, self.source)
        return _validate(data, _Context(self.source, done))

    def to_dict(self) -> dict:
        """Plain dict of the problem's sections (JSON- and TOML-friendly; ``problem_from_dict`` accepts it)."""
        out = _thaw(self.sections)
        # problems built in code without sections: report the objects themselves
        if "robot" not in out:
            r = self.robot
            out["robot"] = {"M": r.M, "L": r.L, "beta": r.beta, "k": r.k, "mu1": r.mu1, "mu2": r.mu2, "g": r.g}
        if "gait" not in out:
            g = self.gait
            out["gait"] = {"drive": self.drive, "gamma1_deg": math.degrees(g.gamma1), "gamma2_deg": math.degrees(g.gamma2),
                           "A1_deg": math.degrees(g.A1), "A2_deg": math.degrees(g.A2), "psi_deg": math.degrees(g.psi)}
        out.setdefault("model", {"gravity": self.gravity})
        out.setdefault("simulation", {k.name: getattr(self.hybrid, k.name) for k in SCHEMA["simulation"].keys})
        return out


# --------------------------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------------------------
def _fmt(value: Any) -> str:
    """A value as it would be written in TOML, shortened to keep messages on one line."""
    if isinstance(value, bool):
        s = "true" if value else "false"
    elif isinstance(value, str):
        s = json.dumps(value)
    elif isinstance(value, float):
        s = "nan" if math.isnan(value) else ("inf" if value == math.inf else "-inf" if value == -math.inf else repr(value))
    elif isinstance(value, Mapping):
        s = "{" + ", ".join(f"{k} = {_fmt(v)}" for k, v in value.items()) + "}"
    elif isinstance(value, (list, tuple)):
        s = "[" + ", ".join(_fmt(v) for v in value) + "]"
    else:
        s = str(value)
    return s if len(s) <= 60 else s[:57] + "..."


def format_value(value: Any) -> str:
    """A value as it would be written in TOML (strings quoted), shortened for one-line messages."""
    return _fmt(value)


def _toml_type(value: Any) -> str:
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, int):
        return "an integer"
    if isinstance(value, float):
        return "a number"
    if isinstance(value, Mapping):
        return "a table"
    if isinstance(value, (list, tuple)):
        return "an array"
    return f"a {type(value).__name__}"


def _suggest(name: str, valid: Sequence[str]) -> str:
    # case slips (Mu for mu) score lower with difflib than a shorter name (M), so they come first
    close = [v for v in valid if v.lower() == name.lower()] or \
        difflib.get_close_matches(name, list(valid), n=1, cutoff=0.6) or \
        sorted((v for v in valid if name.lower().startswith(v.lower())), key=len, reverse=True)
    return f"did you mean {close[0]}? " if close else ""


class _Context:
    """Where values came from, for messages: the file, and which keys were set on the command line."""

    def __init__(self, source: str, overridden: set[tuple[str, str]] | None = None):
        self.source = source
        self.overridden = overridden or set()

    def at(self, section: str, key: str, value: Any) -> str:
        origin = " (from --set)" if (section, key) in self.overridden else ""
        return f"{self.source}: [{section}] {key} = {_fmt(value)}{origin}"

    def error(self, msg: str) -> ProblemError:
        return ProblemError(f"{self.source}: {msg}")


def _check_value(ctx: _Context, section: str, key: Key, value: Any) -> Any:
    where = ctx.at(section, key.name, value)
    if key.type is str:
        if not isinstance(value, str):
            raise ProblemError(f"{where} is invalid: expected a string, {key.valid_text} ({key.what}), "
                               f"got {_toml_type(value)}")
        if key.choices and value not in key.choices:
            hint = _suggest(value, key.choices)
            raise ProblemError(f"{where} is invalid: {hint}must be {key.valid_text} ({key.what})")
        return value
    numeric = isinstance(value, (int, float)) and not isinstance(value, bool)
    if key.type is int and not (numeric and isinstance(value, int)):
        raise ProblemError(f"{where} is invalid: expected {_TYPE_WORDS[int]} ({key.what}), got {_toml_type(value)}")
    if key.type is float and not numeric:
        raise ProblemError(f"{where} is invalid: expected {_TYPE_WORDS[float]} ({key.what}), got {_toml_type(value)}")
    value = key.type(value)
    if not math.isfinite(value):
        raise ProblemError(f"{where} is invalid: must be finite ({key.what})")
    if key.rule is not None and not key.rule.test(value):
        raise ProblemError(f"{where} is invalid: must be {key.rule.text} ({key.what})")
    return value


def _check_section(ctx: _Context, section: Section, given: Mapping[str, Any]) -> dict[str, Any]:
    keys = section.key_map
    for name, value in given.items():
        if name not in keys:
            hint = _suggest(name, list(keys))
            raise ctx.error(f"[{section.name}] unknown key {name} = {_fmt(value)}; {hint}"
                            f"valid keys: {', '.join(keys)}")
    out: dict[str, Any] = {}
    for key in section.keys:
        if key.name in given:
            out[key.name] = _check_value(ctx, section.name, key, given[key.name])
    # pairing rules before missing keys: "mu1 without mu2" says more than "mu is missing"
    for key in section.keys:
        name = key.name
        if name not in given:
            continue
        for other in key.exclusive_with:
            if other in given:
                raise ProblemError(f"{ctx.at(section.name, name, given[name])} and {other} = "
                                   f"{_fmt(given[other])} are mutually exclusive: give {name}, or "
                                   f"{' and '.join(key.exclusive_with)}")
        for other in key.requires:
            if other not in given:
                raise ProblemError(f"{ctx.at(section.name, name, given[name])} is given without {other}: "
                                   f"give both {name} and {other} ({key.what})")
    for key in section.keys:
        name = key.name
        if name in given:
            continue
        if key.required and not (key.required_unless and all(u in given for u in key.required_unless)):
            alt = f" (or {' and '.join(key.required_unless)})" if key.required_unless else ""
            raise ctx.error(f"[{section.name}] {name} is missing (no value given): required{alt}, "
                            f"{key.valid_text} ({key.what})")
        elif key.default is not None:
            out[name] = key.default
    return out


def _check_contact(ctx: _Context, model: Model, gait: Harmonic, drive: str, values: Mapping) -> None:
    """A starting configuration (or, prescribed, any phase) with a foot off the ground is bad input."""
    gait_keys = [k for k in values["gait"] if k.endswith("_deg")]
    blame = ", ".join(f"{k} = {_fmt(values['gait'][k])}" for k in gait_keys)
    blame = f"[gait] {blame} (with [robot] beta = {_fmt(values['robot']['beta'])})"
    try:
        model.check_contact(gait(0.0), where="reference angles at phase 0")
    except ValueError as exc:
        raise ctx.error(f"{blame} are invalid: {exc}") from None
    if drive != "angles":
        return
    t = np.linspace(0.0, 1.0, CONTACT_GRID)
    kin = model.kinematics(gait(t))
    bad = np.nonzero(~((kin["d"] > 0) & (kin["fn1"] > 0) & (kin["fn2"] > 0)))[0]
    if bad.size:
        j = int(bad[0])
        try:
            model.check_contact(gait(t[j]), where=f"prescribed angles at phase {t[j]:.4f}")
            detail = f"prescribed angles at phase {t[j]:.4f}: contact lost"
        except ValueError as exc:
            detail = str(exc)
        raise ctx.error(f"{blame} are invalid for the angles drive: {detail} (both feet must stay on the "
                        "ground over the whole cycle)")


def _validate(data: Mapping[str, Any], ctx: _Context) -> Problem:
    if not isinstance(data, Mapping):
        raise ctx.error(f"a problem must be a table of sections, got {_toml_type(data)}")
    for name, value in data.items():
        if name not in SCHEMA and not isinstance(value, Mapping):
            raise ctx.error(f"top-level key {name} = {_fmt(value)} is not in a section: keys belong in a "
                            f"section, one of {', '.join(f'[{s}]' for s in SCHEMA)}")
        if name not in SCHEMA:
            hint = _suggest(name, list(SCHEMA))
            raise ctx.error(f"unknown section [{name}] = {_fmt(value)}; {hint}valid sections: "
                            f"{', '.join(SCHEMA)}")
        if not isinstance(value, Mapping):
            raise ctx.error(f"{name} = {_fmt(value)} is not a section: keys belong in a table [{name}] "
                            f"(got {_toml_type(value)})")
    values: dict[str, dict[str, Any]] = {}
    for section in SECTIONS:
        if section.name not in data and section.required:
            need = ", ".join(k.name for k in section.keys if k.required)
            raise ctx.error(f"section [{section.name}] is missing (no value given): required, with keys {need}")
        values[section.name] = _check_section(ctx, section, data.get(section.name, {}))

    r, g, sim = values["robot"], values["gait"], values["simulation"]
    mu1, mu2 = (r["mu"], r["mu"]) if "mu" in r else (r["mu1"], r["mu2"])
    # the schema has checked every value the constructors check, so their errors would be internal bugs
    robot = Robot(M=r["M"], L=r["L"], beta=r["beta"], k=r["k"], mu1=mu1, mu2=mu2, g=r["g"])
    gait = Harmonic.from_degrees(g.get("gamma_deg"), g.get("A_deg"), g["psi_deg"], gamma1_deg=g.get("gamma1_deg"),
                                 gamma2_deg=g.get("gamma2_deg"), A1_deg=g.get("A1_deg"), A2_deg=g.get("A2_deg"))
    hybrid = HybridOptions(**{k: sim[k] for k in sim})
    problem = Problem(robot=robot, gait=gait, drive=g["drive"], gravity=values["model"]["gravity"], hybrid=hybrid,
                      sections=values, source=ctx.source)
    _check_contact(ctx, problem.model, gait, problem.drive, values)
    return problem


# --------------------------------------------------------------------------------------------
# overrides, files, dicts
# --------------------------------------------------------------------------------------------
_KEY_RE = re.compile(r"^\s*([A-Za-z0-9_-]+)\.([A-Za-z0-9_-]+)\s*$")


def split_key(dotted: str, where: str) -> tuple[str, str]:
    """``"SECTION.KEY"`` as (section, key) of the schema, or ProblemError naming ``where``."""
    m = _KEY_RE.match(dotted) if isinstance(dotted, str) else None
    if not m:
        shown = _fmt(dotted.strip()) if isinstance(dotted, str) else repr(dotted)
        raise ProblemError(f"{where} is invalid: the key {shown} must be SECTION.KEY, e.g. robot.k=0.05")
    section, name = m.groups()
    if section not in SCHEMA:
        hint = _suggest(section, list(SCHEMA))
        raise ProblemError(f"{where} is invalid: unknown section [{section}]; {hint}valid sections: {', '.join(SCHEMA)}")
    keys = SCHEMA[section].key_map
    if name not in keys:
        hint = _suggest(name, list(keys))
        raise ProblemError(f"{where} is invalid: unknown key {name} in [{section}]; {hint}valid keys: {', '.join(keys)}")
    return section, name


def parse_override(text: str, source: str = "--set") -> tuple[str, str, Any]:
    """Parse ``SECTION.KEY=VALUE`` (VALUE a TOML value; a bare word is accepted for string keys)."""
    if not isinstance(text, str):
        raise ProblemError(f"{source}: --set {text!r} is invalid: expected SECTION.KEY=VALUE, e.g. robot.k=0.05")
    where = f"{source}: --set {_fmt(text)}"
    if "=" not in text:
        raise ProblemError(f"{where} is invalid: expected SECTION.KEY=VALUE, e.g. robot.k=0.05")
    lhs, rhs = text.split("=", 1)
    section, name = split_key(lhs, where)
    key = SCHEMA[section].key_map[name]
    rhs = rhs.strip()
    if not rhs or "\n" in rhs or "\r" in rhs:
        raise ProblemError(f"{where} is invalid: the value must be one TOML value, e.g. {section}.{name}="
                           f"{_fmt(key.default if key.default is not None else (key.choices or (1.0,))[0])}")
    try:
        parsed = tomllib.loads(f"v = {rhs}")
        if set(parsed) != {"v"}:
            raise tomllib.TOMLDecodeError("more than one value")
        value = parsed["v"]
    except tomllib.TOMLDecodeError:
        if key.type is not str:
            raise ProblemError(f"{where} is invalid: {_fmt(rhs)} is not a TOML value; expected "
                               f"{_TYPE_WORDS[key.type]} ({key.what})") from None
        value = rhs
    return section, name, value


def set_values(data: Mapping[str, Any], items: Iterable[tuple[str, str, Any]], source: str = "<dict>"
               ) -> tuple[dict[str, Any], set[tuple[str, str]]]:
    """Copy of ``data`` with typed values set, in order: ``items`` are (section, key, value) triples.

    Setting one of two alternative keys (``mu`` and ``mu1``/``mu2``) removes the other.  Returns the
    new data and the set keys.  Values are validated later, when the problem is built.
    """
    out = {k: dict(v) if isinstance(v, Mapping) else v for k, v in data.items()}
    done: set[tuple[str, str]] = set()
    for section, name, value in items:
        sec = out.setdefault(section, {})
        if not isinstance(sec, dict):
            raise ProblemError(f"{source}: {section}.{name} cannot be set: {section} is not a section in the file")
        for other in SCHEMA[section].key_map[name].exclusive_with:
            sec.pop(other, None)
        if section == "robot" and name in ("mu1", "mu2") and "mu" in sec:
            # one foot's friction changed on a robot given one mu: the other foot keeps mu
            sec.setdefault("mu1" if name == "mu2" else "mu2", sec["mu"])
        for key in SCHEMA[section].keys:
            if name in key.exclusive_with:
                sec.pop(key.name, None)
        sec[name] = value.item() if isinstance(value, np.generic) else value
        done.add((section, name))
    return out, done


def apply_overrides(data: Mapping[str, Any], overrides: Sequence[str], source: str = "<dict>"
                    ) -> tuple[dict[str, Any], set[tuple[str, str]]]:
    """Copy of ``data`` with ``SECTION.KEY=VALUE`` overrides (text, as ``--set``) applied; also returns the
    overridden keys."""
    if isinstance(overrides, str):
        overrides = [overrides]
    items = [parse_override(text, source) for text in overrides]
    for (section, _, _), text in zip(items, overrides):
        if not isinstance(data.get(section, {}), Mapping):
            raise ProblemError(f"{source}: --set {_fmt(text)} is invalid: {section} is not a section in the file")
    return set_values(data, items, source)


def problem_from_dict(data: Mapping[str, Any], source: str = "<dict>", overrides: Sequence[str] = ()) -> Problem:
    """Validate a dict shaped like a problem file (sections of keys) and build the :class:`Problem`."""
    if not isinstance(data, Mapping):
        raise ProblemError(f"{source}: a problem must be a table of sections, got {_toml_type(data)}")
    data, overridden = apply_overrides(data, overrides, source)
    return _validate(data, _Context(source, overridden))


def read_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file; unreadable files and malformed TOML raise ProblemError (with the offending line)."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ProblemError(f"{path}: cannot read the problem file: {reason}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ProblemError(f"{path}: cannot read the problem file: not UTF-8 text (byte {exc.start})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg = str(exc)
        m = re.search(r"line (\d+)", msg)
        line = ""
        if m:
            lines = text.splitlines()
            n = int(m.group(1))
            if 1 <= n <= len(lines):
                line = f": {_fmt(lines[n - 1].strip())}"
        raise ProblemError(f"{path}: malformed TOML: {msg}{line}") from None


def load_problem(path: str | Path, overrides: Sequence[str] = ()) -> Problem:
    """Load and validate a TOML problem file, applying ``SECTION.KEY=VALUE`` overrides (``--set``)."""
    return problem_from_dict(read_toml(path), source=str(path), overrides=overrides)


# --------------------------------------------------------------------------------------------
# running
# --------------------------------------------------------------------------------------------
def run_problem(problem: Problem, t_eval=None) -> CrawlResult:
    """Simulate the problem: event-driven solver for the torque drive, prescribed angles otherwise."""
    if not isinstance(problem, Problem):
        raise TypeError(f"run_problem needs a Problem, got {type(problem).__name__}")
    if problem.drive == "torque":
        return simulate_torque(problem.model, problem.torque, problem.hybrid, t_eval=t_eval)
    return simulate_angles(problem.model, problem.gait, t_eval=t_eval)


#: The paper's robot (Table I) and gait (gamma 90, A 30, psi 45 deg); same values as problems/paper_gait.toml.
PAPER_GAIT: Mapping[str, Mapping[str, Any]] = _freeze({
    "robot": {"M": 0.052, "L": 0.120, "beta": 2.0, "k": 0.1677, "mu": 0.389, "g": 9.81},
    "gait": {"drive": "torque", "gamma_deg": 90.0, "A_deg": 30.0, "psi_deg": 45.0},
    "model": {"gravity": "physical"},
})


def paper_problem(overrides: Sequence[str] = ()) -> Problem:
    """The paper's gait as a Problem, built in code (available without the problems/ directory)."""
    return problem_from_dict(_thaw(PAPER_GAIT), source="<paper gait>", overrides=overrides)
