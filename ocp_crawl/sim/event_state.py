"""State of the event-driven stepper: solved points, constant-mode segments, mode parameters, failures.

Shared by the modules of the event-driven stepper (:mod:`ocp_crawl.sim.event` and its guards,
event location and output modules).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.result import Event, Mode
from ocp_crawl.status import Status


def hermite(t0, x0, xd0, t1, x1, xd1, t):
    """Cubic Hermite interpolation between (t0, x0, x0') and (t1, x1, x1'); scalars or arrays of phases."""
    h = np.asarray(t1 - t0, float)
    s = np.where(h > 0, (np.asarray(t, float) - t0) / np.where(h > 0, h, 1.0), 0.0)
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * x0 + h10 * h * xd0 + h01 * x1 + h11 * h * xd1


def event_kind(guard: str) -> str:
    """Public event kind of an internal guard name (see :class:`~ocp_crawl.sim.result.Event`)."""
    if guard.startswith("slip_"):
        return f"slip_onset_{guard[5]}"
    if guard.startswith("switch_to_"):
        return "slip_switch"
    return {"stick": "slip_to_stick", "asymmetry": "slip_slip_end"}.get(guard, guard)


def mode_q(mode: Mode, d0: float = 0.0) -> np.ndarray:
    """Mode-parameter vector q = (e_ss, sigma, w, d0) of the compiled mode system (d0: stick distance [m])."""
    if mode == Mode.STICK:
        return np.array([1.0, 0.0, 0.0, d0])
    return np.array([0.0, float(mode.sigma), {1: 1.0, 2: 0.0, 3: 0.5}[mode.foot], 0.0])


#: q of the "released" start: f_t = 0, d free
Q_RELEASED = np.array([0.0, 0.0, 1.0, 0.0])


@dataclass
class _Point:
    t: float
    x: np.ndarray
    aux: np.ndarray
    rates: dict | None = None
    """guard rates of the point's mode (cached by ``HybridStepper._dips``)"""
    tau: np.ndarray | None = None
    """torque and its derivative at t (kept from the solve)"""
    dtau: np.ndarray | None = None

    @property
    def xdot(self) -> np.ndarray:
        a = self.aux
        return np.array([a[AUX["dphi1"]], a[AUX["dphi2"]], a[AUX["dft"]]])


@dataclass
class _Segment:
    """A stretch of constant mode: its points, and the foot that stays fixed."""

    mode: Mode
    q: np.ndarray
    x1_fixed: float
    x2_fixed: float
    points: list = field(default_factory=list)

    def foot_positions(self, d):
        d = np.asarray(d, float)
        if self.mode == Mode.STICK:
            return np.full_like(d, self.x1_fixed), np.full_like(d, self.x2_fixed)
        if self.mode.foot == 1:  # foot 2 sticks
            return self.x2_fixed - d, np.full_like(d, self.x2_fixed)
        if self.mode.foot == 2:
            return np.full_like(d, self.x1_fixed), self.x1_fixed + d
        mid = 0.5 * (self.x1_fixed + self.x2_fixed)  # slip-slip: symmetric split about the midpoint
        return mid - 0.5 * d, mid + 0.5 * d


@dataclass(slots=True)
class _Run:
    """What a run has built so far: the segments, the events, the current segment, point and step."""

    seg: _Segment
    pt: _Point
    h: float
    """current continuation step [cycles]"""
    det_sign: float
    """sign of the mode Jacobian's determinant at the segment's start (a change is a fold)"""
    segments: list[_Segment] = field(default_factory=list)
    events: list[Event] = field(default_factory=list)
    cycle: int = 0
    events_in_cycle: int = 0
    extra: dict = field(default_factory=dict)


class _Failure(Exception):
    def __init__(self, status: Status, t: float, mode: Mode, detail: str, extra: dict | None = None):
        super().__init__(detail)
        self.status, self.t, self.mode, self.detail, self.extra = status, t, mode, detail, extra or {}
