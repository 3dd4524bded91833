"""The input of a problem's ``[gait]`` section: harmonic, Fourier series, samples (inline or a CSV
file), pulses, pressures of the ``[pressure]`` actuator.

``[gait] waveform`` selects the keys (schema: ``Key.variants``); :func:`gait_input` turns the
validated values into the reference angles [rad] and, for torque samples, the joint torques [N m]
themselves.  Sample files follow the package's CSV convention (:mod:`ocp_crawl.io.tables`): a header
with the unit in every column name, ``phase [-]`` and either ``tau1 [N m]``, ``tau2 [N m]`` or
``phi1_ref [deg]``, ``phi2_ref [deg]``, optionally ``period [s]`` (the same on every row: the
``[gait] period`` of the samples, as the ``torques.csv`` of ``optimize --out`` carries it); an error
names the file and the line.  Relative file names are read from the directory of the problem file.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ocp_crawl.io.tables import TableError, read_table
from ocp_crawl.model.inputs import FourierSeries, Harmonic, PeriodicSignal, TorqueReference
from ocp_crawl.model.sampled import (MAX_KNOTS, JointLinear, JointPchip, JointSpline,
                                     PeriodicLinear, PeriodicPchip, PeriodicSpline)
from ocp_crawl.model.pressure import (FITTED_REST_DEG, FLAT_REST_DEG, BendingMap, PressureReference,
                                      PressureWaveform)
from ocp_crawl.model.pulse import Pulse
from ocp_crawl.problem.messages import format_value
from ocp_crawl.problem.keys import ProblemError

#: the interpolations of sampled waveforms and the fewest samples each needs over one period
INTERPOLANTS = {"pchip": (PeriodicPchip, 3), "linear": (PeriodicLinear, 2),
                "spline": (PeriodicSpline, 3)}
#: the same interpolations of a chain's joints (any number of rows)
JOINT_INTERPOLANTS = {"pchip": JointPchip, "linear": JointLinear, "spline": JointSpline}
#: most harmonics of a Fourier waveform (per joint and kind)
MAX_HARMONICS = 100
#: the phase column of a sample file (its other columns: :func:`sample_columns`)
PHASE_COLUMN = {"phase": "dimensionless"}
#: the optional column of a sample file giving the period of one cycle (the same on every row)
PERIOD_COLUMN = {"period": "time"}
#: relative tolerance of a closing sample at phase 1 against the sample at phase 0 (files keep ~17
#: digits)
CLOSING_RTOL = 1e-9
#: smallest distance of two sample phases [cycles] (also across the end of the cycle): closer
#: samples make the interpolants' slopes overflow or their knots coincide
MIN_PHASE_GAP = 1e-9

#: ``at(section, key, value)``: the message prefix naming the file, the key and the value
At = Callable[[str, str, Any], str]


@dataclass(frozen=True)
class GaitInput:
    """The signals of a ``[gait]`` section."""

    reference: PeriodicSignal
    """reference angles phi_ref [rad] (for torque samples: pi + tau/k)"""
    torque: PeriodicSignal | None
    """joint torques [N m] when the waveform gives them directly; None: tau = k (phi_ref - pi)"""
    values: dict
    """the section's values as validated (a sample file's name resolved to an absolute path, its
    period column as ``period``)"""


def _joint(g: Mapping[str, Any], name: str) -> tuple[float, float]:
    """Per-joint degrees of ``name`` (``gamma``, ``A``): ``name1_deg`` / ``name2_deg`` over
    ``name_deg``."""
    return tuple(g.get(f"{name}{i}_deg", g.get(f"{name}_deg")) for i in (1, 2))


def _fourier(g: Mapping[str, Any], at: At) -> FourierSeries:
    arrays = [np.radians(g[f"{kind}{i}_deg"]) for i in (1, 2) for kind in ("cos", "sin")]
    for (i, kind), arr in zip(((1, "cos"), (1, "sin"), (2, "cos"), (2, "sin")), arrays):
        if arr.size > MAX_HARMONICS:
            raise ProblemError(f"{at('gait', f'{kind}{i}_deg', g[f'{kind}{i}_deg'])} is invalid: "
                               f"{arr.size} harmonics, at most {MAX_HARMONICS}")
    n = max(1, max(arr.size for arr in arrays))
    a, b = np.zeros((2, n)), np.zeros((2, n))
    for i in (0, 1):
        a[i, :arrays[2 * i].size] = arrays[2 * i]
        b[i, :arrays[2 * i + 1].size] = arrays[2 * i + 1]
    return FourierSeries(np.radians(_joint(g, "gamma")), a, b)


def check_pulse_fits(g: Mapping[str, Any], at: At) -> None:
    """ProblemError unless a pulse's two edges and high level fit in one cycle."""
    if not 2 * g["rise"] + g["hold"] <= 1:
        raise ProblemError(f"{at('gait', 'rise', g['rise'])} and hold = {format_value(g['hold'])} "
                           f"are invalid: 2 rise + hold = {2 * g['rise'] + g['hold']:g} must be <= "
                           "1 (two edges and the high level fit in one cycle)")


