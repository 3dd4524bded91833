"""The schema of problem files: every section and key with its type, unit, default and rule.

One table (:data:`SECTIONS`) lists every section and key; loading, ``--set`` overrides, error
messages and the README's key table (:func:`schema_markdown`) are all driven by it.  To add a
section (e.g. ``[sweep]``), append a :class:`Section`; its validated values (defaults filled in)
appear in ``Problem.sections[name]`` without any other change.

Defaults are defined once, on the dataclass field the key feeds (``Robot``, ``Model``, the options of
the registry's solvers, ``OCPSettings``); the schema reads them from there with :func:`field_default`.
"""
from __future__ import annotations

import dataclasses
import difflib
import json
import math
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Callable, Literal, Mapping, Sequence

from ocp_crawl.model.statics import GRAVITY_CONVENTIONS, Model, Robot
from ocp_crawl.ocp import OCPSettings
from ocp_crawl.sim import DEFAULT_SOLVER, SOLVERS

Drive = Literal["torque", "angles"]
DRIVES = ("torque", "angles")
#: the solvers a problem of the torque drive may name in ``[simulation] solver`` (the registry's torque solvers)
TORQUE_SOLVERS = tuple(name for name, spec in SOLVERS.items() if spec.drive == "torque")


class ProblemError(ValueError):
    """Bad problem input. The message is a single line naming the file, key, value and what is valid."""

    def __init__(self, message: str):
        # one line whatever the user typed (file names, string values)
        super().__init__(" ".join(str(message).split("\n")))


def field_default(cls: type, name: str) -> Any:
    """The default of the dataclass field ``name`` of ``cls`` (the one place a default is defined)."""
    for f in dataclasses.fields(cls):
        if f.name == name:
            if f.default is not dataclasses.MISSING:
                return f.default
            if f.default_factory is not dataclasses.MISSING:
                return f.default_factory()
            break
    raise AttributeError(f"{cls.__name__} has no field {name!r} with a default")


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
STEPS = Rule(lambda v: v >= 4, ">= 4")

TYPE_WORDS = {float: "a number", int: "an integer", str: "a string"}


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
        if self.type not in TYPE_WORDS:
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


def _robot(name: str):
    return field_default(Robot, name)


def _hybrid(name: str):
    return field_default(SOLVERS["event"].options, name)


def _ocp(name: str):
    value = field_default(OCPSettings, name)
    return "none" if value is None else value


_ROBOT = Section("robot", "physical parameters (paper Table I)", required=True, keys=(
    Key("M", float, "kg", "total mass", required=True, rule=GT0),
    Key("L", float, "m", "total length", required=True, rule=GT0),
    Key("beta", float, "-", "body-to-leg length ratio", default=_robot("beta"), rule=GT0),
    Key("k", float, "N m/rad", "torsion stiffness", required=True, rule=GT0),
    Key("mu", float, "-", "friction coefficient of both feet", required=True, rule=GE0,
        required_unless=("mu1", "mu2"), exclusive_with=("mu1", "mu2")),
    Key("mu1", float, "-", "friction coefficient of foot 1 (left)", rule=GE0, requires=("mu2",)),
    Key("mu2", float, "-", "friction coefficient of foot 2 (right)", rule=GE0, requires=("mu1",)),
    Key("g", float, "m/s^2", "gravitational acceleration", default=_robot("g"), rule=GT0),
))

_GAIT = Section("gait", "harmonic reference angles, eq. (ref)", required=True, keys=(
    Key("drive", str, "-", "actuation: spring torque tau = k (phi_ref - pi), or prescribed angles",
        default=DRIVES[0], choices=DRIVES),
    Key("gamma_deg", float, "deg", "nominal joint angle", required=True, rule=ANGLE,
        required_unless=("gamma1_deg", "gamma2_deg")),
    Key("A_deg", float, "deg", "amplitude", required=True, rule=GE0, required_unless=("A1_deg", "A2_deg")),
    Key("psi_deg", float, "deg", "phase lead of joint 1 over joint 2", required=True, rule=PHASE),
    Key("gamma1_deg", float, "deg", "nominal angle of joint 1 (overrides gamma_deg)", rule=ANGLE),
    Key("gamma2_deg", float, "deg", "nominal angle of joint 2 (overrides gamma_deg)", rule=ANGLE),
    Key("A1_deg", float, "deg", "amplitude of joint 1 (overrides A_deg)", rule=GE0),
    Key("A2_deg", float, "deg", "amplitude of joint 2 (overrides A_deg)", rule=GE0),
))

_MODEL = Section("model", "model conventions", keys=(
    Key("gravity", str, "-", "sign of the gravity term: physical (virtual work) or paper (as printed)",
        default=field_default(Model, "gravity"), choices=GRAVITY_CONVENTIONS),
))

_SIMULATION = Section("simulation", "simulator of the torque drive and its options", keys=(
    Key("solver", str, "-", "simulator of the torque drive: event-driven, or MPCC time-stepping (the angles "
        "drive has its own)", default=DEFAULT_SOLVER["torque"], choices=TORQUE_SOLVERS),
    Key("max_step", float, "cycles", "event solver: largest continuation step", default=_hybrid("max_step"),
        rule=MAX_STEP),
    Key("event_xtol", float, "cycles", "event solver: event location tolerance", default=_hybrid("event_xtol"),
        rule=GT0),
    Key("max_cycles", int, "-", "cycles before the gait is declared non-periodic",
        default=_hybrid("max_cycles"), rule=CYCLES),
    Key("periodic_tol", float, "rad", "periodicity tolerance (angles; f_t/(M g) likewise)",
        default=_hybrid("periodic_tol"), rule=GT0),
    Key("steps", int, "-", "mpcc solver: time steps per cycle", default=field_default(SOLVERS["mpcc"].options, "steps"),
        rule=STEPS),
))

