"""Studies of speed and cost: S and CoT+ against the amplitude (Fig. CoT), S against psi at higher
friction (supplementary figure) and S and CoT+ against the stiffness with the friction threshold.

Grids go through :class:`~ocp_crawl.studies.common.SweepOptions`; the bisections of the threshold
run the paper's gait directly.  S < 0 is progress towards foot 1 (psi > 0).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from ocp_crawl.io.paper_data import read_paper_csv
from ocp_crawl.problem import run_problem
from ocp_crawl.studies.common import (COT_K_RATIOS, PAPER_ROBOT, STUCK_TOL, SUCCESS, SweepOptions,
                                      base_problem,
                                      non_increasing, outcome_runs, parabolic_max, status_counts,
                                      stuck_points)

# --------------------------------------------------------------------------------------------
# S and CoT+ against the amplitude (Fig. CoT)
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AmplitudeStudy:
    """S, W+ and CoT+ over (k/(M g L), A) at gamma 90, psi 45 deg; arrays shaped (len(k_ratios),
    len(A_deg))."""

    gravity: str
    k_ratios: np.ndarray
    A_deg: np.ndarray
    S: np.ndarray
    W_plus: np.ndarray
    CoT_plus: np.ndarray
    status: np.ndarray

    @property
    def stuck(self) -> np.ndarray:
        return stuck_points(self.S, self.status)

    @property
    def CoT_moving(self) -> np.ndarray:
        """CoT+ where the robot moves; NaN where it is stuck (CoT+ infinite) or the run failed."""
        return np.where(self.stuck | ~np.isfinite(self.CoT_plus), np.nan, self.CoT_plus)

    @property
    def A_opt(self) -> np.ndarray:
        """Amplitude of least CoT+ for each stiffness [deg] (NaN when the minimum is at the grid's
        end)."""
        out = np.full(len(self.k_ratios), np.nan)
        for i in range(len(self.k_ratios)):
            c = self.CoT_moving[i]
            ok = np.isfinite(c)
            if ok.sum() < 3:
                continue
            a, _ = parabolic_max(self.A_deg[ok], -c[ok])
            if self.A_deg[ok][0] < a < self.A_deg[ok][-1]:
                out[i] = a
        return out

    @property
    def CoT_min(self) -> np.ndarray:
        """Least CoT+ over the amplitudes for each stiffness (NaN if the robot never moves)."""
        c = self.CoT_moving
        return np.array([np.nanmin(row) if np.isfinite(row).any() else np.nan for row in c])

    def paper_comparison(self) -> dict[str, np.ndarray] | None:
        """The paper's CoT+ (``fig_cot_vs_amplitude.csv``) at this study's amplitudes and
        stiffnesses.

        Returns ``paper`` and ``rel_diff`` (ours/paper - 1) shaped like CoT_plus, NaN where either
        is missing; None unless the study uses the paper's three stiffnesses.  Amplitudes between
        the paper's points are interpolated linearly.
        """
        if len(self.k_ratios) != 3 or not np.allclose(self.k_ratios, COT_K_RATIOS):
            return None
        data = read_paper_csv("fig_cot_vs_amplitude.csv")
        cols = ("CoT_plus_large_k", "CoT_plus_realistic_k", "CoT_plus_low_k")
        paper = np.array([np.interp(self.A_deg, data["A_deg"], data[c], left=np.nan,
                                    right=np.nan) for c in cols])
        return {"paper": paper, "rel_diff": self.CoT_moving / paper - 1.0}

    @property
    def counts(self) -> dict[str, int]:
        return status_counts(self.status)


def amplitude_study(gravity: str = "physical",
                    A_deg=(1.0, 5.0, 10.0, 15.0, 20.0, 30.0, 40.0, 50.0, 60.0),
                    k_ratios: Sequence[float] = COT_K_RATIOS, gamma_deg: float = 90.0,
                    psi_deg: float = 45.0, sweep: SweepOptions = SweepOptions()) -> AmplitudeStudy:
    """Fig. CoT (and S against A): gamma 90, psi 45 deg, stiffnesses k/(M g L) = 5, 2.74, 0.3.

    ``gravity``: "physical" or "paper"; ``A_deg``: amplitudes [deg]; ``k_ratios``: stiffnesses
    k/(M g L); ``gamma_deg``, ``psi_deg``: the rest of the gait [deg]; ``sweep``: how the grid is
    evaluated.  Returns an :class:`AmplitudeStudy`.
    """
    ks = np.asarray(k_ratios, float)
    res = sweep.run(base_problem(gravity,
                                 {"gait.gamma_deg": float(gamma_deg),
                                  "gait.psi_deg": float(psi_deg)}),
                    {"robot.k": ks * PAPER_ROBOT.MgL, "gait.A_deg": np.asarray(A_deg, float)},
                    f"amplitude_{gravity}")
    cot = res.array("CoT_plus")
    return AmplitudeStudy(gravity, ks, res.axes["gait.A_deg"], res.array("S"), res.array("W_plus"),
                          cot, res.status_array())


# --------------------------------------------------------------------------------------------
# higher friction (supplementary figure)
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class HigherFriction:
    """S over psi for mu = factor x 0.389; arrays shaped (len(factors), len(psi_deg))."""

    gravity: str
    factors: np.ndarray
    psi_deg: np.ndarray
    S: np.ndarray
    status: np.ndarray

    @property
    def stuck(self) -> np.ndarray:
        return stuck_points(self.S, self.status)

    @property
    def stuck_range(self) -> np.ndarray:
        """Width of the psi range [deg] over (0, 180) on which the robot does not move, per factor
        (grid estimate)."""
        inner = (self.psi_deg > 0) & (self.psi_deg < 180)
        psi = self.psi_deg[inner]
        step = np.gradient(psi) if psi.size > 1 else np.ones_like(psi)
        return np.array([float(np.sum(step[self.stuck[i, inner]]))
                         for i in range(len(self.factors))])

    @property
    def psi_stop(self) -> np.ndarray:
        """psi [deg] from which on the robot stays stuck up to 180 deg, per factor (NaN if it moves
        up to 180).

        The progress is extrapolated linearly to zero from the last two moving points (it falls
        about linearly there), and clipped to the bracket given by the grid.
        """
        out = np.full(len(self.factors), np.nan)
        pos = self.psi_deg > 0
        psi = self.psi_deg[pos]
        for i in range(len(self.factors)):
            stuck = self.stuck[i, pos]
            moving = (~stuck) & (self.status[i, pos] == SUCCESS)
            if not stuck[-1] or not moving.any():
                continue
            j = int(np.nonzero(moving)[0][-1])
            if j + 1 >= len(psi) or not np.all(stuck[j + 1:]):
                continue
            prog = -self.S[i, pos]
            guess = psi[j + 1]
            if j >= 1 and moving[j - 1] and prog[j - 1] > prog[j]:
                guess = psi[j] + prog[j] * (psi[j] - psi[j - 1]) / (prog[j - 1] - prog[j])
            out[i] = float(np.clip(guess, psi[j], psi[j + 1]))
        return out

    def monotone(self, atol: float = 1e-6 * PAPER_ROBOT.L) -> np.ndarray:
        """Whether the progress -S is non-increasing in psi over (0, 180] for each factor."""
        pos = self.psi_deg > 0
        return np.array([non_increasing(-self.S[i, pos], atol) for i in range(len(self.factors))])

    @property
    def counts(self) -> dict[str, int]:
        return status_counts(self.status)


def higher_friction(gravity: str = "physical", psi_deg=tuple(range(0, 181, 15)),
                    factors: Sequence[float] = (1, 2, 3, 4),
                    sweep: SweepOptions = SweepOptions()) -> HigherFriction:
    """Supplementary figure: S against psi for mu = 1, 2, 3, 4 times the measured 0.389.

    ``gravity``: "physical" or "paper"; ``psi_deg``: phase differences [deg]; ``factors``: friction
    coefficients as multiples of 0.389; ``sweep``: how the grid is evaluated.  Returns a
    :class:`HigherFriction`.
    """
    f = np.asarray(factors, float)
    res = sweep.run(base_problem(gravity),
                    {"robot.mu": f * PAPER_ROBOT.mu1, "gait.psi_deg": np.asarray(psi_deg, float)},
                    f"friction_{gravity}")
    return HigherFriction(gravity, f, res.axes["gait.psi_deg"], res.array("S"), res.status_array())


# --------------------------------------------------------------------------------------------
# stiffness and the friction threshold
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StiffnessStudy:
    """S and CoT+ against k/(M g L) at the paper's gait, and the friction threshold."""

    gravity: str
    k_ratios: np.ndarray
    S: np.ndarray
    CoT_plus: np.ndarray
    status: np.ndarray
    threshold: float
    """k/(M g L) above which the robot no longer stays stuck (bisection; NaN if not bracketed)"""
    threshold_bracket: tuple[float, float]
    """final bisection bracket (stuck at the lower end, not stuck at the upper end)"""
    onset: float = math.nan
    """k/(M g L) from which on the robot crawls at every grid point above (bisection; equals the
    threshold when nothing fails in between, as with the paper's sign)"""
    onset_bracket: tuple[float, float] = (math.nan, math.nan)
    """final bisection bracket of the onset (not crawling at the lower end, crawling at the upper
    end)"""

    @property
    def stuck(self) -> np.ndarray:
        return stuck_points(self.S, self.status)

    def ranges(self) -> list[tuple[str, float, float, int]]:
        """Maximal runs of the grid with one outcome: (outcome, first k ratio, last k ratio,
        points).

        The outcome is "stuck", "moves" or a failure status, so that e.g. the fold region of the
        physical convention shows as one run.
        """
        names = ["stuck" if s
                 else ("moves" if st == SUCCESS
                       else str(st)) for s, st in zip(self.stuck, self.status)]
        return outcome_runs(self.k_ratios, names)

    @property
    def counts(self) -> dict[str, int]:
        return status_counts(self.status)


