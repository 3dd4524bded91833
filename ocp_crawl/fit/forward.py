"""The model of every measurement row at a parameter vector: simulations (or closed forms), failures
as statuses.

Rows are independent, so they are evaluated as picklable tasks (:class:`RowTask`), one after the
other in this process or in worker processes (:func:`evaluate_rows`).
"""
from __future__ import annotations

import functools
import json
import math
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from ocp_crawl.fit.data import GAIT_KEYS, Measurements
from ocp_crawl.model.inputs import ReferenceTorque
from ocp_crawl.model.pressure import BendingMap, pressure_torque
from ocp_crawl.problem import Problem, ProblemError, problem_from_dict, run_problem
from ocp_crawl.sim import simulate
from ocp_crawl.status import Status

SUCCESS = Status.SUCCESS.label
PA_PER_BAR = 1e5
#: the source of the rows' problems, at the start of their error messages
SOURCE = "<fit>"
#: |S| [m] at or below which a robot does not move: the simulators' round-off of S is about
#: 1e-14 m (a symmetric gait's S), a crawler's S is millimetres
S_STILL = 1e-12


@dataclass(frozen=True)
class RowTask:
    """One row to evaluate: plain data only (sent to worker processes)."""

    kind: str
    problem_json: str
    """the base problem as JSON of its sections"""
    values: tuple[tuple[str, float], ...]
    """problem keys of the fitted parameters -> values"""
    pressure: tuple[tuple[str, float], ...]
    """all pressure constants (a1, a2, b1, b2, phi_rest_deg, amplitude_bar)"""
    inputs: tuple[tuple[str, float], ...]
    """the row's operating point, SI (angles in rad, pressures in Pa, torques in N m)"""


@functools.lru_cache(maxsize=8)
def _base(problem_json: str) -> Problem:
    return problem_from_dict(json.loads(problem_json), source=SOURCE)


def _problem(task: RowTask, extra: Mapping[str, object]) -> Problem:
    values = {**dict(task.values), **extra}
    base = _base(task.problem_json)
    return base.with_values(values) if values else base


def _setup(task: RowTask) -> tuple[Problem, ReferenceTorque | None]:
    """The problem of a gait or pressure row and, for a pressure row of the three-link robot, its
    torque input (a chain's pressure row: its problem's ``pressure`` waveform); ValueError (a
    ProblemError naming the key) for an operating point or parameter value the model rejects.
    Nothing is simulated."""
    inputs = dict(task.inputs)
    if task.kind == "gait":
        return _problem(task, {GAIT_KEYS[n]: math.degrees(v) for n, v in inputs.items()}), None
    c = dict(task.pressure)
    amplitude = inputs["A_p"] / PA_PER_BAR if "A_p" in inputs else c.get("amplitude_bar", math.nan)
    if _base(task.problem_json).is_chain:
        return _problem(task, _chain_pressure(inputs, c, amplitude)), None
    problem = _problem(task, {})
    bmap = BendingMap(c["a1"], c["a2"], c["b1"], c["b2"])
    signal = pressure_torque(problem.robot, inputs["p0"] / PA_PER_BAR, math.degrees(inputs["psi"]),
                             c["phi_rest_deg"], bmap, None if math.isnan(amplitude) else amplitude)
    return problem, signal


def _chain_pressure(inputs: Mapping[str, float], constants: Mapping[str, float],
                    amplitude: float) -> dict[str, object]:
    """The problem keys of a chain's pressure row: the ``pressure`` waveform at the row's p0 and
    psi, every pressure constant (the raised sine where the amplitude is NaN)."""
    keys: dict[str, object] = {"gait.waveform": "pressure",
                               "gait.p0_bar": inputs["p0"] / PA_PER_BAR,
                               "gait.psi_deg": math.degrees(inputs["psi"]),
                               "pressure.form": "raised" if math.isnan(amplitude) else "paper"}
    keys.update({f"pressure.{n}": constants[n] for n in ("a1", "a2", "b1", "b2", "phi_rest_deg")})
    if not math.isnan(amplitude):
        keys["pressure.amplitude_bar"] = amplitude
    return keys


