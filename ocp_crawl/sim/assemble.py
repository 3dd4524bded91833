"""The one assembly of a :class:`~ocp_crawl.sim.result.CrawlResult`, shared by every simulator.

A simulator computes its own samples and cycle integrals; this module checks the output phases a
user asks for, gives the status and its message, the fields of the sampled arrays and turns the
cycle's displacement, positive work and energy terms into S, W+, CoT+ and the energy balance, the
same way for the event-driven stepper, the prescribed angles, the MPCC time-stepping and MuJoCo.

It also holds the physical gates of a periodic result of the torque solvers: a steady
cycle whose energy balance does not close within the solver's tolerance is not a success
(:func:`imbalance`), nor one with an unstable equilibrium at a sampled phase
(:func:`unstable_sample`);
:func:`failed_metrics` are the fields of such a failure.  A :class:`CrawlResult` is frozen: every
simulator collects its fields (:func:`sample_fields`, :func:`cycle_metrics`,
:func:`balance_metrics`, :func:`failed_metrics`) and builds it in one call (:func:`new_result`);
:func:`energy_gate`, :func:`stability_gate` and :func:`demote` return a derived result
(``dataclasses.replace``).
"""
from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING
from functools import lru_cache

import numpy as np

from ocp_crawl.model.compiled import FastFunction, compiled_function
from ocp_crawl.model.stability import stability_function
from ocp_crawl.model.statics import Model
from ocp_crawl.sim.event_state import mode_q
from ocp_crawl.sim.result import CrawlResult, Mode, cost_of_transport, energy_balance
from ocp_crawl.status import STATUS_MESSAGES, Status

if TYPE_CHECKING:  # (the chain's prescribed-angle simulator builds its results here too)
    from ocp_crawl.model.chain_model import ChainModel

#: phases of the default output grid over the steady cycle (the event phases are added)
DEFAULT_OUTPUT_POINTS = 201
_DEFAULT_GRID = np.linspace(0.0, 1.0, DEFAULT_OUTPUT_POINTS)
#: columns of one call of the compiled, mapped stability function of :func:`sample_margins`
MARGIN_BATCH = 256


#: most output phases of one result: measured on the paper gait, 200,001 phases took 4 s and
#: 0.17 GB, 1,000,001 took 101 s and 0.63 GB (growing faster than the count); 1e-5 cycles apart
#: resolves more than any figure or integral uses (events are located to 1e-13 cycles anyway)
MAX_OUTPUT_PHASES = 100_001


def output_phases(t_eval) -> np.ndarray | None:
    """The output phases ``t_eval`` [cycles, in [0, 1] of the reported cycle] as a float array; None
    stays None.

    Raises ValueError for something that is not a non-empty array of finite phases in [0, 1]
    (1e-12 of round-off allowed at the ends), sorted (non-decreasing: an unsorted array is refused,
    not sorted behind the caller's back), of at most :data:`MAX_OUTPUT_PHASES` phases.
    """
    if t_eval is None:
        return None
    try:
        te = np.asarray(t_eval, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"t_eval must be an array of phases in [0, 1], got {t_eval!r:.60}") \
            from None
    if te.size == 0 or not np.all(np.isfinite(te)) or np.any(te < -1e-12) or np.any(te > 1 + 1e-12):
        raise ValueError("t_eval must be a non-empty array of finite phases in [0, 1] (phase "
                         "within the reported cycle), got "
                         f"{np.array2string(te, threshold=6)}")
    if te.size > MAX_OUTPUT_PHASES:
        raise ValueError(f"t_eval has {te.size} phases, at most {MAX_OUTPUT_PHASES}: each is a "
                         "sampled state and stability check of the result (1e-5 cycles apart "
                         "already resolves every figure)")
    bad = np.flatnonzero(np.diff(te) < 0)
    if bad.size:
        j = int(bad[0])
        raise ValueError(f"t_eval must be sorted (phases in non-decreasing order), "
                         f"got t_eval[{j}] = {float(te[j])!r} followed by t_eval[{j + 1}] = "
                         f"{float(te[j + 1])!r}")
    return te


def default_phases(event_phases) -> np.ndarray:
    """The default output phases [cycles]: DEFAULT_OUTPUT_POINTS equally spaced in [0, 1] and the
    event phases."""
    return np.unique(np.concatenate([_DEFAULT_GRID, event_phases]))


