"""The pressure-driven robot of the paper's experiments (Section III): bending map, waveform, fit.

Each fluidic segment bends by the calibrated map of Table I,

    bending_i(p) = a_i p^2 + b_i p     [rad], p the gauge pressure [bar],

measured on the clamped robot as the edge angle of one half of the beam, i.e. the deflection of
the equivalent joint.  The actuator acts like a spring whose rest angle moves with the pressure,
so the torque input is that of eq. (tau) with the reference angle

    phi_ref,i(t) = phi_rest - bending_i(p_i(t)),      tau_i = k (phi_ref,i - pi).

**Earlier assumptions** (``PressureWaveform(amplitude=None)``, ``form="raised"`` of the pressure
study and of the calibration; the paper's form (ref) below is the default of both,
:data:`DEFAULT_FORM`).  Reading "periodic inputs of the form (ref)" with nominal pressure p0
loosely, we assumed

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

**The paper's form (ref), read literally**: "pressure inputs of the form (ref)" with
"nominal pressure p0", where (ref) is gamma + A sin(w t +- psi/2) and gamma is called the "nominal
angle": p0 is the mean pressure, p_i = p0 + A_p sin(2 pi t +- psi/2)
(``PressureWaveform(amplitude=A_p)``).  The calibration (supplementary material) measures the edge
angle of a clamped segment from the flat beam (phi = asin(z/w), torque = k phi), i.e. the bending
from flat: the rest angle is 180 deg, not a fitted one.  With A_p =
:data:`PAPER_FORM_AMPLITUDE_BAR` = 0.4 bar (the paper's p0 curve starts at exactly 0.4 bar, the
smallest nominal pressure that keeps p_i >= 0) the paper's simulated p0 curve is reproduced with RMS
0.0013 in S/S(1.7 bar) up to 1.7 bar and 0.024 over 0.4..3 bar (paper's gravity sign; the physical
sign: 0.05 up to 1.7 bar), with no fitted parameter.

The published psi curve has two features this family does not reproduce (they dominate the fit
error, see :class:`PressureFit`): S/S_max = 0.34 already at psi = 1 deg, and 0.08 at psi = 180 deg.
Here both ends give S close to 0, as for the symmetric harmonic gait; only the small difference
between the two segments' maps (a1 != a2, b1 != b2) breaks the symmetry.

On a chain of more than three links the joints of a segment share its bend
(:class:`SegmentJoints`): the soft segment bent as an arc of hinges rather than at one joint.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ocp_crawl.model.inputs import TWO_PI, PeriodicSignal, ReferenceTorque
from ocp_crawl.model.statics import PAPER_PRESSURE_COEFFS, Robot

#: pressure amplitude A_p [bar] of the paper's form (ref) read from its p0 curve (see the module
#: docstring)
PAPER_FORM_AMPLITUDE_BAR = 0.4
#: rest angle [deg] of the calibrated bending map: the flat beam
FLAT_REST_DEG = 180.0
#: rest angle [deg] fitted by :func:`ocp_crawl.studies.pressure.fit_rest_angle` on the paper's full
#: curves, per gravity convention (used when a run does not fit again, e.g. ``reproduce --quick``)
FITTED_REST_DEG = {"paper": 131.3, "physical": 128.9}
#: the waveforms of the pressure inputs: "paper", the paper's form (ref) with nominal (mean) p0,
#: flat rest shape and amplitude :data:`PAPER_FORM_AMPLITUDE_BAR`; "raised", the earlier raised sine
#: from 0 to the peak p0 with the fitted rest angle :data:`FITTED_REST_DEG`
PRESSURE_FORMS = ("paper", "raised")
#: the default waveform of the pressure study and of the calibration (``ocp_crawl.fit``)
DEFAULT_FORM = "paper"


def form_constants(form: str = DEFAULT_FORM, gravity: str = "paper") -> dict[str, float]:
    """The waveform constants of a pressure-input form.

    Parameters
    ----------
    form : str
        One of :data:`PRESSURE_FORMS`.
    gravity : str
        Gravity convention ("paper" or "physical"): the stored rest angle of the raised sine depends
        on it.

    Returns
    -------
    dict
        ``phi_rest_deg`` [deg], the rest angle, and ``amplitude_bar`` [bar], the pressure amplitude
        A_p of the paper's form (NaN for the raised sine, whose p0 is the peak pressure).

    Raises
    ------
    ValueError
        An unknown form.
    """
    if form not in PRESSURE_FORMS:
        raise ValueError(f"form must be one of {', '.join(PRESSURE_FORMS)}, got {form!r}")
    if form == "paper":
        return {"phi_rest_deg": FLAT_REST_DEG, "amplitude_bar": PAPER_FORM_AMPLITUDE_BAR}
    return {"phi_rest_deg": FITTED_REST_DEG[gravity], "amplitude_bar": math.nan}


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
        return np.array([self.a1,
                         self.a2]).reshape(shape), np.array([self.b1, self.b2]).reshape(shape)

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
    """Pressure inputs [bar] of segment 1 (leading for psi > 0) and segment 2.

    ``amplitude`` None: the raised sine from 0 to the peak p0, p_i = p0 (1 + sin(2 pi t +- psi/2)) /
    2.  ``amplitude`` a number A_p: the paper's form (ref) with p0 the nominal (mean) pressure,
    p_i = p0 + A_p sin(2 pi t +- psi/2) (0 <= A_p <= p0: a gauge pressure is not negative).
    """

    p0: float
    """peak pressure (raised sine) or nominal pressure (form (ref)) [bar]"""
    psi: float
    """phase lead of segment 1 over segment 2 [rad]"""
    amplitude: float | None = None
    """pressure amplitude A_p of the form (ref) [bar]; None for the raised sine"""

    def __post_init__(self) -> None:
        for name in ("p0", "psi") + (("amplitude",) if self.amplitude is not None else ()):
            v = getattr(self, name)
            if (isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating))
                    or not math.isfinite(v)):
                raise ValueError(f"PressureWaveform.{name} must be a finite number, got {v!r}")
        if self.p0 < 0:
            raise ValueError(f"PressureWaveform.p0 must be >= 0 bar, got {self.p0!r}")
        if self.amplitude is not None and not 0 <= self.amplitude <= self.p0:
            raise ValueError(f"PressureWaveform.amplitude must be in [0, p0 = {self.p0!r}] bar "
                             "(the pressure p0 - amplitude must not be negative), got "
                             f"{self.amplitude!r}")

    def _phases(self, t) -> np.ndarray:
        w = TWO_PI * np.asarray(t, float)
        return np.array([w + self.psi / 2, w - self.psi / 2])

    def __call__(self, t) -> np.ndarray:
        """Pressures [bar] at phase t (scalar -> (2,), N phases -> (2, N))."""
        if self.amplitude is not None:
            return self.p0 + self.amplitude * np.sin(self._phases(t))
        return 0.5 * self.p0 * (1.0 + np.sin(self._phases(t)))

    def derivative(self, t) -> np.ndarray:
        """d p / d t [bar per cycle]."""
        a = 0.5 * self.p0 if self.amplitude is None else self.amplitude
        return a * TWO_PI * np.cos(self._phases(t))

    def at(self, t: float) -> tuple[float, float, float, float]:
        """Both pressures [bar] and their rates [bar per cycle] at one phase t [cycles], with
        :mod:`math` (the steppers' hot path: scalar phases), in the operations of the array
        forms."""
        half_psi, p0, a = self._floats
        w = TWO_PI * float(t)
        s1, s2 = w + half_psi, w - half_psi
        if self.amplitude is None:
            p1, p2 = a * (1.0 + math.sin(s1)), a * (1.0 + math.sin(s2))
        else:
            p1, p2 = p0 + a * math.sin(s1), p0 + a * math.sin(s2)
        return p1, p2, a * TWO_PI * math.cos(s1), a * TWO_PI * math.cos(s2)

    @cached_property
    def _floats(self) -> tuple[float, float, float]:
        """(psi/2, p0, the sine's amplitude) as Python floats, once (frozen fields)."""
        p0 = float(self.p0)
        a = 0.5 * p0 if self.amplitude is None else float(self.amplitude)
        return float(self.psi) / 2, p0, a

    def describe(self) -> str:
        if self.amplitude is None:
            return "p0 (1 + sin(2 pi t +- psi/2)) / 2"
        return f"p0 + {self.amplitude:g} bar sin(2 pi t +- psi/2)"


@dataclass(frozen=True)
class PressureReference(PeriodicSignal):
    """Reference joint angles of the pressure-driven robot, phi_ref,i = phi_rest - bending_i(p_i(t))
    [rad]."""

    waveform: PressureWaveform
    phi_rest: float = math.radians(FITTED_REST_DEG["paper"])
    """joint angle at zero pressure [rad] (fitted; see the module docstring)"""
    bending_map: BendingMap = field(default_factory=BendingMap)

    def __call__(self, t):
        if isinstance(t, float):  # the steppers' hot path, as Harmonic's
            p1, p2, _, _ = self.waveform.at(t)
            rest, a1, a2, b1, b2 = self._floats
            # p * p as numpy's p**2 of an array (the exact square; math's pow may round it)
            return np.array([rest - (a1 * (p1 * p1) + b1 * p1), rest - (a2 * (p2 * p2) + b2 * p2)])
        return self.phi_rest - self.bending_map.bending(self.waveform(t))

    def derivative(self, t):
        if isinstance(t, float):
            p1, p2, dp1, dp2 = self.waveform.at(t)
            _, a1, a2, b1, b2 = self._floats
            return np.array([-(2 * a1 * p1 + b1) * dp1, -(2 * a2 * p2 + b2) * dp2])
        return -self.bending_map.slope(self.waveform(t)) * self.waveform.derivative(t)

    @cached_property
    def _floats(self) -> tuple[float, float, float, float, float]:
        """(phi_rest, a1, a2, b1, b2) as Python floats, once (frozen fields)."""
        m = self.bending_map
        return float(self.phi_rest), float(m.a1), float(m.a2), float(m.b1), float(m.b2)

    def describe(self) -> dict:
        m = self.bending_map
        return {"type": "PressureReference", "p0_bar": self.waveform.p0,
                "psi_deg": math.degrees(self.waveform.psi),
                "phi_rest_deg": math.degrees(self.phi_rest), "a": [m.a1, m.a2], "b": [m.b1, m.b2],
                "waveform": self.waveform.describe()}


@dataclass(frozen=True)
class SegmentJoints(PeriodicSignal):
    """Reference angles of a chain's joints that share the bends of the actuator's two segments
    [rad]: a joint of segment s, one of its n_s joints, takes the share 1/n_s of the segment's
    bend, phi_ref,j = pi + (phi_ref,s - pi) / n_s (a segment bent as an arc of n_s hinges; one
    joint per segment is the three-link robot's :class:`PressureReference`).

    Parameters
    ----------
    reference : PressureReference
        The two segments' reference angles [rad].
    segments : tuple of int
        The segment of each joint, 0 or 1, joint 1 first.
    """

    reference: PressureReference
    segments: tuple[int, ...]

    def __post_init__(self) -> None:
        if sorted(set(self.segments)) != [0, 1]:
            raise ValueError(f"SegmentJoints: segments must name both segments, 0 and 1, got "
                             f"{self.segments!r}")

    @cached_property
    def _rows(self) -> tuple[np.ndarray, np.ndarray]:
        """(the segment of each joint, the share of its segment's bend)."""
        rows = np.array(self.segments, dtype=int)
        return rows, 1.0 / np.bincount(rows)[rows]

    def __call__(self, t):
        rows, share = self._rows
        v = self.reference(t)[rows]
        return math.pi + (share * (v - math.pi) if v.ndim == 1
                          else share[:, None] * (v - math.pi))

    def derivative(self, t):
        rows, share = self._rows
        d = self.reference.derivative(t)[rows]
        return share * d if d.ndim == 1 else share[:, None] * d

    def describe(self) -> dict:
        return {"type": "SegmentJoints", "segments": [s + 1 for s in self.segments],
                "reference": self.reference.describe()}


def pressure_torque(robot: Robot, p0_bar: float, psi_deg: float, phi_rest_deg: float,
                    bending_map: BendingMap | None = None,
                    amplitude_bar: float | None = None) -> ReferenceTorque:
    """Torque input tau = k (phi_ref - pi) of the pressure-driven robot [N m].

    ``p0_bar``: peak (raised sine) or nominal pressure [bar]; ``psi_deg``: phase lead [deg];
    ``phi_rest_deg``: joint angle at zero pressure [deg]; ``amplitude_bar``: None for the raised
    sine, else the pressure amplitude of the paper's form (ref) [bar] (see
    :class:`PressureWaveform`).
    """
    ref = PressureReference(PressureWaveform(p0_bar, math.radians(psi_deg), amplitude_bar),
                            math.radians(phi_rest_deg), bending_map or BendingMap())
    return ReferenceTorque(ref, robot.k)
