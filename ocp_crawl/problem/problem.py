"""The validated :class:`Problem`: robot, gait, drive, gravity convention, solver and its options.

Every bad input raises :class:`~ocp_crawl.problem.keys.ProblemError` with a one-line message that
names the file, the ``[section] key``, the value given and what is valid, for example::

    problems/x.toml: [robot] k = -1.0 is invalid: must be > 0 (torsion stiffness, N m/rad)
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping, Sequence, cast

import numpy as np

from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_inputs import ChainReferenceTorque
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.inputs import Harmonic, PeriodicSignal, ReferenceTorque
from ocp_crawl.problem import chain_robot
from ocp_crawl.problem.waveforms import gait_input
from ocp_crawl.model.statics import GRAVITY_CONVENTIONS, GravityConvention, Model, Robot
from ocp_crawl.problem.overrides import apply_overrides, read_toml, set_values, split_key
from ocp_crawl.problem.messages import format_value, suggest, toml_type
from ocp_crawl.problem.keys import ProblemError, Section, field_default
from ocp_crawl.problem.schema import DRIVES, SCHEMA, SECTIONS, Drive, removed_key
from ocp_crawl.problem.robot_checks import (check_chain_contact, check_contact,
                                            check_stiffness_ratio)
from ocp_crawl.problem.values import Context, check_value
from ocp_crawl.sim import DEFAULT_SOLVER, MUJOCO_SOLVERS, solver_named, unusable


def freeze(d: Mapping) -> Mapping:
    """A read-only copy of nested mappings."""
    return MappingProxyType({k: freeze(v) if isinstance(v, Mapping) else v for k, v in d.items()})


def thaw(d: Mapping) -> dict:
    """A plain, mutable copy of nested mappings."""
    return {k: thaw(v) if isinstance(v, Mapping) else v for k, v in d.items()}


def solver_options(solver: str, values: Mapping[str, Any]):
    """The options dataclass of the registry's ``solver`` from ``[simulation]`` values (its fields
    only; the others keep their defaults)."""
    cls = solver_named(solver).options
    names = {f.name for f in dataclasses.fields(cls)}
    return cls(**{k: v for k, v in values.items() if k in names})


def chain_section(chain: Chain) -> dict[str, Any]:
    """``[robot]`` of a chain as a problem file gives it (SI units, rest bends in degrees)."""
    return {"lengths": list(chain.lengths), "masses": list(chain.masses),
            "stiffness": list(chain.stiffness), "com": list(chain.com),
            "rest_deg": [math.degrees(x) for x in chain.rest], "mu1": chain.mu1,
            "mu2": chain.mu2, "g": chain.g}


@dataclass(frozen=True)
class Problem:
    """A validated simulation problem: robot, gait, drive, gravity convention, solver and its
    options."""

    robot: Robot | Chain
    """physical parameters (SI units): the symmetric three-link robot, or an n-link chain
    (``[robot] lengths``)"""
    gait: PeriodicSignal
    """reference angles [rad] (a :class:`Harmonic` for the default waveform); the values as given
    are in ``sections["gait"]``"""
    drive: Drive = SCHEMA["gait"].key_map["drive"].default
    """actuation: "torque" (tau = k (phi_ref - pi)) or "angles" (phi = phi_ref prescribed)"""
    gravity: GravityConvention = field_default(Model, "gravity")
    """sign convention of the gravity term (see MODEL_NOTES erratum)"""
    solver: str | None = None
    """name in the registry :data:`ocp_crawl.sim.SOLVERS`; None: the drive's default ("event" for
    the torque drive, "angles" for the angles drive)"""
    options: Any = None
    """the solver's options dataclass (``SOLVERS[solver].options``); None: its defaults"""
    sections: Mapping[str, Mapping[str, Any]] = field(default_factory=dict, hash=False)
    """validated values of every section as given, defaults filled in (degrees for the gait)"""
    source: str = field(default="<dict>", compare=False)
    """where the problem came from (file name or "<dict>")"""
    input_torque: PeriodicSignal | None = None
    """joint torques [N m] given directly (samples of torques, e.g. an ``optimize`` result); None:
    the torque drive's tau = k (phi_ref - pi) of ``gait``"""
    given: Mapping[str, Mapping[str, Any]] | None = field(default=None, compare=False, hash=False)
    """the keys the problem was given (file, ``--set``, ``with_values``), validated, without the
    defaults of ``sections``; None: every key of ``sections`` (a problem built in code)"""

    def __post_init__(self) -> None:
        for name, cls in (("robot", (Robot, Chain)), ("gait", (PeriodicSignal,))):
            if not isinstance(getattr(self, name), cls):
                raise TypeError(f"Problem.{name} must be a {' or '.join(c.__name__ for c in cls)}"
                                f", got {type(getattr(self, name)).__name__}")
        if self.drive not in DRIVES:
            raise ValueError(f"Problem.drive must be one of {DRIVES}, got {self.drive!r}")
        joints = self.robot.n_joints if isinstance(self.robot, Chain) else 2
        if np.shape(self.gait(0.0)) != (joints,):
            raise ValueError(f"Problem.gait must have a row per joint of the robot ({joints}), got "
                             f"shape {np.shape(self.gait(0.0))}")
        if self.input_torque is not None and (self.drive != "torque"
                                              or not isinstance(self.input_torque,
                                                                PeriodicSignal)):
            raise ValueError("Problem.input_torque must be a PeriodicSignal of the torque drive, "
                             f"got {type(self.input_torque).__name__} with drive {self.drive!r}")
        if self.gravity not in GRAVITY_CONVENTIONS:
            raise ValueError(f"Problem.gravity must be one of {GRAVITY_CONVENTIONS}, got "
                             f"{self.gravity!r}")
        spec = solver_named(DEFAULT_SOLVER[self.drive] if self.solver is None else self.solver)
        if spec.drive != self.drive:
            raise ValueError(f"Problem.solver = {spec.name!r} simulates the {spec.drive} drive, "
                             f"not {self.drive!r}")
        if self.options is not None and not isinstance(self.options, spec.options):
            raise TypeError(f"Problem.options of solver {spec.name!r} must be "
                            f"{spec.options.__name__}, got {type(self.options).__name__}")
        object.__setattr__(self, "solver", spec.name)
        object.__setattr__(self, "options",
                           spec.options() if self.options is None else self.options)
        object.__setattr__(self, "sections", freeze(self.sections))
        if self.given is not None:
            object.__setattr__(self, "given", freeze(self.given))

    @property
    def period(self) -> float | None:
        """The duration of one cycle [s] (``[gait] period``, or the period column of a sample file);
        None when the problem gives none.  The quasistatic S per cycle does not depend on it; the
        mean speed is S / period."""
        value = self.sections.get("gait", {}).get("period")
        return None if value is None else float(value)

    def speed(self, S: float) -> float | None:
        """The mean speed |S| / period [m/s] of a gait that moves S [m] per cycle (its direction is
        the sign of S); None without a period or a finite S."""
        period = self.period
        return abs(S) / period if period is not None and math.isfinite(S) else None

    @property
    def is_chain(self) -> bool:
        """Whether the robot is an n-link :class:`~ocp_crawl.model.chain.Chain`."""
        return isinstance(self.robot, Chain)

    @property
    def model(self) -> Model | ChainModel:
        """The robot with the problem's gravity convention (a ChainModel for a chain)."""
        if isinstance(self.robot, Chain):
            return ChainModel(self.robot, gravity=self.gravity)
        return Model(self.robot, gravity=self.gravity)

    @property
    def torque(self) -> PeriodicSignal:
        """The torque input [N m]: ``input_torque`` if given, else tau = k (phi_ref - pi) of eq.
        (tau) (a chain: tau_j = k_j (phi_ref_j - pi - rest_j))."""
        if self.input_torque is not None:
            return self.input_torque
        if isinstance(self.robot, Chain):
            return ChainReferenceTorque(self.gait, self.robot)
        return ReferenceTorque(self.gait, self.robot.k)

    @property
    def signal(self) -> PeriodicSignal:
        """The input of the drive: joint torques [N m] (torque drive) or joint angles [rad] (angles
        drive)."""
        return self.torque if self.drive == "torque" else self.gait

    @property
    def hybrid(self):
        """Options of the event-driven stepper (HybridOptions): the solver's own for solver "event";
        else those in ``[simulation]`` (the stepper also finds the released start of every torque
        solver)."""
        if self.solver == "event":
            return self.options
        return solver_options("event", self.sections.get("simulation", {}))

    def with_values(self, values: Mapping[str, Any]) -> "Problem":
        """A new problem with typed values set:
        ``problem.with_values({"robot.mu1": 0.35, "gait.psi_deg": 30.0})``.

        Keys are ``SECTION.KEY`` of the schema (units as in the problem files), or
        ``SECTION.KEY[i]`` for entry i of an array the problem gives; the new problem is validated
        as a whole, so a bad value raises ProblemError naming the key.  No text round trip.
        """
        if not isinstance(values, Mapping):
            raise TypeError("Problem.with_values needs a mapping of SECTION.KEY to values, got "
                            f"{type(values).__name__}")
        items = [(*split_key(k, f"{self.source}: {k}"), v) for k, v in values.items()]
        data, _ = set_values(self.to_dict(), items, self.source)
        problem = _validate(data, Context(self.source))
        given, _ = set_values(self.given_dict(), items, self.source)
        return dataclasses.replace(problem, given=_given(problem.sections, given))

    def given_dict(self) -> dict:
        """The keys the problem was given, sections as ``to_dict()`` without the defaults filled in
        (a problem built in code: ``to_dict()``).  A problem file of these keys is this problem."""
        return thaw(self.given) if self.given is not None else self.to_dict()

    def to_dict(self) -> dict:
        """Plain dict of the problem's sections (JSON- and TOML-friendly; ``problem_from_dict``
        accepts it)."""
        out = thaw(self.sections)
        # problems built in code without sections: report the objects themselves
        r = self.robot
        if "robot" not in out and isinstance(r, Chain):
            out["robot"] = chain_section(r)
        elif "robot" not in out and isinstance(r, Robot):
            out["robot"] = {"M": r.M, "L": r.L, "beta": r.beta, "k": r.k, "mu1": r.mu1,
                            "mu2": r.mu2, "g": r.g}
        if "gait" not in out:
            g = self.gait
            if not isinstance(g, Harmonic):
                raise TypeError(f"a problem built in code with a {type(g).__name__} gait has no "
                                "problem-file form; build it from a problem file or dict "
                                "(gait.waveform)")
            out["gait"] = {"drive": self.drive, "gamma1_deg": math.degrees(g.gamma1),
                           "gamma2_deg": math.degrees(g.gamma2),
                           "A1_deg": math.degrees(g.A1), "A2_deg": math.degrees(g.A2),
                           "psi_deg": math.degrees(g.psi)}
        out.setdefault("model", {"gravity": self.gravity})
        out.setdefault("simulation", self._simulation_values())
        return out

    def _simulation_values(self) -> dict[str, Any]:
        """``[simulation]`` of a problem built in code: its solver's options, the others'
        defaults."""
        out = {key.name: getattr(self.options, key.name,
                                 getattr(self.hybrid, key.name, key.default))
               for key in SCHEMA["simulation"].keys if key.name != "solver"}
        solver = cast(str, self.solver)  # __post_init__ replaced None by the default solver
        named = "mujoco" if "mujoco" in solver else solver   # (MuJoCo: a row per drive)
        return {"solver": named if self.drive == "torque" or named == "mujoco"
                else DEFAULT_SOLVER["torque"], **out}


