"""Friction tolerance: a gait must not depend on an exact friction tie.

A gait decides which foot slips by comparing the feet's friction limits lim_i = mu_i f_n,i: the foot
with the lower limit slips, the other anchors the robot.  Where the limits tie, friction
coefficients that are never known exactly decide: the mirror-symmetric harmonic gait of the paper
robot (gamma 90, A 30 deg, psi 0.01 deg, physical gravity) crawls 60.19 mm per cycle at mu1 = mu2
and 0 mm at mu1/mu2 = 0.995 or 1.005 (the foot with the lower limit takes every slip).  Such a gait
(and an optimum that slips at the tie) is an artefact of exactly known friction.

The measure is the slip-weighted relative margin over the steady cycle,

    m = sum_k [ |dx1_k| (lim2 - lim1)_k + |dx2_k| (lim1 - lim2)_k ]
        / sum_k (|dx1_k| + |dx2_k|) (lim1 + lim2)_k / 2,

(k over the steps of the simulation, limits at the step's midpoint by the trapezoid rule): the mean
of (lim_anchor - lim_slip) / mean(lim) weighted by the slip, a fraction of the mean friction limit.
A gait is admissible when m >= eps (``[ocp] friction_tol``).  The smallest margin over the slip
phases is reported too (``min``), but it is not the rule: every slip phase of a harmonic gait of
equal feet ends near the tie (at psi = 45 deg, gamma 90, A 30 deg, physical gravity, the smallest
margin is 2.5e-4 while m = 0.30).  Both-feet slip (slip-slip modes, only at the tie) has margin 0.

What a margin m guarantees, measured by simulation at mu1/mu2 = 1 +- delta (the geometric mean
fixed; ``scripts/friction_set.py``, ``tests/test_friction_set.py``): an asymmetry delta takes from
the slipping foot the end of each slip phase where the limits approach the tie, so S changes
continuously where a gait at the tie stops.  At delta = m/10 the loss is 0.7 to 1.6 (delta/m)^2 of
S on the harmonic gaits of margins 0.035 to 0.30 and the max_speed optimum below, whose slip phases
end at the tie (0.01 times on a robust_speed optimum), but 4.5 (delta/m)^2 on min_cot's optimum.
So ``friction_tol = eps`` keeps a gait off an exact tie and bounds no loss of S: min_cot's optimum
loses 4.5 % at delta = eps/10 and then misses its speed requirement.  Nor does it hold the speed
under +-eps/2: the max_speed optimum of the robot M 0.08 kg, L 0.15 m, beta 1.5 (its margin on the
rule, 0.0497) keeps its direction at mu1/mu2 = 0.975 and 1.025 but only 40 % and 57 % of its S.  Nor
is it the limit of the set {1 - eps, 1, 1 + eps}: robust_speed's worst case over it (eps = 0.05,
friction_tol = 0, paper robot, N = 50) ends on a margin of 0.103 with S within 0.03 % over the set,
min_cot's on 0.172 with S within 3.4 %.  A gait whose speed holds over a set of friction ratios is
asked for by that set: ``[ocp] mu_ratio_eps`` with ``robust = "worst"``, for any objective (min_cot
from tightened starts, ``start_solve``; docs/guide/optimal_gaits.md, "Friction uncertainty").
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.model.chain import Chain
from ocp_crawl.model.statics import Robot

#: a step slips when its foot moves by more than this fraction of the robot's length L
SLIP_FLOOR = 1e-12


def steady_slice(res) -> np.ndarray:
    """Boolean mask of the samples of an event-driven result in its steady cycle [t0, t0 + 1]."""
    t = np.asarray(res.t, float)
    return (t >= res.t0 - 1e-12) & (t <= res.t0 + 1 + 1e-12)


def slip_margins(robot: Robot | Chain, f_n1, f_n2, x1, x2) -> tuple[float, float]:
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
        m [-] (see the module docstring; +inf when no foot slips) and the smallest (lim_anchor -
        lim_slip) / mean(lim) [-] at the ends of the steps in which a foot slips (+inf when none).
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


def result_margins(res, robot: Robot | Chain) -> tuple[float, float]:
    """:func:`slip_margins` of an event-driven CrawlResult over its steady cycle (its steps and
    events)."""
    sel = steady_slice(res)
    return slip_margins(robot, res.f_n1[sel], res.f_n2[sel], res.x1[sel], res.x2[sel])


def admissible_text(m: float, eps: float) -> str:
    """Why a gait of slip-weighted margin m [-] is not admissible under the friction tolerance eps
    [-]."""
    return (f"the slip runs too close to the friction tie (which foot slips depends on the feet's "
            f"friction coefficients): slip-weighted friction margin {m:.3g} < friction_tol "
            f"{eps:.3g}")
