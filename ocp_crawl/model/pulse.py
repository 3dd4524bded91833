"""Pulses of soft actuators as a periodic input: trapezoids or cosine-edged pulses, per-joint phase
shift (the ``[gait] waveform = "pulse"`` of problem files): :class:`Pulse` of the three-link robot's
two joints, :class:`JointPulse` of a chain's m joints."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ocp_crawl.checks import real
from ocp_crawl.model.inputs import TWO_PI, PeriodicSignal, merged_knots


#: edge shapes of :class:`Pulse`: straight ramps (a trapezoid) or half-cosine ramps (C1 at the
#: corners)
PULSE_RAMPS = ("linear", "cosine")


def unit_pulse(s: Any, rise: float, hold: float, ramp: str) -> tuple[Any, Any]:
    """(p, dp/ds) of the unit pulse at phases s [cycles] (a scalar or an array): rises from 0 to 1
    over ``rise``, holds 1 for ``hold``, falls back to 0 over ``rise`` and stays 0 for the rest of
    the cycle; ``ramp`` one of :data:`PULSE_RAMPS`."""
    # the event stepper's calls: one phase at a time, without numpy's overhead
    if np.ndim(s) == 0:
        return _unit_scalar(float(s), rise, hold, ramp)
    s = np.mod(s, 1.0)
    r, h = rise, hold
    up, down = s < r, (s >= r + h) & (s < 2 * r + h)
    lin = np.where(up, s / r,
                   np.where(s < r + h, 1.0, np.where(down, 1.0 - (s - r - h) / r, 0.0)))
    dlin = np.where(up, 1.0 / r, np.where(down, -1.0 / r, 0.0))
    if ramp == "linear":
        return lin, dlin
    return 0.5 * (1.0 - np.cos(math.pi * lin)), 0.5 * math.pi * np.sin(math.pi * lin) * dlin


def _unit_scalar(s: float, rise: float, hold: float, ramp: str) -> tuple[float, float]:
    """:func:`unit_pulse` at one phase s (the same branches, in floats)."""
    s %= 1.0
    r, h = rise, hold
    if s < r:
        lin, dlin = s / r, 1.0 / r
    elif s < r + h:
        lin, dlin = 1.0, 0.0
    elif s < 2 * r + h:
        lin, dlin = 1.0 - (s - r - h) / r, -1.0 / r
    else:
        lin, dlin = 0.0, 0.0
    if ramp == "linear":
        return lin, dlin
    return 0.5 * (1.0 - math.cos(math.pi * lin)), 0.5 * math.pi * math.sin(math.pi * lin) * dlin


def pulse_knots(rise: float, hold: float, shifts: ArrayLike) -> np.ndarray:
    """The corners of unit pulses shifted by ``shifts`` [cycles] (the pulse of a joint at phase t
    is the unit pulse at t + shift), merged (:func:`merged_knots`), sorted in [0, 1)."""
    corners = np.array([0.0, rise, rise + hold, 2 * rise + hold])
    return merged_knots(np.concatenate([corners - shift for shift in np.atleast_1d(shifts)]))


def check_pulse(rise: float, hold: float, ramp: str, name: str = "Pulse") -> None:
    """ValueError unless 0 < rise <= 0.5, hold >= 0, 2 rise + hold <= 1 and ramp is one of
    :data:`PULSE_RAMPS`."""
    if not 0 < rise <= 0.5:
        raise ValueError(f"{name}: rise must be in (0, 0.5] cycles, got {rise!r}")
    if not 2 * rise + hold <= 1:
        raise ValueError(f"{name}: 2 rise + hold must be <= 1 cycle, got rise {rise!r} and "
                         f"hold {hold!r}")
    if ramp not in PULSE_RAMPS:
        raise ValueError(f"{name}: ramp must be one of {PULSE_RAMPS}, got {ramp!r}")


@dataclass(frozen=True)
class Pulse(PeriodicSignal):
    """Pulses of soft actuators [rad]: phi_i(t) = gamma_i + A_i (2 p(t + s_i) - 1), shifts s_1 =
    psi/(4 pi) and s_2 = -psi/(4 pi) cycles (joint 1 leads by psi, as in :class:`Harmonic`).

    The unit pulse p(s), s in [0, 1): rises from 0 to 1 over ``rise``, holds 1 for ``hold``, falls
    back to 0 over ``rise`` and stays 0 for the rest of the cycle (1 - 2 rise - hold); ``ramp``
    "linear" gives trapezoids (square waves as rise -> 0), "cosine" half-cosine edges with a
    continuous derivative.
    """

    gamma1: float
    """centre of the swing of joint 1 [rad]"""
    gamma2: float
    """centre of the swing of joint 2 [rad]"""
    A1: float
    """half swing of joint 1 [rad] (from gamma1 - A1 to gamma1 + A1)"""
    A2: float
    """half swing of joint 2 [rad]"""
    psi: float
    """phase lead of joint 1 over joint 2 [rad]"""
    rise: float
    """duration of each edge [cycles], in (0, 0.5]"""
    hold: float
    """duration at the high level [cycles], >= 0, with 2 rise + hold <= 1"""
    ramp: str = "linear"
    """edge shape, one of :data:`PULSE_RAMPS`"""

    def __post_init__(self) -> None:
        for name in ("gamma1", "gamma2", "A1", "A2", "psi", "rise", "hold"):
            nonneg = name in ("A1", "A2", "hold")
            object.__setattr__(self, name,
                               real(f"Pulse.{name}", getattr(self, name), nonneg=nonneg))
        check_pulse(self.rise, self.hold, self.ramp)

    def _unit(self, s):
        """(p, dp/ds) of the unit pulse at phases s (any shape)."""
        return unit_pulse(s, self.rise, self.hold, self.ramp)

    def _shifts(self, t):
        t = np.asarray(t, dtype=float)
        shift = self.psi / (2.0 * TWO_PI)
        return t + shift, t - shift

    @property
    def t_knots(self) -> np.ndarray:
        """Phases of the corners of both joints' pulses [cycles], sorted in [0, 1): the slope jumps
        there (linear edges; the curvature, cosine edges), so the simulators' quadratures split
        their panels there."""
        shift = self.psi / (2.0 * TWO_PI)
        return pulse_knots(self.rise, self.hold, [shift, -shift])

    def __call__(self, t):
        if isinstance(t, float):  # the steppers' hot path (as Harmonic's): floats, no numpy
            p1, p2 = (_unit_scalar(s, self.rise, self.hold, self.ramp)[0]
                      for s in self._float_shifts(t))
            return np.array([self.gamma1 + self.A1 * (2.0 * p1 - 1.0),
                             self.gamma2 + self.A2 * (2.0 * p2 - 1.0)])
        s1, s2 = self._shifts(t)
        return np.array([self.gamma1 + self.A1 * (2.0 * self._unit(s1)[0] - 1.0),
                         self.gamma2 + self.A2 * (2.0 * self._unit(s2)[0] - 1.0)])

    def derivative(self, t):
        if isinstance(t, float):
            d1, d2 = (_unit_scalar(s, self.rise, self.hold, self.ramp)[1]
                      for s in self._float_shifts(t))
            return np.array([2.0 * self.A1 * d1, 2.0 * self.A2 * d2])
        s1, s2 = self._shifts(t)
        return np.array([2.0 * self.A1 * self._unit(s1)[1], 2.0 * self.A2 * self._unit(s2)[1]])

    def _float_shifts(self, t: float) -> tuple[float, float]:
        """:meth:`_shifts` of one phase, in floats (the same roundings)."""
        shift = self.psi / (2.0 * TWO_PI)
        return t + shift, t - shift

    def describe(self) -> dict:
        return {"type": "Pulse", "gamma1_deg": math.degrees(self.gamma1),
                "gamma2_deg": math.degrees(self.gamma2),
                "A1_deg": math.degrees(self.A1), "A2_deg": math.degrees(self.A2),
                "psi_deg": math.degrees(self.psi),
                "rise": self.rise, "hold": self.hold, "ramp": self.ramp}


class JointPulse(PeriodicSignal):
    """Pulses of the m joints of an n-link chain [rad]: phi_j(t) = gamma_j + A_j (2 p(t + s_j) -
    1) with the unit pulse p of :class:`Pulse` and shifts s_j = lead_j / (2 pi) cycles; for two
    joints with leads (psi/2, -psi/2) it is :class:`Pulse`.

    Parameters
    ----------
    gamma, A, lead : array_like, shape (m,)
        Centres of the swings [rad], half swings [rad] (>= 0) and phase leads [rad] of the joints.
    rise, hold : float
        Durations of each edge (in (0, 0.5]) and of the high level (>= 0, 2 rise + hold <= 1)
        [cycles].
    ramp : str
        Edge shape, one of :data:`PULSE_RAMPS`.
    """

    def __init__(self, gamma: ArrayLike, A: ArrayLike, lead: ArrayLike, rise: float, hold: float,
                 ramp: str = "linear"):
        arrays = [np.array([real(f"JointPulse.{name}[{j}]", v, nonneg=name == "A")
                            for j, v in enumerate(np.atleast_1d(np.asarray(a, float)))])
                  for name, a in (("gamma", gamma), ("A", A), ("lead", lead))]
        if arrays[0].ndim != 1 or not arrays[0].size or any(a.shape != arrays[0].shape
                                                            for a in arrays):
            raise ValueError("JointPulse: gamma, A and lead must have one entry per joint, got "
                             f"sizes {[a.size for a in arrays]}")
        self.gamma, self.A, self.lead = arrays
        self.rise, self.hold = real("JointPulse.rise", rise), real("JointPulse.hold", hold,
                                                                   nonneg=True)
        self.ramp = ramp
        check_pulse(self.rise, self.hold, ramp, "JointPulse")
        self._shift = self.lead / TWO_PI

    def _unit(self, t):
        t = np.asarray(t, dtype=float)
        shifted = t[None, ...] + self._shift.reshape((-1,) + (1,) * t.ndim)
        p, dp = unit_pulse(shifted, self.rise, self.hold, self.ramp)
        col = (-1,) + (1,) * t.ndim
        return p, dp, col

    def __call__(self, t):
        p, _, col = self._unit(t)
        return self.gamma.reshape(col) + self.A.reshape(col) * (2.0 * p - 1.0)

    def derivative(self, t):
        _, dp, col = self._unit(t)
        return 2.0 * self.A.reshape(col) * dp

    @property
    def t_knots(self) -> np.ndarray:
        """Phases of the corners of every joint's pulse [cycles], sorted in [0, 1) (as
        :attr:`Pulse.t_knots`)."""
        return pulse_knots(self.rise, self.hold, self._shift)

    def describe(self) -> dict:
        return {"type": "JointPulse", "gamma_deg": np.degrees(self.gamma).tolist(),
                "A_deg": np.degrees(self.A).tolist(), "lead_deg": np.degrees(self.lead).tolist(),
                "rise": self.rise, "hold": self.hold, "ramp": self.ramp}
