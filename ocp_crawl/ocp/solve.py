"""Solve the periodic-gait OCP and prove the optimum by replay: :func:`optimize_gait` and :class:`OCPResult`.

The first start is the best harmonic gait of the family (:func:`~ocp_crawl.ocp.search.best_baselines`), then
a Fourier-order start and perturbed starts (:mod:`~ocp_crawl.ocp.starts`, ``settings.starts`` in all); from each,
the transcription (:class:`~ocp_crawl.ocp.transcription.GaitOCP`) is solved by the relaxation homotopy, every
stage read through the IPOPT status table, and the optimum is judged by its event-driven replay
(:func:`~ocp_crawl.ocp.judge.judge_replay`: the transcription's own linear interpolant, the OCP's period).
The reported optimum is the best by replay among the starts the judge accepts, with the spread of the others;
its gain is measured by replay against the best member of each simple waveform family (harmonic, triangle,
pulse: ``settings.baselines``) and against the best of them.
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from ocp_crawl.io import units
from ocp_crawl.io.files import jsonable
from ocp_crawl.model.statics import Model, Robot
from ocp_crawl.nlp.ipopt import ipopt_status, result_status
from ocp_crawl.ocp.baseline import Baselines, WaveChoice, value_from
from ocp_crawl.ocp.dynamic_margin import check_dynamic_margin
from ocp_crawl.ocp.judge import (gain_over, is_better, judge_replay, ratio_labels, replay_signal,
                                 spread_text, value_text)
from ocp_crawl.ocp.rates import JOINT_RATE_RTOL, signal_peaks
from ocp_crawl.ocp.search import best_baselines
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.starts import start_guesses
from ocp_crawl.ocp.transcription import GaitOCP
from ocp_crawl.sim.event import simulate_torque
from ocp_crawl.sim.result import cost_of_transport
from ocp_crawl.status import Status


@dataclass
class StartRecord:
    """One start of the multi-start OCP and what became of it."""

    label: str
    """which start: 'harmonic baseline', 'second harmonic' or 'perturbed i'"""
    status: Status
    T_start: float
    """the start's period [s]"""
    value_ocp: float = float("nan")
    value_replay: float = float("nan")
    message: str = ""
    iterations: int = 0
    """IPOPT iterations of the start's homotopies"""

    @property
    def converged(self) -> bool:
        """The OCP converged from this start and its optimum was replayed (judged or not)."""
        return math.isfinite(self.value_replay) and self.status in (Status.SUCCESS, Status.REPLAY_MISMATCH,
                                                                     Status.WORSE_THAN_BASELINE)

    def to_dict(self) -> dict:
        """JSON-able (the status as its lower-case label)."""
        return jsonable(dict(asdict(self), status=self.status.label, converged=self.converged))