def _variant(ctx: Context, section: Section, given: Mapping[str, Any]) -> str | None:
    """The value of the section's selector key (``[gait] waveform``); keys of other variants are
    errors."""
    if section.selector is None:
        return None
    selector = section.key_map[section.selector]
    variant = check_value(ctx, section.name, selector, given.get(selector.name, selector.default))
    for name, value in given.items():
        key = section.key_map[name]
        if not section.applies(key, variant):
            own = [k.name for k in section.keys if k.variants and section.applies(k, variant)]
            owned = (f"the keys of {selector.name} = {format_value(variant)} are {', '.join(own)}"
                     if own else
                     f"{selector.name} = {format_value(variant)} has no keys of its own")
            raise ProblemError(f"{ctx.at(section.name, name, value)} is invalid with "
                               f"{selector.name} = {format_value(variant)}: it is a key of "
                               f"{selector.name} = "
                               f"{' or '.join(format_value(v) for v in key.variants)} "
                               f"({key.what}); {owned}")
    return variant


def _check_section(ctx: Context, section: Section, given: Mapping[str, Any]) -> dict[str, Any]:
    keys = section.key_map
    for name, value in given.items():
        if name not in keys:
            removed = removed_key(section.name, name)
            if removed is not None:
                raise ctx.error(f"{removed} (here {name} = {format_value(value)})")
            hint = suggest(name, list(keys))
            raise ctx.error(f"[{section.name}] unknown key {name} = {format_value(value)}; {hint}"
                            f"valid keys: {', '.join(keys)}")
    variant = _variant(ctx, section, given)
    out: dict[str, Any] = {}
    for key in section.keys:
        if key.name in given:
            out[key.name] = check_value(ctx, section.name, key, given[key.name])
    # pairing rules before missing keys: "mu1 without mu2" says more than "mu is missing"
    for key in section.keys:
        name = key.name
        if name not in given:
            continue
        for other in key.exclusive_with:
            if other in given:
                raise ProblemError(f"{ctx.at(section.name, name, given[name])} and {other} = "
                                   f"{format_value(given[other])} are mutually exclusive: give "
                                   f"{name}, or {' and '.join(key.exclusive_with)}")
        for other in key.requires:
            if other not in given:
                raise ProblemError(f"{ctx.at(section.name, name, given[name])} is given without "
                                   f"{other}: give both {name} and {other} ({key.what})")
    # a key that a given key excludes is not asked for (gamma_deg beside a chain's per-joint list)
    excluded = {o for name in given for o in keys[name].exclusive_with}
    for key in section.keys:
        name = key.name
        if name in given or name in excluded or not section.applies(key, variant):
            continue
        if key.required and not (key.required_unless
                                 and all(u in given for u in key.required_unless)):
            alt = f" (or {' and '.join(key.required_unless)})" if key.required_unless else ""
            if key.variants and section.selector is not None:
                alt += f" with {section.selector} = {format_value(variant)}"
            raise ctx.error(f"[{section.name}] {name} is missing (no value given): required{alt}, "
                            f"{key.valid_text} ({key.what})")
        elif key.default is not None:
            out[name] = list(key.default) if key.type is list else key.default
    return out


