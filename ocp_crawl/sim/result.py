"""Result objects shared by every simulator, one table of statuses and the contact modes."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

from ocp_crawl.checks import finite_or_none
from ocp_crawl.status import Status


class Mode(IntEnum):
    """Contact modes. SLIP1_POS: foot 1 slips towards +x while foot 2 sticks, etc."""

    STICK = 0
    SLIP1_POS = 1
    SLIP1_NEG = 2
    SLIP2_POS = 3
    SLIP2_NEG = 4
    SLIP_BOTH_POS = 5
    """both feet slip apart (d' > 0); only when mu1 f_n1 = mu2 f_n2 identically (mirror-symmetric
    gaits)"""
    SLIP_BOTH_NEG = 6
    """both feet slip together (d' < 0); see SLIP_BOTH_POS"""

    @property
    def label(self) -> str:
        return {0: "stick-stick", 1: "slip1+", 2: "slip1-", 3: "slip2+", 4: "slip2-",
                5: "slip-slip+", 6: "slip-slip-"}[int(self)]

    @property
    def foot(self) -> int:
        """slipping foot: 0 for stick-stick, 1 or 2, 3 for both"""
        return (0, 1, 1, 2, 2, 3, 3)[self]

    @property
    def sigma(self) -> int:
        """sign of d' in this mode (0 for stick-stick)"""
        return (0, -1, 1, 1, -1, 1, -1)[self]

    @classmethod
    def from_label(cls, label: str) -> "Mode":
        return {m.label: m for m in cls}[label]

    @classmethod
    def slip(cls, foot: int, sigma: int) -> "Mode":
        """Mode in which ``foot`` slips with sign(d') = sigma (foot 1 moves along -sigma, foot 2
        along +sigma)."""
        if foot == 1:
            return cls.SLIP1_POS if sigma < 0 else cls.SLIP1_NEG
        if foot == 2:
            return cls.SLIP2_POS if sigma > 0 else cls.SLIP2_NEG
        return cls.SLIP_BOTH_POS if sigma > 0 else cls.SLIP_BOTH_NEG


def mode_change_kind(before: Mode, after: Mode) -> str:
    """The :class:`Event` kind of a change of contact mode from ``before`` to ``after``, for a
    change decided by the modes (the MPCC time-stepping's steps, the event-driven stepper's
    decisions by the rates)."""
    if before == Mode.STICK:
        return "slip_onset_both" if after.foot == 3 else f"slip_onset_{after.foot}"
    if after == Mode.STICK:
        return "slip_to_stick"
    if before.foot == 3:
        return "slip_slip_end"
    if after.foot == 3:
        return "slip_slip_start"
    return "slip_switch" if after.foot != before.foot else "slip_reversal"


@dataclass(frozen=True)
class Event:
    """A located event: phase t (cycles, counted from the start of the run), kind, modes
    before/after.

    Kinds: ``slip_onset_1``/``slip_onset_2`` (stick-stick -> foot i slips; the direction is in
    ``mode_after``), ``slip_to_stick`` (d' = 0), ``slip_switch`` (the slipping foot changes),
    ``slip_slip_end``, ``lift_off_1``/``lift_off_2``, ``feet_crossed``, ``joint_1_on_ground``/
    ``joint_2_on_ground``, ``fold``; ``graze_<kind>`` when a guard touches zero and turns back, so
    that the mode continues (for example f_t touching a friction limit in stick-stick); prescribed
    angles: ``slip_reversal``, ``slip_switch``, and ``slip_to_stick``/``slip_onset_*`` where the
    input holds still; MPCC time-stepping (mode changes between steps): also ``slip_onset_both``,
    ``slip_slip_start``.
    """

    t: float
    kind: str
    mode_before: str
    mode_after: str
    guard: float = 0.0
    """value of the event's guard function at the located phase"""
    guard_name: str = ""
    """name of the guard function that located the event (solver internal)"""

    def to_dict(self) -> dict:
        """JSON-safe dict of the event (a non-finite guard value is None)."""
        return {"t": float(self.t), "kind": self.kind, "mode_before": self.mode_before,
                "mode_after": self.mode_after,
                "guard": finite_or_none(self.guard), "guard_name": self.guard_name}


def cost_of_transport(w_plus: float, robot, S: float) -> float:
    """CoT+ = W+/(M g |S|); infinite when the robot does not move (|S| at round-off, <= 1e-12 L)."""
    den = robot.M * robot.g * abs(S)
    if abs(S) <= 1e-12 * robot.L or not den > 0:  # (den underflows for absurdly small robots)
        return float("inf")
    return float(w_plus / den)


def energy_balance(input_work: float, potential_change: float, dissipation: float,
                   gross_work: float, robot) -> dict:
    """Energy balance of a cycle [J]: input work = potential change + friction dissipation.

    ``balance_residual`` is relative to the gross work (integral of sum |tau_i phi_i'|, which the
    springs store and return even when the net work is a small difference of large works), floored
    at 1e-12 M g L for a robot that does not move (and at 1e-300 against underflow).
    """
    scale = max(abs(input_work), abs(dissipation), abs(potential_change), gross_work,
                1e-12 * robot.MgL, 1e-300)
    return {"input_work": input_work, "potential_change": potential_change,
            "dissipation": dissipation,
            "gross_work": gross_work,
            "balance_residual": (input_work - potential_change - dissipation) / scale}


ARRAY_FIELDS = ("t", "phi", "theta", "d", "x1", "x2", "f_t", "f_n1", "f_n2", "tau", "mode")


@dataclass(frozen=True, eq=False)
class CrawlResult:
    """Outcome of a simulation, in the manner of scipy's ``OdeResult``.

    Frozen: a simulator builds it once from all its fields, and assigning to an attribute raises
    :class:`dataclasses.FrozenInstanceError`; ``dataclasses.replace(res, ...)`` gives a derived
    result (a physical check's failure, an added error estimate).  Equality and hash are the
    object's identity (a result holds arrays, which have neither): compare fields, e.g. ``S``, or
    :meth:`summary`.

    Arrays are sampled on the output phases ``t`` (cycles; the reported steady cycle spans
    ``[t0, t0 + 1]``). ``phi`` and ``tau`` have shape (m, N) with m joints (2 for the three-link
    robot, n - 1 for a chain of n links); the others shape (N,). ``mode`` holds :class:`Mode`
    codes. ``S`` [m] is the displacement of the robot over the steady cycle along +x (from foot 1
    to foot 2); ``W_plus`` [J] the positive work per cycle summed over the actuators
    (``W_plus_joint`` per actuator); ``CoT_plus`` = W+/(M g |S|); ``theta`` the body angle (of a
    chain: the angle of link n // 2 + 1) [rad].

    Attributes
    ----------
    success : bool
        True if a periodic gait was found and passed the checks (stability, continuity, energy).
    status : Status
        The outcome; ``status_name`` its label, ``message`` why (one line).
    t : ndarray, shape (N,)
        Output phases [cycles], counted from the start of the run.
    phi, tau : ndarray, shape (m, N)
        Joint angles [rad] and actuator torques [N m] (m = 2 for the three-link robot).
    x1, x2, d : ndarray, shape (N,)
        Contact positions of the feet and their distance [m].
    f_t, f_n1, f_n2 : ndarray, shape (N,)
        Tangential force and normal forces at the feet [N].
    S, W_plus, CoT_plus : float
        Displacement per cycle [m], positive work per cycle [J], cost of transport [-]; NaN on
        failure.
    events : list of Event
        The located contact events (``steady_events()``: those of the steady cycle).

    ``summary()`` gives the numbers as JSON types, ``arrays()`` the trajectories.
    """

    success: bool
    status: Status
    """the outcome (an IntEnum: equal to its integer code)"""
    message: str
    drive: str = "torque"
    gravity: str = "physical"
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    phi: np.ndarray = field(default_factory=lambda: np.zeros((2, 0)))
    theta: np.ndarray = field(default_factory=lambda: np.zeros(0))
    d: np.ndarray = field(default_factory=lambda: np.zeros(0))
    x1: np.ndarray = field(default_factory=lambda: np.zeros(0))
    x2: np.ndarray = field(default_factory=lambda: np.zeros(0))
    f_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    f_n1: np.ndarray = field(default_factory=lambda: np.zeros(0))
    f_n2: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tau: np.ndarray = field(default_factory=lambda: np.zeros((2, 0)))
    mode: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    events: list[Event] = field(default_factory=list)
    S: float = float("nan")
    W_plus: float = float("nan")
    W_plus_joint: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    CoT_plus: float = float("nan")
    cycles: int = 0
    t0: float = 0.0
    """phase at which the reported steady cycle starts"""
    energy: dict = field(default_factory=dict)
    """per-cycle energy balance of the steady cycle: input work, potential change, dissipation
    [J]"""
    periodicity_residual: float = float("nan")
    S_error: float = float("nan")
    """estimate of the discretisation error of S [m] (MPCC time-stepping: |S_N - S_2N+1|, see
    :mod:`ocp_crawl.sim.discretisation`; NaN where not estimated)"""
    nfev: int = 0
    """number of calls of the compiled mode solver"""
    nsteps: int = 0
    failure_t: float | None = None
    failure_mode: str | None = None
    extra: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        return (f"CrawlResult(success={self.success}, status={self.status}, "
                f"message={self.message!r}, S={self.S:.6g} m, W_plus={self.W_plus:.6g} J, "
                f"CoT_plus={self.CoT_plus:.6g}, events={len(self.events)}, cycles={self.cycles})")

    @property
    def status_name(self) -> str:
        return Status(self.status).label

    def steady_events(self) -> list[Event]:
        """Events inside the reported steady cycle."""
        return [e for e in self.events if self.t0 - 1e-12 <= e.t <= self.t0 + 1 + 1e-12]

    def event_dicts(self) -> list[dict]:
        """Every event as :meth:`Event.to_dict`, labelled as the text summary shows it: ``steady``
        (True in the reported steady cycle of a successful run, False for the transient before it
        and for every event of a failed run) and ``phase`` (t - t0 in the steady cycle, else t
        modulo 1)."""
        out, ids = [], {id(e) for e in self.steady_events()} if self.success else set()
        for e in self.events:
            steady = id(e) in ids
            phase = e.t - self.t0 if steady else e.t % 1.0
            out.append(dict(e.to_dict(), steady=steady, phase=float(phase)))
        return out

    def summary(self) -> dict:
        """JSON-friendly summary (no arrays; non-finite numbers are None)."""
        return {
            "status": int(self.status), "status_name": self.status_name,
            "success": bool(self.success),
            "message": self.message, "drive": self.drive, "gravity": self.gravity,
            "S": finite_or_none(self.S), "W_plus": finite_or_none(self.W_plus),
            "W_plus_joint": [finite_or_none(w) for w in self.W_plus_joint],
            "CoT_plus": finite_or_none(self.CoT_plus), "cycles": int(self.cycles),
            "t0": float(self.t0), "events": self.event_dicts(),
            "energy": {k: finite_or_none(v) for k, v in self.energy.items()},
            "periodicity_residual": finite_or_none(self.periodicity_residual),
            "S_error": finite_or_none(self.S_error),
            "nfev": int(self.nfev), "nsteps": int(self.nsteps),
            "failure_t": self.failure_t, "failure_mode": self.failure_mode,
        }

    def to_json(self, **kw) -> str:
        return json.dumps(self.summary(), **kw)

    def arrays(self) -> dict[str, np.ndarray]:
        return {name: np.asarray(getattr(self, name)) for name in ARRAY_FIELDS}

    def raise_on_failure(self) -> "CrawlResult":
        if not self.success:
            raise SimulationError(self)
        return self


class SimulationError(RuntimeError):
    """Raised by ``raise_on_failure`` for an unsuccessful result."""

    def __init__(self, result: CrawlResult):
        super().__init__(result.message)
        self.result = result
