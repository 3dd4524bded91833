"""The paper's studies: one function per study, each returning a small frozen result.

Every grid is evaluated by :func:`ocp_crawl.sweep.run_sweep` (parallel workers, progress, an
optional journal on disk) through :class:`SweepOptions`; single gaits (the configuration and
force figures) and the bisection of the friction threshold call the solvers directly.  Failed
points are data: each result keeps the status of every point (``success``, ``fold``,
``lift_off``, ...) next to its numbers, and the derived numbers (optimal psi, threshold, ...)
use the successful points only.

Sign convention: S is the displacement per cycle along +x, from foot 1 to foot 2.  With psi > 0
joint 1 leads and the robot moves towards foot 1, S < 0; the "progress" -S is what the paper's
figures show for psi > 0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from ocp_crawl.model.statics import Robot
from ocp_crawl.problem import Problem, paper_problem, run_problem
from ocp_crawl.io.paper_data import read_paper_csv
from ocp_crawl.model.pressure import FITTED_REST_DEG
from ocp_crawl.studies.pressure import PressureFit, evaluate_fit, fit_rest_angle
from ocp_crawl.sim.result import CrawlResult
from ocp_crawl.sweep import SUCCESS, SweepResult, run_sweep

#: the paper's robot (Table I)
PAPER_ROBOT = Robot.paper()
#: k/(M g L) of the paper's robot, the "realistic" stiffness (about 2.74)
REALISTIC_K_RATIO = PAPER_ROBOT.k / PAPER_ROBOT.MgL
#: the three stiffnesses of the paper's CoT+ figure, k/(M g L): large, realistic, low
COT_K_RATIOS = (5.0, REALISTIC_K_RATIO, 0.3)
COT_K_LABELS = ("large", "realistic", "low")
#: low stiffness of the configuration figure, k/(M g L)
LOW_K_RATIO = 0.3
#: rest angle of a flat robot [deg], the alternative to the fitted rest angle of the pressure-driven robot
FLAT_REST_DEG = 180.0
#: |S| below this fraction of L counts as no motion ("stuck"): a stuck gait has S at round-off
STUCK_TOL = 1e-6


# --------------------------------------------------------------------------------------------
# grid evaluation
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SweepOptions:
    """How the studies evaluate grids: passed through to :func:`~ocp_crawl.sweep.run_sweep`."""

    jobs: int = 1
    """worker processes"""
    progress: bool = False
    """progress bar on stderr"""
    out_dir: Path | None = None
    """if given, each sweep is journaled in ``out_dir/<name>`` (results.csv, settings.json)"""
    resume: bool = False
    """reuse the finished points of an interrupted run in ``out_dir`` (else its sweeps are overwritten)"""
    scheduler: str | None = None
    """Dask scheduler address or "local" (None: local worker processes)"""

    def run(self, problem: Problem, grid: Mapping[str, Any], name: str) -> SweepResult:
        out = None if self.out_dir is None else Path(self.out_dir) / name
        return run_sweep(problem, grid, out_dir=out, jobs=self.jobs, resume=self.resume and out is not None,
                         force=out is not None and not self.resume, progress=self.progress, scheduler=self.scheduler)


def base_problem(gravity: str = "paper", overrides: Sequence[str] = ()) -> Problem:
    """The paper's gait (Table I robot; gamma 90, A 30, psi 45 deg; torque drive) in a gravity convention."""
    return paper_problem([f"model.gravity={gravity}", *overrides])


def _stuck(S: np.ndarray, status: np.ndarray, L: float = PAPER_ROBOT.L) -> np.ndarray:
    """Successful points at which the robot does not move."""
    return (status == SUCCESS) & (np.abs(np.nan_to_num(S, nan=np.inf)) <= STUCK_TOL * L)


def _counts(status: np.ndarray) -> dict[str, int]:
    names, n = np.unique(np.asarray(status).ravel(), return_counts=True)
    return {str(a): int(b) for a, b in sorted(zip(names, n), key=lambda p: (-p[1], p[0]))}