def _check_friction_set(ctx: Context, given: Mapping[str, Any]) -> None:
    """``[ocp] robust = "worst"`` asks for the worst over a friction set: without one (no
    ``mu_ratio_eps`` > 0, no ``mu_levels``, no robust_speed) it would be ignored, so it is an error
    (the mean of one scenario is its value)."""
    if given.get("robust") != "worst" or given.get("objective") == "robust_speed":
        return
    if given.get("mu_ratio_eps", 0) > 0 or "mu_levels" in given:
        return
    raise ProblemError(f"{ctx.at('ocp', 'robust', given['robust'])} needs a friction set: give "
                       "[ocp] "
                    f"mu_ratio_eps > 0 (the scenarios mu1/mu2 in {{1 - eps, 1, 1 + eps}}), "
                    "mu_levels or "
                    f'objective = "robust_speed"')


def _check_sections(data: Mapping[str, Any], ctx: Context) -> dict[str, dict[str, Any]]:
    """Every section's values checked, defaults filled in; unknown and misplaced sections
    rejected."""
    if not isinstance(data, Mapping):
        raise ctx.error(f"a problem must be a table of sections, got {toml_type(data)}")
    for name, value in data.items():
        if name not in SCHEMA and not isinstance(value, Mapping):
            raise ctx.error(f"top-level key {name} = {format_value(value)} is not in a section: "
                            "keys belong in a section, one of "
                            f"{', '.join(f'[{s}]' for s in SCHEMA)}")
        if name not in SCHEMA:
            hint = suggest(name, list(SCHEMA))
            raise ctx.error(f"unknown section [{name}] = {format_value(value)}; {hint}valid "
                            f"sections: {', '.join(SCHEMA)}")
        if not isinstance(value, Mapping):
            raise ctx.error(f"{name} = {format_value(value)} is not a section: keys belong in a "
                            f"table [{name}] (got {toml_type(value)})")
    values: dict[str, dict[str, Any]] = {}
    for section in SECTIONS:
        if section.name not in data and section.required:
            need = ", ".join(k.name for k in section.keys if k.required)
            raise ctx.error(f"section [{section.name}] is missing (no value given): required, with "
                            f"keys {need}")
        values[section.name] = _check_section(ctx, section, data.get(section.name, {}))
    _check_friction_set(ctx, data.get("ocp", {}))
    return values


