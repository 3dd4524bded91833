"""The one assembly of a :class:`~ocp_crawl.sim.result.CrawlResult`, shared by every simulator.

A simulator computes its own samples and cycle integrals; this module checks the output phases a
user asks for, writes the status and its message, stores the sampled arrays and turns the cycle's
displacement, positive work and energy terms into S, W+, CoT+ and the energy balance, the same
way for the event-driven stepper, the prescribed angles and the MPCC time-stepping.
"""
from __future__ import annotations

import numpy as np

from ocp_crawl.model.statics import Model
from ocp_crawl.sim.result import CrawlResult, cost_of_transport, energy_balance
from ocp_crawl.status import STATUS_MESSAGES, Status

#: phases of the default output grid over the steady cycle (the event phases are added)
DEFAULT_OUTPUT_POINTS = 201


def output_phases(t_eval) -> np.ndarray | None:
    """The output phases ``t_eval`` [cycles, in [0, 1] of the reported cycle] as a float array; None stays None.

    Raises ValueError for something that is not a non-empty array of finite phases in [0, 1]
    (1e-12 of round-off allowed at the ends).
    """
    if t_eval is None:
        return None
    try:
        te = np.asarray(t_eval, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"t_eval must be an array of phases in [0, 1], got {t_eval!r:.60}") from None
    if te.size == 0 or not np.all(np.isfinite(te)) or np.any(te < -1e-12) or np.any(te > 1 + 1e-12):
        raise ValueError("t_eval must be a non-empty array of finite phases in [0, 1] (phase within the "
                         f"reported cycle), got {np.array2string(te, threshold=6)}")
    return te


def default_phases(event_phases) -> np.ndarray:
    """The default output phases [cycles]: DEFAULT_OUTPUT_POINTS equally spaced in [0, 1] and the event phases."""
    return np.unique(np.concatenate([np.linspace(0.0, 1.0, DEFAULT_OUTPUT_POINTS), event_phases]))


def failure_message(status: Status, detail: str) -> str:
    """The message of an unsuccessful result: the status's text, then ``detail``."""
    return f"{STATUS_MESSAGES[status]}: {detail}"


def success_message(cycles: int, t0: float, how: str = "") -> str:
    """The message of a periodic gait found after ``cycles`` cycles (``how``: e.g. " of 200 MPCC steps")."""
    return f"{STATUS_MESSAGES[Status.SUCCESS]} after {cycles} cycles{how}; steady cycle t in [{t0:g}, {t0 + 1:g}]"


def new_result(model: Model, drive: str, status: Status, message: str = "", **fields) -> CrawlResult:
    """A result with its status (a :class:`~ocp_crawl.status.Status`) and message; ``fields``: any other
    :class:`CrawlResult` field."""
    return CrawlResult(success=status == Status.SUCCESS, status=Status(status), message=message, drive=drive,
                       gravity=model.gravity, **fields)


def no_start_result(model: Model, detail: str, **fields) -> CrawlResult:
    """The result of a run without a released equilibrium at t = 0 (status NO_START, no samples)."""
    return new_result(model, "torque", Status.NO_START, failure_message(Status.NO_START, detail), failure_t=0.0,
                      failure_mode="released start", **fields)


def set_samples(res: CrawlResult, t, phi, theta, d, x1, x2, f_t, f_n1, f_n2, tau, mode) -> None:
    """Store the output arrays on the phases ``t`` [cycles]: angles phi [rad] (2, N), body angle theta [rad],
    foot distance d and foot positions x1, x2 [m], tangential and normal forces [N], torques tau [N m]
    (2, N) and the contact mode codes."""
    res.t, res.phi, res.theta, res.d = t, phi, theta, d
    res.x1, res.x2, res.f_t, res.f_n1, res.f_n2 = x1, x2, f_t, f_n1, f_n2
    res.tau, res.mode = tau, mode


def set_cycle_metrics(res: CrawlResult, robot, S: float, w_plus_joint, input_work: float, potential_change: float,
                      dissipation: float, gross_work: float) -> None:
    """Store the metrics of the reported cycle: S [m], W+ per actuator and summed [J], CoT+ [-] and the
    energy balance of input work, potential change, friction dissipation and gross work [J]."""
    res.S = S
    res.W_plus_joint = w_plus_joint
    res.W_plus = float(np.sum(w_plus_joint))
    res.CoT_plus = cost_of_transport(res.W_plus, robot, S)
    res.energy = energy_balance(input_work, potential_change, dissipation, gross_work, robot)
