"""The pressure-driven robot of the paper's experiments (Section III): bending map, waveform, fit.

Each fluidic segment bends by the calibrated map of Table I,

    bending_i(p) = a_i p^2 + b_i p     [rad], p the gauge pressure [bar],

measured on the clamped robot as the edge angle of one half of the beam, i.e. the deflection of
the equivalent joint.  The actuator acts like a spring whose rest angle moves with the pressure,
so the torque input is that of eq. (tau) with the reference angle

    phi_ref,i(t) = phi_rest - bending_i(p_i(t)),      tau_i = k (phi_ref,i - pi).

**Assumptions (the paper does not state them).**  The paper says only that the pressures are
"periodic inputs of the form (ref)" with nominal pressure p0 and phase difference psi. We assume

* a raised sine between zero and the peak pressure p0 (a pressure controller cannot go below
  atmospheric, and the largest experimental p0 = 1.7 bar gives a plausible 28 deg of bending):
  p_i(t) = p0 (1 + sin(2 pi t +- psi/2)) / 2, segment 1 leading for psi > 0;
* an equivalent rest angle ``phi_rest`` of the joints at zero pressure, fitted to the paper's
  simulated curves (:func:`fit_rest_angle`).  With the flat rest shape (phi_rest = 180 deg) the
  robot stays nearly flat, where S depends steeply on the nominal angle, and S(p0) grows like p0^3
  instead of the published ~p0^1.8 (RMS error 0.84 in S/S_max on the paper's p0 points, paper's
  gravity sign); the fitted rest angle, 131 deg (a pre-curved, arched robot, as in the paper's
  Fig. 1 snapshots), brings it to 0.021 (0.053 on the psi curve);
* the operating points the paper leaves unstated: its p0 curve is normalised at p0 = 1.7 bar and
  assumed computed at psi = 45 deg (the paper's reference gait; the normalised curve is
  insensitive to it: +-0.01 between 45 and 90 deg), its psi curve is assumed computed at
  p0 = 1.7 bar (the largest experimental pressure) and is normalised by its maximum.

The published psi curve has two features this family does not reproduce (they dominate the fit
error, see :class:`PressureFit`): S/S_max = 0.34 already at psi = 1 deg, and 0.08 at psi = 180 deg.
Here both ends give S close to 0, as for the symmetric harmonic gait; only the small difference
between the two segments' maps (a1 != a2, b1 != b2) breaks the symmetry.
"""
from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.optimize import minimize_scalar

from .hybrid import HybridOptions, simulate_torque
from .inputs import TWO_PI, PeriodicSignal, ReferenceTorque
from .model import GRAVITY_CONVENTIONS, PAPER_PRESSURE_COEFFS, Model, Robot
from .result import CrawlResult

#: environment variable naming the directory of the paper's data files
PAPER_DATA_ENV = "OCP_CRAWL_PAPER_DATA"

#: rest angle [deg] fitted by :func:`fit_rest_angle` on the paper's full curves, per gravity convention
#: (used when a run does not fit again, e.g. ``reproduce --quick``)
FITTED_REST_DEG = {"paper": 131.3, "physical": 128.9}

#: pressure at which the paper normalises its p0 curve, and the assumed operating points [bar, deg]
P0_NORMALISE_BAR = 1.7
PSI_FOR_P0_CURVE_DEG = 45.0
P0_FOR_PSI_CURVE_BAR = 1.7


@dataclass(frozen=True)
class BendingMap:
    """Calibrated pressure-to-bending map of each segment, bending_i = a_i p^2 + b_i p (Table I)."""

    a1: float = PAPER_PRESSURE_COEFFS["a1"]
    """quadratic coefficient, segment 1 [rad/bar^2]"""
    a2: float = PAPER_PRESSURE_COEFFS["a2"]
    """quadratic coefficient, segment 2 [rad/bar^2]"""
    b1: float = PAPER_PRESSURE_COEFFS["b1"]
    """linear coefficient, segment 1 [rad/bar]"""
    b2: float = PAPER_PRESSURE_COEFFS["b2"]
    """linear coefficient, segment 2 [rad/bar]"""

    def _ab(self, ndim: int) -> tuple[np.ndarray, np.ndarray]:
        shape = (2,) + (1,) * ndim
        return np.array([self.a1, self.a2]).reshape(shape), np.array([self.b1, self.b2]).reshape(shape)

    def bending(self, p) -> np.ndarray:
        """Bending angles [rad] for pressures p [bar] of shape (2, ...)."""
        p = np.asarray(p, float)
        a, b = self._ab(p.ndim - 1)
        return a * p**2 + b * p

    def slope(self, p) -> np.ndarray:
        """d bending / d p [rad/bar] at pressures p of shape (2, ...)."""
        p = np.asarray(p, float)
        a, b = self._ab(p.ndim - 1)
        return 2 * a * p + b