def failure_message(status: Status, detail: str) -> str:
    """The message of an unsuccessful result: the status's text, then ``detail``."""
    return f"{STATUS_MESSAGES[status]}: {detail}"


def success_message(cycles: int, t0: float, how: str = "") -> str:
    """The message of a periodic gait found after ``cycles`` cycles (``how``: e.g. " of 200 MPCC
    steps")."""
    return (f"{STATUS_MESSAGES[Status.SUCCESS]} after {cycles} cycles{how}; steady cycle t in "
            f"[{t0:g}, {t0 + 1:g}]")


def new_result(model: Model | ChainModel, drive: str, status: Status, message: str = "",
               **fields) -> CrawlResult:
    """A result with its status (a :class:`~ocp_crawl.status.Status`) and message; ``fields``: any
    other :class:`CrawlResult` field."""
    return CrawlResult(success=status == Status.SUCCESS, status=Status(status), message=message,
                       drive=drive, gravity=model.gravity, **fields)


def no_start_result(model: Model, detail: str, **fields) -> CrawlResult:
    """The result of a run without a released equilibrium at t = 0 (status NO_START, no samples)."""
    return new_result(model, "torque", Status.NO_START, failure_message(Status.NO_START, detail),
                      failure_t=0.0, failure_mode="released start", **fields)


def sample_fields(t, phi, theta, d, x1, x2, f_t, f_n1, f_n2, tau, mode) -> dict:
    """The output array fields of a :class:`CrawlResult` on the phases ``t`` [cycles]: angles phi
    [rad] (2, N), body angle theta [rad], foot distance d and foot positions x1, x2 [m], tangential
    and normal forces [N], torques tau [N m] (2, N) and the contact mode codes."""
    return {"t": t, "phi": phi, "theta": theta, "d": d, "x1": x1, "x2": x2, "f_t": f_t,
            "f_n1": f_n1, "f_n2": f_n2, "tau": tau, "mode": mode}


def cycle_metrics(robot, S: float, w_plus_joint, energy: dict) -> dict:
    """The metric fields of a :class:`CrawlResult` of the reported cycle: S [m], W+ per actuator and
    summed [J], CoT+ [-] and the energy balance ``energy``
    (:func:`~ocp_crawl.sim.result.energy_balance`)."""
    w_plus = float(np.sum(w_plus_joint))
    return {"S": S, "W_plus_joint": w_plus_joint, "W_plus": w_plus,
            "CoT_plus": cost_of_transport(w_plus, robot, S), "energy": energy}


def balance_metrics(robot, S: float, w_plus_joint, input_work: float, potential_change: float,
                    dissipation: float, gross_work: float) -> dict:
    """The metric fields of the reported cycle (:func:`cycle_metrics`): S [m], W+ per actuator and
    summed [J], CoT+ [-] and the energy balance of input work, potential change, friction
    dissipation and gross work [J]."""
    energy = energy_balance(input_work, potential_change, dissipation, gross_work, robot)
    return cycle_metrics(robot, S, w_plus_joint, energy)


def failed_metrics(t: float | None, mode: str | None) -> dict:
    """The fields of a result that its solver found periodic and a physical check turned into a
    failure at phase ``t`` [cycles] in ``mode``: S, W+ and CoT+ become NaN (they would describe a
    motion the robot cannot make); samples and energy stay, to diagnose."""
    nan = float("nan")
    return {"failure_t": t, "failure_mode": mode, "S": nan, "W_plus": nan, "CoT_plus": nan,
            "W_plus_joint": np.full(2, np.nan)}


def demote(res: CrawlResult, status: Status, detail: str, t: float | None,
           mode: str | None) -> CrawlResult:
    """The failure ``status`` of a result that its solver found periodic (a physical check
    failed): the message says ``detail``, ``failure_t`` [cycles] and ``failure_mode`` say where
    (:func:`failed_metrics`); the other fields are those of ``res``."""
    return replace(res, success=False, status=Status(status),
                   message=failure_message(status, detail), **failed_metrics(t, mode))