def _solver(ctx: Context, drive: str, sim: Mapping[str, Any], gravity: str = "physical",
            chain: bool = False) -> str:
    """The registry name of the problem's solver, if it can run (``unusable``): ``[simulation]
    solver`` for the torque drive; the angles drive has its own, or ``mujoco`` (servos hold the
    angles); naming another is bad input."""
    name = MUJOCO_SOLVERS[drive] if sim["solver"] == "mujoco" else sim["solver"]
    if drive == "torque" or name != sim["solver"]:
        why = unusable(name, gravity, sim, chain)
        if why:
            raise ProblemError(f"{ctx.at('simulation', 'solver', sim['solver'])} {why}")
        return name
    default = SCHEMA["simulation"].key_map["solver"].default
    if sim["solver"] != default:
        raise ProblemError(f"{ctx.at('simulation', 'solver', sim['solver'])} is invalid with "
                           f"[gait] drive = {format_value(drive)}: the {drive} drive has its own "
                           f"solver ({DEFAULT_SOLVER[drive]}); [simulation] solver chooses the "
                           "simulator of the torque drive (or \"mujoco\")")
    return DEFAULT_SOLVER[drive]


def _given(values: Mapping[str, Mapping[str, Any]], data: Mapping[str, Any]) -> dict:
    """The validated ``values`` of the keys ``data`` gives (sections it gives, keys in the schema's
    order)."""
    return {name: {k: v for k, v in values[name].items() if k in data[name]} for name in values
            if name in data}


