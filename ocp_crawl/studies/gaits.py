"""Studies of the gait's shape: one gait in detail (Fig. simu_conf, simu_forces), S over the
psi-gamma plane (Fig. parametric) and the friction sensitivity over psi (Fig. d_mu).

Single gaits call the solvers directly; grids go through
:class:`~ocp_crawl.studies.common.SweepOptions`.  S < 0 is progress towards foot 1 (psi > 0), see
:mod:`ocp_crawl.studies.common`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ocp_crawl.model.statics import Robot
from ocp_crawl.problem import run_problem
from ocp_crawl.sim.result import CrawlResult
from ocp_crawl.studies.common import (LOW_K_RATIO, PAPER_ROBOT, REALISTIC_K_RATIO, STUCK_TOL,
                                      SweepOptions, base_problem, parabolic_max, status_counts)

# --------------------------------------------------------------------------------------------
# Fig. simu_conf and simu_forces: one gait, prescribed angles vs torque drive
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class GaitComparison:
    """The paper's gait with prescribed angles and with the torque drive at two stiffnesses."""

    gravity: str
    prescribed: CrawlResult
    k_ratios: tuple[float, ...]
    """k/(M g L) of the torque-driven runs (realistic, low)"""
    torque: tuple[CrawlResult, ...]
    """torque-driven runs, one per k ratio (a failed run holds its samples up to the failure)"""
    robot: Robot = PAPER_ROBOT

    def robot_at(self, i: int) -> Robot:
        return self.robot.with_stiffness_ratio(self.k_ratios[i])

    @property
    def S(self) -> dict[str, float]:
        """S [m] by run name (NaN for a failed run)."""
        out = {"prescribed": self.prescribed.S}
        out.update({f"k={r:.3g}": res.S if res.success
                    else math.nan for r, res in zip(self.k_ratios, self.torque)})
        return out

    @staticmethod
    def stick_fraction(res: CrawlResult) -> float:
        """Fraction of the cycle in stick-stick (both feet fixed), from the events of the steady
        cycle."""
        if not res.success:
            return math.nan
        # an event at the end of the cycle is the one at its start, one period later
        events = [e for e in res.steady_events() if e.t < res.t0 + 1 - 1e-12]
        if not events:
            return 1.0 if res.mode.size and np.all(res.mode == 0) else 0.0
        t = [e.t - res.t0 for e in events] + [1.0]
        after = [e.mode_after for e in events]
        total = sum(t1 - t0 for t0, t1, m in zip(t[:-1], t[1:], after) if m == "stick-stick")
        # the stretch from the cycle start to the first event is in the mode of the last event
        if after[-1] == "stick-stick":
            total += t[0]
        return float(total)

    @staticmethod
    def d_max(res: CrawlResult) -> float:
        return float(np.max(res.d)) if np.size(res.d) else math.nan

    @staticmethod
    def force_jump(res: CrawlResult) -> float:
        """Largest change of f_t [N] across an event (samples EVENT_SIDE either side): a
        discontinuity if large."""
        t, ft = np.asarray(res.t), np.asarray(res.f_t)
        if t.size < 2:
            return 0.0
        same = np.abs(np.diff(t)) <= 3 * EVENT_SIDE
        return float(np.max(np.abs(np.diff(ft))[same], initial=0.0))


#: phase offset [cycles] of the samples taken on either side of each event
EVENT_SIDE = 1e-9


def _dense(run, t_grid: np.ndarray) -> CrawlResult:
    """Run twice: once for the events, then on a fine phase grid with samples on both sides of each
    event, so that corners stay sharp and jumps (prescribed forces) show as jumps."""
    first = run(None)
    if not first.success:
        return first
    ev = np.array([e.t - first.t0 for e in first.steady_events()], float)
    return run(np.unique(np.clip(np.concatenate([t_grid, ev - EVENT_SIDE, ev + EVENT_SIDE]), 0.0,
                                 1.0)))


