"""Pulses of soft actuators as a periodic input: trapezoids or cosine-edged pulses, per-joint phase
shift (the ``[gait] waveform = "pulse"`` of problem files)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ocp_crawl.checks import real
from ocp_crawl.model.inputs import TWO_PI, PeriodicSignal, merged_knots


#: edge shapes of :class:`Pulse`: straight ramps (a trapezoid) or half-cosine ramps (C1 at the
#: corners)
PULSE_RAMPS = ("linear", "cosine")


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
        if not 0 < self.rise <= 0.5:
            raise ValueError(f"Pulse: rise must be in (0, 0.5] cycles, got {self.rise!r}")
        if not 2 * self.rise + self.hold <= 1:
            raise ValueError(f"Pulse: 2 rise + hold must be <= 1 cycle, got rise {self.rise!r} and "
                             f"hold {self.hold!r}")
        if self.ramp not in PULSE_RAMPS:
            raise ValueError(f"Pulse: ramp must be one of {PULSE_RAMPS}, got {self.ramp!r}")

    def _unit(self, s):
        """(p, dp/ds) of the unit pulse at phases s (any shape)."""
        # the event stepper's calls: one phase at a time, without numpy's overhead
        if np.ndim(s) == 0:
            return self._unit_scalar(float(s))
        s = np.mod(s, 1.0)
        r, h = self.rise, self.hold
        up, down = s < r, (s >= r + h) & (s < 2 * r + h)
        lin = np.where(up, s / r,
                       np.where(s < r + h, 1.0, np.where(down, 1.0 - (s - r - h) / r, 0.0)))
        dlin = np.where(up, 1.0 / r, np.where(down, -1.0 / r, 0.0))
        if self.ramp == "linear":
            return lin, dlin
        return 0.5 * (1.0 - np.cos(math.pi * lin)), 0.5 * math.pi * np.sin(math.pi * lin) * dlin

    def _unit_scalar(self, s: float) -> tuple[float, float]:
        """:meth:`_unit` at one phase s (the same branches, in floats)."""
        s %= 1.0
        r, h = self.rise, self.hold
        if s < r:
            lin, dlin = s / r, 1.0 / r
        elif s < r + h:
            lin, dlin = 1.0, 0.0
        elif s < 2 * r + h:
            lin, dlin = 1.0 - (s - r - h) / r, -1.0 / r
        else:
            lin, dlin = 0.0, 0.0
        if self.ramp == "linear":
            return lin, dlin
        return 0.5 * (1.0 - math.cos(math.pi * lin)), 0.5 * math.pi * math.sin(math.pi * lin) * dlin

    def _shifts(self, t):
        t = np.asarray(t, dtype=float)
        shift = self.psi / (2.0 * TWO_PI)
        return t + shift, t - shift

    @property
    def t_knots(self) -> np.ndarray:
        """Phases of the corners of both joints' pulses [cycles], sorted in [0, 1): the slope jumps
        there (linear edges; the curvature, cosine edges), so the simulators' quadratures split
        their panels there."""
        corners = np.array([0.0, self.rise, self.rise + self.hold, 2 * self.rise + self.hold])
        shift = self.psi / (2.0 * TWO_PI)
        return merged_knots(np.concatenate([corners - shift, corners + shift]))

    def __call__(self, t):
        s1, s2 = self._shifts(t)
        return np.array([self.gamma1 + self.A1 * (2.0 * self._unit(s1)[0] - 1.0),
                         self.gamma2 + self.A2 * (2.0 * self._unit(s2)[0] - 1.0)])

    def derivative(self, t):
        s1, s2 = self._shifts(t)
        return np.array([2.0 * self.A1 * self._unit(s1)[1], 2.0 * self.A2 * self._unit(s2)[1]])

    def describe(self) -> dict:
        return {"type": "Pulse", "gamma1_deg": math.degrees(self.gamma1),
                "gamma2_deg": math.degrees(self.gamma2),
                "A1_deg": math.degrees(self.A1), "A2_deg": math.degrees(self.A2),
                "psi_deg": math.degrees(self.psi),
                "rise": self.rise, "hold": self.hold, "ramp": self.ramp}