def _validate(data: Mapping[str, Any], ctx: Context) -> Problem:
    robot, gait = data.get("robot"), data.get("gait")
    if isinstance(robot, Mapping) and "lengths" in robot and isinstance(gait, Mapping):
        chain_robot.chain_waveform(ctx, gait)
    values = _check_sections(data, ctx)
    r, g, sim = values["robot"], values["gait"], values["simulation"]
    if chain_robot.is_chain(r):
        return _validate_chain(data, ctx, values)
    chain_robot.joint_keys_of_a_chain(ctx, g)
    chain_robot.segments_of_a_chain(ctx, values["pressure"])
    mu1, mu2 = chain_robot.feet_friction(r)
    # the schema has checked every value the constructors check, so their errors would be internal
    # bugs
    robot = Robot(M=r["M"], L=r["L"], beta=r["beta"], k=r["k"], mu1=mu1, mu2=mu2, g=r["g"])
    check_stiffness_ratio(ctx, robot, g["drive"])
    gravity = values["model"]["gravity"]
    signals = gait_input(g, robot.k, ctx.at, ctx.base, values["pressure"], gravity)
    values["gait"] = signals.values
    solver = _solver(ctx, g["drive"], sim, gravity)
    problem = Problem(robot=robot, gait=signals.reference, drive=g["drive"], gravity=gravity,
                      solver=solver, options=solver_options(solver, sim), sections=values,
                      source=ctx.source, input_torque=signals.torque, given=_given(values, data))
    check_contact(ctx, Model(robot, gravity=gravity), problem.gait, problem.drive, values)
    return problem


