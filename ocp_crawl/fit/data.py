"""Measurement files of a calibration: which experiment a CSV table holds, read and checked.

Every file follows the package's CSV convention (:mod:`ocp_crawl.io.tables`: units in the header,
``#`` comments, errors naming file and line).  A file holds one observable with its standard
uncertainty (one sigma, same unit) and the operating point of every row:

=============  ==================================  =================================================
kind           columns                             model of a row
=============  ==================================  =================================================
``gait``       ``S`` or ``S_norm``, and any of     S per cycle of the problem's gait (its drive),
               ``psi``, ``A``, ``gamma`` [angle]   with the row's values of ``gait.psi_deg``,
                                                   ``gait.A_deg``, ``gait.gamma_deg``
``pressure``   ``S`` or ``S_norm``, ``p0``         S per cycle of the pressure-driven robot
               [pressure] and ``psi`` [angle],     (:mod:`ocp_crawl.model.pressure`) at nominal
               optionally ``A_p`` [pressure]       pressure p0 (the peak of the raised sine) and
                                                   phase difference psi; ``A_p``: the row's
                                                   amplitude of the paper's form (ref), in place of
                                                   the constant ``pressure.amplitude_bar``
``stiffness``  ``phi`` [angle], ``tau`` [torque]   clamped segment: edge angle phi = tau / k
``bending``    ``phi`` [angle], ``p`` [pressure],  clamped segment: phi = a_i p^2 + b_i p
               ``segment`` [-] (1 or 2)            (Table I map)
=============  ==================================  =================================================

Every value must be finite and at most 1e12 in magnitude once converted to SI (:data:`MAX_SI`);
every uncertainty at least 1e-12 x max(the largest |value| of the observable column, 1 in SI units)
(:data:`SIGMA_FLOOR`): smaller ones make the weighted residuals and their Jacobian overflow.

``S_norm`` is S divided by S at the file's reference row, the row of the largest ``S_norm``
(normally 1): the model is normalised the same way, by its own S at that row, so that the
(unknown) scale of the measured S drops out, and with it whatever sets only that scale.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Mapping, cast

import numpy as np

from ocp_crawl.io.tables import UNITS, Table, TableError, read_table
from ocp_crawl.problem.schema import SCHEMA

#: observable column -> its dimension (each file holds exactly one, with ``sigma_<name>``)
OBSERVABLES = {"S": "length", "S_norm": "dimensionless", "phi": "angle"}
#: operating-point columns -> dimension
INPUTS = {"psi": "angle", "A": "angle", "gamma": "angle", "p0": "pressure", "A_p": "pressure",
          "tau": "torque", "p": "pressure", "segment": "dimensionless"}
#: gait columns -> the problem key they set (degrees, as in problem files)
GAIT_KEYS = {"psi": "gait.psi_deg", "A": "gait.A_deg", "gamma": "gait.gamma_deg"}
#: every column a measurement file may hold -> dimension
COLUMNS: Mapping[str, str] = {**OBSERVABLES, **{"sigma_" + k: v for k, v in OBSERVABLES.items()},
                              **INPUTS}
#: kind -> operating-point columns whose values must pass the rule of a problem key (the schema's
#: ranges): a gait row's keys, and a pressure row's phase difference, which has the range of the
#: gait's
RULE_KEYS = {"gait": GAIT_KEYS, "pressure": {"psi": GAIT_KEYS["psi"]}}
#: kind -> (observables allowed, inputs required, inputs allowed)
KINDS: dict[str, tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]] = {
    "pressure": (("S", "S_norm"), ("p0", "psi"), ("p0", "psi", "A_p")),
    "gait": (("S", "S_norm"), (), ("psi", "A", "gamma")),
    "stiffness": (("phi",), ("tau",), ("tau",)),
    "bending": (("phi",), ("p", "segment"), ("p", "segment")),
}
#: units in which observables are reported and plotted (name -> (unit, factor from SI))
DISPLAY = {"S": ("mm", 1e3), "S_norm": ("-", 1.0), "phi": ("deg", 180.0 / np.pi)}
#: largest magnitude of any value of a measurement file in SI units (m, rad, Pa, N m, -): far beyond
#: any measurement, small enough that squares, weighted residuals and their Jacobian stay finite
MAX_SI = 1e12
#: smallest uncertainty, relative to max(largest |value| of the observable column, 1 SI unit): a
#: smaller sigma makes the weighted residuals (model - y) / sigma and their Jacobian overflow or
#: drown in round-off
SIGMA_FLOOR = 1e-12
#: the SI unit of every column, for messages
SI_NAMES = {"length": "m", "angle": "rad", "pressure": "Pa", "torque": "N m", "dimensionless": "-"}


@dataclass(frozen=True)
class Measurements:
    """One measurement file, checked: the observable, its sigma and the operating point of every row
    (SI)."""

    table: Table = field(repr=False)
    kind: str
    """``gait``, ``pressure``, ``stiffness`` or ``bending`` (see the module docstring)"""
    observable: str
    """``S`` [m], ``S_norm`` [-] or ``phi`` [rad]"""

    @property
    def path(self) -> str:
        return self.table.path

    @property
    def y(self) -> np.ndarray:
        """measured values (SI)"""
        return self.table[self.observable]

    @property
    def sigma(self) -> np.ndarray:
        """their standard uncertainties (SI, > 0)"""
        return self.table["sigma_" + self.observable]

    @property
    def inputs(self) -> tuple[str, ...]:
        return tuple(n for n in INPUTS if n in self.table)

    @property
    def reference_row(self) -> int | None:
        """Row whose model S normalises the others (``S_norm`` files), else None."""
        return int(np.argmax(self.y)) if self.observable == "S_norm" else None

    @property
    def abscissa(self) -> str:
        """The input varying most across the rows (the x axis of the figure)."""
        spans = {n: float(np.ptp(self.table[n])) for n in self.inputs if n != "segment"}
        return max(spans, key=spans.__getitem__) if spans else self.inputs[0]

    def __len__(self) -> int:
        return len(self.table)

    def shown(self, name: str, row: int) -> str:
        """The value of column ``name`` in row ``row`` as written: a plain number and the file's
        unit (``"900 deg"``)."""
        unit = self.table.units[name]
        value = float(self.table[name][row]) / UNITS[COLUMNS[name]][unit]
        return f"{value:g}" + ("" if unit in ("-", "1") else f" {unit}")

    def point(self, row: int) -> str:
        """The operating point of row ``row`` as written (``"psi = 900 deg, p0 = 1.7 bar"``)."""
        return ", ".join(f"{n} = {self.shown(n, row)}" for n in self.inputs)


def _kind(path: str, present: set[str]) -> tuple[str, str]:
    observables = [o for o in OBSERVABLES if o in present]
    if len(observables) != 1:
        raise TableError(path,
                         "a measurement file holds exactly one observable column of "
                         f"{', '.join(OBSERVABLES)} (found {', '.join(observables) or 'none'})")
    obs = observables[0]
    inputs = present & set(INPUTS)
    for kind, (allowed_obs, required, allowed) in KINDS.items():
        if obs in allowed_obs and set(required) <= inputs and inputs <= set(allowed) and inputs:
            return kind, obs
    valid = "; ".join(f"{k}: {'/'.join(o)} with {', '.join(r) or 'any of ' + ', '.join(a)}"
                      for k, (o, r, a) in KINDS.items())
    raise TableError(path,
                     f"columns {', '.join(sorted(inputs)) or '(no operating point)'} with {obs} "
                     f"match no measurement kind ({valid})")


def _check_rules(m: Measurements) -> None:
    """Every operating-point value of :data:`RULE_KEYS` must pass its problem key's rule (degrees,
    as the model gets them: :mod:`ocp_crawl.fit.forward`)."""
    for name, dotted in RULE_KEYS.get(m.kind, {}).items():
        section, key = dotted.split(".", 1)
        rule = SCHEMA[section].key_map[key].rule
        if name not in m.table or rule is None:
            continue
        for j, v in enumerate(m.table[name]):
            if not rule.test(math.degrees(float(v))):
                how = "it sets" if m.kind == "gait" else "the range of"
                raise m.table.error(f"{name} = {m.shown(name, j)} is invalid: must be {rule.text} "
                                    f"({how} {dotted}: {SCHEMA[section].key_map[key].what})", j)


def _check_magnitudes(m: Measurements) -> None:
    """Every value, converted to SI, must be finite and at most :data:`MAX_SI` in magnitude
    (``1e308 bar`` is not finite in Pa; ``phi = 1e308 deg`` is finite in rad but overflows the
    residuals)."""
    for name in m.table.columns:
        si, unit = SI_NAMES[COLUMNS[name]], m.table.units[name]
        limit = f"{MAX_SI:g}".replace("e+", "e") + ("" if si == "-" else f" {si}")
        if unit != si and unit not in ("-", "1"):
            limit += f" = {MAX_SI / UNITS[COLUMNS[name]][unit]:.3g} {unit}"
        for j, v in enumerate(m.table[name]):
            if not abs(v) <= MAX_SI:
                what = (f"{name} = {m.shown(name, j)} is out of range" if math.isfinite(v)
                        else f"{name} is out of range: its value overflows when converted to {si}")
                raise m.table.error(f"{what}; every value of a measurement file must be at most "
                                    f"{limit} in magnitude", j)


def _check_sigmas(m: Measurements) -> None:
    """Every sigma must be > 0 and at least :data:`SIGMA_FLOOR` times max(largest |observable|, 1 SI
    unit)."""
    sigma = "sigma_" + m.observable
    floor = SIGMA_FLOOR * max(float(np.max(np.abs(m.y))), 1.0)
    for j, s in enumerate(m.sigma):
        if not s > 0:
            raise m.table.error(f"{sigma} = {m.shown(sigma, j)}: an uncertainty must be > 0", j)
        if s < floor:
            unit = m.table.units[sigma]
            shown = f"{floor / UNITS[COLUMNS[sigma]][unit]:.3g}" + ("" if unit in ("-", "1")
                                                                    else f" {unit}")
            si = SI_NAMES[COLUMNS[sigma]]
            raise m.table.error(f"{sigma} = {m.shown(sigma, j)} is too small: an uncertainty must "
                                f"be at least {SIGMA_FLOOR:g} x max(the largest |{m.observable}| "
                                f"of the file, {'1' if si == '-' else '1 ' + si}) = {shown}; a "
                                "smaller one overflows the weighted residuals (model - data) / "
                                "sigma", j)


def _check_rows(m: Measurements) -> None:
    _check_magnitudes(m)
    _check_sigmas(m)
    if m.kind == "bending":
        for j, seg in enumerate(m.table["segment"]):
            if seg not in (1.0, 2.0):
                raise m.table.error(f"segment = {m.shown('segment', j)}: must be 1 or 2", j)
    if m.observable == "S_norm":
        ref = cast(int, m.reference_row)  # a row when the observable is S_norm
        if not m.y[ref] > 0:
            raise m.table.error(f"S_norm: the largest value, {m.shown('S_norm', ref)}, must be > 0 "
                                "(it is the normalising row)", ref)
    if m.kind == "pressure":
        amplitudes = m.table["A_p"] if "A_p" in m.inputs else np.zeros(len(m))
        for j, (p0, amp) in enumerate(zip(m.table["p0"], amplitudes)):
            if p0 < 0:
                raise m.table.error(f"p0 = {m.shown('p0', j)}: a nominal gauge pressure must be >= "
                                    "0", j)
            if not 0 <= amp <= p0:
                raise m.table.error(f"A_p = {m.shown('A_p', j)} with p0 = {m.shown('p0', j)}: the "
                                    "amplitude must lie in [0, p0] (a gauge pressure p0 - A_p >= "
                                    "0)", j)
    _check_rules(m)


def read_measurements(path: str | os.PathLike, min_rows: int = 2) -> Measurements:
    """Read and check one measurement file (see the module docstring for the kinds).

    Parameters
    ----------
    path : str or path-like
        The CSV file, e.g. with header ``psi [deg],S [mm],sigma_S [mm]``.
    min_rows : int
        The fewest rows accepted (``S_norm`` files need one more: the reference row fits nothing).

    Returns
    -------
    Measurements

    Raises
    ------
    TableError
        One line naming the file and, for a bad row, its line: a missing or unknown column, a unit
        of the wrong dimension, a value that is not a finite number (NaN), a value whose magnitude
        in SI units (m, rad, Pa, N m) is above :data:`MAX_SI` = 1e12 or not finite once converted
        (``1e308 bar``), an uncertainty <= 0 or below :data:`SIGMA_FLOOR` = 1e-12 times max(the
        largest |value| of the observable column, 1 in SI units: m, rad, -) (a smaller one overflows
        the weighted residuals), too few rows, an operating point outside the range of its problem
        key (``psi``, ``A``, ``gamma``: ``gait.psi_deg``, ...; a pressure row's ``psi`` has the
        range of ``gait.psi_deg``), a pressure p0 < 0 or A_p outside [0, p0].
    """
    table = read_table(path, {}, COLUMNS, min_rows=1)
    kind, obs = _kind(table.path, set(table.columns))
    if "sigma_" + obs not in table:
        raise TableError(table.path,
                         f"missing column 'sigma_{obs}': every measurement needs its standard "
                         f"uncertainty (same unit as {obs})")
    extra = [c for c in table.columns if c.startswith("sigma_") and c != "sigma_" + obs]
    if extra:
        raise TableError(table.path,
                         f"column {extra[0]!r} has no observable {extra[0][6:]!r} in this file")
    need = min_rows + (obs == "S_norm")
    if len(table) < need:
        raise TableError(table.path,
                         f"{len(table)} data row(s); a {kind} fit of {obs} needs at least {need}")
    m = Measurements(table, kind, obs)
    _check_rows(m)
    return m
