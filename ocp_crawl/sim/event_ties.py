"""Slips the two feet share at a tie of their friction limits: the symmetric split against the
one-sided limits.

Where a mirror-symmetric state moves mirror-symmetrically (equal friction, equal joint motion), the
friction limits of the two feet stay tied: the one-foot slips keep the tie and the event-driven
stepper lets both feet slip, half of d' each (``slip-slip``, the symmetric solution).  How the slip
is split is not decided by the statics: any split is an equilibrium.  The answer is physical only if
it does not depend on how the tie is broken, so a run that shares a slip is repeated with mu1 = mu2
(1 + eps) and mu1 = mu2 (1 - eps) and each extrapolated to eps -> 0 (linearly, from eps and 2 eps).
Both one-sided limits equal to the run's S (a gait whose shared slips cancel over the cycle, e.g.
identical joint motions): the run stands.  Otherwise the problem is set-valued: the run ends with
status ``set_valued`` (S, W+ and CoT+ NaN, as for any failure) and both values in its message and in
``extra["one_sided_S"]``.
"""
from __future__ import annotations

import math
from dataclasses import replace

from ocp_crawl.model.statics import Model
from ocp_crawl.sim.result import CrawlResult, Mode
from ocp_crawl.status import STATUS_MESSAGES, Status

#: relative change of mu1 of the one-sided friction limits
TIE_EPS = 1e-4
#: largest |S(0+-) - S| accepted, relative to |S| and, for a robot that stands still, to L
TIE_RTOL, TIE_ATOL_L = 1e-5, 1e-8

_SHARED = {Mode.SLIP_BOTH_POS.label, Mode.SLIP_BOTH_NEG.label}


def shares_a_slip(res: CrawlResult) -> bool:
    """Whether the steady cycle of the successful run ``res`` has a slip-slip segment."""
    if not res.success:
        return False
    sampled = bool(((res.mode == Mode.SLIP_BOTH_POS) | (res.mode == Mode.SLIP_BOTH_NEG)).any())
    return sampled or any(e.mode_after in _SHARED for e in res.steady_events())


def one_sided_limits(run, model: Model) -> tuple[float, float]:
    """S [m] in the limits mu1 -> mu2 from above and from below: ``run(model)`` -> CrawlResult is
    called with mu1 = mu2 (1 +- eps) for eps = TIE_EPS and 2 TIE_EPS, and each side extrapolated
    linearly to eps = 0 (NaN for a side whose runs fail)."""
    robot = model.robot
    out = []
    for side in (1.0, -1.0):
        s = []
        for eps in (TIE_EPS, 2 * TIE_EPS):
            res = run(Model(robot.replace(mu1=robot.mu2 * (1 + side * eps)), gravity=model.gravity))
            s.append(res.S if res.success else math.nan)
        out.append(2 * s[0] - s[1])
    return out[0], out[1]


def check_shared_slip(res: CrawlResult, model: Model, run) -> CrawlResult:
    """``res`` unchanged unless it shares a slip at an equal-friction tie: then a copy with both
    one-sided limits (:func:`one_sided_limits` with ``run``) in ``extra["one_sided_S"]``, and status
    SET_VALUED if they differ from its S."""
    robot = model.robot
    if not shares_a_slip(res) or robot.mu1 != robot.mu2:
        return res
    up, down = one_sided_limits(run, model)
    tol = TIE_RTOL * abs(res.S) + TIE_ATOL_L * robot.L
    extra = {**res.extra, "one_sided_S": [up, down]}
    if abs(up - res.S) <= tol and abs(down - res.S) <= tol:
        return replace(res, extra=extra)
    symmetric = res.S
    if math.isnan(up) or math.isnan(down):  # (a one-sided run failed: the split is not checked)
        message = (f"{STATUS_MESSAGES[Status.SET_VALUED]}: the feet share a slip at a held tie "
                   f"(the symmetric split gives S = {symmetric * 1e3:.6g} mm per cycle), and the "
                   "runs with mu1 and mu2 apart that would check it did not all succeed "
                   f"(S = {up * 1e3:.6g} mm from above, {down * 1e3:.6g} mm from below); simulate "
                   "with mu1 and mu2 apart")
    else:
        message = (f"{STATUS_MESSAGES[Status.SET_VALUED]}: the feet share a slip at a held tie, "
                   f"and S = {up * 1e3:.6g} mm per cycle as mu1 -> mu2 from above, "
                   f"{down * 1e3:.6g} mm from below (the symmetric split: "
                   f"{symmetric * 1e3:.6g} mm); set mu1 and mu2 apart to choose one")
    return replace(res, success=False, status=Status.SET_VALUED, message=message, S=math.nan,
                   W_plus=math.nan, CoT_plus=math.nan, extra=extra)
