"""Solve the periodic-gait OCP and prove the optimum by replay: :func:`optimize_gait` and :class:`OCPResult`.

The initial guess is the best harmonic gait of the envelope (:func:`~ocp_crawl.ocp.baseline.best_harmonic`);
the transcription (:class:`~ocp_crawl.ocp.transcription.GaitOCP`) is solved by the relaxation homotopy,
every stage read through the IPOPT status table; the optimal profile is then replayed in the event-driven
simulator (the transcription's own interpolant: torque linear in phase between the nodes, period T) and
compared with the harmonic gait.
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from ocp_crawl.io.files import jsonable
from ocp_crawl.model.inputs import Harmonic, PeriodicLinear, ReferenceTorque
from ocp_crawl.model.statics import Robot
from ocp_crawl.nlp.ipopt import ipopt_status, result_status
from ocp_crawl.ocp.baseline import HarmonicChoice, best_harmonic, objective_value, value_from
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.transcription import GaitOCP
from ocp_crawl.sim.event import simulate_torque
from ocp_crawl.sim.result import cost_of_transport
from ocp_crawl.status import Status


@dataclass
class OCPResult:
    """Outcome of :func:`optimize_gait`: the optimal profile, its transcription residuals, the harmonic
    baseline and the replay (per scenario lists: one entry unless robust_speed)."""

    success: bool
    status: Status
    """the result's :class:`~ocp_crawl.status.Status` (written as its lower-case label in JSON)"""
    message: str
    objective: str
    settings: OCPSettings
    phase: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tau: np.ndarray = field(default_factory=lambda: np.zeros((2, 0)))
    """optimal torques [N m] at the node phases (2, N)"""
    phi: list = field(default_factory=list)
    """per scenario: angles (2, N+1) [rad] at phases k/N, k = 0..N"""
    x1: list = field(default_factory=list)
    f_t: list = field(default_factory=list)
    modes: list = field(default_factory=list)
    S_ocp: list = field(default_factory=list)
    T_ocp: float = float("nan")
    """period of the optimal gait [s]"""
    v_ocp: list = field(default_factory=list)
    """per scenario: mean speed direction * S / T [m/s]"""
    theta: list = field(default_factory=list)
    """per scenario: the interior points of the intervals (N,) [fraction of the interval]"""
    W_plus_ocp: list = field(default_factory=list)
    CoT_plus_ocp: list = field(default_factory=list)
    value_ocp: float = float("nan")
    complementarity_residual: float = float("nan")
    periodicity_residual: float = float("nan")
    equation_residual: float = float("nan")
    homotopy: list = field(default_factory=list)
    """:class:`~ocp_crawl.nlp.homotopy.Stage` records of every IPOPT call"""
    failed_stage: str | None = None
    solve_time_s: float = float("nan")
    harmonic: HarmonicChoice | None = None
    replay: list = field(default_factory=list)
    """per scenario: CrawlResult of the event-driven replay"""
    S_replay: list = field(default_factory=list)
    v_replay: list = field(default_factory=list)
    """per scenario: replayed mean speed direction * S / T [m/s] (the replay at the OCP's period)"""
    W_plus_replay: list = field(default_factory=list)
    CoT_plus_replay: list = field(default_factory=list)
    value_replay: float = float("nan")
    rel_diff_replay: float = float("nan")
    gain: float = float("nan")

    def summary(self) -> dict:
        """The result as strict JSON types (non-finite numbers None; the status as its lower-case label)."""
        one = len(self.S_ocp) == 1

        def per_scenario(values):
            return (values[0] if one else values) if values else None

        return jsonable({
            "status": self.status.label, "success": bool(self.success), "message": self.message,
            "objective": self.objective, "nodes": self.settings.nodes,
            "parametrization": self.settings.parametrization,
            "S_ocp": per_scenario(self.S_ocp), "S_replay": per_scenario(self.S_replay),
            "T_ocp": self.T_ocp, "v_ocp": per_scenario(self.v_ocp), "v_replay": per_scenario(self.v_replay),
            "W_plus_ocp": self.W_plus_ocp, "W_plus_replay": self.W_plus_replay,
            "CoT_plus_ocp": self.CoT_plus_ocp, "CoT_plus_replay": per_scenario(self.CoT_plus_replay),
            "objective_value_ocp": self.value_ocp, "objective_value_replay": self.value_replay,
            "rel_diff_replay": self.rel_diff_replay,
            "best_harmonic": self.harmonic.to_dict() if self.harmonic else None,
            "gain": self.gain, "solve_time_s": self.solve_time_s,
            "complementarity_residual": self.complementarity_residual,
            "periodicity_residual": self.periodicity_residual,
            "equation_residual": self.equation_residual,
            "failed_stage": self.failed_stage,
            "homotopy": [asdict(h) for h in self.homotopy],
        })