@dataclass
class OCPResult:
    """Outcome of :func:`optimize_gait`: the optimal profile, its residuals, the harmonic baseline, the
    replay that judges it (per scenario lists: one entry without a friction set) and the starts."""

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
    """the OCP's objective value (max_speed, robust_speed: a speed [m/s]; min_cot: CoT+ [-])"""
    complementarity_residual: float = float("nan")
    periodicity_residual: float = float("nan")
    equation_residual: float = float("nan")
    homotopy: list = field(default_factory=list)
    """:class:`~ocp_crawl.nlp.homotopy.Stage` records of every IPOPT call (of the reported start)"""
    failed_stage: str | None = None
    solve_time_s: float = float("nan")
    harmonic: WaveChoice | None = None
    """the best harmonic gait of the family: the first start"""
    baselines: Baselines | None = None
    """the best member of each waveform family searched (``settings.baseline_shapes``)"""
    replay: list = field(default_factory=list)
    """per scenario: CrawlResult of the event-driven replay"""
    S_replay: list = field(default_factory=list)
    v_replay: list = field(default_factory=list)
    """per scenario: replayed mean speed direction * S / T [m/s]"""
    W_plus_replay: list = field(default_factory=list)
    CoT_plus_replay: list = field(default_factory=list)
    value_replay: float = float("nan")
    rel_diff_replay: float = float("nan")
    envelope_excess: float = float("nan")
    """largest excursion of the torques beyond the envelope, relative to its half-width (<= 0: inside)"""
    rate_ratio: float = float("nan")
    """largest torque rate of the replayed profile over the bandwidth k R (<= 1: within)"""
    accel_ratio: float = float("nan")
    """largest second difference over the bound of max_accel_deg_s2 (<= 1: within; NaN: no such bound)"""
    peak_joint_rate_deg_s: list = field(default_factory=list)
    """per scenario: the replay's peak actual joint rates |d phi_i/dt| of joints 1, 2 [deg/s]
    (:mod:`~ocp_crawl.ocp.rates`)"""
    peak_slip_speed_m_s: list = field(default_factory=list)
    """per scenario: the replay's peak sliding speeds |d x_i/dt| of feet 1, 2 [m/s]"""
    joint_rate_ratio: float = float("nan")
    """the replay's peak joint rate over max_joint_rate_deg_s (<= 1: within; NaN: no such bound)"""
    harmonic_peak_joint_rate_deg_s: list = field(default_factory=list)
    """per scenario: the harmonic baseline's peak joint rates [deg/s] (its own replay; empty if not
    measured)"""
    harmonic_peak_slip_speed_m_s: list = field(default_factory=list)
    """per scenario: the harmonic baseline's peak foot sliding speeds [m/s]"""
    gain: float = float("nan")
    """relative gain by replay over the best baseline of every family searched (positive: better)"""
    gains: dict = field(default_factory=dict)
    """relative gain by replay over each family's best member, by shape (NaN: none, or infeasible)"""
    starts: list = field(default_factory=list)
    """:class:`StartRecord` of every start of the multi-start (the reported one among them)"""
    dynamic_margin: dict | None = None
    """with ``[ocp] dynamic_margin``: the MuJoCo check (:mod:`ocp_crawl.ocp.dynamic_margin`)"""

    @property
    def gain_significant(self) -> bool:
        """Whether the gain exceeds the replay tolerance (|gain| > replay_tol)."""
        return math.isfinite(self.gain) and abs(self.gain) > self.settings.replay_tol

    def _best_baseline(self) -> dict | None:
        best = self.baselines.best if self.baselines else self.harmonic
        return {"shape": best.shape, "value": best.value, "feasible": best.feasible} if best else None

    @property
    def spread(self) -> tuple[float, float, int]:
        """(min, max) of the replayed objective over the converged starts and how many converged (NaNs if none)."""
        values = [s.value_replay for s in self.starts if s.converged]
        return (min(values), max(values), len(values)) if values else (float("nan"), float("nan"), 0)

    def summary(self) -> dict:
        """The result as strict JSON types (non-finite numbers None; the status as its lower-case label)."""
        one = len(self.S_ocp) == 1

        def per_scenario(values):
            return (values[0] if one else values) if values else None

        low, high, converged = self.spread
        return jsonable({
            "status": self.status.label, "success": bool(self.success), "message": self.message,
            "objective": self.objective, "nodes": self.settings.nodes,
            "parametrization": self.settings.parametrization,
            "S_ocp": per_scenario(self.S_ocp), "S_replay": per_scenario(self.S_replay),
            "T_ocp": self.T_ocp, "v_ocp": per_scenario(self.v_ocp), "v_replay": per_scenario(self.v_replay),
            "W_plus_ocp": self.W_plus_ocp, "W_plus_replay": self.W_plus_replay,
            "CoT_plus_ocp": self.CoT_plus_ocp, "CoT_plus_replay": per_scenario(self.CoT_plus_replay),
            "objective_value_ocp": self.value_ocp, "objective_value_replay": self.value_replay,
            "rel_diff_replay": self.rel_diff_replay, "replay_tol": self.settings.replay_tol,
            "envelope_excess": self.envelope_excess, "rate_ratio": self.rate_ratio,
            "accel_ratio": self.accel_ratio,
            "peak_joint_rate_deg_s": per_scenario(self.peak_joint_rate_deg_s),
            "peak_slip_speed_m_s": per_scenario(self.peak_slip_speed_m_s),
            "max_joint_rate_deg_s": self.settings.max_joint_rate_deg_s,
            "joint_rate_ratio": self.joint_rate_ratio,
            "harmonic_peak_joint_rate_deg_s": per_scenario(self.harmonic_peak_joint_rate_deg_s),
            "harmonic_peak_slip_speed_m_s": per_scenario(self.harmonic_peak_slip_speed_m_s),
            "best_harmonic": self.harmonic.to_dict() if self.harmonic else None,
            "baselines": self.baselines.table() if self.baselines else None,
            "best_baseline": self._best_baseline(),
            "gain": self.gain, "gain_significant": self.gain_significant, "gains": self.gains,
            "starts": [s.to_dict() for s in self.starts], "starts_converged": converged,
            "objective_value_replay_min": low, "objective_value_replay_max": high,
            "solve_time_s": self.solve_time_s, "dynamic_margin": self.dynamic_margin,
            "complementarity_residual": self.complementarity_residual,
            "periodicity_residual": self.periodicity_residual,
            "equation_residual": self.equation_residual, "failed_stage": self.failed_stage,
            "homotopy": [asdict(h) for h in self.homotopy], "scenarios": self.scenarios(),
        })

    def scenarios(self) -> list[dict] | None:
        """Over a friction set: per scenario, in the order of the per-scenario lists, its ratio ``mu1_mu2``,
        its ``label`` (:func:`~ocp_crawl.ocp.judge.ratio_labels`) and its values (S, speed, W+, CoT+ of the
        OCP and the replay; None where not computed); None without a set (one scenario, the robot's)."""
        if not self.settings.friction_set:
            return None
        ratios = self.settings.friction_ratios
        names = ("S_ocp", "S_replay", "v_ocp", "v_replay", "W_plus_ocp", "W_plus_replay", "CoT_plus_ocp",
                 "CoT_plus_replay")
        lists = [getattr(self, name) for name in names]
        return jsonable([{"mu1_mu2": r, "label": label,
                          **{n: values[j] if j < len(values) else None for n, values in zip(names, lists)}}
                         for j, (r, label) in enumerate(zip(ratios, ratio_labels(ratios)))])


