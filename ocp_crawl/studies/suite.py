"""The grids of the quick and the full run (:data:`GRIDS`) and every study in one gravity convention
(:func:`run_studies`), as ``reproduce`` runs them."""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ocp_crawl.io.paper_data import read_paper_csv
from ocp_crawl.studies.common import SweepOptions
from ocp_crawl.studies.cot import (AmplitudeStudy, HigherFriction, StiffnessStudy, amplitude_study,
                                   higher_friction, stiffness_study)
from ocp_crawl.studies.gaits import (FrictionBand, GaitComparison, PsiGammaMap, friction_band,
                                     gait_comparison, psi_gamma_map)
from ocp_crawl.studies.pressure import PressureStudy, paper_grids, pressure_study


def _sym(values) -> np.ndarray:
    """Phases -v..v for the given non-negative v (0 once), sorted."""
    v = np.unique(np.abs(np.asarray(values, float)))
    return np.concatenate([-v[::-1][:-1] if v[0] == 0 else -v[::-1], v])


# --------------------------------------------------------------------------------------------
# the grids of the quick and the full run
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Grids:
    """Grids of one run mode (angles in deg, stiffness as k/(M g L), pressure in bar)."""

    gait_samples: int
    """phase samples of the configuration and force figures"""
    map_psi: np.ndarray
    map_gamma: np.ndarray
    band_psi: np.ndarray
    """psi of the friction band (both signs); denser at small psi where the average peaks"""
    band_ratios: int
    """number of mu1/mu2 values in [0.9, 1.1] (odd)"""
    amplitude_A: np.ndarray
    """amplitudes: the paper's points of Fig. CoT (every one in the full run)"""
    friction_psi: np.ndarray
    stiffness_k: np.ndarray
    bisection_steps: int
    """bisections of the friction threshold"""
    pressure_fit: bool
    """fit the rest angle (full) or evaluate the stored fit (quick)"""
    pressure_p0: np.ndarray | None
    """None: the paper's points"""
    pressure_psi: np.ndarray | None

    def rows(self) -> dict[str, str]:
        """Human-readable size of every grid (the report's table)."""
        def axis(a) -> str:
            if a is None:
                return "the paper's points"
            a = np.asarray(a)
            return f"{a.size} ({a.min():g} .. {a.max():g})"
        return {
            "configuration and forces: phase samples": str(self.gait_samples),
            "parametric map: psi x gamma [deg]": f"{axis(self.map_psi)} x {axis(self.map_gamma)}",
            "friction band: psi [deg] x mu1/mu2": f"{axis(self.band_psi)} x {self.band_ratios}",
            "amplitude: A [deg] x 3 stiffnesses": axis(self.amplitude_A),
            "higher friction: psi [deg] x 4 factors": axis(self.friction_psi),
            "stiffness: k/(M g L), bisection steps": f"{axis(self.stiffness_k)}, "
                                                     f"{self.bisection_steps}",
            "pressure: fit / p0 [bar] / psi "
            "[deg]": f"{'fit' if self.pressure_fit else 'stored fit'} / "
                                                     f"{axis(self.pressure_p0)} / "
                                                     f"{axis(self.pressure_psi)}",
        }


def _paper_A() -> np.ndarray:
    return read_paper_csv("fig_cot_vs_amplitude.csv")["A_deg"]


def _grids() -> dict[str, Grids]:
    A = _paper_A()
    p0, psi = paper_grids()
    small = [0, 1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60]
    return {
        "quick": Grids(
            gait_samples=201, map_psi=np.arange(0.0, 181.0, 30.0),
            map_gamma=np.arange(70.0, 151.0, 20.0),
            band_psi=_sym([0, 5, 15, 30, 45, 60, 90, 135, 180]), band_ratios=3,
            amplitude_A=A[::6].copy(),
            friction_psi=np.array([0.0, 10, 30, 60, 90, 120, 150, 165, 175, 180]),
            stiffness_k=np.geomspace(0.05, 5.0, 10), bisection_steps=6,
            pressure_fit=False, pressure_p0=p0[[0, 6, 13, 18, 26]],
            pressure_psi=psi[[0, 1, 2, 3, 5, 12, 24, 36, 48]]),
        "full": Grids(
            gait_samples=601, map_psi=np.arange(0.0, 181.0, 5.0),
            map_gamma=np.arange(50.0, 151.0, 5.0),
            band_psi=_sym(small + list(range(70, 181, 10))), band_ratios=9, amplitude_A=A.copy(),
            friction_psi=np.concatenate([np.arange(0.0, 150.0, 5.0), np.arange(150.0, 181.0, 2.5)]),
            stiffness_k=np.unique(np.concatenate([np.geomspace(0.03, 10.0, 36),
                                                  np.arange(0.06, 0.2, 0.01)])),
            bisection_steps=14, pressure_fit=True, pressure_p0=None, pressure_psi=None),
    }


#: the one table of grid sizes: "quick" (coarse, for tests and a first look) and "full" (the
#: default)
GRIDS: dict[str, Grids] = _grids()


# --------------------------------------------------------------------------------------------
# all studies in one convention
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StudySet:
    """Every study in one gravity convention."""

    gravity: str
    gait: GaitComparison
    parametric: PsiGammaMap
    band: FrictionBand
    amplitude: AmplitudeStudy
    friction: HigherFriction
    stiffness: StiffnessStudy
    pressure: PressureStudy
    elapsed: dict[str, float] = field(default_factory=dict)
    """wall time per study [s]"""


def run_studies(gravity: str, grids: Grids, sweep: SweepOptions = SweepOptions(),
                log: Callable[[str], None] | None = None) -> StudySet:
    """Run every study in gravity convention ``gravity`` ("physical" or "paper") on ``grids``.

    ``sweep``: how the grids are evaluated; ``log`` receives one line per study.  Returns the
    :class:`StudySet` with the wall time of each study.
    """
    say = log or (lambda msg: None)
    elapsed: dict[str, float] = {}
    out: dict[str, Any] = {}  # name -> that study's result (a field of StudySet)
    steps = (
        ("gait", lambda: gait_comparison(gravity=gravity, samples=grids.gait_samples)),
        ("parametric",
         lambda: psi_gamma_map(gravity=gravity, psi_deg=grids.map_psi, gamma_deg=grids.map_gamma,
                               sweep=sweep)),
        ("band",
         lambda: friction_band(gravity=gravity, psi_deg=grids.band_psi, n_ratios=grids.band_ratios,
                               sweep=sweep)),
        ("amplitude",
         lambda: amplitude_study(gravity=gravity, A_deg=grids.amplitude_A, sweep=sweep)),
        ("friction",
         lambda: higher_friction(gravity=gravity, psi_deg=grids.friction_psi, sweep=sweep)),
        ("stiffness", lambda: stiffness_study(gravity=gravity, k_ratios=grids.stiffness_k,
                                              bisection_steps=grids.bisection_steps, sweep=sweep)),
        ("pressure",
         lambda: pressure_study(gravity=gravity, fit=grids.pressure_fit, p0_bar=grids.pressure_p0,
                                psi_deg=grids.pressure_psi, compare_flat=True)),
    )
    for name, run in steps:
        t = time.perf_counter()
        say(f"{gravity} convention: {name} ...")
        out[name] = run()
        elapsed[name] = time.perf_counter() - t
    return StudySet(gravity=gravity, elapsed=elapsed, **out)


__all__ = ["GRIDS", "Grids", "StudySet", "run_studies"]