def _simulated(task: RowTask) -> tuple[float, str]:
    try:
        problem, signal = _setup(task)
    # a key the problem rejects, or e.g. an amplitude above the nominal pressure
    except ValueError as exc:
        return math.nan, f"{Status.BAD_INPUT.label}: {exc}"
    if signal is None:
        result = run_problem(problem)
    else:
        try:
            result = simulate(problem.model, signal, "event", problem.hybrid)
        except ValueError as exc:  # no released equilibrium at t = 0
            return math.nan, f"{Status.NO_START.label}: {exc}"
    if not result.success:
        return math.nan, f"{result.status_name}: {result.message}"
    return float(result.S), SUCCESS


def row_error(task: RowTask) -> str | None:
    """Why the model rejects the row before simulating it (the problem's validation of its keys, the
    pressure waveform's of its pressures), one line without the problem's source; None if it accepts
    it."""
    try:
        if task.kind in ("gait", "pressure"):
            _setup(task)
        elif task.kind == "stiffness":
            _problem(task, {})
    except ValueError as exc:
        return " ".join(str(exc).removeprefix(f"{SOURCE}: ").split())
    return None


def _closed_form(task: RowTask) -> float:
    inputs = dict(task.inputs)
    if task.kind == "stiffness":
        return inputs["tau"] / _problem(task, {}).robot.k
    c = dict(task.pressure)
    seg = "1" if inputs["segment"] == 1.0 else "2"
    p = inputs["p"] / PA_PER_BAR
    return c["a" + seg] * p**2 + c["b" + seg] * p


def evaluate_row(task: RowTask) -> tuple[float, str]:
    """The model's value of one row (SI: S [m] or phi [rad]) and ``"success"``, or (NaN,
    ``"status: message"``).

    A failure of the simulation, a parameter value the problem rejects, or any error is a status,
    never raised.
    """
    try:
        with np.errstate(all="ignore"):
            if task.kind in ("gait", "pressure"):
                return _simulated(task)
            return _closed_form(task), SUCCESS
    except ProblemError as exc:
        return math.nan, f"{Status.BAD_INPUT.label}: {exc}"
    except Exception as exc:  # noqa: BLE001 - a failed point is a status of the fit, not a crash
        return math.nan, f"{Status.ERROR.label}: {type(exc).__name__}: {exc}"


def row_tasks(problem: Problem, data: Measurements, values: Mapping[str, float],
              pressure: Mapping[str, float]) -> list[RowTask]:
    """The tasks of every row of ``data`` at the given problem values and pressure constants."""
    pj = json.dumps(problem.to_dict(), sort_keys=True)
    vals, pres = tuple(sorted(values.items())), tuple(sorted(pressure.items()))
    names = data.inputs
    return [RowTask(data.kind, pj, vals, pres, tuple((n, float(data.table[n][j])) for n in names))
            for j in range(len(data))]


def evaluate_rows(tasks: Sequence[RowTask],
                  executor: Executor | None = None) -> list[tuple[float, str]]:
    """:func:`evaluate_row` of every task, in this process (``executor`` None) or by
    ``executor.map``."""
    if executor is None:
        return [evaluate_row(t) for t in tasks]
    return list(executor.map(evaluate_row, tasks, chunksize=max(1, len(tasks) // 8)))


def model_values(data: Measurements, results: Sequence[tuple[float, str]]) -> np.ndarray:
    """The model's values in the file's observable: S [m], phi [rad], or S normalised at the
    reference row (NaN where the model's S there is at most :data:`S_STILL`: it does not
    move)."""
    y = np.array([r[0] for r in results], dtype=float)
    ref = data.reference_row
    if ref is None:
        return y
    if not abs(y[ref]) > S_STILL:   # (NaN too) a failed evaluation, not a huge residual
        return np.full_like(y, math.nan)
    return y / y[ref]