def baseline_gait(harm: WaveChoice, robot: Robot) -> tuple:
    """The harmonic baseline as a start: its torque signal (``signal(t)`` [N m] at phases t [cycles]) and its
    period T [s]."""
    return harm.torque_signal(robot.k), harm.T


def optimize_gait(robot: Robot, gravity: str = "physical", settings: OCPSettings | None = None,
                  replay: bool = True, jobs: int | None = None) -> OCPResult:
    """Solve the periodic-gait OCP from several starts, judge each optimum by replay, report the best.

    Parameters
    ----------
    robot : Robot
        The robot (SI units).
    gravity : str
        The gravity convention ("physical" or "paper").
    settings : OCPSettings, optional
        The OCP's settings (None: the defaults), ``settings.starts`` starts.
    replay : bool
        Judge each optimum by its event-driven replay (default).  False: the OCP's own verdict only, the
        best start by the OCP's value (a solver test; the message says that nothing was replayed).
    jobs : int, optional
        Worker processes of the harmonic baseline's search (:func:`~ocp_crawl.ocp.baseline.best_harmonic`; None:
        the CPUs available).  The result does not depend on it.

    Returns
    -------
    OCPResult
        The best start by replay among those the judge accepts (else the best replayed, else the first
        start's failure): SUCCESS, INFEASIBLE, SOLVER_FAILURE, NOT_COMPLEMENTARY, NO_INITIAL_GUESS (no
        harmonic gait simulates), REPLAY_FAILED, REPLAY_MISMATCH or WORSE_THAN_BASELINE (confirmed by replay but
        worse than the harmonic baseline it started from); ``starts`` holds every start's outcome.
    """
    settings = settings or OCPSettings()
    t_start = time.perf_counter()
    ocp = GaitOCP(robot, gravity, settings)
    base = best_baselines(robot, gravity, settings, jobs=jobs, meanwhile=ocp.prepare)  # NLP built meanwhile
    harm = base.choices["harmonic"]
    if harm is None:
        return OCPResult(success=False, status=Status.NO_INITIAL_GUESS, objective=settings.objective,
                         settings=settings,
                         message="no harmonic gait of the family simulates successfully: no initial guess")
    models = [Model(r, gravity=gravity) for r in settings.scenarios(robot)]
    signal, T0 = baseline_gait(harm, robot)
    N = settings.nodes
    phase = np.arange(N) / N

    def follows(tau: np.ndarray) -> bool:
        return all(simulate_torque(m, replay_signal(phase, tau)).success for m in models)
    guesses = start_guesses(settings, robot, signal(phase).reshape(2, N), T0, follows)
    runs = [solve_from(ocp, models, replay_signal(phase, g.tau), g.T, harm, replay, baselines=base)
            for g in guesses]
    res = _pick(runs, settings, replay)
    if replay:
        harmonic_peaks(res, models)
        check_dynamic_margin(res, models)
    res.starts = [StartRecord(g.label, r.status, g.T, r.value_ocp, r.value_replay, r.message,
                              sum(stage.iterations for stage in r.homotopy)) for g, r in zip(guesses, runs)]
    if len(guesses) > 1:
        spread = spread_text(settings.objective, *res.spread)   # (low, high, converged)
        res.message += f"; best of {len(guesses)} starts ({spread})"
    res.solve_time_s = time.perf_counter() - t_start
    return res


