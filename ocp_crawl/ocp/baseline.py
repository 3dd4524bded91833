"""The baselines of the gait OCP: the best member of each simple waveform family (harmonic,
triangle, pulse: ``ocp/family.py``) and the objective values measured on simulations.

Objective values (one definition, :func:`value_from`, shared by the baselines, the OCP and the
replay judge): the mean speed of scenario j is v_j = direction * S_j / T [m/s];

* ``max_speed``: v_j (maximise); with a friction set (``settings.friction_set``) the mean or the
  worst (``settings.robust``) of v_j over ``settings.scenarios(robot)`` (one profile and one period
  for all);
* ``robust_speed``: max_speed over a friction set (0.1 unless ``mu_ratio_eps`` says otherwise);
* ``min_cot``: CoT+ = W+/(M g |S|) (minimise; over a set its mean or its worst, the largest) subject
  to v_j >= ``speed_min`` in every scenario; a gait that misses the requirement (or moves the wrong
  way) has the value +inf;
* every objective: a gait that misses a bound of ``settings.constraints``
  (:mod:`ocp_crawl.ocp.quantities`) is infeasible (+inf for CoT+, -inf for the speeds).

A family's members keep gamma_i +- A_i inside the envelope gamma +- A_max and run at the shortest
period the bandwidth allows (always the best one: see the family module).  The best member of each
family is found by :func:`~ocp_crawl.ocp.search.best_baselines`; the harmonic one is the OCP's first
start, and the best of all families (:attr:`Baselines.best`) is what an optimum's gain is measured
against: under a bound on the reference rate, a triangle wave covers its amplitude in 4 A / R where
a sine needs 2 pi A / R, so most of what an optimum gains over the best sine a triangle wave gains
too.

On a robot with equal feet the fastest members in the model are nearly mirror-symmetric: gamma1 =
gamma2, A1 = A2 and psi -> 0+ (towards foot 1; 0- the other way), a one-sided limit (at psi = 0
exactly the feet tie and S = 0) in which the anchoring foot holds by a margin O(psi): which foot
slips there depends on friction coefficients known only approximately (full-envelope sine of the
paper's robot: S = -60.19 mm at psi = 0.01 deg and mu1 = mu2, 0 at mu1/mu2 = 0.995 or 1.005).  Over
a friction set (``mu_ratio_eps``) such a member stops in a scenario and the search passes it by; at
one friction it may be the best member, and its baseline then rides a tie as an optimum may (the
optimum's ``friction_asymmetry`` report says so).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Callable

import numpy as np

from ocp_crawl.io.files import jsonable
from ocp_crawl.model.inputs import PeriodicSignal, ReferenceTorque
from ocp_crawl.ocp.family import SHAPES, Evaluation, WaveParams
from ocp_crawl.ocp.quantities import Cycle, minimises, shortfall
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.sim.result import CrawlResult

#: search ranks (smaller is better) of members that miss speed_min (plus the shortfall) and that
#: fail
MISS_RANK, FAIL_RANK = 1e6, 1e9


def speeds(settings: OCPSettings, S, T: float) -> list[float]:
    """Mean speeds direction * S_j / T [m/s] of the scenarios (S_j [m] per cycle, T [s] the
    period)."""
    return [settings.direction * s / T for s in S]


def value_from(settings: OCPSettings, S, CoT, T: float, *, feasible: bool = True,
               cycle: Cycle | None = None) -> float:
    """Objective value of a gait from its S [m] and CoT+ [-] per scenario and its period T [s].

    max_speed, robust_speed: the mean or the worst (``settings.robust``) of direction * S_j / T
    [m/s] (one scenario without a friction set), -inf when not ``feasible``; min_cot: the mean or
    the worst (largest) CoT+_j, or +inf when the gait moves against ``direction`` (or not at all) in
    a scenario or is not ``feasible``.  ``feasible``: whether the gait meets the requirements
    (:func:`meets`; the baselines' rule: the replay judge reports the value and checks the
    requirements within its own tolerance).  Larger is better for the speeds, smaller for CoT+
    (:func:`better`).  A user objective (``settings.user_objective``) is its ``value`` of the gait's
    ``cycle`` (required then)."""
    user = settings.user_objective
    if user is not None:
        if cycle is None:
            raise ValueError(f"value_from: the user objective {user.label} needs the gait's cycle")
        if not feasible:
            return math.inf if user.sense == "min" else -math.inf
        return float(user.value(cycle))
    v = speeds(settings, S, T)
    mean = settings.robust == "mean"
    if settings.objective != "min_cot":
        return float(np.mean(v) if mean else np.min(v)) if feasible else -math.inf
    if not min(v) > 0 or not feasible:
        return math.inf
    return float(np.mean(CoT) if mean else np.max(CoT))


def cycle_of(settings: OCPSettings, S, W_plus, CoT, T: float,
             profile: tuple = (math.nan, math.nan)) -> Cycle:
    """The :class:`~ocp_crawl.ocp.quantities.Cycle` of a simulated gait (``profile``: its peak |tau|
    [N m] and mean squared torque [N^2 m^2], needed by profile constraints only)."""
    return Cycle(tuple(S), tuple(W_plus), tuple(CoT), T, settings.direction, *profile)


def shortfalls(settings: OCPSettings, cycle: Cycle) -> float:
    """The sum over ``settings.requirements`` of how far the gait misses each, relative to its bound
    (0: every requirement met; :func:`~ocp_crawl.ocp.quantities.shortfall`)."""
    return float(sum(shortfall(c, cycle) for c in settings.requirements))


def objective_value(settings: OCPSettings, results: list[CrawlResult], T: float,
                    enforce: bool = True, *, profile: tuple = (math.nan, math.nan)) -> float:
    """Objective of a set of simulations (one per scenario) of a gait of period T [s]
    (:func:`value_from`), with ``enforce`` an infeasible value where it misses a requirement
    (``profile``: the torque profile's peak |tau| [N m] and mean squared torque [N^2 m^2], for
    profile constraints); NaN when a simulation failed."""
    if any(not r.success for r in results):
        return math.nan
    S, W, CoT = ([getattr(r, k) for r in results] for k in ("S", "W_plus", "CoT_plus"))
    cycle = cycle_of(settings, S, W, CoT, T, profile)
    ok = not enforce or shortfalls(settings, cycle) <= 0
    return value_from(settings, S, CoT, T, feasible=ok, cycle=cycle)


def required_value(settings: OCPSettings, S, CoT, T: float, W_plus=None,
                   profile: tuple = (math.nan, math.nan)) -> float:
    """:func:`value_from` with the requirements enforced (the baselines' rule), from S [m], CoT+ [-]
    and (for W+ bounds) W+ [J] per scenario, the period T [s] and the torque ``profile`` (for
    profile bounds)."""
    W = [math.nan] * len(S) if W_plus is None else W_plus
    cycle = cycle_of(settings, S, W, CoT, T, profile)
    return value_from(settings, S, CoT, T, feasible=shortfalls(settings, cycle) <= 0, cycle=cycle)


def better(settings: OCPSettings, a: float, b: float) -> bool:
    """True if the objective value a is strictly better than b (NaN is never better; a NaN b is
    beaten by any number)."""
    if math.isnan(a):
        return False
    if math.isnan(b):
        return True
    return a < b if settings.minimises else a > b


def _cycle(settings: OCPSettings, ev: Evaluation) -> Cycle:
    return cycle_of(settings, ev.S, ev.W_plus, ev.CoT_plus, ev.T, ev.profile)


def search_rank(settings: OCPSettings, ev: Evaluation) -> float:
    """Rank of an evaluation for the search, smaller is better: the negated speed objective, CoT+ of
    a gait that meets the requirements, else 1e6 plus how far it misses them (min_cot: the speed
    shortfall [m/s] below speed_min; the relative shortfalls of the constraints), so that the
    search, and the fallback, reach for the requirements; 1e9 for a failed simulation."""
    if not ev.success:
        return FAIL_RANK
    cycle = _cycle(settings, ev)
    miss = shortfalls(settings, cycle)
    value = value_from(settings, ev.S, ev.CoT_plus, ev.T, feasible=miss <= 0, cycle=cycle)
    if math.isfinite(value):
        # a user objective in its own unit, over its typical size (of order one, far below
        # MISS_RANK, unless its scale or weights say otherwise)
        size = 1.0 if settings.user_objective is None else settings.user_objective.scale
        return (value if settings.minimises else -value) / size
    if settings.objective != "min_cot":
        return MISS_RANK + miss
    v = speeds(settings, ev.S, ev.T)
    speed, others = settings.speed_requirement, list(settings.requirements)
    assert speed is not None and speed.min is not None  # min_cot always has one
    others.remove(speed)  # its shortfall in m/s, the others' relative
    rest = sum(shortfall(c, cycle) for c in others)
    return MISS_RANK + max(speed.min - min(v), 0.0) + (0.0 if all(ev.S) else 1.0) + rest


def value_of(settings: OCPSettings, ev: Evaluation) -> float:
    """The objective value of an evaluation (requirements enforced), NaN for a failed simulation."""
    if not ev.success:
        return math.nan
    cycle = _cycle(settings, ev)
    return value_from(settings, ev.S, ev.CoT_plus, ev.T, feasible=shortfalls(settings, cycle) <= 0,
                      cycle=cycle)


@dataclass
class WaveChoice:
    """The best member of one waveform family for the objective, measured with the event-driven
    stepper.

    Angles in degrees, the ``shape`` (with ``rise`` [cycles] and ``duty`` [-] of a pulse:
    :class:`~ocp_crawl.ocp.family.WaveParams`), T [s] the period (the shortest allowed by the
    bandwidth), per scenario S [m], W+ [J], CoT+ [-] and the mean speed v = direction * S / T [m/s].
    ``value`` is the objective (:func:`value_from` with the speed requirement enforced: +inf for a
    min_cot gait short of speed_min, which is then only the gait nearest to it, ``feasible`` False,
    kept as an initial guess); ``evaluated`` the simulated gaits, ``starts`` the local searches
    (seed and result), ``time_s`` the wall time of the search [s] (of all families, when searched
    together)."""

    gamma1_deg: float
    gamma2_deg: float
    A1_deg: float
    A2_deg: float
    psi_deg: float
    T: float
    S: list
    W_plus: list
    CoT_plus: list
    v: list
    value: float
    feasible: bool
    objective: str
    evaluated: int = 0
    starts: list = field(default_factory=list)
    time_s: float = 0.0
    shape: str = "harmonic"
    rise: float = 0.5
    duty: float = 0.0

    @property
    def params(self) -> WaveParams:
        """The member's parameters."""
        return WaveParams(self.gamma1_deg, self.gamma2_deg, self.A1_deg, self.A2_deg, self.psi_deg,
                          self.shape, self.rise, self.duty)

    def gait(self) -> PeriodicSignal:
        """The reference angles phi_ref(t) [rad] of the gait (t the phase, in cycles of period
        ``T``)."""
        return self.params.gait()

    def torque_signal(self, k: float) -> ReferenceTorque:
        """The torque input tau(t) = k (phi_ref(t) - pi) [N m] at the phase t [cycles] (period ``T``
        [s]), for the joint stiffness ``k`` [N m/rad] (the harmonic one is the OCP's initial
        guess)."""
        return self.params.torque(k)

    def signal_for(self, robot, settings: OCPSettings) -> ReferenceTorque:
        """:meth:`torque_signal` for the stiffness of ``robot`` (the interface it shares with a
        chain's :class:`~ocp_crawl.ocp.chain_search.ChainWaveChoice`; ``settings`` unused)."""
        return self.torque_signal(robot.k)

    def to_dict(self) -> dict:
        """JSON-able (strict: a non-finite number, e.g. the infinite value of a gait short of
        speed_min, is None)."""
        return jsonable(asdict(self))


def choice_of(settings: OCPSettings, ev: Evaluation) -> WaveChoice:
    """The :class:`WaveChoice` of a successful evaluation."""
    p = ev.params
    value = value_of(settings, ev)
    return WaveChoice(p.gamma1_deg, p.gamma2_deg, p.A1_deg, p.A2_deg, p.psi_deg, ev.T, list(ev.S),
                      list(ev.W_plus), list(ev.CoT_plus), speeds(settings, ev.S, ev.T), value,
                      math.isfinite(value), settings.objective, shape=p.shape, rise=p.rise,
                      duty=p.duty)


@dataclass
class Baselines:
    """The best member of each searched family (``choices``, by shape, in
    :data:`~ocp_crawl.ocp.family.SHAPES` order; None where no member simulates successfully) for one
    objective."""

    objective: str
    choices: dict
    time_s: float = 0.0
    """wall time of the search of every family [s]"""

    @property
    def best(self) -> WaveChoice | None:
        """The best choice over the families (the first in shape order among equals); for min_cot
        a feasible one before any infeasible."""
        found = [c for c in self.choices.values() if c is not None]
        if not found:
            return None
        sign = 1.0 if minimises(self.objective) else -1.0
        return min(found, key=lambda c: (not c.feasible, sign * c.value if c.feasible else 0.0))

    def merged(self, other: "Baselines") -> "Baselines":
        """These families and ``other``'s (searched apart, e.g. while the OCP solves), in shape
        order; the time is the sum of both searches' wall times."""
        choices = {**self.choices, **other.choices}
        order = {s: i for i, s in enumerate(SHAPES)}
        return Baselines(self.objective, dict(sorted(choices.items(), key=lambda kv: order[kv[0]])),
                         self.time_s + other.time_s)

    def gains(self, value: float, gain: Callable[[str, float, float], float]) -> dict:
        """The gain of the objective value ``value`` over each family's best, by shape (NaN where it
        has none or it is infeasible), computed by ``gain(objective, value, baseline_value)``."""
        return {s: (gain(self.objective, value, c.value) if c is not None and c.feasible
                    else math.nan)
                for s, c in self.choices.items()}

    def table(self) -> list[dict]:
        """One row per family: its shape, value, feasibility, period [s] and parameters
        (JSON-able)."""
        return [{"shape": s,
                 **(c.to_dict() if c is not None else {"value": None, "feasible": False})}
                for s, c in self.choices.items()]
