"""The checks of a calibration's input before anything is simulated: the files' kinds against the
robot, the counts of measurements and parameters, pressure constants fitted or fixed, and every
row's operating point at the start values.  Each raises a TableError naming the file (and row) or
a ProblemError naming the option or file."""
from __future__ import annotations

import math
from typing import Mapping, Sequence

from ocp_crawl.fit.data import GAIT_KEYS, Measurements
from ocp_crawl.fit.forward import row_error, row_tasks
from ocp_crawl.fit.params import Parameter, pressure_form, problem_pressure, split_values
from ocp_crawl.io.tables import TableError
from ocp_crawl.model.pressure import DEFAULT_FORM
from ocp_crawl.problem import Problem, ProblemError


def _n_residuals(datasets: Sequence[Measurements]) -> int:
    return sum(len(d) - (d.reference_row is not None) for d in datasets)


def check_counts(datasets: Sequence[Measurements], params: Sequence[Parameter],
                 form: str = DEFAULT_FORM) -> None:
    """TableError naming a file: fewer measurements than parameters + 1, a fitted gait key that a
    file's column sets, or an amplitude column ``A_p`` (the paper's form) with ``form`` "raised"."""
    for d in datasets:
        if form == "raised" and "A_p" in d.inputs:
            raise TableError(d.path,
                             "column 'A_p' is an amplitude of the paper's form (ref): it cannot be "
                             "used with the raised sine (--form raised)")
        for name in d.inputs:
            key = GAIT_KEYS.get(name)
            if d.kind == "gait" and key in {p.name for p in params}:
                raise TableError(d.path,
                                 f"column {name!r} sets {key} in every row: it cannot also be "
                                 f"fitted (--param {key})")
    n = _n_residuals(datasets)
    if n < len(params) + 1:
        names = ", ".join(d.path for d in datasets)
        raise TableError(datasets[0].path,
                         f"too few points: {n} measurement(s) in {names} (normalising rows not "
                         f"counted) for {len(params)} parameter(s); at least {len(params) + 1} "
                         "needed")


def check_kinds(problem: Problem, datasets: Sequence[Measurements]) -> None:
    """ProblemError naming the file of rows the problem's robot does not model: stiffness rows
    (phi = tau / k, the three-link robot's one k) on a chain."""
    for d in datasets:
        if d.kind == "stiffness" and problem.is_chain:
            raise ProblemError(f"{d.path}: stiffness rows (phi = tau / k) model the three-link "
                               "robot's one stiffness k; a chain ([robot] lengths) has one per "
                               "joint (robot.stiffness[j]): fit them to its S rows")


def check_pressure(params: Sequence[Parameter], pressure: Mapping[str, float]) -> None:
    """ProblemError for a pressure constant both fitted and held fixed (``--pressure`` and
    ``--param``)."""
    for p in params:
        key = p.name.removeprefix("pressure.")
        if p.name.startswith("pressure.") and key in pressure:
            raise ProblemError(f"--pressure {key}={pressure[key]:g} and --param {p.name}: a "
                               "constant is either fitted or held fixed, not both (to start the "
                               f"fit there: --start {p.name}={pressure[key]:g})")


def check_rows(problem: Problem, datasets: Sequence[Measurements], params: Sequence[Parameter],
               pressure: Mapping[str, float] | None = None, form: str | None = None) -> None:
    """TableError naming the file and row whose operating point the model rejects at the start
    values: a gait row's keys that ``Problem.with_values`` rejects (a range, a foot off the ground,
    a key of another waveform), a pressure row whose waveform is invalid (an amplitude above its
    p0).  Nothing is simulated."""
    keys, fitted = split_values(params, [p.x0 for p in params])
    constants = {**problem_pressure(problem, form), **(pressure or {}), **fitted}
    for d in datasets:
        for j, task in enumerate(row_tasks(problem, d, keys, constants)):
            why = row_error(task)
            if why is not None:
                amp = (f" (amplitude pressure.amplitude_bar = {constants['amplitude_bar']:g} bar)"
                       if d.kind == "pressure" and "A_p" not in d.inputs
                       and math.isfinite(constants.get("amplitude_bar", math.nan)) else "")
                raise d.table.error("at the start values the model rejects the operating point "
                                    f"{d.point(j)}{amp}: {why}", j)


def check_inputs(problem: Problem, datasets: Sequence[Measurements], params: Sequence[Parameter],
                 pressure: Mapping[str, float] | None = None, form: str | None = None) -> None:
    """Every check of a fit's input before any simulation: :func:`check_kinds`,
    :func:`check_counts`, :func:`check_pressure`, :func:`check_rows`.  TableError (naming a file
    and row) or ProblemError (naming an option or file)."""
    check_kinds(problem, datasets)
    check_counts(datasets, params, pressure_form(problem, form))
    check_pressure(params, pressure or {})
    check_rows(problem, datasets, params, pressure, form)