def _pick(runs: list[OCPResult], settings: OCPSettings, replay: bool) -> OCPResult:
    """The reported start: the best by replay among the judged successes (by the OCP's value without
    replay), else the best replayed one, else the first start."""
    key = "value_replay" if replay else "value_ocp"
    for pool in ([r for r in runs if r.success], [r for r in runs if math.isfinite(r.value_replay)]):
        best = None
        for r in pool:
            if best is None or is_better(settings.objective, getattr(r, key), getattr(best, key)):
                best = r
        if best is not None:
            return best
    return runs[0]


def solve_from(ocp: GaitOCP, models: list[Model], signal, T: float, harmonic: WaveChoice | None = None,
               replay: bool = True, tightened: bool = False,
               baselines: Baselines | None = None) -> OCPResult:
    """Solve the OCP from one start and judge its optimum by replay.

    Parameters
    ----------
    ocp : GaitOCP
        The transcription (built once for its settings).
    models : list of Model
        The friction scenarios' models (the judge's replays), in the order of ``ocp.settings.scenarios``.
    signal : callable
        The start's torques ``signal(t)`` [N m] at phases t [cycles] (must simulate successfully).
    T : float
        The start's period [s].
    harmonic : WaveChoice, optional
        The harmonic baseline (an optimum significantly worse than it, its first start, is not one).
    replay : bool
        Judge the optimum by replay (default).
    tightened : bool
        Solve only the tightened NLP on the branches of the start's simulated guess, no homotopy
        (:meth:`~ocp_crawl.ocp.transcription.GaitOCP.solve_tightened`: a coarser N's optimum refined); default False.
    baselines : Baselines, optional
        The best member of each waveform family (the gains are measured against them; without them,
        against ``harmonic``).

    Returns
    -------
    OCPResult
        The start's outcome (``starts`` empty; ``solve_time_s`` of this start).
    """
    settings = ocp.settings
    t_start = time.perf_counter()
    res = OCPResult(success=False, status=Status.SOLVER_FAILURE, message="", objective=settings.objective,
                    settings=settings, harmonic=harmonic, baselines=baselines)
    bad = next((r for r in (simulate_torque(m, signal) for m in models) if not r.success), None)
    if bad is not None:
        res.status = Status.NO_INITIAL_GUESS
        res.message = f"{Status.NO_INITIAL_GUESS.text}: the start gait fails in the simulator: {bad.message}"
        return res
    x0 = ocp.initial_guess(signal, T)
    x, hist, failed, status = ocp.solve_tightened(x0) if tightened else ocp.solve(x0)
    res.homotopy = hist
    if not _accept(res, ocp, x, failed, status):
        res.solve_time_s = time.perf_counter() - t_start
        return res
    if replay:
        _judge(res, models)
    else:
        res.message += "; not replayed (the judge did not run)"
    res.solve_time_s = time.perf_counter() - t_start
    return res