def _outcome(gravity: str, ratio: float) -> str:
    """"stuck", "moves" or the failure status of the paper's gait at stiffness ratio k/(M g L)."""
    problem = base_problem(gravity, {"robot.k": float(ratio * PAPER_ROBOT.MgL)})
    r = run_problem(problem)
    if not r.success:
        return r.status_name
    return "stuck" if abs(r.S) <= STUCK_TOL * problem.robot.L else "moves"


def _bisect(gravity: str, lo: float, hi: float, at_hi: Callable[[str], bool],
            steps: int) -> tuple[float, float]:
    """Shrink the bracket [lo, hi] of k/(M g L) by ``steps`` bisections; ``at_hi(outcome)`` holds at
    hi, not at lo."""
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        if at_hi(_outcome(gravity, mid)):
            hi = mid
        else:
            lo = mid
    return lo, hi


def _last_change(ks: np.ndarray, low: np.ndarray) -> tuple[float, float] | None:
    """Grid bracket (k_j, k_j+1) after the last point j where ``low`` holds (None unless low holds
    somewhere and not at the last point)."""
    if not low.any() or low[-1]:
        return None
    j = int(np.nonzero(low)[0][-1])
    return float(ks[j]), float(ks[j + 1])


def stiffness_study(gravity: str = "physical",
                    k_ratios=(0.05, 0.08, 0.1, 0.15, 0.2, 0.3, 0.5, 1.0, 2.0, 5.0),
                    bisection_steps: int = 10,
                    sweep: SweepOptions = SweepOptions()) -> StiffnessStudy:
    """S and CoT+ against k/(M g L) (gamma 90, A 30, psi 45 deg), locating the friction threshold.

    The threshold is bracketed by the largest k on the grid at which the robot is stuck and the
    next grid point, and refined by ``bisection_steps`` bisections (direct runs).  The onset of
    crawling is bracketed likewise by the last grid point at which the robot does not crawl (stuck
    or failed) and the next one.  With the paper's sign the two coincide; with the physical sign
    folds and failures to stand lie between them.

    ``gravity``: "physical" or "paper"; ``k_ratios``: stiffnesses k/(M g L); ``sweep``: how the grid
    is evaluated.  Returns a :class:`StiffnessStudy`.
    """
    ks = np.sort(np.asarray(k_ratios, float))
    res = sweep.run(base_problem(gravity), {"robot.k": ks * PAPER_ROBOT.MgL},
                    f"stiffness_{gravity}")
    S, status = res.array("S"), res.status_array()
    stuck = stuck_points(S, status)
    threshold, bracket = math.nan, (math.nan, math.nan)
    grid_bracket = _last_change(ks, stuck)
    if grid_bracket is not None:
        # the bisection's predicate is "not stuck" at the upper end: any other outcome
        bracket = _bisect(gravity, *grid_bracket, lambda o: o != "stuck", bisection_steps)
        threshold = 0.5 * (bracket[0] + bracket[1])
    onset, onset_bracket = math.nan, (math.nan, math.nan)
    grid_bracket = _last_change(ks, ~((status == SUCCESS) & ~stuck))
    if grid_bracket is not None:
        onset_bracket = _bisect(gravity, *grid_bracket, lambda o: o == "moves", bisection_steps)
        onset = 0.5 * sum(onset_bracket)
    return StiffnessStudy(gravity, ks, S, res.array("CoT_plus"), status, threshold, bracket, onset,
                          onset_bracket)
