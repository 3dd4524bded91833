"""Friction tolerance: which foot slips must not depend on friction coefficients known only to +-eps/2.

A gait decides which foot slips by comparing the feet's friction limits lim_i = mu_i f_n,i: the foot with
the lower limit slips, the other anchors the robot.  Friction coefficients are known to a relative
tolerance eps (``[ocp] friction_tol``); where the two limits differ by less than eps times their mean, a
change of the coefficients within +-eps/2 can hand the slip to the other foot, which moves the body the
other way.  A gait that slips at the friction tie (the mirror-symmetric harmonic gaits with psi -> 0+, the
OCP's optima that hold mu1 f_n1 = mu2 f_n2 all cycle) is therefore an artefact of exactly known friction.

The measure is the slip-weighted relative margin over the steady cycle,

    m = sum_k [ |dx1_k| (lim2 - lim1)_k + |dx2_k| (lim1 - lim2)_k ] / sum_k (|dx1_k| + |dx2_k|) (lim1 + lim2)_k / 2,

(k over the steps of the simulation, limits at the step's midpoint by the trapezoid rule): the mean of
(lim_anchor - lim_slip) / mean(lim) weighted by the slip.  A gait is admissible when m >= eps.  The
smallest margin over the slip phases is reported too (``min``), but it is not the rule: every slip phase
of a harmonic gait of equal feet ends near the tie (at psi = 45 deg, gamma 90, A 30 deg the smallest margin
is 2.5e-4 while m = 0.26), and the slip done there, near its stop, is a small share of the cycle's slip.
Both-feet slip (slip-slip modes, only at the tie) has margin 0.
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.model.statics import Robot

#: a step slips when its foot moves by more than this fraction of the robot's length L
SLIP_FLOOR = 1e-12


def steady_slice(res) -> np.ndarray:
    """Boolean mask of the samples of an event-driven result in its steady cycle [t0, t0 + 1]."""
    t = np.asarray(res.t, float)
    return (t >= res.t0 - 1e-12) & (t <= res.t0 + 1 + 1e-12)


def slip_margins(robot: Robot, f_n1, f_n2, x1, x2) -> tuple[float, float]:
    """Slip-weighted relative friction margin and the smallest margin over the slipping steps.

    Parameters
    ----------
    robot : Robot
        Its friction coefficients mu1, mu2 [-].
    f_n1, f_n2 : array_like, shape (n,)
        Normal forces at the feet [N] at successive samples of one cycle.
    x1, x2 : array_like, shape (n,)
        Foot positions [m] at the same samples.

    Returns
    -------
    (float, float)
        m [-] (see the module docstring; +inf when no foot slips) and the smallest (lim_anchor - lim_slip) /
        mean(lim) [-] at the ends of the steps in which a foot slips (+inf when none).
    """
    l1, l2 = robot.mu1 * np.asarray(f_n1, float), robot.mu2 * np.asarray(f_n2, float)
    d1, d2 = np.abs(np.diff(np.asarray(x1, float))), np.abs(np.diff(np.asarray(x2, float)))
    gap = 0.5 * ((l2 - l1)[1:] + (l2 - l1)[:-1])  # lim2 - lim1 at the step's midpoint
    mean = 0.25 * ((l1 + l2)[1:] + (l1 + l2)[:-1])
    den = float(np.sum((d1 + d2) * mean))
    if not den > 0:
        return math.inf, math.inf
    m = float(np.sum(d1 * gap - d2 * gap)) / den
    rel = (l2 - l1) / (0.5 * (l1 + l2))
    s1, s2 = d1 > SLIP_FLOOR * robot.L, d2 > SLIP_FLOOR * robot.L
    ends_all = np.concatenate([rel[:-1][s1], rel[1:][s1], -rel[:-1][s2], -rel[1:][s2]])
    return m, float(np.min(ends_all)) if ends_all.size else math.inf


def result_margins(res, robot: Robot) -> tuple[float, float]:
    """:func:`slip_margins` of an event-driven CrawlResult over its steady cycle (its steps and events)."""
    sel = steady_slice(res)
    return slip_margins(robot, res.f_n1[sel], res.f_n2[sel], res.x1[sel], res.x2[sel])


def admissible_text(m: float, eps: float) -> str:
    """Why a gait of slip-weighted margin m [-] is not admissible under the friction tolerance eps [-]."""
    return (f"which foot slips depends on the friction coefficients: slip-weighted friction margin "
            f"{m:.3g} < friction_tol {eps:.3g}")