def _pulse(g: Mapping[str, Any], at: At) -> Pulse:
    check_pulse_fits(g, at)
    (g1, g2), (a1, a2) = _joint(g, "gamma"), _joint(g, "A")
    return Pulse(math.radians(g1), math.radians(g2), math.radians(a1), math.radians(a2),
                 math.radians(g["psi_deg"]), g["rise"], g["hold"], g["ramp"])


@dataclass(frozen=True)
class _Samples:
    """Samples over one period before the checks: phases, values (2, N) in SI units, and where row j
    is."""

    phase: np.ndarray
    values: np.ndarray
    torque: bool
    """True: joint torques [N m]; False: reference angles [rad]"""
    where: Callable[[int], str]
    """the message prefix naming row j (file and line, or the key and the entry)"""
    names: tuple[str, ...]


def _sample_columns(joints: int) -> tuple[dict[str, str], dict[str, str]]:
    """The torque and the reference-angle columns of a sample file of ``joints`` joints:
    ``tau1 .. tau<m> [N m]``, ``phi1_ref .. phi<m>_ref [deg]``."""
    return ({f"tau{j}": "torque" for j in range(1, joints + 1)},
            {f"phi{j}_ref": "angle" for j in range(1, joints + 1)})


def _listed(columns: Mapping[str, str]) -> str:
    unit = {"torque": "N m", "angle": "deg"}
    return ", ".join(f"'{n} [{unit[d]}]'" for n, d in columns.items())


def _sample_file(g: Mapping[str, Any], at: At, base: Path,
                joints: int = 2) -> tuple[_Samples, str, float | None]:
    """The samples of ``g["file"]`` for ``joints`` joints, its resolved path and the period of its
    ``period [s]`` column (None: none)."""
    path = Path(g["file"]).expanduser()
    path = path if path.is_absolute() else base / path
    torques, angles = _sample_columns(joints)
    try:
        table = read_table(path, PHASE_COLUMN, {**torques, **angles, **PERIOD_COLUMN},
                           min_rows=2)
    except TableError as exc:
        raise ProblemError(f"{at('gait', 'file', g['file'])} is invalid: {exc}") from None
    sets = [cols for cols in (torques, angles) if any(c in table for c in cols)]
    if len(sets) != 1 or not all(c in table for c in sets[0]):
        have = ", ".join(f"'{n} [{u}]'" for n, u in table.units.items())
        raise ProblemError(f"{at('gait', 'file', g['file'])} is invalid: {path}: needs 'phase [-]' "
                           f"and either {_listed(torques)} or {_listed(angles)} (header has "
                           f"{have})")
    cols = list(sets[0])
    # noqa: E731
    where = lambda j: f"{at('gait', 'file', g['file'])} is invalid: {path}:{table.line_of(j)}"
    samples = _Samples(table["phase"], np.array([table[c] for c in cols]),
                       sets[0] is torques, where, tuple(cols))
    return samples, str(path.resolve()), _file_period(table, where)


def _file_period(table, where: Callable[[int], str]) -> float | None:
    """The period [s] of a sample table's ``period`` column, one positive number on every row; None
    without it."""
    if "period" not in table:
        return None
    column = table["period"]
    for j, value in enumerate(column):
        if not value > 0:
            raise ProblemError(f"{where(j)}: period {float(value)!r} s must be > 0 (the duration "
                               "of one cycle)")
        if value != column[0]:
            raise ProblemError(f"{where(j)}: period {float(value)!r} s differs from "
                               f"{float(column[0])!r} s on the first row: the column gives the one "
                               "period of the cycle")
    return float(column[0])