_OCP = Section("ocp", "periodic-gait optimal control (ocp-crawl optimize)", keys=(
    Key("objective", str, "-", "what to optimise", default=_ocp("objective"),
        choices=("max_speed", "min_cot", "robust_speed")),
    Key("nodes", int, "-", "steps per cycle of the transcription", default=_ocp("nodes"),
        rule=Rule(lambda v: v >= 8, ">= 8")),
    Key("direction", int, "-", "sign of S to pursue (-1: towards foot 1, as psi > 0 gaits)", default=_ocp("direction"),
        rule=Rule(lambda v: v in (-1, 1), "-1 or 1")),
    Key("A_max_deg", float, "deg", "half-width of the reference-angle envelope around gait.gamma_deg",
        default=_ocp("A_max_deg"), rule=Rule(lambda v: 0 < v < 90, "in (0, 90)")),
    Key("parametrization", str, "-", "torques free at every node or a Fourier series",
        default=_ocp("parametrization"), choices=("free", "fourier")),
    Key("fourier_order", int, "-", "order of the Fourier series", default=_ocp("fourier_order"),
        rule=Rule(lambda v: v >= 1, ">= 1")),
    Key("rate_limit", str, "-", "torque rate limit: the harmonic envelope's peak rate, none, or max_rate",
        default=_ocp("rate_limit"), choices=("harmonic", "none", "max_rate")),
    Key("max_rate", float, "N m/cycle", "largest |d tau/dt| when rate_limit = \"max_rate\"", rule=GT0),
    Key("curvature_limit", str, "-", "limit on d^2 tau/dt^2: 4 x the harmonic envelope's peak, or none",
        default=_ocp("curvature_limit"), choices=("harmonic", "none")),
    Key("regularization", float, "-", "weight of the torque-change regularisation", default=_ocp("regularization"),
        rule=GE0),
    Key("tie_margin", float, "-", "friction-limit margin (fraction of M g) required for a foot to slip",
        default=_ocp("tie_margin"), rule=GE0),
    Key("S_min", float, "m", "min_cot: smallest progress direction * S per cycle", default=_ocp("S_min"), rule=GE0),
    Key("mu_ratio_eps", float, "-", "robust_speed: scenarios mu1/mu2 in {1 - eps, 1, 1 + eps}",
        default=_ocp("mu_ratio_eps"), rule=Rule(lambda v: 0 <= v < 1, "in [0, 1)")),
    Key("robust", str, "-", "robust_speed: maximise the mean or the worst S", default=_ocp("robust"),
        choices=("mean", "worst")),
    Key("harmonic_psi", int, "-", "psi values of the harmonic sweep (initial guess, comparison)",
        default=_ocp("harmonic_psi"), rule=Rule(lambda v: v >= 4, ">= 4")),
))

#: The schema: every section and key of a problem file, in the order they are validated and reported.
SECTIONS: tuple[Section, ...] = (_ROBOT, _GAIT, _MODEL, _SIMULATION, _OCP)

SCHEMA: Mapping[str, Section] = MappingProxyType({s.name: s for s in SECTIONS})


def _requirement(k: Key) -> str:
    if k.required and k.required_unless:
        req = "required unless " + " and ".join(f"`{u}`" for u in k.required_unless) + " given"
    elif k.required:
        req = "required"
    elif k.requires:
        req = "optional, with " + ", ".join(f"`{r}`" for r in k.requires)
    elif k.default is None:
        req = "optional"
    else:
        req = f"default `{format_value(k.default)}`"
    if k.exclusive_with:
        req += "; not with " + ", ".join(f"`{e}`" for e in k.exclusive_with)
    return req


def schema_markdown() -> str:
    """The schema as a Markdown table (section, key, type, unit, required/default, valid values, meaning)."""
    rows = ["| key | type | unit | required / default | valid | meaning |", "|---|---|---|---|---|---|"]
    for sec in SECTIONS:
        for k in sec.keys:
            kind = {float: "float", int: "int", str: "string"}[k.type]
            rows.append(f"| `{sec.name}.{k.name}` | {kind} | {k.unit} | {_requirement(k)} | {k.valid_text} | {k.help} |")
    return "\n".join(rows)


# --------------------------------------------------------------------------------------------
# values in messages
# --------------------------------------------------------------------------------------------
def format_value(value: Any) -> str:
    """A value as it would be written in TOML (strings quoted), shortened to keep messages on one line."""
    if isinstance(value, bool):
        s = "true" if value else "false"
    elif isinstance(value, str):
        s = json.dumps(value)
    elif isinstance(value, float):
        s = "nan" if math.isnan(value) else ("inf" if value == math.inf else "-inf" if value == -math.inf else repr(value))
    elif isinstance(value, Mapping):
        s = "{" + ", ".join(f"{k} = {format_value(v)}" for k, v in value.items()) + "}"
    elif isinstance(value, (list, tuple)):
        s = "[" + ", ".join(format_value(v) for v in value) + "]"
    else:
        s = str(value)
    return s if len(s) <= 60 else s[:57] + "..."


def toml_type(value: Any) -> str:
    """What a value is, in TOML's words ("a boolean", "a table", ...), for messages."""
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


def suggest(name: str, valid: Sequence[str]) -> str:
    """"did you mean X? " for the valid name closest to ``name``, or ""."""
    # case slips (Mu for mu) score lower with difflib than a shorter name (M), so they come first
    close = [v for v in valid if v.lower() == name.lower()] or \
        difflib.get_close_matches(name, list(valid), n=1, cutoff=0.6) or \
        sorted((v for v in valid if name.lower().startswith(v.lower())), key=len, reverse=True)
    return f"did you mean {close[0]}? " if close else ""