def _accept(res: OCPResult, ocp: GaitOCP, x, failed: str | None, status: str) -> bool:
    """Fill res from the solve's outcome; True if the OCP converged to a usable, complementary point."""
    outcome = ipopt_status(status)
    if failed is not None:
        # every homotopy failed: the status table decides infeasible vs solver failure
        res.failed_stage = failed
        res.status = result_status(outcome, usable=False)
        res.message = (f"{'infeasible' if res.status == Status.INFEASIBLE else 'IPOPT failed'}: "
                       f"IPOPT {outcome.describe()} at {failed}")
    if x is None:
        return False
    _fill_solution(res, ocp, x)
    if failed is not None:
        res.message += "; the last accepted iterate is reported (not an optimum)"
        return False
    if not _check_solution(res, ocp.settings, outcome):
        res.message += _not_kept(ocp.kept_run)
        return False
    res.success = True
    res.status = Status.SUCCESS
    res.message = (f"optimal {ocp.settings.objective} profile found ({len(res.homotopy)} IPOPT calls, final IPOPT "
                   f"status {status}){_not_kept(ocp.kept_run)}")
    return True


def _not_kept(run: list) -> str:
    """A note on the IPOPT calls after the kept point that IPOPT did not accept, the last of each kind: the polish,
    and the loose last stage solved again tightly (:meth:`~ocp_crawl.ocp.transcription.GaitOCP.solve`); '' if none."""
    last = {}
    for stage in reversed(run):
        if stage.accepted:
            break
        last.setdefault(stage.kind, stage)
    what = {"polish": "polish", "homotopy": "the last stage solved again tightly"}
    return "".join(f"; {what.get(kind, kind)} not kept: IPOPT {stage.message}" for kind, stage in last.items())


def _fill_solution(res: OCPResult, ocp: GaitOCP, x: np.ndarray) -> None:
    """The profile, period, trajectories, S, v, W+, CoT+ and residuals of the NLP point x."""
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
    res.value_ocp = value_from(ocp.settings, res.S_ocp, res.CoT_plus_ocp, res.T_ocp)


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


def _judge(res: OCPResult, models: list[Model]) -> None:
    """Replay the optimal profile (every scenario) and let the judge decide; the gain over the baseline."""
    verdict = judge_replay(models, res.settings, res.tau, res.T_ocp, res.value_ocp, res.S_ocp)
    res.replay = verdict.replay
    res.envelope_excess, res.rate_ratio = verdict.envelope_excess, verdict.rate_ratio
    res.accel_ratio, res.joint_rate_ratio = verdict.accel_ratio, verdict.joint_rate_ratio
    res.peak_joint_rate_deg_s = [list(p.joint_rate_deg_s) for p in verdict.peaks]
    res.peak_slip_speed_m_s = [list(p.slip_speed_m_s) for p in verdict.peaks]
    res.S_replay, res.v_replay = verdict.S, verdict.speed
    res.W_plus_replay, res.CoT_plus_replay = verdict.W_plus, verdict.CoT_plus
    res.value_replay, res.rel_diff_replay = verdict.value, verdict.rel_diff
    if not verdict.ok:
        res.success = False
        res.status = verdict.status
        res.message = verdict.message
    else:
        res.message += (f"; confirmed by the event-driven replay (objective within {units.ratio(verdict.rel_diff)}, "
                        f"replay_tol {units.ratio(res.settings.replay_tol)})")
    _gains(res, models)


