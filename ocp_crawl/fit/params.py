"""The parameters a calibration can fit: problem-file keys and the pressure actuator's constants.

A parameter is named like a problem key, ``SECTION.KEY`` (``robot.k``, ``robot.mu``, ``robot.mu1``,
``gait.gamma_deg``, ...: any number of the ``[robot]`` and ``[gait]`` sections, and of any section
the schema gains that is not a numerics setting), ``SECTION.KEY[i]`` for entry i of an array of
numbers the problem gives (a chain's ``robot.stiffness[0]``, ``robot.lengths[2]``), or
``pressure.NAME``, a key of the ``[pressure]`` section, for the pressure-driven robot of
:mod:`ocp_crawl.model.pressure`: ``pressure.a1``, ``pressure.a2`` [rad/bar^2], ``pressure.b1``,
``pressure.b2`` [rad/bar] (Table I's map), ``pressure.phi_rest_deg`` [deg] (the rest angle) and
``pressure.amplitude_bar`` [bar] (the waveform's amplitude A_p).  The pressure constants are those
of the problem's ``[pressure]`` section as given, else those of the input ``form``
(:func:`ocp_crawl.model.pressure.form_constants`): the default form is the pressure study's, the
paper's form (ref), p0 + A_p sin(2 pi t +- psi/2) with p0 the nominal (mean) pressure, A_p = 0.4
bar and the flat rest shape, 180 deg; ``form="raised"`` is the earlier raised sine from 0 to the
peak p0 (no amplitude, NaN) with the stored fitted rest angle.
Values are in the units of the problem files (degrees for angles).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Callable, Iterable, Mapping, Sequence

from ocp_crawl.model.pressure import (DEFAULT_FORM, PRESSURE_FORMS, BendingMap, PressureWaveform,
                                      form_constants)
from ocp_crawl.problem import Problem, ProblemError
from ocp_crawl.problem.messages import suggest
from ocp_crawl.problem.keys import Rule
from ocp_crawl.problem.overrides import entry, entry_value
from ocp_crawl.problem.schema import SCHEMA

#: pressure parameters -> unit
PRESSURE_UNITS = {"a1": "rad/bar^2", "a2": "rad/bar^2", "b1": "rad/bar", "b2": "rad/bar",
                  "phi_rest_deg": "deg", "amplitude_bar": "bar"}
#: sections whose numbers are settings of the numerics, not properties of the robot or its input
NOT_FITTED = ("model", "simulation", "ocp")
#: sections whose numbers can be fitted (every other section of the schema, e.g. ones added for new
#: inputs)
FIT_SECTIONS = tuple(name for name in SCHEMA if name not in NOT_FITTED)
#: default bounds: x0 +- this for angles [deg]; x0 / and * this factor for the others
ANGLE_SPAN_DEG, SCALE_FACTOR = 45.0, 10.0
#: bisection steps that pull a default bound into the valid range of its parameter
CLIP_STEPS = 60


def _amplitude_ok(v: float) -> bool:
    """The pressure model's own check of an amplitude
    (:class:`~ocp_crawl.model.pressure.PressureWaveform`), at the largest nominal pressure it allows
    (each row's p0 is checked with the rows)."""
    try:
        PressureWaveform(max(v, 0.0), 0.0, v)
    except ValueError:
        return False
    return True


#: pressure constants whose values the pressure model restricts -> the rule (the others: any finite
#: number)
PRESSURE_RULES = {"amplitude_bar": Rule(_amplitude_ok, ">= 0",
                                        "the amplitude A_p of the paper's form (ref), at most "
                                                                 "each row's p0")}


@dataclass(frozen=True)
class Parameter:
    """One fitted parameter: its name, unit, start value and bounds (problem-file units)."""

    name: str
    unit: str
    """unit of the values (problem-file units, e.g. N m/rad, deg)"""
    x0: float
    """start value"""
    low: float
    """lower bound"""
    high: float
    """upper bound"""

    def __post_init__(self) -> None:
        if not (math.isfinite(self.low) and math.isfinite(self.high)
                and self.low <= self.x0 <= self.high and self.low < self.high):
            raise ValueError(f"Parameter {self.name}: start {float(self.x0)!r} must lie in bounds "
                             f"[{float(self.low)!r}, {float(self.high)!r}] with low < high, all "
                             "finite")


def fittable_names() -> list[str]:
    """Every name :func:`resolve_parameters` accepts of any problem (a problem's array entries,
    :func:`array_entries`, besides)."""
    keys = [f"{s}.{k.name}" for s in FIT_SECTIONS for k in SCHEMA[s].keys if k.type is float]
    return list(dict.fromkeys(keys + [f"pressure.{n}" for n in PRESSURE_UNITS]))


def array_entries(problem: Problem) -> list[str]:
    """The entries ``SECTION.KEY[i]`` of the arrays of numbers ``problem`` gives in a fitted
    section (a chain's ``robot.stiffness[1]``, ``robot.lengths[0]``, ...)."""
    out = []
    # (the pressure section's array, the joints' segments, is a choice of the model, not a number)
    for section in (s for s in FIT_SECTIONS if s != "pressure"):
        for key in SCHEMA[section].keys:
            value = problem.sections.get(section, {}).get(key.name)
            if key.type is list and isinstance(value, (list, tuple)):
                out += [f"{section}.{key.name}[{i}]" for i in range(len(value))]
    return out


def pressure_defaults(gravity: str, form: str = DEFAULT_FORM) -> dict[str, float]:
    """The pressure constants used when not fitted: Table I's map and the waveform constants of
    ``form`` (:func:`ocp_crawl.model.pressure.form_constants`: rest angle [deg], amplitude [bar] or
    NaN); ValueError for an unknown form."""
    return {**{f.name: getattr(BendingMap(), f.name) for f in dataclasses.fields(BendingMap)},
            **form_constants(form, gravity)}


def pressure_form(problem: Problem, form: str | None = None) -> str:
    """The pressure input form of a fit: ``form`` (``--form``), else the problem's
    ``[pressure] form`` as given, else :data:`~ocp_crawl.model.pressure.DEFAULT_FORM`; ProblemError
    for an unknown form or one that differs from the problem's."""
    if form is not None and form not in PRESSURE_FORMS:
        raise ProblemError(f"--form {form}: unknown pressure input form; one of "
                           f"{', '.join(PRESSURE_FORMS)}")
    given = problem.given_dict().get("pressure", {}).get("form")
    if form is not None and given is not None and form != given:
        raise ProblemError(f"--form {form} and {problem.source}: [pressure] form = \"{given}\" "
                           "differ: give one (the problem file's, or drop the key)")
    return form or given or DEFAULT_FORM


def problem_pressure(problem: Problem, form: str | None = None) -> dict[str, float]:
    """The pressure constants of ``problem`` (:data:`PRESSURE_UNITS`): those its ``[pressure]``
    section gives, the others :func:`pressure_defaults` of its form (:func:`pressure_form`)."""
    given = problem.given_dict().get("pressure", {})
    return {**pressure_defaults(problem.gravity, pressure_form(problem, form)),
            **{k: float(v) for k, v in given.items() if k in PRESSURE_UNITS}}


def _schema_key(name: str) -> tuple[str, str]:
    """(section, key) of a parameter name, an array entry's index dropped (``robot.stiffness[1]``:
    ``("robot", "stiffness")``)."""
    section, key = name.split(".", 1)
    return section, entry(key)[0]


def value_rule(name: str) -> tuple[Rule | None, str]:
    """The rule every value of the parameter ``name`` must pass (None: any finite number) and what
    it is: the schema's rule of a problem key (the one ``Problem.with_values`` applies; an array's
    entry: the array's rule of each entry); for a pressure constant :data:`PRESSURE_RULES`, else
    its key's in ``[pressure]``."""
    section, key = _schema_key(name)
    if section == "pressure":
        rule = PRESSURE_RULES.get(key) or SCHEMA["pressure"].key_map[key].rule
        return rule, f"pressure constant, {PRESSURE_UNITS[key]}"
    k = SCHEMA[section].key_map[key]
    return k.rule, k.what


def check_value(name: str, value: float, what: str) -> None:
    """ProblemError naming ``what`` (the option and the value given) if ``value`` is outside the
    valid range of the parameter ``name``."""
    rule, help_text = value_rule(name)
    if rule is not None and not rule.test(value):
        raise ProblemError(f"{what} is invalid: {name} ({help_text}) must be {rule.explained}")


def _clip(valid: Callable[[float], bool], end: float, x0: float) -> float:
    """``end`` if valid, else the valid value nearest it between it and the valid ``x0`` (bisection,
    then the roundest such value: 0 rather than 1e-17)."""
    if valid(end):
        return end
    bad, good = end, x0
    for _ in range(CLIP_STEPS):
        mid = 0.5 * (bad + good)
        bad, good = (bad, mid) if valid(mid) else (mid, good)
    for digits in range(16):
        r = round(good, digits)
        if min(end, x0) <= r <= max(end, x0) and abs(r - x0) >= abs(good - x0) and valid(r):
            return r
    return good


def _exclusive(names: Sequence[str]) -> None:
    """ProblemError for two fitted keys the schema gives as alternatives (``robot.mu`` and
    ``robot.mu1``/``mu2``)."""
    for name in names:
        section, key = _schema_key(name)
        if section == "pressure":
            continue
        others = SCHEMA[section].key_map[key].exclusive_with
        clash = [f"{section}.{o}" for o in others if f"{section}.{o}" in names]
        if clash:
            raise ProblemError(f"--param {name} and --param {clash[0]}: alternative keys of "
                               f"[{section}] (fit {name}, or "
                               f"{' and '.join(f'{section}.{o}' for o in others)}), not both")


def _current(problem: Problem, name: str, form: str | None) -> tuple[float | None, str]:
    section, key = name.split(".", 1)
    if section == "pressure":
        return problem_pressure(problem, form)[key], PRESSURE_UNITS[key]
    values = problem.sections.get(section, {})
    unit = SCHEMA[section].key_map[entry(key)[0]].unit
    value = entry_value(values, key)
    if value is None and key in ("mu1", "mu2"):
        value = values.get("mu")
    if value is None and key.endswith(("1_deg", "2_deg")):
        value = values.get(key[:-5] + "_deg")
    return value, unit


def _default_bounds(x0: float, unit: str) -> tuple[float, float]:
    if unit == "deg":
        return x0 - ANGLE_SPAN_DEG, x0 + ANGLE_SPAN_DEG
    if x0 > 0:
        return x0 / SCALE_FACTOR, x0 * SCALE_FACTOR
    span = max(abs(x0) * SCALE_FACTOR, 1.0)
    return x0 - span, x0 + span


def _pairs(items: Sequence[str], option: str) -> dict[str, str]:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ProblemError(f"{option} {item!r}: expected NAME=VALUE")
        out[name.strip()] = value.strip()
    return out


def _number(text: str, what: str) -> float:
    try:
        x = float(text)
    except ValueError:
        x = math.nan
    if not math.isfinite(x):
        raise ProblemError(f"{what}: {text!r} is not a finite number")
    return x


def resolve_parameters(problem: Problem, names: Sequence[str], start: Sequence[str] = (),
                       bounds: Sequence[str] = (), form: str | None = None) -> list[Parameter]:
    """The parameters to fit, checked: names, start values and bounds.

    Parameters
    ----------
    problem : Problem
        The problem whose values are the start values (pressure constants:
        :func:`problem_pressure`).
    names : sequence of str
        ``SECTION.KEY`` names (see the module docstring), or ``SECTION.KEY[i]``, entry i (from 0)
        of an array the problem gives (a chain's ``robot.stiffness[1]``), each once.
    start : sequence of str
        ``NAME=VALUE`` start values replacing the problem's (problem-file units).
    bounds : sequence of str
        ``NAME=LOW:HIGH`` bounds, both in the parameter's valid range; default x0 +- 45 deg for
        angles, [x0/10, 10 x0] for positive numbers, each end pulled into the valid range
        (``gait.A_deg`` = 30: [0, 75]).
    form : str, optional
        The pressure input form whose constants are the default start values of ``pressure.*``
        (:data:`ocp_crawl.model.pressure.PRESSURE_FORMS`; None: the problem's,
        :func:`pressure_form`).

    Returns
    -------
    list of Parameter

    Raises
    ------
    ProblemError
        An unknown or repeated name (with a suggestion), alternative keys fitted together
        (``robot.mu`` and ``robot.mu1``), a start or bound that is not a number or outside the valid
        range of the parameter (the schema's rule of its key, :data:`PRESSURE_RULES`), a start
        outside its bounds, start values the problem rejects together (``Problem.with_values``), an
        unknown form.
    """
    pressure_form(problem, form)
    valid = fittable_names() + array_entries(problem)
    if not names:
        raise ProblemError(f"no parameter to fit: give --param NAME (one of {', '.join(valid)})")
    starts = {k: _number(v, f"--start {k}") for k, v in _pairs(start, "--start").items()}
    limits = _pairs(bounds, "--bounds")
    for option, given in (("--param", names), ("--start", starts), ("--bounds", limits)):
        for name in given:
            if name not in valid:
                raise ProblemError(f"{option} {name}: unknown parameter; "
                                   f"{suggest(name, valid)}fittable: {', '.join(valid)}")
    for name in [*starts, *limits]:
        if name not in names:
            raise ProblemError(f"{name}: a start value or bounds for a parameter not fitted (add "
                               f"--param {name})")
    if len(set(names)) != len(names):
        raise ProblemError(f"--param: a parameter named twice in {', '.join(names)}")
    _exclusive(names)
    params = [_parameter(problem, name, starts, limits, form) for name in names]
    keys, _ = split_values(params, [p.x0 for p in params])
    if keys:
        try:
            problem.with_values(keys)
        except ProblemError as exc:
            shown = ", ".join(f"{k} = {v:g}" for k, v in keys.items())
            raise ProblemError(f"--param {', '.join(keys)}: the start values ({shown}) are "
                               f"invalid: {exc}") from None
    return params


def _parameter(problem: Problem, name: str, starts: Mapping[str, float], limits: Mapping[str, str],
               form: str | None) -> Parameter:
    value, unit = _current(problem, name, form)
    if name in starts:
        value = starts[name]
    if value is None or math.isnan(value):
        raise ProblemError(f"--param {name}: no value to start from (the problem file gives none, "
                           f"or the {pressure_form(problem, form)} form has no such constant); "
                           f"give --start {name}=VALUE")
    check_value(name, value, f"--start {name}={value:g}" if name in starts else
                f"--param {name}: the start value {value:g} {unit}")
    rule, _ = value_rule(name)
    low, high = _default_bounds(float(value), unit)
    # the default bounds end in the valid range (A_deg = 30: [0, 75], not [-15, 75])
    if rule is not None:
        low, high = _clip(rule.test, low, float(value)), _clip(rule.test, high, float(value))
    if name in limits:
        lo, sep, hi = limits[name].partition(":")
        if not sep:
            raise ProblemError(f"--bounds {name}={limits[name]}: expected LOW:HIGH")
        low, high = _number(lo, f"--bounds {name} low"), _number(hi, f"--bounds {name} high")
        for end, x in (("low", low), ("high", high)):
            check_value(name, x, f"--bounds {name}={limits[name]}: the {end} end {x:g}")
    if not low < high or not low <= value <= high:
        raise ProblemError(f"--param {name}: start value {value:g} {unit} must lie within bounds "
                           f"[{low:g}, {high:g}] with low < high")
    return Parameter(name, unit, float(value), float(low), float(high))


def split_values(params: Sequence[Parameter], x: Iterable[float]) -> tuple[dict[str, float],
                                                                           dict[str, float]]:
    """(problem key -> value, pressure constant -> value) of the parameter vector ``x``."""
    keys: dict[str, float] = {}
    pressure: dict[str, float] = {}
    for p, v in zip(params, x):
        section, key = p.name.split(".", 1)
        (pressure if section == "pressure" else keys)[key if section == "pressure"
                                                      else p.name] = float(v)
    return keys, pressure


def at_bound(p: Parameter, x: float, rtol: float = 1e-4) -> bool:
    """True if ``x`` lies within ``rtol`` of the bound interval's width from a bound of ``p`` (the
    fit was stopped there: its uncertainty is not a confidence interval)."""
    tol = rtol * (p.high - p.low)
    return x <= p.low + tol or x >= p.high - tol


def fixed_pressure(items: Sequence[str]) -> dict[str, float]:
    """``NAME=VALUE`` texts of pressure constants held fixed (``a1``, ..., ``phi_rest_deg``) ->
    values; ProblemError for an unknown name, a value that is not a number or is outside the
    constant's valid range (:data:`PRESSURE_RULES`)."""
    out = {}
    for name, text in _pairs(items, "--pressure").items():
        key = name.removeprefix("pressure.")
        if key not in PRESSURE_UNITS:
            raise ProblemError(f"--pressure {name}: unknown pressure constant; "
                               f"{suggest(key, list(PRESSURE_UNITS))}one of "
                               f"{', '.join(PRESSURE_UNITS)}")
        out[key] = _number(text, f"--pressure {name}")
        check_value(f"pressure.{key}", out[key], f"--pressure {name}={text}")
    return out
