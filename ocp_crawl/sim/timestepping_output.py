"""The result of an MPCC time-stepping run (:mod:`ocp_crawl.sim.timestepping`): the reported cycle's
samples, its metrics on the step grid and the resampling to the output phases.

The metrics and their quadrature rules (midpoint work, trapezoid friction dissipation) are those
of the module docstring of :mod:`ocp_crawl.sim.timestepping`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ocp_crawl.sim.assemble import (balance_metrics, energy_gate, failure_message, new_result,
                                    sample_fields, success_message)
from ocp_crawl.sim.result import CrawlResult, Mode
from ocp_crawl.sim.step import StepResult, StepState
from ocp_crawl.status import Status


@dataclass
class SteppingRun:
    """What a time-stepping run has built so far."""

    state: StepState
    rows: list
    """(t, phi, theta, d, x1, x2, f_t, f_n1, f_n2, mode) per step, the start first"""
    events: list = field(default_factory=list)
    mode: Mode = Mode.STICK
    det_ref: float | None = None
    prev: StepResult | None = None
    n: int = 0
    """steps done"""
    ncycles: int = 0
    cycle_ends: list = field(default_factory=list)
    periodic_dev: float = float("nan")
    times: list = field(default_factory=list)
    retries: int = 0
    comp_max: float = 0.0
    eq_max: float = 0.0
    polished: int = 0
    split_calls: int = 0
    """IPOPT calls of the event searches"""
    calls_mark: int = 0
    unsplit: list = field(default_factory=list)
    """why steps with a mode change were not split"""


def build_result(stepper, run, status, detail, fail_t, fail_mode, te, stats) -> CrawlResult:
    """The reported cycle (the last one, or the one of the failure) of ``run`` on the step phases
    or ``te``; ``stepper``: the :class:`~ocp_crawl.sim.timestepping.TimeStepper` of the run."""
    N, ncycles, rows = stepper.steps, run.ncycles, run.rows
    if status == Status.SUCCESS:
        t0 = float(ncycles - 1)
        message, t_end = success_message(ncycles, t0, f" of {N} MPCC steps"), t0 + 1.0
    else:
        t0 = float(max(0, math.floor(fail_t - 1e-12)))
        # (a lost contact found inside an earlier step ends the run there: nothing after it)
        message, t_end = failure_message(status, detail), fail_t
    events = [e for e in run.events if e.t <= t_end + 1e-12]
    fields = dict(events=events, cycles=ncycles, failure_t=fail_t, failure_mode=fail_mode,
                  nfev=stats["ipopt_calls"], nsteps=run.n, extra=stats, t0=t0)
    # the step phases and the located events of the cycle
    sel = [r for r in rows if t0 - 1e-12 <= r[0] <= t_end + 1e-12]
    t = np.array([r[0] for r in sel])
    phi = np.stack([r[1] for r in sel], axis=1)
    cols = {name: np.array([r[i] for r in sel]) for i, name in
            ((2, "theta"), (3, "d"), (4, "x1"), (5, "x2"), (6, "f_t"), (7, "f_n1"), (8, "f_n2"))}
    mode = np.array([r[9] for r in sel], dtype=int)
    if status == Status.SUCCESS:
        fields.update(grid_metrics(stepper.model, stepper.torque, t, phi, cols),
                      periodicity_residual=stats["periodicity_deviation"])
    if te is not None:
        t, phi, cols, mode = resample(t0 + te, t, phi, cols, mode)
    tau = np.asarray(stepper.torque(t), float).reshape(2, -1)
    res = new_result(stepper.model, "torque", status, message, **fields,
                     **sample_fields(t=t, phi=phi, tau=tau, mode=mode, **cols))
    return energy_gate(res, stepper.opt.energy_tol_n2 / N**2, "TimeSteppingOptions.energy_tol_n2 "
                       f"/ N^2 ({stepper.opt.energy_tol_n2:g}/{N}^2; the steps may be coarser "
                       "than the input's edges: raise [simulation] steps)")


def grid_metrics(model, torque, t, phi, cols) -> dict:
    """S, W+ (midpoint rule), CoT+ and the energy balance (trapezoidal friction) on the step grid
    of ``model`` driven by ``torque``."""
    tau_mid = np.asarray(torque(0.5 * (t[1:] + t[:-1])), float).reshape(2, -1)
    work = tau_mid * np.diff(phi, axis=1)
    dx1, dx2 = np.diff(cols["x1"]), np.diff(cols["x2"])
    # friction on the robot is f_t at foot 1 and -f_t at foot 2, averaged over the step's ends
    # (trapezoid: second order like the work's midpoint rule; the end-of-step force alone leaves
    # an O(1/N) balance error, measured e.g. -0.89/N against 9/N^2 with the average)
    f_mid = 0.5 * (cols["f_t"][1:] + cols["f_t"][:-1])
    diss = float(np.sum(-(f_mid * dx1 - f_mid * dx2)))
    dV = float(model.potential(phi[:, -1]) - model.potential(phi[:, 0]))
    return balance_metrics(model.robot, float(cols["x1"][-1] - cols["x1"][0]),
                           np.maximum(work, 0.0).sum(axis=1), float(work.sum()), dV, diss,
                           float(np.abs(work).sum()))


def resample(te: np.ndarray, t, phi, cols, mode):
    """The step samples at the phases te [cycles] by linear interpolation (a failed run: the
    phases it reached)."""
    te = te[te <= t[-1] + 1e-12]
    phi = np.stack([np.interp(te, t, row) for row in phi])
    cols = {k: np.interp(te, t, v) for k, v in cols.items()}
    mode = mode[np.clip(np.searchsorted(t, te - 1e-12, side="left"), 0, len(t) - 1)]
    return te, phi, cols, mode