def _period(g: Mapping[str, Any], file_period: float | None, at: At) -> float | None:
    """The samples' period [s]: ``[gait] period`` and the file's period column agree (to
    :data:`CLOSING_RTOL`) when both are given; either one alone is the period."""
    given = g.get("period")
    if (given is not None and file_period is not None and abs(given - file_period) > CLOSING_RTOL
        * file_period):
        raise ProblemError(f"{at('gait', 'period', given)} is invalid: the sample file {g['file']} "
                           f"gives the period {file_period!r} s in its period column: give one "
                           "period (drop the key or the column)")
    return given if given is not None else file_period


def _inline(g: Mapping[str, Any], at: At) -> _Samples:
    pair = ("tau1", "tau2") if "tau1" in g else ("phi1_ref_deg",
                                                 "phi2_ref_deg") if "phi1_ref_deg" in g else None
    if "phase" not in g or pair is None:
        given = ", ".join(k for k in ("phase", "tau1", "tau2", "phi1_ref_deg", "phi2_ref_deg")
                          if k in g)
        raise ProblemError(f"{at('gait', 'waveform', 'samples')} needs file, or phase with tau1 "
                           "and tau2 (or phi1_ref_deg and phi2_ref_deg) (given: "
                           f"{given or 'none of them'})")
    # the rows are counted per period in _periodic; there is no row to name here
    if not g["phase"]:
        raise ProblemError(f"{at('gait', 'phase', g['phase'])} is invalid: no samples (phases of "
                           f"one cycle, with {pair[0]} and {pair[1]} at them)")
    for name in pair:
        if len(g[name]) != len(g["phase"]):
            raise ProblemError(f"{at('gait', name, g[name])} is invalid: {len(g[name])} entries "
                               f"where phase has {len(g['phase'])} (one value per phase)")
    torque = pair[0] == "tau1"
    values = np.array([g[pair[0]], g[pair[1]]], dtype=float)
    return _Samples(np.array(g["phase"], dtype=float), values if torque else np.radians(values),
                    torque,
                    lambda j: f"{at('gait', 'phase', g['phase'])} is invalid: entry {j}", pair)


def _periodic(s: _Samples, interpolation: str) -> tuple[np.ndarray, np.ndarray]:
    """Phases in [0, 1) and values of one period: sorted, unique, a closing sample at phase 1
    repeating the sample at phase 0 dropped; anything else is a ProblemError naming the row."""
    t, v = s.phase, s.values
    for j in range(t.size):
        if not 0 <= t[j] <= 1:
            raise ProblemError(f"{s.where(j)}: phase {float(t[j])!r} outside [0, 1] (phases of one "
                               "cycle)")
        if j and not t[j] > t[j - 1]:
            raise ProblemError(f"{s.where(j)}: phase {float(t[j])!r} after {float(t[j - 1])!r}: "
                               "phases must be sorted and unique")
        if j and t[j] - t[j - 1] < MIN_PHASE_GAP and not (t[j] == 1.0 and j == t.size - 1):
            raise ProblemError(f"{s.where(j)}: phase {float(t[j])!r} after {float(t[j - 1])!r}: "
                               f"phases must be at least {MIN_PHASE_GAP:g} cycles apart (the "
                               "interpolants divide by their differences)")
    if t[-1] == 1.0:
        scale = max(float(np.max(np.abs(v))), np.finfo(float).tiny)
        gap = np.abs(v[:, -1] - v[:, 0])
        if t[0] != 0.0 or np.any(gap > CLOSING_RTOL * scale):
            first = ", ".join(f"{n} {float(a)!r}" for n, a in zip(s.names, v[:, 0]))
            last = ", ".join(f"{n} {float(a)!r}" for n, a in zip(s.names, v[:, -1]))
            raise ProblemError(f"{s.where(t.size - 1)}: not periodic: the sample at phase 1 must "
                               f"repeat the sample at phase 0 (phase {float(t[0])!r}: {first}; "
                               f"phase 1: {last}), or give phases in [0, 1) only")
        t, v = t[:-1], v[:, :-1]
    if t.size and t[0] + 1.0 - t[-1] < MIN_PHASE_GAP:
        raise ProblemError(f"{s.where(t.size - 1)}: phase {float(t[-1])!r} is less than "
                           f"{MIN_PHASE_GAP:g} cycles before phase {float(t[0])!r} of the next "
                           "cycle: phases must be at least that far apart")
    cls, fewest = INTERPOLANTS[interpolation]
    if t.size > MAX_KNOTS:
        raise ProblemError(f"{s.where(t.size - 1)}: {t.size} samples in one period, at most "
                           f"{MAX_KNOTS}: each sample is work of the solvers in every cycle (a "
                           "kink where the event-driven stepper stops, for linear interpolation)")
    if t.size < fewest:
        raise ProblemError(f"{s.where(t.size - 1)}: {t.size} samples in one period; interpolation "
                           f"{format_value(interpolation)} needs at least {fewest}")
    return t, v


