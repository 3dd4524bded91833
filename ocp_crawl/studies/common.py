"""What the paper's studies share: the paper's robot and gait, the grid evaluation, small grid
helpers.

Every grid is evaluated by :func:`ocp_crawl.sweep.run_sweep` (parallel workers, progress, an
optional journal on disk) through :class:`SweepOptions`.  Failed points are data: each study keeps
the status of every point (``success``, ``fold``, ``lift_off``, ...) next to its numbers, and the
derived numbers (optimal psi, threshold, ...) use the successful points only.

Sign convention: S is the displacement per cycle along +x, from foot 1 to foot 2.  With psi > 0
joint 1 leads and the robot moves towards foot 1, S < 0; the "progress" -S is what the paper's
figures show for psi > 0.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ocp_crawl.model.statics import Robot
from ocp_crawl.problem import Problem, paper_problem
from ocp_crawl.status import Status
from ocp_crawl.sweep import SweepResult, run_sweep

#: metres to millimetres (the unit of S in figures and the report)
MM = 1e3
#: status label of a successful point (sweep rows and results)
SUCCESS = Status.SUCCESS.label
#: the paper's robot (Table I)
PAPER_ROBOT = Robot.paper()
#: k/(M g L) of the paper's robot, the "realistic" stiffness (about 2.74)
REALISTIC_K_RATIO = PAPER_ROBOT.k / PAPER_ROBOT.MgL
#: the three stiffnesses of the paper's CoT+ figure, k/(M g L): large, realistic, low
COT_K_RATIOS = (5.0, REALISTIC_K_RATIO, 0.3)
#: the names of :data:`COT_K_RATIOS` in the figures
COT_K_LABELS = ("large", "realistic", "low")
#: low stiffness of the configuration figure, k/(M g L)
LOW_K_RATIO = 0.3
#: |S| below this fraction of L counts as no motion ("stuck"): a stuck gait has S at round-off
STUCK_TOL = 1e-6


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
    """reuse the finished points of an interrupted run in ``out_dir`` (else its sweeps are
    overwritten)"""
    scheduler: str | None = None
    """Dask scheduler address or "local" (None: local worker processes)"""

    def __post_init__(self) -> None:
        if self.resume and self.out_dir is None:
            raise ValueError("SweepOptions: resume=True reuses the sweeps journaled in out_dir, "
                             "and out_dir is None: give out_dir or drop resume")

    def run(self, problem: Problem, grid: Mapping[str, Any], name: str) -> SweepResult:
        """Evaluate ``problem`` on ``grid`` ({SECTION.KEY: values}), journaled as ``out_dir/name``
        if out_dir is set."""
        out = None if self.out_dir is None else Path(self.out_dir) / name
        return run_sweep(problem, grid, out_dir=out, jobs=self.jobs,
                         resume=self.resume and out is not None,
                         force=out is not None and not self.resume, progress=self.progress,
                         scheduler=self.scheduler)


def base_problem(gravity: str = "physical", values: Mapping[str, Any] | None = None) -> Problem:
    """The paper's gait (Table I robot; gamma 90, A 30, psi 45 deg; torque drive) in a gravity
    convention.

    ``gravity``: "physical" or "paper"; ``values``: typed values by ``SECTION.KEY`` in the problem
    files' units (e.g. ``{"robot.k": 0.2, "gait.A_deg": 20.0}``), set with
    :meth:`Problem.with_values`.
    """
    return paper_problem().with_values({"model.gravity": gravity, **(values or {})})


def stuck_points(S: np.ndarray, status: np.ndarray, L: float = PAPER_ROBOT.L) -> np.ndarray:
    """Successful points at which the robot does not move (|S| <= STUCK_TOL L; S [m], L [m])."""
    return (status == SUCCESS) & (np.abs(np.nan_to_num(S, nan=np.inf)) <= STUCK_TOL * L)


def status_counts(status: np.ndarray) -> dict[str, int]:
    """Number of points by status, most frequent first."""
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


def parabolic_max(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Maximum (x, y) of y(x) on a grid, refined by the parabola through the best point and its
    neighbours."""
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


def non_increasing(y: np.ndarray, atol: float) -> bool:
    """Whether the finite values of y never rise by more than ``atol`` from one to the next."""
    y = np.asarray(y, float)
    y = y[np.isfinite(y)]
    return bool(np.all(np.diff(y) <= atol))
