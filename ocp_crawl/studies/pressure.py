"""The pressure-driven robot of the paper's experiments (Section III): its gaits, the paper's
curves, the fit, and the study of Fig. exp.

The actuator (bending map, assumed waveform, reference angles) is :mod:`ocp_crawl.model.pressure`,
whose docstring states the assumptions the paper leaves open.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import cast

import numpy as np
from scipy.optimize import minimize_scalar

from ocp_crawl.sim import simulate
from ocp_crawl.sim.event import HybridOptions
from ocp_crawl.model.statics import GRAVITY_CONVENTIONS, GravityConvention, Model, Robot
from ocp_crawl.sim.result import CrawlResult
from ocp_crawl.io.paper_data import read_paper_csv
from ocp_crawl.model.pressure import (DEFAULT_FORM, FITTED_REST_DEG, FLAT_REST_DEG,
                                      PAPER_FORM_AMPLITUDE_BAR, PRESSURE_FORMS, pressure_torque)
from ocp_crawl.status import Status
from ocp_crawl.studies.common import SUCCESS, parabolic_max

#: pressure at which the paper normalises its p0 curve, and the assumed operating points [bar, deg]
P0_NORMALISE_BAR = 1.7
PSI_FOR_P0_CURVE_DEG = 45.0
P0_FOR_PSI_CURVE_BAR = 1.7
#: pressure amplitude [bar] of the paper's form (ref) on its psi curve (at p0 = 1.7 bar, flat rest):
#: the paper does not state it; :func:`fit_psi_amplitude` on the paper's full psi curve gives 0.99
#: (paper's sign; physical: 0.95)
PSI_CURVE_AMPLITUDE_BAR = 0.99


def simulate_pressure(model: Model, p0_bar: float, psi_deg: float,
                      phi_rest_deg: float | None = None,
                      options: HybridOptions | None = None, t_eval=None,
                      amplitude_bar: float | None = None) -> CrawlResult:
    """Hybrid-quasistatic gait of the pressure-driven robot (torque drive).

    ``p0_bar``: peak pressure [bar]; ``psi_deg``: phase difference [deg]; ``phi_rest_deg``: rest
    angle [deg], by default the stored fit of the model's gravity convention; ``t_eval``: phases
    [cycles] to sample; ``amplitude_bar``: None for the raised sine from 0 to ``p0_bar``, else the
    pressure amplitude [bar] of the paper's form (ref) around the nominal ``p0_bar``.  Returns the
    :class:`~ocp_crawl.sim.result.CrawlResult`.
    """
    rest = FITTED_REST_DEG[model.gravity] if phi_rest_deg is None else phi_rest_deg
    return simulate(model,
                    pressure_torque(model.robot, p0_bar, psi_deg, rest,
                                    amplitude_bar=amplitude_bar), "event",
                    options, t_eval=t_eval)


# --------------------------------------------------------------------------------------------
# the paper's curves and the fit
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PressureCurves:
    """Progress of the pressure-driven robot along the paper's two curves (S < 0: towards foot
    1)."""

    gravity: str
    phi_rest_deg: float
    p0_bar: np.ndarray
    """pressures of the p0 curve [bar] (psi = ``psi_for_p0_deg``)"""
    S_p0: np.ndarray
    """S [m] at each p0 (NaN where the run failed)"""
    psi_deg: np.ndarray
    """phase differences of the psi curve [deg] (p0 = ``p0_for_psi_bar``)"""
    S_psi: np.ndarray
    """S [m] at each psi"""
    S_norm: float
    """S [m] at p0 = 1.7 bar, psi = ``psi_for_p0_deg``: the p0 curve's normalisation"""
    status_p0: tuple[str, ...]
    status_psi: tuple[str, ...]
    psi_for_p0_deg: float = PSI_FOR_P0_CURVE_DEG
    p0_for_psi_bar: float = P0_FOR_PSI_CURVE_BAR
    amplitude_p0_bar: float | None = None
    """pressure amplitude [bar] of the form (ref) on the p0 curve (None: raised sine, p0 the
    peak)"""
    amplitude_psi_bar: float | None = None
    """pressure amplitude [bar] of the form (ref) on the psi curve (None: raised sine)"""

    @property
    def progress_p0(self) -> np.ndarray:
        """-S/S(p0 = 1.7 bar) along the p0 curve (the paper's normalisation)."""
        return self.S_p0 / self.S_norm

    @property
    def progress_psi(self) -> np.ndarray:
        """-S/max(-S) along the psi curve."""
        prog = -self.S_psi
        return prog / np.nanmax(prog)