def gait_comparison(gravity: str = "physical",
                    k_ratios: Sequence[float] = (REALISTIC_K_RATIO, LOW_K_RATIO),
                    samples: int = 401) -> GaitComparison:
    """Fig. simu_conf / simu_forces: gamma 90, A 30, psi 45 deg, prescribed angles vs torque drive.

    ``gravity``: "physical" or "paper" (the paper's figures); ``k_ratios``: stiffnesses k/(M g L) of
    the torque-driven runs; ``samples``: phase samples per cycle (plus two at each event).
    Returns a :class:`GaitComparison`.
    """
    t_grid = np.linspace(0.0, 1.0, samples)
    angles = base_problem(gravity, {"gait.drive": "angles"})
    prescribed = _dense(lambda t: run_problem(angles, t_eval=t), t_grid)
    runs = []
    for ratio in k_ratios:
        prob = base_problem(gravity, {"robot.k": float(ratio * PAPER_ROBOT.MgL)})
        runs.append(_dense(lambda t, p=prob: run_problem(p, t_eval=t), t_grid))
    return GaitComparison(gravity, prescribed, tuple(float(r) for r in k_ratios), tuple(runs))


# --------------------------------------------------------------------------------------------
# Fig. parametric: S over the psi-gamma plane
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PsiGammaMap:
    """S over (gamma, psi) at fixed amplitude; arrays shaped (len(gamma_deg), len(psi_deg))."""

    gravity: str
    A_deg: float
    gamma_deg: np.ndarray
    psi_deg: np.ndarray
    S: np.ndarray
    """[m], NaN where the point failed"""
    status: np.ndarray

    @property
    def progress(self) -> np.ndarray:
        return -self.S

    @property
    def gamma_opt(self) -> np.ndarray:
        """Nominal angle of largest progress at each psi [deg] (parabolic refinement; NaN if none
        moves)."""
        out = np.full(len(self.psi_deg), np.nan)
        for j in range(len(self.psi_deg)):
            col = self.progress[:, j]
            if np.nanmax(np.abs(col), initial=0.0) > STUCK_TOL * PAPER_ROBOT.L:
                out[j] = parabolic_max(self.gamma_deg, col)[0]
        return out

    @property
    def best(self) -> tuple[float, float, float]:
        """(gamma [deg], psi [deg], S [m]) of the largest progress on the grid."""
        p = np.where(np.isfinite(self.progress), self.progress, -np.inf)
        i, j = np.unravel_index(int(np.argmax(p)), p.shape)
        return float(self.gamma_deg[i]), float(self.psi_deg[j]), float(self.S[i, j])

    @property
    def counts(self) -> dict[str, int]:
        return status_counts(self.status)


def psi_gamma_map(gravity: str = "physical", psi_deg=tuple(range(0, 181, 15)),
                  gamma_deg=tuple(range(60, 151, 10)),
                  A_deg: float = 30.0, sweep: SweepOptions = SweepOptions()) -> PsiGammaMap:
    """Fig. parametric: S over the psi-gamma plane for amplitude A (paper: A = 30 deg).

    ``gravity``: "physical" or "paper"; ``psi_deg``, ``gamma_deg``: the grid [deg]; ``A_deg``: the
    amplitude [deg]; ``sweep``: how the grid is evaluated.  Returns a :class:`PsiGammaMap`.
    """
    res = sweep.run(base_problem(gravity, {"gait.A_deg": float(A_deg)}),
                    {"gait.gamma_deg": np.asarray(gamma_deg, float),
                     "gait.psi_deg": np.asarray(psi_deg, float)},
                    f"parametric_{gravity}")
    return PsiGammaMap(gravity, float(A_deg), res.axes["gait.gamma_deg"], res.axes["gait.psi_deg"],
                       res.array("S"), res.status_array())