def imbalance(energy: dict, tol: float, why: str, t0: float) -> str | None:
    """Why the energy balance ``energy`` of the steady cycle [t0, t0 + 1] does not close: its
    |residual| (relative to the gross work) exceeds ``tol`` (``why`` names the option and the reason
    for its value); None when it closes."""
    r = energy.get("balance_residual", float("nan")) if energy else float("nan")
    if abs(r) <= tol:
        return None
    return (f"residual {r:.4g} of the gross work over the steady cycle t in [{t0:g}, {t0 + 1:g}] "
            f"exceeds {why} = {tol:.3g}")


def energy_gate(res: CrawlResult, tol: float, why: str) -> CrawlResult:
    """``res``, or its ENERGY_IMBALANCE failure (:func:`demote`) when it is a success whose
    |balance residual| (relative to the gross work) exceeds ``tol`` (:func:`imbalance`); ``why``
    names the option and the reason for its value (for the message)."""
    detail = imbalance(res.energy, tol, why, res.t0) if res.success else None
    if detail is None:
        return res
    return demote(res, Status.ENERGY_IMBALANCE, detail, res.t0, "steady cycle")


def unstable_sample(model: Model, t: np.ndarray, phi: np.ndarray, f_t: np.ndarray,
                    mode: np.ndarray) -> tuple[str, float, str] | None:
    """The first sampled phase (of the phases ``t`` with angles phi (2, N) [rad], tangential forces
    f_t [N] and mode codes) whose equilibrium has a stability margin <= 0 in its sample's contact
    mode (:func:`ocp_crawl.model.stability.stability_margins`): (detail naming its mode and margin,
    phase, mode); None if every one is stable."""
    r = model.robot
    X = np.vstack([phi, f_t / (r.M * r.g)])
    modes = np.asarray(mode, dtype=int)
    # (ValueError for a code that is not a mode: they are 0, 1, ...)
    Mode(int(modes.min())), Mode(int(modes.max()))
    margin = sample_margins(model, X, _MODE_Q.take(modes.ravel(), axis=1))
    bad = np.nonzero(~(margin > 0))[0]
    if not bad.size:
        return None
    j = bad[0]
    tj, label = float(t[j]), Mode(int(modes[j])).label
    return (f"stability margin {margin[j]:.4g} <= 0 at the sampled phase t = {tj:.10f} "
            f"(cycle {int(np.floor(tj)) + 1}, phase {tj % 1:.10f}) in mode {label}", tj, label)


def stability_gate(res: CrawlResult, model: Model) -> CrawlResult:
    """``res``, or its UNSTABLE failure (:func:`demote`) when it is a success and the equilibrium
    at one of its sampled phases has a stability margin <= 0 in its sample's contact mode
    (:func:`unstable_sample`); the message names the first such phase, its mode and margin."""
    if not res.success or res.t.size == 0:
        return res
    found = unstable_sample(model, res.t, res.phi, res.f_t, res.mode)
    return res if found is None else demote(res, Status.UNSTABLE, *found)


#: mode_q of each mode (4, number of modes), by mode code
_MODE_Q = np.stack([mode_q(m) for m in Mode], axis=1)


@compiled_function
@lru_cache(maxsize=1)
def _mapped_stability() -> FastFunction:
    return FastFunction(stability_function().map(MARGIN_BATCH))


def sample_margins(model: Model, X: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Stability margins (nondimensional, > 0 <=> stable) of the equilibria ``X`` (3, n) = (phi1,
    phi2 [rad], f_t/(M g)) in the modes ``Q`` (4, n) = (e_ss, sigma, w, d0): the values of
    :func:`ocp_crawl.model.stability.stability_margins`, by a compiled function mapped over
    MARGIN_BATCH columns (about 0.05 ms per batch instead of 0.7 ms for 200 points), the last batch
    padded with its last column."""
    n = X.shape[1]
    out = np.empty(n)
    f = _mapped_stability()
    P = np.tile(np.asarray(model.p, float)[:, None], (1, MARGIN_BATCH)).ravel(order="F")
    XT, QT = X.T, Q.T  # (the columns as rows: a selection of rows, raveled, is column-major)
    for a in range(0, n, MARGIN_BATCH):
        b = min(n, a + MARGIN_BATCH)
        # (the last column repeated as padding)
        cols = np.minimum(np.arange(a, a + MARGIN_BATCH), b - 1)
        s = f(XT.take(cols, axis=0).ravel(), QT.take(cols, axis=0).ravel(), P)[0]
        out[a:b] = s[:4 * (b - a):4]  # (the margins: the first of the 4 numbers of each column)
    return out
