"""The cycle quantities an OCP can bound: the vocabulary of ``[[ocp.constraint]]``.

A :class:`Constraint` bounds one quantity of the gait's cycle (:data:`QUANTITIES`) from below, above
or both; a quantity of the friction scenarios (speed, distance, W+, CoT+) is bounded in every
scenario or as the mean over them (``over``).  The same constraint has three readings, one per
layer, from one definition here:

* in the NLP (:func:`constraint_rows`): rows in the transcription's scaled variables;
* on a simulated gait (:func:`cycle_values`, :func:`shortfall`): the values computed from the
  event-driven simulations and the torque signal alone (the baselines' members, the replay judge);
* in text (:meth:`Constraint.text`): reports and messages.

Which bounds a quantity admits is set by what the transcription can state exactly
(:attr:`Quantity.bounds`): W+ is a sum of slack variables v >= tau dphi, v >= 0, exact only where
something presses it down (an upper bound, or min_cot's objective), and the peak torque is a maximum
over nodes, exact as an upper bound on every node.  A lower bound on either would be met by
inflating the slacks or by one node: it is refused.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import casadi as cs
import numpy as np

#: how a scenario quantity's bound applies over the friction scenarios: in every one, or to their
#: mean
OVERS = ("every", "mean")
#: phases at which a torque signal is sampled for its profile quantities (a family member's; the
#: replay's linear interpolant is evaluated on its nodes exactly)
PROFILE_SAMPLES = 4096


@dataclass(frozen=True)
class Quantity:
    """One quantity of a gait's cycle: its unit, whether it is per friction scenario, its meaning,
    the bounds the transcription states exactly (``"min"``, ``"max"``), whether it is positive by
    nature (its bounds must then be > 0) and its reference size (:func:`reference_sizes`)."""

    name: str
    unit: str
    per_scenario: bool
    meaning: str
    bounds: tuple = ("min", "max")
    positive: bool = False


#: the cycle quantities of objectives and constraints, by name
QUANTITIES = {q.name: q for q in (
    Quantity("speed", "m/s", True, "mean speed direction * S / T"),
    Quantity("distance", "m", True, "distance per cycle direction * S"),
    Quantity("W_plus", "J", True, "positive actuator work per cycle", ("max",), True),
    Quantity("CoT_plus", "-", True,
             "cost of transport W+ / (M g direction S) (+inf moving backwards)", ("max",), True),
    Quantity("peak_torque", "N m", False, "largest joint torque |tau_i| over the cycle", ("max",),
             True),
    Quantity("mean_torque_sq", "N^2 m^2", False,
             "mean over the cycle of the sum of tau_i^2 over the joints (the joule heating of the "
             "actuators, up to a factor)",
             positive=True),
    Quantity("period", "s", False, "period T of the gait", positive=True),
)}


#: the quantities of the torque profile alone (the same in every scenario)
PROFILE_QUANTITIES = tuple(q.name for q in QUANTITIES.values()
                           if not q.per_scenario and q.name != "period")


@dataclass(frozen=True)
class Constraint:
    """A bound ``min <= quantity <= max`` (either may be None) on a cycle quantity of
    :data:`QUANTITIES` (SI units, as listed there), in ``over`` = "every" friction scenario or on
    their "mean"."""

    quantity: str
    min: float | None = None
    max: float | None = None
    over: str = "every"

    def __post_init__(self) -> None:
        where = f"constraint on {self.quantity!r}"
        if self.quantity not in QUANTITIES:
            raise ValueError(f"OCPSettings.constraints: unknown quantity {self.quantity!r}; one of "
                             f"{', '.join(QUANTITIES)}")
        q = QUANTITIES[self.quantity]
        for side in ("min", "max"):
            value = getattr(self, side)
            if value is None:
                continue
            if (isinstance(value, bool) or not isinstance(value, (int, float))
                    or not math.isfinite(value)):
                raise ValueError(f"OCPSettings.constraints: {where}: {side} must be a finite "
                                 f"number, got {value!r}")
            if q.positive and not value > 0:
                raise ValueError(f"OCPSettings.constraints: {where}: {side} must be > 0 "
                                 f"({q.name} is positive), got {value!r}")
            if side not in q.bounds:
                raise ValueError(f"OCPSettings.constraints: {where}: a {side} bound is not "
                                 f"available ({q.name} admits only {' and '.join(q.bounds)}: "
                                 f"{_WHY_ONE_SIDED})")
            object.__setattr__(self, side, float(value))
        if self.min is None and self.max is None:
            raise ValueError(f"OCPSettings.constraints: {where} has neither min nor max")
        if self.min is not None and self.max is not None and not self.min <= self.max:
            raise ValueError(f"OCPSettings.constraints: {where}: min {self.min:g} > max "
                             f"{self.max:g}")
        if self.over not in OVERS:
            raise ValueError(f"OCPSettings.constraints: {where}: over must be one of {OVERS}, got "
                             f"{self.over!r}")

    @classmethod
    def of(cls, value) -> "Constraint":
        """A Constraint from itself or a mapping of its fields (a problem file's table)."""
        if isinstance(value, Constraint):
            return value
        if not isinstance(value, Mapping):
            raise ValueError("OCPSettings.constraints: each must be a table of quantity, min, max, "
                             f"over; got {value!r}")
        unknown = sorted(set(value) - {"quantity", "min", "max", "over"})
        if unknown or "quantity" not in value:
            raise ValueError("OCPSettings.constraints: a constraint has the keys quantity "
                             f"(required), min, max, over; got {', '.join(map(str, value))}")
        return cls(**value)

    @property
    def unit(self) -> str:
        return QUANTITIES[self.quantity].unit

    def text(self) -> str:
        """E.g. "speed >= 0.04 m/s in every scenario", "peak_torque <= 0.3 N m"."""
        unit = "" if self.unit == "-" else f" {self.unit}"
        sides = [f">= {self.min:g}{unit}" if self.min is not None else "",
                 f"<= {self.max:g}{unit}" if self.max is not None else ""]
        scope = ""
        if QUANTITIES[self.quantity].per_scenario:
            scope = (" in every scenario" if self.over == "every"
                     else " on the mean of the scenarios")
        return f"{self.quantity} {' and '.join(s for s in sides if s)}{scope}"

    def to_dict(self) -> dict:
        """The problem file's table (absent bounds left out)."""
        out = {"quantity": self.quantity}
        out.update({k: getattr(self, k) for k in ("min", "max") if getattr(self, k) is not None})
        if QUANTITIES[self.quantity].per_scenario:
            out["over"] = self.over
        return out


_WHY_ONE_SIDED = ("W+ and CoT+ are sums of slacks v >= tau dphi, v >= 0 and the peak torque a "
                  "maximum over nodes: exact under an upper bound only")


@dataclass(frozen=True)
class Symbols:
    """The transcription's expressions a constraint is stated in, scaled as the NLP is: node torques
    ``T`` (m, N) over M g L, the period ``Th`` over ``period_ref`` [s], per scenario S over L
    (``S``) and W+ over M g L (``W``, None where not built), and the scales."""

    T: Any
    Th: Any
    S: list
    W: list
    MgL: float
    L: float
    period_ref: float
    direction: int


def _over(c: Constraint, rows: list):
    """The rows of a scenario quantity: one per scenario, or their mean."""
    if c.over == "mean":
        return sum(rows) / len(rows)
    return cs.vertcat(*rows)


def constraint_rows(c: Constraint, sym: Symbols) -> list[tuple]:
    """The NLP rows ``(expr, lb, ub)`` of constraint ``c``, each of order one in the scaled
    variables.

    speed v = d S_hat L / (T_hat period_ref): ``d S_hat - (v* period_ref / L) T_hat`` against 0 (the
    form of min_cot's speed requirement); distance ``d S_hat - s*/L``; W+
    ``W_hat - W*/(M g L) <= 0``; CoT+ ``W_hat - c* d S_hat <= 0`` (CoT+ = W_hat / (d S_hat)); the
    peak torque ``-b <= T_hat <= b`` at every node (the linear interpolant's extremes are its
    nodes'); the mean squared torque ``sum over intervals and joints of (a^2 + a b + b^2) / 3 / N``
    (exact for the linear interpolant); the period ``T_hat``."""
    q, d, out = c.quantity, sym.direction, []
    if q in ("speed", "distance"):
        for side, bound, lb, ub in (("min", c.min, 0.0, np.inf), ("max", c.max, -np.inf, 0.0)):
            if bound is None:
                continue
            if q == "speed":
                rows = [d * S - bound * sym.period_ref / sym.L * sym.Th for S in sym.S]
            else:
                rows = [d * S - bound / sym.L for S in sym.S]
            out.append((_over(c, rows), lb, ub))
        return out
    # W+, CoT+ and the peak torque: an upper bound always (Quantity.bounds, checked by Constraint)
    hi = c.max if c.max is not None else math.inf
    if q == "W_plus":
        return [(_over(c, [W - hi / sym.MgL for W in sym.W]), -np.inf, 0.0)]
    if q == "CoT_plus":
        if c.over == "mean":  # each scenario forwards (a backwards one would lower the mean)
            rows = [W / (d * S) for W, S in zip(sym.W, sym.S)]
            return [(cs.vertcat(*[d * S for S in sym.S]), 0.0, np.inf),
                    (sum(rows) / len(rows) - hi, -np.inf, 0.0)]
        return [(cs.vertcat(*[W - hi * d * S for W, S in zip(sym.W, sym.S)]), -np.inf, 0.0)]
    if q == "peak_torque":
        b = hi / sym.MgL
        return [(cs.vec(sym.T), -b, b)]
    if q == "mean_torque_sq":
        value = mean_square_nodes(sym.T)
        scale = sym.MgL**2
        return [(value, -np.inf if c.min is None else c.min / scale,
                 np.inf if c.max is None else c.max / scale)]
    # period
    return [(sym.Th, -np.inf if c.min is None else c.min / sym.period_ref,
             np.inf if c.max is None else c.max / sym.period_ref)]


def mean_square_nodes(T):
    """Mean over the cycle of the sum over joints of the squared linear interpolant of node values
    ``T`` (m, N) (periodic): per interval (a^2 + a b + b^2) / 3; a CasADi expression or a float."""
    if isinstance(T, np.ndarray):
        nxt = np.roll(T, -1, axis=1)
        return float(np.sum(T**2 + T * nxt + nxt**2) / (3 * T.shape[1]))
    nxt = cs.horzcat(T[:, 1:], T[:, 0])
    return cs.sum2(cs.sum1(T**2 + T * nxt + nxt**2)) / (3 * T.shape[1])


def needs_work(constraints) -> bool:
    """Whether a constraint needs W+ in the NLP (W_plus, CoT_plus)."""
    return any(c.quantity in ("W_plus", "CoT_plus") for c in constraints)


@dataclass(frozen=True)
class Cycle:
    """A simulated gait's numbers that constraints are checked on: per scenario S [m], W+ [J], CoT+
    [-], the period T [s], ``direction``, and the torque profile's peak |tau| [N m] and mean squared
    torque [N^2 m^2] (:func:`profile_of_nodes`, :func:`profile_of_signal`)."""

    S: tuple
    W_plus: tuple
    CoT_plus: tuple
    T: float
    direction: int
    peak_torque: float
    mean_torque_sq: float


def profile_of_nodes(tau: np.ndarray) -> tuple[float, float]:
    """(peak |tau| [N m], mean squared torque [N^2 m^2]) of the linear interpolant of node torques
    ``tau`` (m, N), exactly."""
    tau = np.asarray(tau, float)
    return float(np.max(np.abs(tau))), mean_square_nodes(tau)


def profile_of_signal(signal) -> tuple[float, float]:
    """(peak |tau| [N m], mean squared torque [N^2 m^2]) of a torque signal tau(t) [N m] of the
    phase t [cycles]: the peak over :data:`PROFILE_SAMPLES` phases and the signal's knots
    (``t_knots``: the corners of triangle and pulse waves, where their peaks lie), the mean square
    by the trapezoid rule on the uniform phases (relative error O(1e-7) on the paper's
    waveforms)."""
    t = np.arange(PROFILE_SAMPLES) / PROFILE_SAMPLES
    tau = np.asarray(signal(t), float).reshape(-1, t.size)   # a row per joint
    knots = np.mod(np.asarray(getattr(signal, "t_knots", ()), float).ravel(), 1.0)
    peak = float(np.max(np.abs(tau)))
    if knots.size:
        peak = max(peak, float(np.max(np.abs(np.asarray(signal(knots), float)))))
    return peak, mean_square_nodes(tau)


def quantity_values(name: str, cycle: Cycle) -> list[float]:
    """The values of the quantity ``name`` on a simulated gait: one per scenario (speed, distance,
    W+, CoT+; CoT+ +inf where the gait moves backwards or not at all) or one (the profile's
    quantities, the period)."""
    d, T = cycle.direction, cycle.T
    if name == "speed":
        return [d * s / T for s in cycle.S]
    if name == "distance":
        return [d * s for s in cycle.S]
    if name == "W_plus":
        return list(cycle.W_plus)
    if name == "CoT_plus":
        return [c if d * s > 0 else math.inf for c, s in zip(cycle.CoT_plus, cycle.S)]
    return [float({"peak_torque": cycle.peak_torque, "mean_torque_sq": cycle.mean_torque_sq,
                   "period": T}[name])]


def cycle_values(c: Constraint, cycle: Cycle) -> list[float]:
    """The values of the constrained quantity on a simulated gait: one per scenario ("every") or
    one."""
    values = quantity_values(c.quantity, cycle)
    if QUANTITIES[c.quantity].per_scenario and c.over == "mean":
        return [float(np.mean(values))]
    return values


def reference_sizes(M: float, g: float, L: float, period_ref: float) -> dict[str, float]:
    """The size of each quantity on a robot of mass M [kg] and length L [m] under gravity g [m/s^2]
    with the reference period ``period_ref`` [s] (the NLP's scales): a zero bound's miss is measured
    against it (speed L / period_ref, distance L, W+ M g L, CoT+ 1, peak torque M g L, mean squared
    torque (M g L)^2, period period_ref)."""
    MgL = M * g * L
    return {"speed": L / period_ref, "distance": L, "W_plus": MgL, "CoT_plus": 1.0,
            "peak_torque": MgL, "mean_torque_sq": MgL**2, "period": period_ref}


def shortfall(c: Constraint, cycle: Cycle, sizes: dict | None = None) -> float:
    """How far the gait misses the constraint, relative to its bound's size (0 when met; NaN values
    miss by infinity): max over the values of (min - value) / |min| and (value - max) / |max|; a
    zero bound's miss relative to the quantity's size in ``sizes`` (:func:`reference_sizes`; None:
    in its unit)."""
    worst = 0.0
    size = 1.0 if sizes is None else sizes[c.quantity]
    for value in cycle_values(c, cycle):
        if not math.isfinite(value):
            return math.inf
        if c.min is not None:
            worst = max(worst, (c.min - value) / (abs(c.min) or size))
        if c.max is not None:
            worst = max(worst, (value - c.max) / (abs(c.max) or size))
    return worst


def missed(constraints, cycle: Cycle, tol: float = 0.0, sizes: dict | None = None) -> list[str]:
    """The constraints the gait misses by more than ``tol`` (relative to the bound, or for a zero
    bound to the quantity's size in ``sizes``), each as a text with the gait's values."""
    out = []
    for c in constraints:
        if shortfall(c, cycle, sizes) > tol:
            values = ", ".join(f"{v:.6g}" for v in cycle_values(c, cycle))
            out.append(f"{c.text()} (here {values})")
    return out


#: the sign of a user objective's value: minimised or maximised
SENSES = ("min", "max")


@dataclass(frozen=True)
class UserObjective:
    """An objective of the user's, for what the named objectives do not say (the Python hook).

    ``nlp(q)`` returns the objective as a CasADi expression of the transcription's symbols in
    physical units, ``q`` a :class:`Physical`; ``value(cycle)`` the same number on a simulated gait,
    from a :class:`Cycle` (the baselines' members, the replay: the judge compares the two within
    replay_tol).  ``sense`` "min" or "max"; ``scale`` its typical size in its ``unit`` (the NLP
    minimises value / scale: an objective of order one converges to IPOPT's tolerances as the named
    ones do); ``work``: whether ``nlp`` uses W+ (the NLP then builds it: a sum of slacks v >= tau
    dphi, v >= 0, exact only where the objective presses it down).  The settings name the objective
    "min:<name>" or "max:<name>".  ``nlp`` and ``value`` should be module-level functions: the
    baselines' search sends the settings to worker processes, which a lambda does not reach under
    the forkserver and spawn start methods."""

    name: str
    nlp: Callable[[Physical], Any]
    value: Callable[[Cycle], float]
    sense: str = "min"
    unit: str = "-"
    scale: float = 1.0
    work: bool = False

    def __post_init__(self) -> None:
        if self.sense not in SENSES:
            raise ValueError(f"UserObjective.sense must be one of {SENSES}, got {self.sense!r}")
        if not (callable(self.nlp) and callable(self.value)):
            raise ValueError("UserObjective: nlp and value must be callables (of the symbols, "
                             "of a Cycle)")
        if not (isinstance(self.scale, (int, float)) and math.isfinite(self.scale)
                and self.scale > 0):
            raise ValueError(f"UserObjective.scale must be a positive number, got {self.scale!r}")
        if not (isinstance(self.name, str) and self.name.isidentifier()):
            raise ValueError(f"UserObjective.name must be an identifier, got {self.name!r}")

    @property
    def label(self) -> str:
        """The objective's name in settings and reports: "min:<name>" or "max:<name>"."""
        return f"{self.sense}:{self.name}"


@dataclass(frozen=True)
class Physical:
    """The transcription's symbols in physical units, for a :class:`UserObjective`: node torques
    ``tau`` (m, N) [N m] (linear in phase between nodes), the period ``T`` [s], per scenario ``S``
    [m] and ``W_plus`` [J] (None unless the objective says ``work``), the mean squared torque
    ``mean_torque_sq`` [N^2 m^2], ``direction`` (the sign of S pursued) and ``sizes``, the
    reference size of each quantity on the robot (:func:`reference_sizes`: e.g. to make an
    expression of order one)."""

    tau: Any
    T: Any
    S: list
    W_plus: list
    mean_torque_sq: Any
    direction: int
    sizes: dict


def physical(sym: Symbols) -> Physical:
    """The symbols of ``sym`` (scaled) in physical units."""
    W = [None if w is None else w * sym.MgL for w in sym.W]
    sizes = reference_sizes(sym.MgL / sym.L, 1.0, sym.L, sym.period_ref)
    return Physical(sym.T * sym.MgL, sym.Th * sym.period_ref, [s * sym.L for s in sym.S], W,
                    mean_square_nodes(sym.T) * sym.MgL**2, sym.direction, sizes)


def minimises(objective: str) -> bool:
    """Whether the objective named ``objective`` is minimised: min_cot and "min:<name>" user
    objectives."""
    return objective == "min_cot" or objective.startswith("min:")