# --------------------------------------------------------------------------------------------
# Fig. d_mu: friction sensitivity over psi, including negative psi
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FrictionBand:
    """S over psi for friction ratios mu1/mu2 in [1 - eps, 1 + eps]; arrays shaped (len(ratios),
    len(psi_deg)).

    The ratio is varied at a fixed geometric mean sqrt(mu1 mu2) = mu (Table I), so that only the
    asymmetry between the feet changes, not the overall friction level.
    """

    gravity: str
    eps: float
    ratios: np.ndarray
    psi_deg: np.ndarray
    S: np.ndarray
    status: np.ndarray

    @property
    def nominal(self) -> np.ndarray:
        """S [m] at mu1 = mu2 (ratio 1)."""
        return self.S[int(np.argmin(np.abs(self.ratios - 1.0)))]

    @property
    def band(self) -> tuple[np.ndarray, np.ndarray]:
        """(lowest, highest) S [m] over the ratios at each psi."""
        return np.nanmin(self.S, axis=0), np.nanmax(self.S, axis=0)

    @property
    def average(self) -> np.ndarray:
        """S [m] averaged over the ratios (uniform in mu1/mu2, trapezoidal rule) at each psi."""
        if len(self.ratios) == 1:
            return self.S[0]
        w = np.zeros(len(self.ratios))
        dr = np.diff(self.ratios)
        w[:-1] += dr / 2
        w[1:] += dr / 2
        return np.einsum("r,rp->p", w / w.sum(), self.S)

    @property
    def psi_opt(self) -> tuple[float, float]:
        """(psi [deg] in (0, 180] of largest average progress -S, that progress [m])."""
        pos = self.psi_deg > 0
        return parabolic_max(self.psi_deg[pos], -self.average[pos])

    @property
    def psi_opt_negative(self) -> tuple[float, float]:
        """(psi [deg] in [-180, 0) of largest average progress along +x, S [m]): the mirror of
        psi_opt."""
        neg = self.psi_deg < 0
        return parabolic_max(self.psi_deg[neg], self.average[neg])

    def antisymmetry(self, S: np.ndarray | None = None) -> float:
        """max |S(psi) + S(-psi)| over the psi pairs on the grid [m] (0 for an odd function)."""
        S = self.nominal if S is None else S
        worst = 0.0
        for j, p in enumerate(self.psi_deg):
            k = np.nonzero(np.isclose(self.psi_deg, -p))[0]
            if k.size and np.isfinite(S[j]) and np.isfinite(S[k[0]]):
                worst = max(worst, abs(S[j] + S[k[0]]))
        return float(worst)

    @property
    def counts(self) -> dict[str, int]:
        return status_counts(self.status)


def friction_band(gravity: str = "physical", psi_deg=tuple(range(-180, 181, 15)), eps: float = 0.1,
                  n_ratios: int = 5, sweep: SweepOptions = SweepOptions()) -> FrictionBand:
    """Fig. d_mu: S against psi for mu1/mu2 = 1 - eps ... 1 + eps (``n_ratios`` values, odd, so 1 is
    one).

    ``gravity``: "physical" or "paper"; ``psi_deg``: phase differences [deg], both signs allowed;
    ``sweep``: how the grids are evaluated.  Returns a :class:`FrictionBand`.
    """
    if not (isinstance(n_ratios, int) and n_ratios >= 1 and n_ratios % 2 == 1):
        raise ValueError("n_ratios must be an odd integer >= 1 (so that mu1 = mu2 is included), "
                         f"got {n_ratios!r}")
    if not 0 <= eps < 1:
        raise ValueError(f"eps must be in [0, 1), got {eps!r}")
    ratios = np.linspace(1.0 - eps, 1.0 + eps, n_ratios) if n_ratios > 1 else np.ones(1)
    mu = PAPER_ROBOT.mu1
    rows, status = [], []
    psi = np.asarray(psi_deg, float)
    for i, r in enumerate(ratios):
        base = base_problem(gravity,
                            {"robot.mu1": mu * math.sqrt(r), "robot.mu2": mu / math.sqrt(r)})
        res = sweep.run(base, {"gait.psi_deg": psi}, f"d_mu_{gravity}_ratio{i}")
        rows.append(res.array("S"))
        status.append(res.status_array())
    return FrictionBand(gravity, float(eps), ratios, psi, np.array(rows), np.array(status))


