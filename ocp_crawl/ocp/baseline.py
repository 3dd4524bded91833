"""The harmonic baseline of the gait OCP: the best harmonic gait of the envelope (initial guess and
comparison) and the objective values measured on simulations (the harmonic sweep and the replay use the
same definition, :func:`value_from`)."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ocp_crawl.io.files import jsonable
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.statics import Model, Robot
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.sim.event import simulate_torque
from ocp_crawl.sim.result import CrawlResult


@dataclass
class HarmonicChoice:
    """The best harmonic gait of the envelope for the objective, measured with the event-driven stepper."""

    psi_deg: float
    A_deg: float
    gamma_deg: float
    value: float
    """objective value (max_speed/robust_speed: direction * S [m]; min_cot: CoT+)"""
    S: list
    W_plus: list
    CoT_plus: list
    evaluated: int

    def to_dict(self) -> dict:
        """JSON-able (strict: a non-finite number, e.g. the infinite CoT+ of a gait short of S_min, is None)."""
        return jsonable(asdict(self))


def value_from(settings: OCPSettings, S: list, CoT: list, enforce_s_min: bool = False, period: float = 1.0) -> float:
    """Objective value from S [m] and CoT+ per scenario and the period [s] (see :func:`objective_value`):
    max_speed/robust_speed the mean speed direction S / T [m/s] (mean or worst), min_cot the CoT+ [-]."""
    v = [settings.direction * s / period for s in S]
    if settings.objective == "max_speed":
        return v[0]
    if settings.objective == "robust_speed":
        return float(np.mean(v) if settings.robust == "mean" else np.min(v))
    if v[0] <= 0 or (enforce_s_min and v[0] < settings.speed_min):
        return float("inf")
    return CoT[0]


def objective_value(settings: OCPSettings, results: list[CrawlResult], enforce_s_min: bool = True,
                    period: float = 1.0) -> float:
    """Objective of a set of simulations (one per scenario); larger is better for speeds, smaller for CoT.

    Failed simulations give NaN.  min_cot of a gait that misses S_min gives +inf when
    ``enforce_s_min`` (harmonic selection); the replay reports the CoT+ itself and checks S_min apart.
    """
    if any(not r.success for r in results):
        return float("nan")
    return value_from(settings, [r.S for r in results], [r.CoT_plus for r in results], enforce_s_min, period)


def _better(settings: OCPSettings, a: float, b: float) -> bool:
    """a strictly better than b (NaN never better)."""
    if not math.isfinite(a) and not (settings.objective == "min_cot" and a == math.inf):
        return False
    if not math.isfinite(b):
        return math.isfinite(a) or (b != b)
    return a < b if settings.objective == "min_cot" else a > b


def best_harmonic(robot: Robot, gravity: str, settings: OCPSettings) -> HarmonicChoice | None:
    """Best harmonic gait of the envelope (gamma fixed, psi and A <= A_max swept) for the objective.

    ``robot``: the robot (SI units); ``gravity``: its gravity convention; ``settings``: the envelope, the
    sweep sizes and the objective.  Each gait is simulated with the event-driven stepper (every friction
    scenario).  Returns the best :class:`HarmonicChoice` (for min_cot, when no gait reaches S_min, the one
    closest to it, as an initial guess only), or None when no gait simulates successfully."""
    models = [Model(r, gravity=gravity) for r in settings.scenarios(robot)]
    psis = np.linspace(-180.0, 180.0, settings.harmonic_psi + 1)[1:]
    amps = np.linspace(settings.A_max_deg / settings.harmonic_A, settings.A_max_deg, settings.harmonic_A)
    if settings.objective in ("max_speed", "robust_speed"):
        amps = amps[-1:]  # S grows with A (paper): the largest amplitude of the envelope
    best = None
    closest = None  # min_cot: the gait nearest to S_min when none reaches it (initial guess only)
    n = 0
    for A in amps:
        for psi in psis:
            gait = Harmonic.from_degrees(settings.gamma_deg, float(A), float(psi))
            try:
                res = [simulate_torque(m, ReferenceTorque(gait, m.robot.k)) for m in models]
            except ValueError:
                continue
            n += 1
            if any(not r.success for r in res):
                continue
            value = objective_value(settings, res, period=settings.min_period(A, A))
            choice = HarmonicChoice(float(psi), float(A), settings.gamma_deg, value,
                                    [r.S for r in res], [r.W_plus for r in res], [r.CoT_plus for r in res], 0)
            if math.isfinite(choice.value) and (best is None or _better(settings, choice.value, best.value)):
                best = choice
            if closest is None or settings.direction * choice.S[0] > settings.direction * closest.S[0]:
                closest = choice
    best = best or (closest if settings.objective == "min_cot" else None)
    if best is not None:
        best.evaluated = n
    return best