@dataclass(frozen=True)
class PressureWaveform:
    """Assumed pressure inputs: raised sines from 0 to p0, p_i = p0 (1 + sin(2 pi t +- psi/2)) / 2 [bar]."""

    p0: float
    """peak ("nominal") pressure [bar]"""
    psi: float
    """phase lead of segment 1 over segment 2 [rad]"""

    def __post_init__(self) -> None:
        for name in ("p0", "psi"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
                raise ValueError(f"PressureWaveform.{name} must be a finite number, got {v!r}")
        if self.p0 < 0:
            raise ValueError(f"PressureWaveform.p0 must be >= 0 bar, got {self.p0!r}")

    def _phases(self, t) -> np.ndarray:
        w = TWO_PI * np.asarray(t, float)
        return np.array([w + self.psi / 2, w - self.psi / 2])

    def __call__(self, t) -> np.ndarray:
        """Pressures [bar] at phase t (scalar -> (2,), N phases -> (2, N))."""
        return 0.5 * self.p0 * (1.0 + np.sin(self._phases(t)))

    def derivative(self, t) -> np.ndarray:
        """d p / d t [bar per cycle]."""
        return 0.5 * self.p0 * TWO_PI * np.cos(self._phases(t))


@dataclass(frozen=True)
class PressureReference(PeriodicSignal):
    """Reference joint angles of the pressure-driven robot, phi_ref,i = phi_rest - bending_i(p_i(t)) [rad]."""

    waveform: PressureWaveform
    phi_rest: float = math.radians(FITTED_REST_DEG["paper"])
    """joint angle at zero pressure [rad] (fitted; see the module docstring)"""
    bending_map: BendingMap = field(default_factory=BendingMap)

    def __call__(self, t):
        return self.phi_rest - self.bending_map.bending(self.waveform(t))

    def derivative(self, t):
        return -self.bending_map.slope(self.waveform(t)) * self.waveform.derivative(t)

    def describe(self) -> dict:
        m = self.bending_map
        return {"type": "PressureReference", "p0_bar": self.waveform.p0, "psi_deg": math.degrees(self.waveform.psi),
                "phi_rest_deg": math.degrees(self.phi_rest), "a": [m.a1, m.a2], "b": [m.b1, m.b2],
                "waveform": "p0 (1 + sin(2 pi t +- psi/2)) / 2"}


def pressure_torque(robot: Robot, p0_bar: float, psi_deg: float, phi_rest_deg: float,
                    bending_map: BendingMap | None = None) -> ReferenceTorque:
    """Torque input tau = k (phi_ref - pi) of the pressure-driven robot [N m]."""
    ref = PressureReference(PressureWaveform(p0_bar, math.radians(psi_deg)), math.radians(phi_rest_deg),
                            bending_map or BendingMap())
    return ReferenceTorque(ref, robot.k)


def simulate_pressure(model: Model, p0_bar: float, psi_deg: float, phi_rest_deg: float | None = None,
                      options: HybridOptions | None = None, t_eval=None) -> CrawlResult:
    """Hybrid-quasistatic gait of the pressure-driven robot (torque drive).

    ``phi_rest_deg`` defaults to the stored fit of the model's gravity convention.
    """
    rest = FITTED_REST_DEG[model.gravity] if phi_rest_deg is None else phi_rest_deg
    return simulate_torque(model, pressure_torque(model.robot, p0_bar, psi_deg, rest), options, t_eval=t_eval)


# --------------------------------------------------------------------------------------------
# the paper's curves and the fit
# --------------------------------------------------------------------------------------------
def paper_data_dir() -> Path:
    """Directory of the paper's data files: ``$OCP_CRAWL_PAPER_DATA``, else the copy shipped in the package."""
    env = os.environ.get(PAPER_DATA_ENV)
    return Path(env) if env else Path(__file__).resolve().parent / "data" / "paper"


def read_paper_csv(name: str, data_dir: str | Path | None = None) -> dict[str, np.ndarray]:
    """Columns of one of the paper's data files (``<paper_data_dir>/<name>``) as float arrays."""
    path = Path(data_dir or paper_data_dir()) / name
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except OSError as exc:
        raise FileNotFoundError(f"paper data file {path}: {exc.strerror or exc}") from None
    header, body = rows[0], [r for r in rows[1:] if r]
    return {h: np.array([float(r[j]) for r in body]) for j, h in enumerate(header)}


@dataclass(frozen=True)
class PressureCurves:
    """Progress of the pressure-driven robot along the paper's two curves (S < 0: towards foot 1)."""

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

    @property
    def progress_p0(self) -> np.ndarray:
        """-S/S(p0 = 1.7 bar) along the p0 curve (the paper's normalisation)."""
        return self.S_p0 / self.S_norm

    @property
    def progress_psi(self) -> np.ndarray:
        """-S/max(-S) along the psi curve."""
        prog = -self.S_psi
        return prog / np.nanmax(prog)


def _run(model: Model, p0: float, psi: float, rest: float) -> tuple[float, str]:
    try:
        r = simulate_pressure(model, p0, psi, rest)
    except ValueError:
        # no released equilibrium at the start: the input cannot even start the robot
        return float("nan"), "no_start"
    return (r.S if r.success else float("nan")), r.status_name


def pressure_curves(phi_rest_deg: float, gravity: str = "paper", p0_bar=None, psi_deg=None,
                    robot: Robot | None = None) -> PressureCurves:
    """S along the paper's p0 and psi curves for one rest angle (defaults: the paper's own grids)."""
    if gravity not in GRAVITY_CONVENTIONS:
        raise ValueError(f"gravity must be one of {GRAVITY_CONVENTIONS}, got {gravity!r}")
    model = Model(robot or Robot.paper(), gravity=gravity)
    default_p0, default_psi = paper_grids()
    p0 = default_p0 if p0_bar is None else np.asarray(p0_bar, float)
    psi = default_psi if psi_deg is None else np.asarray(psi_deg, float)
    run_p0 = [_run(model, p, PSI_FOR_P0_CURVE_DEG, phi_rest_deg) for p in p0]
    run_psi = [_run(model, P0_FOR_PSI_CURVE_BAR, s, phi_rest_deg) for s in psi]
    s_norm, _ = _run(model, P0_NORMALISE_BAR, PSI_FOR_P0_CURVE_DEG, phi_rest_deg)
    return PressureCurves(gravity, float(phi_rest_deg), p0, np.array([r[0] for r in run_p0]), psi,
                          np.array([r[0] for r in run_psi]), s_norm, tuple(r[1] for r in run_p0),
                          tuple(r[1] for r in run_psi))


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
        return sum(s != "success" for s in self.curves.status_p0 + self.curves.status_psi)


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
    return np.interp(p0, d0["p0_bar"], d0["S_over_Smax"]), np.interp(psi, dp["psi_deg"], dp["S_over_Smax"])


def evaluate_fit(phi_rest_deg: float, gravity: str = "paper", p0_bar=None, psi_deg=None) -> PressureFit:
    """The fit error of a given rest angle on the given grids (default: the paper's points)."""
    curves = pressure_curves(phi_rest_deg, gravity, p0_bar, psi_deg)
    ref_p0, ref_psi = _reference(curves.p0_bar, curves.psi_deg)
    return PressureFit(curves, ref_p0, ref_psi, fitted=False)


def fit_rest_angle(gravity: str = "paper", p0_bar=None, psi_deg=None, bounds=(95.0, 175.0),
                   xatol: float = 0.1) -> PressureFit:
    """Fit the rest angle phi_rest [deg] to the paper's simulated curves (bounded scalar minimisation).

    Default grids: :func:`paper_grids`.
    """
    calls = {"n": 0}

    def objective(rest: float) -> float:
        calls["n"] += 1
        return evaluate_fit(rest, gravity, p0_bar, psi_deg).rms

    res = minimize_scalar(objective, bounds=bounds, method="bounded", options={"xatol": xatol})
    best = evaluate_fit(float(res.x), gravity, p0_bar, psi_deg)
    return PressureFit(best.curves, best.ref_p0, best.ref_psi, fitted=True, nfev=calls["n"] + 1)