def outcome_runs(x, outcomes) -> list[tuple[str, float, float, int]]:
    """Maximal runs of equal outcomes along a grid: (outcome, first x, last x, points)."""
    out: list[tuple[str, float, float, int]] = []
    for xi, name in zip(np.asarray(x, float), outcomes):
        name = str(name)
        if out and out[-1][0] == name:
            out[-1] = (name, out[-1][1], float(xi), out[-1][3] + 1)
        else:
            out.append((name, float(xi), float(xi), 1))
    return out


def _parabolic_max(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Maximum of y(x) on a grid, refined by the parabola through the best point and its neighbours."""
    ok = np.isfinite(y)
    if not ok.any():
        return float("nan"), float("nan")
    x, y = np.asarray(x, float)[ok], np.asarray(y, float)[ok]
    j = int(np.argmax(y))
    if 0 < j < len(x) - 1:
        c = np.polyfit(x[j - 1:j + 2], y[j - 1:j + 2], 2)
        if c[0] < 0:
            xv = -c[1] / (2 * c[0])
            if x[j - 1] <= xv <= x[j + 1]:
                return float(xv), float(np.polyval(c, xv))
    return float(x[j]), float(y[j])


def _non_increasing(y: np.ndarray, atol: float) -> bool:
    y = np.asarray(y, float)
    y = y[np.isfinite(y)]
    return bool(np.all(np.diff(y) <= atol))


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
        out.update({f"k={r:.3g}": res.S if res.success else math.nan for r, res in zip(self.k_ratios, self.torque)})
        return out

    @staticmethod
    def stick_fraction(res: CrawlResult) -> float:
        """Fraction of the cycle in stick-stick (both feet fixed), from the events of the steady cycle."""
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
        """Largest change of f_t [N] across an event (samples EVENT_SIDE either side): a discontinuity if large."""
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
    return run(np.unique(np.clip(np.concatenate([t_grid, ev - EVENT_SIDE, ev + EVENT_SIDE]), 0.0, 1.0)))


def gait_comparison(gravity: str = "paper", k_ratios: Sequence[float] = (REALISTIC_K_RATIO, LOW_K_RATIO),
                    samples: int = 401) -> GaitComparison:
    """Fig. simu_conf / simu_forces: gamma 90, A 30, psi 45 deg, prescribed angles vs torque drive."""
    t_grid = np.linspace(0.0, 1.0, samples)
    angles = base_problem(gravity, ["gait.drive=angles"])
    prescribed = _dense(lambda t: run_problem(angles, t_eval=t), t_grid)
    runs = []
    for ratio in k_ratios:
        prob = base_problem(gravity, [f"robot.k={ratio * PAPER_ROBOT.MgL!r}"])
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
        """Nominal angle of largest progress at each psi [deg] (parabolic refinement; NaN if none moves)."""
        out = np.full(len(self.psi_deg), np.nan)
        for j in range(len(self.psi_deg)):
            col = self.progress[:, j]
            if np.nanmax(np.abs(col), initial=0.0) > STUCK_TOL * PAPER_ROBOT.L:
                out[j] = _parabolic_max(self.gamma_deg, col)[0]
        return out

    @property
    def best(self) -> tuple[float, float, float]:
        """(gamma [deg], psi [deg], S [m]) of the largest progress on the grid."""
        p = np.where(np.isfinite(self.progress), self.progress, -np.inf)
        i, j = np.unravel_index(int(np.argmax(p)), p.shape)
        return float(self.gamma_deg[i]), float(self.psi_deg[j]), float(self.S[i, j])

    @property
    def counts(self) -> dict[str, int]:
        return _counts(self.status)


def psi_gamma_map(gravity: str = "paper", psi_deg=tuple(range(0, 181, 15)), gamma_deg=tuple(range(60, 151, 10)),
                  A_deg: float = 30.0, sweep: SweepOptions = SweepOptions()) -> PsiGammaMap:
    """Fig. parametric: S over the psi-gamma plane for amplitude A (paper: A = 30 deg)."""
    res = sweep.run(base_problem(gravity, [f"gait.A_deg={float(A_deg)!r}"]),
                    {"gait.gamma_deg": np.asarray(gamma_deg, float), "gait.psi_deg": np.asarray(psi_deg, float)},
                    f"parametric_{gravity}")
    return PsiGammaMap(gravity, float(A_deg), res.axes["gait.gamma_deg"], res.axes["gait.psi_deg"], res.array("S"),
                       res.status_array())


# --------------------------------------------------------------------------------------------
# Fig. d_mu: friction sensitivity over psi, including negative psi
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FrictionBand:
    """S over psi for friction ratios mu1/mu2 in [1 - eps, 1 + eps]; arrays shaped (len(ratios), len(psi_deg)).

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
        return _parabolic_max(self.psi_deg[pos], -self.average[pos])

    @property
    def psi_opt_negative(self) -> tuple[float, float]:
        """(psi [deg] in [-180, 0) of largest average progress along +x, S [m]): the mirror of psi_opt."""
        neg = self.psi_deg < 0
        return _parabolic_max(self.psi_deg[neg], self.average[neg])

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
        return _counts(self.status)


def friction_band(gravity: str = "paper", psi_deg=tuple(range(-180, 181, 15)), eps: float = 0.1,
                  n_ratios: int = 5, sweep: SweepOptions = SweepOptions()) -> FrictionBand:
    """Fig. d_mu: S against psi for mu1/mu2 = 1 - eps ... 1 + eps (``n_ratios`` values, odd, so 1 is one)."""
    if not (isinstance(n_ratios, int) and n_ratios >= 1 and n_ratios % 2 == 1):
        raise ValueError(f"n_ratios must be an odd integer >= 1 (so that mu1 = mu2 is included), got {n_ratios!r}")
    if not 0 <= eps < 1:
        raise ValueError(f"eps must be in [0, 1), got {eps!r}")
    ratios = np.linspace(1.0 - eps, 1.0 + eps, n_ratios) if n_ratios > 1 else np.ones(1)
    mu = PAPER_ROBOT.mu1
    rows, status = [], []
    psi = np.asarray(psi_deg, float)
    for i, r in enumerate(ratios):
        base = base_problem(gravity, [f"robot.mu1={mu * math.sqrt(r)!r}", f"robot.mu2={mu / math.sqrt(r)!r}"])
        res = sweep.run(base, {"gait.psi_deg": psi}, f"d_mu_{gravity}_ratio{i}")
        rows.append(res.array("S"))
        status.append(res.status_array())
    return FrictionBand(gravity, float(eps), ratios, psi, np.array(rows), np.array(status))


# --------------------------------------------------------------------------------------------
# S and CoT+ against the amplitude (Fig. CoT)
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AmplitudeStudy:
    """S, W+ and CoT+ over (k/(M g L), A) at gamma 90, psi 45 deg; arrays shaped (len(k_ratios), len(A_deg))."""

    gravity: str
    k_ratios: np.ndarray
    A_deg: np.ndarray
    S: np.ndarray
    W_plus: np.ndarray
    CoT_plus: np.ndarray
    status: np.ndarray

    @property
    def stuck(self) -> np.ndarray:
        return _stuck(self.S, self.status)

    @property
    def CoT_moving(self) -> np.ndarray:
        """CoT+ where the robot moves; NaN where it is stuck (CoT+ infinite) or the run failed."""
        return np.where(self.stuck | ~np.isfinite(self.CoT_plus), np.nan, self.CoT_plus)

    @property
    def A_opt(self) -> np.ndarray:
        """Amplitude of least CoT+ for each stiffness [deg] (NaN when the minimum is at the grid's end)."""
        out = np.full(len(self.k_ratios), np.nan)
        for i in range(len(self.k_ratios)):
            c = self.CoT_moving[i]
            ok = np.isfinite(c)
            if ok.sum() < 3:
                continue
            a, _ = _parabolic_max(self.A_deg[ok], -c[ok])
            if self.A_deg[ok][0] < a < self.A_deg[ok][-1]:
                out[i] = a
        return out

    @property
    def CoT_min(self) -> np.ndarray:
        """Least CoT+ over the amplitudes for each stiffness (NaN if the robot never moves)."""
        c = self.CoT_moving
        return np.array([np.nanmin(row) if np.isfinite(row).any() else np.nan for row in c])

    def paper_comparison(self) -> dict[str, np.ndarray] | None:
        """The paper's CoT+ (``fig_cot_vs_amplitude.csv``) at this study's amplitudes and stiffnesses.

        Returns ``paper`` and ``rel_diff`` (ours/paper - 1) shaped like CoT_plus, NaN where either is
        missing; None unless the study uses the paper's three stiffnesses.  Amplitudes between the
        paper's points are interpolated linearly.
        """
        if len(self.k_ratios) != 3 or not np.allclose(self.k_ratios, COT_K_RATIOS):
            return None
        data = read_paper_csv("fig_cot_vs_amplitude.csv")
        cols = ("CoT_plus_large_k", "CoT_plus_realistic_k", "CoT_plus_low_k")
        paper = np.array([np.interp(self.A_deg, data["A_deg"], data[c], left=np.nan, right=np.nan) for c in cols])
        return {"paper": paper, "rel_diff": self.CoT_moving / paper - 1.0}

    @property
    def counts(self) -> dict[str, int]:
        return _counts(self.status)


def amplitude_study(gravity: str = "paper", A_deg=(1.0, 5.0, 10.0, 15.0, 20.0, 30.0, 40.0, 50.0, 60.0), k_ratios: Sequence[float] = COT_K_RATIOS,
                    gamma_deg: float = 90.0, psi_deg: float = 45.0, sweep: SweepOptions = SweepOptions()) -> AmplitudeStudy:
    """Fig. CoT (and S against A): gamma 90, psi 45 deg, stiffnesses k/(M g L) = 5, 2.74, 0.3."""
    ks = np.asarray(k_ratios, float)
    res = sweep.run(base_problem(gravity, [f"gait.gamma_deg={float(gamma_deg)!r}", f"gait.psi_deg={float(psi_deg)!r}"]),
                    {"robot.k": ks * PAPER_ROBOT.MgL, "gait.A_deg": np.asarray(A_deg, float)}, f"amplitude_{gravity}")
    cot = res.array("CoT_plus")
    return AmplitudeStudy(gravity, ks, res.axes["gait.A_deg"], res.array("S"), res.array("W_plus"), cot,
                          res.status_array())


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
        return _stuck(self.S, self.status)

    @property
    def stuck_range(self) -> np.ndarray:
        """Width of the psi range [deg] over (0, 180) on which the robot does not move, per factor (grid estimate)."""
        inner = (self.psi_deg > 0) & (self.psi_deg < 180)
        psi = self.psi_deg[inner]
        step = np.gradient(psi) if psi.size > 1 else np.ones_like(psi)
        return np.array([float(np.sum(step[self.stuck[i, inner]])) for i in range(len(self.factors))])

    @property
    def psi_stop(self) -> np.ndarray:
        """psi [deg] from which on the robot stays stuck up to 180 deg, per factor (NaN if it moves up to 180).

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
        return np.array([_non_increasing(-self.S[i, pos], atol) for i in range(len(self.factors))])

    @property
    def counts(self) -> dict[str, int]:
        return _counts(self.status)


def higher_friction(gravity: str = "paper", psi_deg=tuple(range(0, 181, 15)), factors: Sequence[float] = (1, 2, 3, 4),
                    sweep: SweepOptions = SweepOptions()) -> HigherFriction:
    """Supplementary figure: S against psi for mu = 1, 2, 3, 4 times the measured 0.389."""
    f = np.asarray(factors, float)
    res = sweep.run(base_problem(gravity), {"robot.mu": f * PAPER_ROBOT.mu1, "gait.psi_deg": np.asarray(psi_deg, float)},
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
    """final bisection bracket of the onset (not crawling at the lower end, crawling at the upper end)"""

    @property
    def stuck(self) -> np.ndarray:
        return _stuck(self.S, self.status)

    def ranges(self) -> list[tuple[str, float, float, int]]:
        """Maximal runs of the grid with one outcome: (outcome, first k ratio, last k ratio, points).

        The outcome is "stuck", "moves" or a failure status, so that e.g. the fold region of the
        physical convention shows as one run.
        """
        names = ["stuck" if s else ("moves" if st == SUCCESS else str(st)) for s, st in zip(self.stuck, self.status)]
        return outcome_runs(self.k_ratios, names)

    @property
    def counts(self) -> dict[str, int]:
        return _counts(self.status)


def _outcome(gravity: str, ratio: float) -> str:
    """"stuck", "moves" or the failure status of the paper's gait at stiffness ratio k/(M g L)."""
    problem = base_problem(gravity, [f"robot.k={ratio * PAPER_ROBOT.MgL!r}"])
    r = run_problem(problem)
    if not r.success:
        return r.status_name
    return "stuck" if abs(r.S) <= STUCK_TOL * problem.robot.L else "moves"


def _bisect(gravity: str, lo: float, hi: float, upper: str, steps: int) -> tuple[float, float]:
    """Shrink [lo, hi] (outcome at hi: ``upper``, at lo: anything else) by bisection."""
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        if _outcome(gravity, mid) == upper:
            hi = mid
        else:
            lo = mid
    return lo, hi


def stiffness_study(gravity: str = "paper", k_ratios=(0.05, 0.08, 0.1, 0.15, 0.2, 0.3, 0.5, 1.0, 2.0, 5.0), bisection_steps: int = 10,
                    sweep: SweepOptions = SweepOptions()) -> StiffnessStudy:
    """S and CoT+ against k/(M g L) (gamma 90, A 30, psi 45 deg), locating the friction threshold.

    The threshold is bracketed by the largest k on the grid at which the robot is stuck and the
    next grid point, and refined by ``bisection_steps`` bisections (direct runs).  The onset of
    crawling is bracketed likewise by the last grid point at which the robot does not crawl (stuck
    or failed) and the next one.  With the paper's sign the two coincide; with the physical sign
    folds and failures to stand lie between them.
    """
    ks = np.sort(np.asarray(k_ratios, float))
    base = base_problem(gravity)
    res = sweep.run(base, {"robot.k": ks * PAPER_ROBOT.MgL}, f"stiffness_{gravity}")
    S, status = res.array("S"), res.status_array()
    stuck = _stuck(S, status)
    threshold, bracket = math.nan, (math.nan, math.nan)
    if stuck.any() and not stuck[-1]:
        j = int(np.nonzero(stuck)[0][-1])
        # the bisection's predicate is "not stuck" at the upper end: any other outcome
        lo, hi = float(ks[j]), float(ks[j + 1])
        for _ in range(bisection_steps):
            mid = 0.5 * (lo + hi)
            if _outcome(gravity, mid) == "stuck":
                lo = mid
            else:
                hi = mid
        threshold, bracket = 0.5 * (lo + hi), (lo, hi)
    moves = (status == SUCCESS) & ~stuck
    onset, onset_bracket = math.nan, (math.nan, math.nan)
    if moves[-1] and not moves.all():
        j = int(np.nonzero(~moves)[0][-1])
        onset_bracket = _bisect(gravity, float(ks[j]), float(ks[j + 1]), "moves", bisection_steps)
        onset = 0.5 * sum(onset_bracket)
    return StiffnessStudy(gravity, ks, S, res.array("CoT_plus"), status, threshold, bracket, onset, onset_bracket)


# --------------------------------------------------------------------------------------------
# the pressure-driven robot (Fig. exp)
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PressureStudy:
    """Normalised progress of the pressure-driven robot against p0 and psi, with the paper's data."""

    fit: PressureFit
    experiment_p0: dict[str, np.ndarray] = field(repr=False)
    """the paper's measured S/S_max against p0 with error bars (columns of the CSV file)"""
    experiment_psi: dict[str, np.ndarray] = field(repr=False)
    paper_p0: dict[str, np.ndarray] = field(repr=False)
    """the paper's simulated curves"""
    paper_psi: dict[str, np.ndarray] = field(repr=False)
    flat: PressureFit | None = None
    """the same curves with the flat rest shape (phi_rest = 180 deg), to show why the rest angle is fitted"""

    @property
    def gravity(self) -> str:
        return self.fit.curves.gravity

    def experiment_rms(self) -> tuple[float, float]:
        """RMS of (model - experiment) in S/S_max at the measured points, for p0 and for psi."""
        c = self.fit.curves
        e0 = np.interp(self.experiment_p0["p0_bar"], c.p0_bar, c.progress_p0) - self.experiment_p0["S_over_Smax"]
        psi_exp = self.experiment_psi["psi_deg"]
        keep = (psi_exp >= c.psi_deg.min()) & (psi_exp <= c.psi_deg.max())
        e1 = np.interp(psi_exp[keep], c.psi_deg, c.progress_psi) - self.experiment_psi["S_over_Smax"][keep]
        return float(np.sqrt(np.nanmean(e0**2))), float(np.sqrt(np.nanmean(e1**2)))

    @property
    def psi_opt(self) -> tuple[float, float]:
        """(psi [deg], S/S_max) of the largest progress on the psi curve (parabolic refinement)."""
        return _parabolic_max(self.fit.curves.psi_deg, self.fit.curves.progress_psi)


def pressure_study(gravity: str = "paper", fit: bool = True, p0_bar=None, psi_deg=None,
                   phi_rest_deg: float | None = None, compare_flat: bool = False) -> PressureStudy:
    """Fig. exp: the pressure-driven robot against p0 and psi (see :mod:`ocp_crawl.studies.pressure`).

    ``fit``: fit the rest angle to the paper's simulated curves on the given grids (default: the
    paper's own points); otherwise evaluate ``phi_rest_deg`` (default: the stored fit).  The
    points run one after another in this process: the pressure input is not a problem-file key,
    so the sweep engine cannot express it.  ``compare_flat`` also evaluates the flat rest shape.
    """
    if fit:
        result = fit_rest_angle(gravity, p0_bar, psi_deg)
    else:
        rest = FITTED_REST_DEG[gravity] if phi_rest_deg is None else phi_rest_deg
        result = evaluate_fit(rest, gravity, p0_bar, psi_deg)
    flat = evaluate_fit(FLAT_REST_DEG, gravity, p0_bar, psi_deg) if compare_flat else None
    return PressureStudy(result, read_paper_csv("fig_exp_p0_experiment.csv"),
                         read_paper_csv("fig_exp_psi_experiment.csv"), read_paper_csv("fig_exp_p0_simulation.csv"),
                         read_paper_csv("fig_exp_psi_simulation.csv"), flat)


__all__ = [
    "SweepOptions", "base_problem", "REALISTIC_K_RATIO", "COT_K_RATIOS", "COT_K_LABELS", "LOW_K_RATIO", "STUCK_TOL",
    "GaitComparison", "gait_comparison", "PsiGammaMap", "psi_gamma_map", "FrictionBand", "friction_band",
    "AmplitudeStudy", "amplitude_study", "HigherFriction", "higher_friction", "StiffnessStudy", "stiffness_study",
    "PressureStudy", "pressure_study",
]