#: the ``[gait] interpolation`` of a problem file of samples that reproduces :func:`replay_signal` (the
#: ``optimal_gait.toml`` that ``optimize --out`` writes replays the optimum with it)
REPLAY_INTERPOLATION = "linear"


def replay_signal(phase: np.ndarray, tau: np.ndarray) -> PeriodicLinear:
    """Torque input of the event-driven replay: the transcription's own interpolant, linear in phase between
    the node torques [N m] at ``phase`` [cycles] (it keeps the envelope and the bandwidth of the nodes)."""
    return PeriodicLinear(phase, tau)


def optimize_gait(robot: Robot, gravity: str = "physical", settings: OCPSettings | None = None,
                  replay: bool = True) -> OCPResult:
    """Solve the periodic-gait OCP, replay the optimum in the event-driven simulator, compare with harmonics.

    ``robot``: the robot (SI units); ``gravity``: the gravity convention ("physical" or "paper");
    ``settings``: the OCP's settings (defaults: :class:`OCPSettings`); ``replay``: replay the optimum.
    Returns an :class:`OCPResult` whose ``status`` says whether an optimum was found (SUCCESS), the problem
    is infeasible (INFEASIBLE), IPOPT failed (SOLVER_FAILURE), complementarity was not reached
    (NOT_COMPLEMENTARY), no harmonic gait gave an initial guess (NO_INITIAL_GUESS) or the replay failed
    (REPLAY_FAILED)."""
    settings = settings or OCPSettings()
    t_start = time.perf_counter()
    res = OCPResult(success=False, status=Status.SOLVER_FAILURE, message="", objective=settings.objective,
                    settings=settings)
    harm = best_harmonic(robot, gravity, settings)
    res.harmonic = harm
    if harm is None:
        res.status = Status.NO_INITIAL_GUESS
        res.message = "no harmonic gait of the envelope simulates successfully: no initial guess"
        return res
    ocp = GaitOCP(robot, gravity, settings)
    gait = Harmonic.from_degrees(harm.gamma_deg, harm.A_deg, harm.psi_deg)
    period = settings.min_period(harm.A_deg, harm.A_deg)  # the harmonic gait at the bandwidth
    x, hist, failed, status = ocp.solve(ocp.initial_guess(ReferenceTorque(gait, robot.k), period))
    res.homotopy = hist
    res.solve_time_s = time.perf_counter() - t_start
    outcome = ipopt_status(status)
    if failed is not None:
        # every homotopy failed: the status table decides infeasible vs solver failure
        res.failed_stage = failed
        res.status = result_status(outcome, usable=False)
        res.message = (f"{'infeasible' if res.status == Status.INFEASIBLE else 'IPOPT failed'}: "
                       f"IPOPT {outcome.describe()} at {failed}")
    if x is None:
        return res
    _fill_solution(res, ocp, x)
    if failed is not None:
        res.message += "; the last accepted iterate is reported (not an optimum)"
        return res
    if not _check_solution(res, settings, outcome):
        return res
    res.success = True
    res.status = Status.SUCCESS
    res.message = f"optimal {settings.objective} profile found ({len(hist)} IPOPT calls, final IPOPT status " \
                  f"{status})"
    last = ocp.kept_run[-1] if ocp.kept_run else None
    if last is not None and last.kind == "polish" and not last.accepted:
        res.message += f"; polish not kept: IPOPT {last.message}"
    if replay:
        _replay(res, settings, ocp)
    res.solve_time_s = time.perf_counter() - t_start
    return res