def _validate_chain(data: Mapping[str, Any], ctx: Context, values: dict) -> Problem:
    """The problem of a chain (:mod:`ocp_crawl.problem.chain_robot`)."""
    g, sim, gravity = values["gait"], values["simulation"], values["model"]["gravity"]
    if "s_error_tol" in data.get("simulation", {}):   # (ctx.at names --set too)
        raise ProblemError(f"{ctx.at('simulation', 's_error_tol', sim['s_error_tol'])} is "
                           "invalid with a chain ([robot] lengths): the chain's steps solve each "
                           "mode exactly and estimate no error of S")
    chain = chain_robot.chain_robot(ctx, values["robot"], data["robot"])
    # (defaults of the three-link robot's keys: no keys of a chain)
    values["robot"].pop("beta")
    values["simulation"].pop("s_error_tol")
    check_stiffness_ratio(ctx, chain, g["drive"])
    reference, values["gait"] = chain_robot.chain_gait(ctx, g, chain, values["pressure"], gravity)
    solver = _solver(ctx, g["drive"], sim, gravity, chain=True)
    problem = Problem(robot=chain, gait=reference, drive=g["drive"], gravity=gravity,
                      solver=solver, options=solver_options(solver, sim), sections=values,
                      source=ctx.source, given=_given(values, data))
    check_chain_contact(ctx, ChainModel(chain, gravity), reference, g["drive"], values)
    return problem


def problem_from_dict(data: Mapping[str, Any], source: str = "<dict>",
                      overrides: Sequence[str] = ()) -> Problem:
    """Validate a dict shaped like a problem file (sections of keys) and build the :class:`Problem`.

    Parameters
    ----------
    data : mapping
        Sections of keys as in a TOML problem file, e.g.
        ``{"robot": {"M": 0.052, "L": 0.12, "k": 0.1677, "mu": 0.389}, "gait": {"gamma_deg": 90,
        "A_deg": 30, "psi_deg":
        45}}``; every key in the unit of the key reference (kg, m, N m/rad, deg, ...); missing
        optional keys take their defaults.
    source : str
        Names the origin at the start of every error message (default ``"<dict>"``).
    overrides : sequence of str
        ``SECTION.KEY=VALUE`` texts applied on top of ``data``, as ``--set`` (the value parsed as
        TOML).

    Returns
    -------
    Problem
        The validated problem (``problem.model``, ``problem.signal``, ``problem.solver``, ...).

    Raises
    ------
    ProblemError
        Bad input (a ValueError), with a one-line message naming the source, key, value and what is
        valid.
    """
    if not isinstance(data, Mapping):
        raise ProblemError(f"{source}: a problem must be a table of sections, got "
                           f"{toml_type(data)}")
    for name, section in data.items():  # a file's names are strings; a dict's may be anything
        keys = list(section) if isinstance(section, Mapping) else []
        bad = [k for k in [name, *keys] if not isinstance(k, str)]
        if bad:
            where = "a section" if bad[0] is name else f"a key of [{name}]"
            raise ProblemError(f"{source}: {where} is named {bad[0]!r} ({type(bad[0]).__name__}): "
                               "section and key names are strings")
    data, overridden = apply_overrides(data, overrides, source)
    return _validate(data, Context(source, overridden))


def load_problem(path: str | Path, overrides: Sequence[str] = ()) -> Problem:
    """Load and validate a TOML problem file, applying ``SECTION.KEY=VALUE`` overrides (``--set``).

    Parameters
    ----------
    path : str or Path
        The problem file (TOML, at most 1 MiB); the shipped examples are written out by
        ``ocp-crawl init`` or found with :func:`ocp_crawl.problem.shipped.shipped_problem`.
    overrides : sequence of str
        ``SECTION.KEY=VALUE`` texts, e.g. ``["robot.k=0.2", "gait.drive=angles"]`` (values parsed as
        TOML, in the units of the file's keys).

    Returns
    -------
    Problem
        The validated problem; ``problem.source`` is ``str(path)``.

    Raises
    ------
    ProblemError
        An unreadable or malformed file, or an invalid key or value (one line naming the file and
        key).
    """
    return problem_from_dict(read_toml(path), source=str(path), overrides=overrides)