def _gains(res: OCPResult, models: list[Model]) -> None:
    """The gains by replay over each family's best member and over the best of them; an optimum
    significantly worse than the harmonic baseline (its first start) is not one (WORSE_THAN_BASELINE); one
    worse than another family's best says so in its message (a local optimum: that gait is a start to try)."""
    objective = res.settings.objective
    if res.baselines is not None:
        res.gains = res.baselines.gains(res.value_replay, gain_over)
        best = res.baselines.best
    else:
        best = res.harmonic
        res.gains = {"harmonic": math.nan if best is None else
                     gain_over(objective, res.value_replay, best.value)}
    if best is None:
        return
    res.gain = gain_over(objective, res.value_replay, best.value)  # NaN for an infeasible one's +inf
    h_gain, tol = res.gains.get("harmonic", math.nan), res.settings.replay_tol
    if res.success and h_gain < -tol and _baseline_within(res, models, h_gain):
        _worse_than_baseline(res, h_gain)
    elif res.success and res.gain < -tol and best is not res.harmonic:
        res.message += (f"; the best {best.shape} gait is better ({value_text(objective, best.value)}, gain "
                        f"{units.ratio(res.gain)}): the resolution of N = {res.settings.nodes} nodes or a "
                        f"local optimum")


def harmonic_peaks(res: OCPResult, models: list[Model]) -> None:
    """The harmonic baseline's peak joint rates and foot sliding speeds (its replay in every
    scenario), unless measured already or there is no baseline."""
    if res.harmonic is None or res.harmonic_peak_joint_rate_deg_s:
        return
    signal = res.harmonic.torque_signal(models[0].robot.k)
    peaks = [signal_peaks(m, signal, res.harmonic.T) for m in models]
    res.harmonic_peak_joint_rate_deg_s = [list(p.joint_rate_deg_s) for p in peaks]
    res.harmonic_peak_slip_speed_m_s = [list(p.slip_speed_m_s) for p in peaks]


def _baseline_within(res: OCPResult, models: list[Model], gain: float) -> bool:
    """Whether the harmonic baseline meets the optional max_joint_rate_deg_s (the bandwidth and the
    envelope it meets by construction); a baseline beyond it is no gait of the problem, so a profile
    worse than it is no failure (the message says so)."""
    bound = res.settings.max_joint_rate_deg_s
    if bound is None:
        return True
    harmonic_peaks(res, models)
    peak = max(max(p) for p in res.harmonic_peak_joint_rate_deg_s)
    if peak <= bound * (1 + JOINT_RATE_RTOL):
        return True
    res.message += (f"; worse than the harmonic baseline by replay ({units.ratio(gain)}), whose "
                    f"joint rate reaches {units.significant(peak, 4)} deg/s, beyond max_joint_rate_deg_s")
    return False


def _worse_than_baseline(res: OCPResult, gain: float) -> None:
    """A profile confirmed by replay but worse than the harmonic baseline (a gait inside the same envelope and
    bandwidth, and the first start) is not an optimum: WORSE_THAN_BASELINE with both values."""
    objective = res.settings.objective
    res.success = False
    res.status = Status.WORSE_THAN_BASELINE
    res.message = (f"{Status.WORSE_THAN_BASELINE.text}: replay {value_text(objective, res.value_replay)} against "
                   f"the baseline's {value_text(objective, res.harmonic.value)} (gain {units.ratio(gain)}, "
                   f"replay_tol {units.ratio(res.settings.replay_tol)})")