def _run(model: Model, p0: float, psi: float, rest: float,
         amplitude: float | None = None) -> tuple[float, str]:
    try:
        r = simulate_pressure(model, p0, psi, rest, amplitude_bar=amplitude)
    except ValueError:
        # no released equilibrium at the start: the input cannot even start the robot
        return float("nan"), Status.NO_START.label
    return (r.S if r.success else float("nan")), r.status_name


def pressure_curves(phi_rest_deg: float, gravity: str = "physical", p0_bar=None, psi_deg=None,
                    robot: Robot | None = None, amplitude_p0_bar: float | None = None,
                    amplitude_psi_bar: float | None = None) -> PressureCurves:
    """S along the paper's p0 and psi curves for one rest angle [deg] (defaults: the paper's own
    grids).

    ``p0_bar``: pressures [bar] of the p0 curve; ``psi_deg``: phase differences [deg] of the psi
    curve; ``robot``: default Table I; ``amplitude_p0_bar``, ``amplitude_psi_bar``: pressure
    amplitudes [bar] of the paper's form (ref) on each curve (None: the raised sine, p0 the peak).
    Returns :class:`PressureCurves`.
    """
    if gravity not in GRAVITY_CONVENTIONS:
        raise ValueError(f"gravity must be one of {GRAVITY_CONVENTIONS}, got {gravity!r}")
    model = Model(robot or Robot.paper(), gravity=cast(GravityConvention, gravity))  # checked above
    default_p0, default_psi = paper_grids()
    p0 = default_p0 if p0_bar is None else np.asarray(p0_bar, float)
    psi = default_psi if psi_deg is None else np.asarray(psi_deg, float)
    run_p0 = [_run(model, p, PSI_FOR_P0_CURVE_DEG, phi_rest_deg, amplitude_p0_bar) for p in p0]
    run_psi = [_run(model, P0_FOR_PSI_CURVE_BAR, s, phi_rest_deg, amplitude_psi_bar) for s in psi]
    s_norm, _ = _run(model, P0_NORMALISE_BAR, PSI_FOR_P0_CURVE_DEG, phi_rest_deg, amplitude_p0_bar)
    return PressureCurves(gravity, float(phi_rest_deg), p0, np.array([r[0] for r in run_p0]), psi,
                          np.array([r[0] for r in run_psi]), s_norm, tuple(r[1] for r in run_p0),
                          tuple(r[1] for r in run_psi), amplitude_p0_bar=amplitude_p0_bar,
                          amplitude_psi_bar=amplitude_psi_bar)


@dataclass(frozen=True)
class PressureFit:
    """Rest angle fitted to the paper's simulated curves and the remaining error.

    Errors are in units of the normalised progress S/S_max (the paper's axis), model minus paper,
    at the paper's points; ``rms`` is the objective, sqrt((rms_p0^2 + rms_psi^2)/2), so that the
    two curves weigh the same whatever their number of points.
    """

    curves: PressureCurves
    ref_p0: np.ndarray
    """the paper's S/S_max at ``curves.p0_bar``"""
    ref_psi: np.ndarray
    """the paper's S/S_max at ``curves.psi_deg``"""
    fitted: bool
    """True if the rest angle was fitted here, False if the stored value was evaluated"""
    nfev: int = 0

    @property
    def phi_rest_deg(self) -> float:
        return self.curves.phi_rest_deg

    @property
    def err_p0(self) -> np.ndarray:
        return self.curves.progress_p0 - self.ref_p0

    @property
    def err_psi(self) -> np.ndarray:
        return self.curves.progress_psi - self.ref_psi

    @staticmethod
    def _rms(e: np.ndarray) -> float:
        return float(np.sqrt(np.nanmean(e**2))) if np.any(np.isfinite(e)) else float("inf")

    @property
    def rms_p0(self) -> float:
        return self._rms(self.err_p0)

    @property
    def rms_psi(self) -> float:
        return self._rms(self.err_psi)

    @property
    def rms(self) -> float:
        return math.sqrt(0.5 * (self.rms_p0**2 + self.rms_psi**2))

    @property
    def max_p0(self) -> tuple[float, float]:
        """(largest |error|, p0 [bar] where it occurs) on the p0 curve"""
        return _worst(self.err_p0, self.curves.p0_bar)

    @property
    def max_psi(self) -> tuple[float, float]:
        """(largest |error|, psi [deg] where it occurs) on the psi curve"""
        return _worst(self.err_psi, self.curves.psi_deg)

    @property
    def failures(self) -> int:
        return sum(s != SUCCESS for s in self.curves.status_p0 + self.curves.status_psi)