def _fill_solution(res: OCPResult, ocp: GaitOCP, x: np.ndarray) -> None:
    """The profile, trajectories, S, W+, CoT+ and residuals of the NLP point x."""
    un = ocp.unpack(x)
    res.phase = np.arange(ocp.settings.nodes) / ocp.settings.nodes
    res.tau = un["tau"]
    res.T_ocp = un["T"]
    for sc, model in zip(un["scen"], ocp.scen):
        res.phi.append(sc["phi"])
        res.x1.append(sc["x1"])
        res.f_t.append(sc["f_t"])
        res.modes.append(sc["modes"])
        res.theta.append(sc["theta"])
        res.S_ocp.append(sc["S"])
        res.v_ocp.append(sc["v"])
        w = sc["W_plus"]
        res.W_plus_ocp.append(w)
        res.CoT_plus_ocp.append(cost_of_transport(w, model.robot, sc["S"]))
    res.complementarity_residual = max(sc["comp"] for sc in un["scen"])
    res.periodicity_residual = max(sc["periodic"] for sc in un["scen"])
    res.equation_residual = ocp.equation_residual(x)
    res.value_ocp = value_from(ocp.settings, res.S_ocp, res.CoT_plus_ocp, period=res.T_ocp)


def _check_solution(res: OCPResult, settings: OCPSettings, outcome) -> bool:
    """False (with the status and message set) if the accepted point has non-finite values or is not
    complementary."""
    numbers = [*res.S_ocp, res.T_ocp, *res.W_plus_ocp, res.complementarity_residual, res.periodicity_residual,
               res.equation_residual, *np.ravel(res.tau)]
    if not all(math.isfinite(v) for v in numbers):
        res.status = Status.SOLVER_FAILURE
        res.message = f"IPOPT returned {outcome.describe()} but the solution has NaN or Inf values"
        return False
    if not res.complementarity_residual <= settings.comp_tol:
        res.status = Status.NOT_COMPLEMENTARY
        res.message = (f"complementarity residual {res.complementarity_residual:.2e} above {settings.comp_tol:.1e} "
                       "after the homotopy")
        return False
    return True


def _replay(res: OCPResult, settings: OCPSettings, ocp: GaitOCP) -> None:
    """Replay the optimal profile in the event-driven simulator (each scenario) and compare."""
    sig = replay_signal(res.phase, res.tau)
    sims = [simulate_torque(m, sig) for m in ocp.scen]
    res.replay = sims
    if any(not r.success for r in sims):
        bad = next(r for r in sims if not r.success)
        res.success = False
        res.status = Status.REPLAY_FAILED
        res.message = f"the replay of the optimal profile failed: {bad.message}"
        return
    res.S_replay = [r.S for r in sims]
    res.v_replay = [settings.direction * r.S / res.T_ocp for r in sims]
    res.W_plus_replay = [r.W_plus for r in sims]
    res.CoT_plus_replay = [r.CoT_plus for r in sims]
    res.value_replay = objective_value(settings, sims, enforce_s_min=False, period=res.T_ocp)
    res.rel_diff_replay = (abs(res.value_replay - res.value_ocp) / abs(res.value_replay) if res.value_replay != 0
                           else float("nan"))
    if res.harmonic is not None and math.isfinite(res.harmonic.value) and res.harmonic.value != 0:
        h = res.harmonic.value
        res.gain = (h - res.value_replay) / h if settings.objective == "min_cot" else (res.value_replay - h) / abs(h)