def _check_angles(s: _Samples) -> None:
    """Reference angles inside the geometry: each in (0, 360) deg, the limits of the harmonic
    keys."""
    bad = np.argwhere(~((s.values > 0) & (s.values < 2 * math.pi)))
    if bad.size:
        i, j = (int(x) for x in bad[0])
        angle = math.degrees(float(s.values[i, j]))
        raise ProblemError(f"{s.where(j)}: {s.names[i]} = {angle!r} deg outside (0, 360) deg "
                           "(an interior joint angle)")


def file_samples(g: Mapping[str, Any], at: At, base: Path, values: dict,
                 joints: int = 2) -> _Samples:
    """The samples of the file ``g["file"]`` of ``joints`` joints; ``values`` (the section's) get
    the file's resolved name and the period (the key's or the file's column)."""
    samples, values["file"], file_period = _sample_file(g, at, base, joints)
    period = _period(g, file_period, at)
    if period is not None:
        values["period"] = period
    return samples


def driven_samples(s: _Samples, interpolation: str, drive: str,
                   at: At) -> tuple[np.ndarray, np.ndarray]:
    """The phases and values of one period (:func:`_periodic`) of samples that the drive
    can take (torques drive torques only; reference angles inside the geometry)."""
    if s.torque and drive != "torque":
        angles = ", ".join(f"phi{n.removeprefix('tau')}_ref" for n in s.names)
        raise ProblemError(f"{at('gait', 'drive', drive)} is invalid with torque samples "
                           f"({', '.join(s.names)}): prescribed angles need reference angles "
                           f"({angles})")
    if not s.torque:
        _check_angles(s)
    return _periodic(s, interpolation)


def _samples(g: Mapping[str, Any], k: float, drive: str, at: At, base: Path) -> GaitInput:
    values = dict(g)
    samples = file_samples(g, at, base, values) if "file" in g else _inline(g, at)
    t, v = driven_samples(samples, g["interpolation"], drive, at)
    signal = INTERPOLANTS[g["interpolation"]][0](t, v)
    if samples.torque:
        return GaitInput(TorqueReference(signal, k), signal, values)
    return GaitInput(signal, None, values)


def pressure_reference(g: Mapping[str, Any], pressure: Mapping[str, Any], gravity: str,
              at: At) -> PressureReference:
    """The reference angles of the pressure-driven robot: the ``[pressure]`` actuator at
    ``[gait] p0_bar``, ``psi_deg`` (:func:`ocp_crawl.model.pressure.pressure_torque` with k
    (phi_ref - pi) the torque)."""
    paper = pressure["form"] == "paper"
    rest = pressure.get("phi_rest_deg", FLAT_REST_DEG if paper else FITTED_REST_DEG[gravity])
    # the raised sine has none: p0 is its peak
    amplitude = pressure["amplitude_bar"] if paper else None
    try:
        waveform = PressureWaveform(g["p0_bar"], math.radians(g["psi_deg"]), amplitude)
    except ValueError:
        raise ProblemError(f"{at('gait', 'p0_bar', g['p0_bar'])} is invalid with [pressure] "
                           f"amplitude_bar = {format_value(amplitude)}: the amplitude must be at "
                           "most p0 (the pressure p0 - amplitude must not be negative)") from None
    bending = BendingMap(*(pressure[name] for name in ("a1", "a2", "b1", "b2")))
    return PressureReference(waveform, math.radians(rest), bending)


