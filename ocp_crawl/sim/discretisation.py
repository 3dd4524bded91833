"""The discretisation error of S of the MPCC time-stepping, estimated on its steady cycle.

Inside one contact mode the incremental step is exact (quasistatics: the step equations are the
mode's equations at the step's end), and switch-exact steps (:mod:`ocp_crawl.sim.step_split`) put
every located event on a step boundary. What S can still miss is what a step does not see: a slip
that starts and stops inside one step, a change of mode that the event search cannot locate (a guard
that is not violated at the step's end, more than ``MAX_SPLITS`` events in a step), a stop at a
corner of a linear pulse or at the end of a hold. Such an error is not asymptotic in N: it is zero
or O(1) in S depending on where the grid falls, and the same for nested grids when the feature sits
on a grid phase (measured: a soft robot with a linear pulse input gives the same S to 5e-11 at
N = 50, 100 and 200, 2.4 % off the event-driven S, and 5 % and 3.8 % off at N = 51 and 101).

The estimate therefore re-runs the reported (steady) cycle once with M = 2 N + 1 steps from the same
state (the start of the reported cycle: its angles, foot positions, force and contact mode; the
first step cold-started), on a grid that halves the steps and shares no phase with N's but 0: a
feature the N grid meets badly falls inside a step of the check run, or elsewhere in it. The
estimate of S's error is |S_N - S_M| [m]. It is not multiplied by a Richardson factor: with an
observed order p the factor 1 / (1 - 2^-p) would need the errors to be asymptotic, which they are
not (above). The guard residuals of the located events are not used either: they confirm the events
that were found and say nothing about the ones that were not.

Cost: one cycle of 2 N + 1 steps with the run's own step NLP (no new IPOPT build), about as much as
the steps of a run that is periodic after the two cycles it needs at least (measured on the paper
gait: 264 IPOPT calls and 4.3 s against 494 calls and 14.5 s for the whole run at N = 50, 561 calls
and 14.5 s against 746 calls and 31 s at N = 200).

A successful run whose estimate exceeds the bound ``s_error_tol (|S| + 1e-3 L)`` (1e-3 |S| + 1e-6 L
with the default 1e-3: the accuracy a sweep or a figure of S needs, far above the solvers'
tolerance, 1e-9 to 2e-8 relative, and the floor 1e-6 L keeps gaits that barely move from failing on
round-off) is ``COARSE_STEPS``, and so is one whose check run fails (the finer steps see something
the run did not).
"""
from __future__ import annotations

import copy
import time
from dataclasses import replace

from ocp_crawl.sim.assemble import demote
from ocp_crawl.sim.result import CrawlResult, Mode
from ocp_crawl.sim.step import StepState
from ocp_crawl.sim.step_dips import CONTACT
from ocp_crawl.status import Status

#: the length scale of the floor of the bound: s_error_tol * ABS_FLOOR * L [m]
ABS_FLOOR = 1e-3


def check_steps(N: int) -> int:
    """Steps per cycle of the check run of a run with ``N`` steps per cycle: 2 N + 1 (halved
    steps, no common phase but 0)."""
    return 2 * N + 1


def error_bound(S: float, L: float, tol: float) -> float:
    """The bound on the estimate of S's error [m]: ``tol`` (|S| + 1e-3 L), for S [m] and the
    robot's length L [m]."""
    return tol * (abs(S) + ABS_FLOOR * L)


def estimate_S_error(stepper, run, stop) -> dict:
    """The reported cycle of ``run`` again, with ``check_steps(N)`` steps from the same state.

    Parameters
    ----------
    stepper : TimeStepper
        The stepper of the run (its step NLP is shared by the check run).
    run : SteppingRun
        The run; the row at the start of its reported cycle (the last one) starts the check run,
        from a cold start of the step NLP.
    stop : type
        The stepper's exception class of a failed step.

    Returns
    -------
    dict
        ``S_check`` [m] (S of the check run, NaN when it failed), ``steps`` (N),
        ``steps_check`` (M), ``check_ipopt_calls``, ``check_time`` [s] and ``check_failure``
        (the failure's status label, phase and detail, or ""; with a failure ``check_status``
        (label), ``check_t`` [cycles from the reported cycle's start] and ``check_mode``).
    """
    t_start, calls = time.perf_counter(), stepper.step.ncalls
    M = check_steps(stepper.steps)
    check = copy.copy(stepper)
    check.steps = M
    t0 = float(run.ncycles - 1)
    first = [r for r in run.rows if abs(r[0] - t0) <= 1e-12][-1]
    state = StepState(first[1], first[4], first[5], first[6])
    start = type(run)(state, [(0.0,) + tuple(first[1:])], mode=Mode(first[9]))
    out = {"S_check": float("nan"), "steps": stepper.steps, "steps_check": M, "check_failure": ""}
    try:
        check._run_cycles(start, 1)
    except stop as exc:
        out["check_failure"] = f"{exc.status.label} at phase {exc.t:.6f} ({exc.detail})"
        out.update(check_status=exc.status.label, check_t=float(exc.t), check_mode=exc.mode.label)
    else:
        out["S_check"] = float(start.rows[-1][4] - first[4])
    out.update(check_ipopt_calls=stepper.step.ncalls - calls,
               check_time=time.perf_counter() - t_start)
    return out


def error_gate(res: CrawlResult, check: dict | None, L: float, tol: float) -> CrawlResult:
    """A successful ``res`` with ``S_error`` [m] from the check run (and
    ``extra["S_error_bound"]``), or its COARSE_STEPS failure
    (:func:`~ocp_crawl.sim.assemble.demote`, ``extra["S_coarse"]``: its S) when the estimate
    exceeds :func:`error_bound` (or the check run failed); the message names the estimate, the
    bound and the steps to try.  A check run that ends at a lost contact (``lift_off``,
    ``joint_on_ground``, ``feet_crossed``) ends ``res`` with that status at its phase.  ``res``
    as it is for a failure or without a check run (``check`` None).
    ``L``: the robot's length [m]; ``tol``: the relative bound [-]."""
    if check is None or not res.success:
        return res
    est, N = abs(res.S - check["S_check"]), check["steps"]
    bound = error_bound(res.S, L, tol)
    res = replace(res, S_error=est, extra={**res.extra, "S_error_bound": bound})
    if check.get("check_status") in [c.label for c in CONTACT]:
        # (the finer steps find a contact lost in the steady cycle, between the run's steps' ends:
        # the run ends there, whatever the steps)
        res = replace(res, extra={**res.extra, "S_coarse": res.S})
        return demote(res, Status.from_label(check["check_status"]),
                      f"found by the check run at {check['steps_check']} steps per cycle: "
                      f"{check['check_failure']}", res.t0 + check["check_t"], check["check_mode"])
    if check["check_failure"]:
        detail = (f"the check run at {check['steps_check']} steps per cycle failed: "
                  f"{check['check_failure']}; S error not estimated: use steps >= {4 * N}")
    elif est > bound:
        rel = f" ({100 * est / abs(res.S):.2g} % of |S|)" if res.S != 0 else ""
        detail = (f"S error estimate {est:.2g} m{rel} above the bound {bound:.2g} m = {tol:g} "
                  f"(|S| + {ABS_FLOOR:g} L), from |S_N - S_M| at N = {N} and "
                  f"M = {check['steps_check']} steps: use steps >= {4 * N}")
    else:
        return res
    res = replace(res, extra={**res.extra, "S_coarse": res.S})
    return demote(res, Status.COARSE_STEPS, detail, res.t0, "steady cycle")