def _worst(err: np.ndarray, x: np.ndarray) -> tuple[float, float]:
    if not np.any(np.isfinite(err)):
        return float("nan"), float("nan")
    j = int(np.nanargmax(np.abs(err)))
    return float(abs(err[j])), float(x[j])


def paper_grids() -> tuple[np.ndarray, np.ndarray]:
    """The paper's simulated points: p0 [bar], and psi [deg] without its leading (0, 0) point.

    That point is not a simulation output (the others are 50 equally spaced phases from 1 to
    180 deg): at psi = 0 the paper sets S = 0 by symmetry, which its unequal segments break.
    """
    psi = read_paper_csv("fig_exp_psi_simulation.csv")["psi_deg"]
    return read_paper_csv("fig_exp_p0_simulation.csv")["p0_bar"], psi[psi > 0]


def _reference(p0: np.ndarray, psi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d0 = read_paper_csv("fig_exp_p0_simulation.csv")
    dp = read_paper_csv("fig_exp_psi_simulation.csv")
    return np.interp(p0, d0["p0_bar"], d0["S_over_Smax"]), np.interp(psi, dp["psi_deg"],
                                                                     dp["S_over_Smax"])


def evaluate_fit(phi_rest_deg: float, gravity: str = "physical", p0_bar=None, psi_deg=None,
                 amplitude_p0_bar: float | None = None,
                 amplitude_psi_bar: float | None = None) -> PressureFit:
    """The fit error of a given rest angle [deg] on the given grids (p0 [bar], psi [deg]; default:
    the paper's points); ``amplitude_*_bar``: as :func:`pressure_curves`.  Returns a
    :class:`PressureFit` (``fitted`` False)."""
    curves = pressure_curves(phi_rest_deg, gravity, p0_bar, psi_deg,
                             amplitude_p0_bar=amplitude_p0_bar, amplitude_psi_bar=amplitude_psi_bar)
    ref_p0, ref_psi = _reference(curves.p0_bar, curves.psi_deg)
    return PressureFit(curves, ref_p0, ref_psi, fitted=False)


def fit_rest_angle(gravity: str = "physical", p0_bar=None, psi_deg=None, bounds=(95.0, 175.0),
                   xatol: float = 0.1) -> PressureFit:
    """Fit the rest angle phi_rest [deg] to the paper's simulated curves (bounded scalar
    minimisation).

    ``p0_bar`` [bar], ``psi_deg`` [deg]: the grids, default :func:`paper_grids`; ``bounds`` [deg]
    and ``xatol`` [deg]: the search interval and tolerance.  Returns a :class:`PressureFit`.
    """
    calls = {"n": 0}

    def objective(rest: float) -> float:
        calls["n"] += 1
        return evaluate_fit(rest, gravity, p0_bar, psi_deg).rms

    res = minimize_scalar(objective, bounds=bounds, method="bounded", options={"xatol": xatol})
    best = evaluate_fit(float(res.x), gravity, p0_bar, psi_deg)
    return PressureFit(best.curves, best.ref_p0, best.ref_psi, fitted=True, nfev=calls["n"] + 1)


def fit_psi_amplitude(gravity: str = "paper", p0_bar=None, psi_deg=None,
                      bounds=(PAPER_FORM_AMPLITUDE_BAR, 1.7), xatol: float = 0.01) -> PressureFit:
    """The paper's form (ref) with the flat rest shape: the p0 curve at amplitude 0.4 bar, the psi
    curve's amplitude [bar] (at p0 = 1.7 bar; unstated by the paper) fitted to the published psi
    curve (bounded scalar minimisation of its RMS error; ``bounds`` [bar] keep the pressure >= 0).

    ``p0_bar`` [bar], ``psi_deg`` [deg]: the grids, default :func:`paper_grids`.  Returns a
    :class:`PressureFit` (``fitted`` True).
    """
    calls = {"n": 0}

    def objective(amp: float) -> float:
        calls["n"] += 1
        return evaluate_fit(FLAT_REST_DEG, gravity, [P0_NORMALISE_BAR], psi_deg,
                            PAPER_FORM_AMPLITUDE_BAR, amp).rms_psi

    res = minimize_scalar(objective, bounds=bounds, method="bounded", options={"xatol": xatol})
    best = evaluate_fit(FLAT_REST_DEG, gravity, p0_bar, psi_deg, PAPER_FORM_AMPLITUDE_BAR,
                        float(res.x))
    return PressureFit(best.curves, best.ref_p0, best.ref_psi, fitted=True, nfev=calls["n"] + 1)


# --------------------------------------------------------------------------------------------
# Fig. exp
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PressureStudy:
    """Normalised progress of the pressure-driven robot against p0 and psi, with the paper's
    data."""

    fit: PressureFit
    experiment_p0: dict[str, np.ndarray] = field(repr=False)
    """the paper's measured S/S_max against p0 with error bars (columns of the CSV file)"""
    experiment_psi: dict[str, np.ndarray] = field(repr=False)
    paper_p0: dict[str, np.ndarray] = field(repr=False)
    """the paper's simulated curves"""
    paper_psi: dict[str, np.ndarray] = field(repr=False)
    flat: PressureFit | None = None
    """the same curves with a raised sine and the flat rest shape (phi_rest = 180 deg), for
    comparison"""

    @property
    def gravity(self) -> str:
        return self.fit.curves.gravity

    def experiment_rms(self) -> tuple[float, float]:
        """RMS of (model - experiment) in S/S_max at the measured points, for p0 and for psi."""
        c = self.fit.curves
        e0 = np.interp(self.experiment_p0["p0_bar"], c.p0_bar,
                       c.progress_p0) - self.experiment_p0["S_over_Smax"]
        psi_exp = self.experiment_psi["psi_deg"]
        keep = (psi_exp >= c.psi_deg.min()) & (psi_exp <= c.psi_deg.max())
        e1 = np.interp(psi_exp[keep], c.psi_deg,
                       c.progress_psi) - self.experiment_psi["S_over_Smax"][keep]
        return float(np.sqrt(np.nanmean(e0**2))), float(np.sqrt(np.nanmean(e1**2)))

    @property
    def psi_opt(self) -> tuple[float, float]:
        """(psi [deg], S/S_max) of the largest progress on the psi curve (parabolic refinement)."""
        return parabolic_max(self.fit.curves.psi_deg, self.fit.curves.progress_psi)


def pressure_study(gravity: str = "physical", fit: bool = True, p0_bar=None, psi_deg=None,
                   phi_rest_deg: float | None = None, compare_flat: bool = False,
                   form: str = DEFAULT_FORM) -> PressureStudy:
    """Fig. exp: the pressure-driven robot against p0 and psi (the curves and the fit above).

    ``form`` "paper" (default): the paper's form (ref), p_i = p0 + A_p sin(2 pi t +- psi/2) with the
    flat rest shape (:mod:`ocp_crawl.model.pressure`): A_p = 0.4 bar on the p0 curve; on the psi
    curve ``fit`` fits A_p (:func:`fit_psi_amplitude`), else the stored
    :data:`PSI_CURVE_AMPLITUDE_BAR`.  ``form`` "raised": raised sines from 0 to the peak p0 with a
    rest angle: ``fit`` fits it to the paper's simulated curves, else ``phi_rest_deg`` (default: the
    stored fit) is evaluated.  The points run one after another in this process: the pressure input
    is not a problem-file key, so the sweep engine cannot express it.  ``compare_flat`` also
    evaluates the raised sine with the flat rest shape.  ``gravity``: "physical" or "paper";
    ``p0_bar`` [bar], ``psi_deg`` [deg]: the grids (None: the paper's points).  Returns a
    :class:`PressureStudy`.
    """
    if form not in PRESSURE_FORMS:
        raise ValueError(f"form must be one of {', '.join(PRESSURE_FORMS)}, got {form!r}")
    if form == "paper":
        result = fit_psi_amplitude(gravity, p0_bar, psi_deg) if fit else evaluate_fit(
            FLAT_REST_DEG, gravity, p0_bar, psi_deg, PAPER_FORM_AMPLITUDE_BAR,
            PSI_CURVE_AMPLITUDE_BAR)
    elif fit:
        result = fit_rest_angle(gravity, p0_bar, psi_deg)
    else:
        rest = FITTED_REST_DEG[gravity] if phi_rest_deg is None else phi_rest_deg
        result = evaluate_fit(rest, gravity, p0_bar, psi_deg)
    flat = evaluate_fit(FLAT_REST_DEG, gravity, p0_bar, psi_deg) if compare_flat else None
    return PressureStudy(result, read_paper_csv("fig_exp_p0_experiment.csv"),
                         read_paper_csv("fig_exp_psi_experiment.csv"),
                         read_paper_csv("fig_exp_p0_simulation.csv"),
                         read_paper_csv("fig_exp_psi_simulation.csv"), flat)