def gait_input(g: Mapping[str, Any], k: float, at: At, base: Path,
               pressure: Mapping[str, Any] | None = None, gravity: str = "physical") -> GaitInput:
    """The signals of the validated ``[gait]`` values ``g`` (schema checked, defaults filled in).

    Parameters
    ----------
    g : mapping
        The section's values (degrees, cycles, N m as in the problem file).
    k : float
        Joint stiffness [N m/rad] (reference angles of torque samples: pi + tau/k).
    at : callable
        ``at(section, key, value)``: the message prefix naming the file, key and value.
    base : Path
        Directory that relative sample-file names are read from (the problem file's).
    pressure : mapping, optional
        The validated ``[pressure]`` values (defaults filled in), read by the ``pressure`` waveform.
    gravity : str
        The gravity convention (the rest angle of the ``raised`` pressure form depends on it).

    Returns
    -------
    GaitInput
        Reference angles [rad], the torques [N m] if the waveform gives them, the values (file
        resolved).

    Raises
    ------
    ProblemError
        A waveform that is not periodic, not finite, unsorted, outside the geometry or an unreadable
        file.
    """
    waveform = g["waveform"]
    if waveform == "samples":
        return _samples(g, k, g["drive"], at, base)
    if waveform == "fourier":
        return GaitInput(_fourier(g, at), None, dict(g))
    if waveform == "pulse":
        return GaitInput(_pulse(g, at), None, dict(g))
    if waveform == "pressure":
        return GaitInput(pressure_reference(g, pressure, gravity, at), None, dict(g))
    (g1, g2), (a1, a2) = _joint(g, "gamma"), _joint(g, "A")
    gait = Harmonic.from_degrees(gamma1_deg=g1, gamma2_deg=g2, A1_deg=a1, A2_deg=a2,
                                 psi_deg=g["psi_deg"])
    return GaitInput(gait, None, dict(g))


def samples_problem(problem: Mapping[str, Mapping[str, Any]], file: str,
                    interpolation: str = "pchip") -> dict:
    """A problem dict that drives ``problem``'s robot (and gravity convention) with the torques or
    reference angles of the sample file ``file`` (the ``samples`` waveform, torque drive, default
    simulation options).

    ``problem``: sections as ``Problem.to_dict()``; ``file``: the CSV file, relative to where the
    problem file will be written; ``interpolation``: one of :data:`INTERPOLANTS`.  Returns the
    sections ``robot``, ``gait`` and ``model``.
    """
    if interpolation not in INTERPOLANTS:
        raise ValueError(f"interpolation must be one of {tuple(INTERPOLANTS)}, got "
                         f"{interpolation!r}")
    return {"robot": dict(problem["robot"]),
            "gait": {"drive": "torque", "waveform": "samples", "file": str(file),
                     "interpolation": interpolation},
            "model": dict(problem.get("model", {}))}


def waveform_text(g: Mapping[str, Any]) -> str:
    """One line describing a ``[gait]`` section's input: the harmonic keys in degrees
    (``gamma = 90 deg, ...``), preceded by the waveform's name and its own settings for the other
    waveforms."""
    degrees = ", ".join(f"{k[:-4]} = {v:g} deg" for k, v in g.items() if k.endswith("_deg") and
                        isinstance(v, (int, float)))
    waveform = g.get("waveform", "harmonic")
    if waveform == "harmonic":   # (a chain's per-joint lists after the common values)
        joints = [f"{k[:-4]} = [{', '.join(f'{x:g}' for x in g[k])}] deg"
                  for k in ("gamma_joints_deg", "A_joints_deg") if k in g]
        return ", ".join([degrees, *joints])
    if waveform == "fourier":
        order = max(len(g.get(f"{kind}{i}_deg", ())) for kind in ("cos", "sin") for i in (1, 2))
        own = f"order {order}"
    elif waveform == "pulse":
        own = f"rise {g['rise']:g}, hold {g['hold']:g} cycles, {g['ramp']} edges"
    elif waveform == "pressure":
        own = f"p0 = {g['p0_bar']:g} bar"
    else:
        where = g["file"] if "file" in g else f"{len(g.get('phase', ()))} inline samples"
        own = f"{where}, {g.get('interpolation')} interpolation"
    return f"{waveform} ({own})" + (f": {degrees}" if degrees else "")
