"""Replay is the judge: the OCP's optimum counts only when the event-driven simulator confirms it.

The replay signal is the transcription's own interpolant: the node torques tau_k at phases k/N,
linear in phase between nodes (:class:`~ocp_crawl.model.sampled.PeriodicLinear`, the
``[gait] waveform = "samples"`` with ``interpolation = "linear"``), run with the OCP's period T.
:func:`judge_replay` replays it in every friction scenario and accepts the optimum only when

* every replay succeeds (else ``REPLAY_FAILED``);
* the profile stays in the envelope gamma +- A_max and within the bandwidth |d tau_i/dt| <= k R,
  both to :data:`BOUND_RTOL` relative (the linear interpolant's extremes and slopes are those of its
  nodes), and, with the optional ``max_accel_deg_s2`` = a, its second differences within k a
  (T/N)^2;
* every requirement (min_cot's ``speed_min``, the bounds of ``constraints`` on cycle quantities:
  :mod:`ocp_crawl.ocp.quantities`) holds on the replay within ``replay_tol`` (relative to the
  bound);
* the replayed objective agrees with the OCP's own within ``replay_tol`` (relative to the replay's);
* with the optional ``max_joint_rate_deg_s``: the replay's peak actual joint rate
  (:mod:`ocp_crawl.ocp.rates`) is within it to :data:`~ocp_crawl.ocp.rates.JOINT_RATE_RTOL`
  (relative: the OCP bounds the mean rates of the intervals and, 0.5 % looser, of the sub-steps; the
  peak inside a sub-step is O(1/N) above its mean);

otherwise ``REPLAY_MISMATCH`` with both sets of numbers in the message.  The judge computes its
numbers itself, from the torques and the period alone; the OCP's numbers enter only to be compared.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ocp_crawl.io import units
from ocp_crawl.model.sampled import JointLinear, PeriodicLinear
from ocp_crawl.ocp.plant import (AnyRobot, as_plant, joint_accel_bounds, joint_rate_bounds,
                                 joint_torque_bounds)
from ocp_crawl.ocp.baseline import cycle_of, value_from
from ocp_crawl.ocp.quantities import Cycle, minimises, missed, profile_of_nodes, reference_sizes
from ocp_crawl.ocp.rates import JOINT_RATE_RTOL, replay_peaks
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.status import Status

#: the ``[gait] interpolation`` of a problem file of samples that reproduces :func:`replay_signal`
#: (the ``optimal_gait.toml`` that ``optimize --out`` writes replays the optimum with it)
REPLAY_INTERPOLATION = "linear"
#: relative tolerance of the envelope and bandwidth checks (the NLP meets its bounds to round-off)
BOUND_RTOL = 1e-9


def replay_signal(phase: np.ndarray, tau: np.ndarray) -> PeriodicLinear:
    """Torque input of the event-driven replay: the transcription's own interpolant, linear in
    phase.

    Parameters
    ----------
    phase : array_like, shape (N,)
        Node phases [cycles] in [0, 1) (k/N).
    tau : array_like, shape (m, N)
        Joint torques [N m] at the nodes (m = 2 for the three-link robot).

    Returns
    -------
    PeriodicLinear
        tau(t) [N m] of the phase t [cycles]; its extremes and slopes are those of the nodes (a
        :class:`~ocp_crawl.model.sampled.JointLinear` for m != 2).
    """
    if np.shape(tau)[0] != 2:
        return JointLinear(phase, tau)
    return PeriodicLinear(phase, tau)


def value_text(objective: str, value: float) -> str:
    """An objective value with its unit: a speed [m/s] in mm/s (max_speed, robust_speed), else CoT+
    [-]."""
    if objective.startswith(("min:", "max:")):
        return units.significant(value, 6)
    return units.cot(value) if objective == "min_cot" else units.speed(value)


def spread_text(objective: str, low: float, high: float, converged: int) -> str:
    """The outcome of several starts: "3 converged, replayed objective from a to b" (one value when
    a = b), or "none converged"."""
    if not converged:
        return "none converged"
    low_text, high_text = value_text(objective, low), value_text(objective, high)
    spread = low_text if low_text == high_text else f"from {low_text} to {high_text}"
    return f"{converged} converged, replayed objective {spread}"


def ratio_labels(ratios) -> list[str]:
    """Labels of the friction scenarios mu1/mu2 = ``ratios``: each ratio to the fewest significant
    digits (from 6) that tell every scenario apart, e.g. ["0.9", "1", "1.1"] (files and text name
    the scenarios by them)."""
    ratios = [float(r) for r in ratios]
    for digits in range(6, 18):
        labels = [f"{r:.{digits}g}" for r in ratios]
        if len(set(labels)) == len(set(ratios)):
            return labels
    return [repr(r) for r in ratios]


def scenario_labels(settings: OCPSettings) -> list[str]:
    """Labels of the friction scenarios of ``settings``, in their order: the ratio's
    (:func:`ratio_labels`), and with friction levels (``mu_levels``) "<ratio>_level_<level>" ("own"
    for the robot's own ratio, without a ratio set)."""
    ratios = ratio_labels(settings.friction_ratios) if settings.ratio_set else ["own"]
    if settings.mu_levels is None:
        return ratios
    levels = ratio_labels(settings.levels)
    return [f"{r}_level_{lv}" for lv in levels for r in ratios]


def first_failure(models: list, signal):
    """The first failed simulation of ``signal`` over the friction scenarios' ``models`` (the
    scenarios after it not simulated), or None when every one succeeds."""
    return next((r for r in (as_plant(m).simulate(signal) for m in models) if not r.success), None)


def replay_misses(settings: OCPSettings, robot, runs: list, T: float,
                  tau: np.ndarray) -> tuple[Cycle, list[str]]:
    """The :class:`~ocp_crawl.ocp.quantities.Cycle` of a profile's successful replays ``runs`` (one
    per friction scenario of ``robot``, period ``T`` [s], node torques ``tau`` (m, N) [N m]) and the
    requirements it misses by more than ``replay_tol``, as texts."""
    cycle = cycle_of(settings, [r.S for r in runs], [r.W_plus for r in runs],
                     [r.CoT_plus for r in runs], T, profile_of_nodes(tau))
    sizes = reference_sizes(robot.M, robot.g, robot.L, settings.period_ref())
    return cycle, missed(settings.requirements, cycle, settings.replay_tol, sizes)


def is_better(objective: str, a: float, b: float) -> bool:
    """Whether objective value ``a`` is strictly better than ``b`` (CoT+ smaller, speeds larger);
    NaN never is."""
    if math.isnan(a):
        return False
    if math.isnan(b):
        return True
    return a < b if minimises(objective) else a > b


def gain_over(objective: str, value: float, baseline: float) -> float:
    """Relative gain [-] of ``value`` over the ``baseline`` value (positive: better), NaN if
    undefined.

    min_cot: (CoT_baseline - CoT) / CoT_baseline; speeds: (v - v_baseline) / |v_baseline|."""
    if not (math.isfinite(value) and math.isfinite(baseline)) or baseline == 0:
        return float("nan")
    if minimises(objective):
        return (baseline - value) / abs(baseline)
    return (value - baseline) / abs(baseline)


def bound_ratios(settings: OCPSettings, robot: AnyRobot, tau: np.ndarray,
                 T: float) -> tuple[float, float, float]:
    """How far a node profile goes to its limits.

    Parameters
    ----------
    settings : OCPSettings
        The envelope (gamma, A_max), the bandwidth (max_rate_deg_s) and the optional
        max_accel_deg_s2.
    robot : Robot or Chain
        The robot (its stiffness per joint [N m/rad] turns angles into torques).
    tau : array_like, shape (m, N)
        Node torques of the m joints [N m] at phases k/N (periodic).
    T : float
        Period [s].

    Returns
    -------
    (float, float, float)
        The largest excursion beyond the envelope relative to its half-width k A_max (<= 0 inside);
        the largest slope |d tau_i/dt| of the linear interpolant over the bound k R (<= 1 within the
        bandwidth); the largest second difference over its bound k a (T/N)^2 (<= 1 within it; NaN
        without max_accel_deg_s2); each the largest over the joints.
    """
    tau = np.asarray(tau, float)
    N = tau.shape[1]
    lo, hi = joint_torque_bounds(settings, robot)
    # each joint's largest value over its own bound, then the largest over the joints
    outside = np.max(np.maximum(lo[:, None] - tau, tau - hi[:, None]), axis=1)
    excess = float(np.max(outside / (0.5 * (hi - lo))))
    steps = np.diff(np.c_[tau, tau[:, :1]], axis=1)  # tau_k+1 - tau_k, periodic
    bound = joint_rate_bounds(settings, robot)
    rate = (float(np.max(np.max(np.abs(steps), axis=1) * N / T / bound)) if T > 0
            else math.inf)
    accel = joint_accel_bounds(settings, robot)
    if accel is None:
        return excess, rate, math.nan
    second = np.diff(np.c_[steps[:, -1:], steps], axis=1)  # tau_k+1 - 2 tau_k + tau_k-1
    return (excess, rate,
            float(np.max(np.max(np.abs(second), axis=1) / (accel * (T / N) ** 2))) if T > 0
            else math.inf)


@dataclass
class Verdict:
    """The judge's findings on one profile: its status, the replayed numbers and the margins."""

    status: Status
    message: str
    replay: list = field(default_factory=list)
    """per scenario: the CrawlResult of the event-driven replay"""
    S: list = field(default_factory=list)
    """per scenario: replayed displacement per cycle [m]"""
    W_plus: list = field(default_factory=list)
    """per scenario: replayed positive work per cycle [J]"""
    CoT_plus: list = field(default_factory=list)
    """per scenario: replayed CoT+ [-]"""
    speed: list = field(default_factory=list)
    """per scenario: replayed mean speed direction * S / T [m/s]"""
    value: float = float("nan")
    """replayed objective value (speeds [m/s], CoT+ [-])"""
    rel_diff: float = float("nan")
    """|value_replay - value_ocp| / |value_replay| [-] (a vocabulary sum: over the sum of its
    terms' magnitudes, ``TermsValue.magnitude``)"""
    envelope_excess: float = float("nan")
    rate_ratio: float = float("nan")
    accel_ratio: float = float("nan")
    """largest second difference over its bound (NaN: no max_accel_deg_s2)"""
    peaks: list = field(default_factory=list)
    """per scenario: the replay's peak joint rates and foot sliding speeds
    (:class:`~ocp_crawl.ocp.rates.Peaks`)"""
    joint_rate_ratio: float = float("nan")
    """the replay's peak joint rate over max_joint_rate_deg_s (NaN: no such bound)"""
    cycle: Cycle | None = None
    """the replayed cycle quantities the requirements are checked on
    (:class:`~ocp_crawl.ocp.quantities.Cycle`)"""

    @property
    def ok(self) -> bool:
        """True when the replay confirms the OCP."""
        return self.status == Status.SUCCESS


def judge_replay(models: list, settings: OCPSettings, tau: np.ndarray, T: float,
                 value_ocp: float, S_ocp: list | None = None) -> Verdict:
    """Replay node torques in the event-driven simulator and judge the OCP's claim (see the module
    docstring).

    Parameters
    ----------
    models : list of Model, ChainModel or Plant
        One model per friction scenario (the OCP's scenarios, in its order).
    settings : OCPSettings
        Objective, envelope, bandwidth, speed_min and replay_tol.
    tau : array_like, shape (m, N)
        Node torques of the m joints [N m] at phases k/N.
    T : float
        The OCP's period [s].
    value_ocp : float
        The OCP's own objective value (speeds [m/s], CoT+ [-]).
    S_ocp : list of float, optional
        The OCP's S per scenario [m], quoted in the message.

    Returns
    -------
    Verdict
        ``SUCCESS``, ``REPLAY_FAILED`` or ``REPLAY_MISMATCH`` (the message gives the OCP's and the
        replay's numbers), with the replayed numbers and the envelope and bandwidth margins.
    """
    tau = np.asarray(tau, float)
    N = tau.shape[1]
    plants = [as_plant(m) for m in models]
    v = Verdict(Status.SUCCESS, "the replay confirms the optimum")
    v.envelope_excess, v.rate_ratio, v.accel_ratio = bound_ratios(settings, plants[0].robot, tau, T)
    # the transcription's own interpolant from phase 0 (the event-driven stepper passes the input's
    # kinks, also one at the cycle boundary: ocp_crawl/sim/event_kinks.py), as torques.csv replays
    # it
    sig = replay_signal(np.arange(N) / N, tau)
    v.replay = [p.simulate(sig) for p in plants]
    bad = next((r for r in v.replay if not r.success), None)
    if bad is not None:
        v.status = Status.REPLAY_FAILED
        v.message = f"{Status.REPLAY_FAILED.text}: {bad.message}"
        return v
    v.S = [r.S for r in v.replay]
    v.W_plus = [r.W_plus for r in v.replay]
    v.CoT_plus = [r.CoT_plus for r in v.replay]
    v.speed = [settings.direction * s / T for s in v.S]
    v.cycle = cycle_of(settings, v.S, v.W_plus, v.CoT_plus, T, profile_of_nodes(tau))
    v.value = value_from(settings, v.S, v.CoT_plus, T, cycle=v.cycle)
    v.peaks = [replay_peaks(p, sig, T, r, N) for r, p in zip(v.replay, plants)]
    r = plants[0].robot
    problems = _problems(v, settings, value_ocp,
                         reference_sizes(r.M, r.g, r.L, settings.period_ref()))
    if problems:
        v.status = Status.REPLAY_MISMATCH
        S_text = ", ".join(units.distance(s) for s in (S_ocp or []))
        v.message = (f"{Status.REPLAY_MISMATCH.text}: {'; '.join(problems)} (OCP: value "
                     f"{value_text(settings.objective, value_ocp)}"
                     f"{', S ' + S_text if S_text else ''}; replay: value "
                     f"{value_text(settings.objective, v.value)}, S "
                     f"{', '.join(units.distance(s) for s in v.S)}, speed "
                     f"{', '.join(units.speed(s) for s in v.speed)}; T = {units.seconds(T)})")
    return v


def _problems(v: Verdict, settings: OCPSettings, value_ocp: float, sizes: dict) -> list[str]:
    """What the replay misses: the envelope, the bandwidth, the requirements, the joint rate, the
    agreement with the OCP."""
    tol = settings.replay_tol
    out = []
    if not v.envelope_excess <= BOUND_RTOL:
        out.append(f"the torques leave the envelope by {units.scientific(v.envelope_excess)} of "
                   f"its half-width (tolerance {units.scientific(BOUND_RTOL)})")
    if not v.rate_ratio <= 1 + BOUND_RTOL:
        out.append(f"the torque rate reaches {units.significant(v.rate_ratio, 10)} times the "
                   f"bandwidth {units.significant(settings.max_rate_deg_s)} deg/s (tolerance "
                   f"{units.scientific(BOUND_RTOL)})")
    if not (math.isnan(v.accel_ratio) or v.accel_ratio <= 1 + BOUND_RTOL):
        out.append(f"the torque's second difference reaches {units.significant(v.accel_ratio, 10)} "
                   "times the bound of max_accel_deg_s2 = "
                   f"{units.significant(settings.max_accel_deg_s2)} deg/s^2 (tolerance "
                   f"{units.scientific(BOUND_RTOL)})")
    out += [f"the replay misses {text} by more than replay_tol {units.ratio(tol)}"
            for text in (missed(settings.requirements, v.cycle, tol, sizes)
                         if v.cycle is not None else [])]
    out += _joint_rate_problems(v, settings)
    size = abs(v.value)
    magnitude = getattr(getattr(settings.user_objective, "value", None), "magnitude", None)
    if magnitude is not None and v.cycle is not None:  # a sum near 0: relative to its terms
        size = max(size, magnitude(v.cycle))
    if size != 0:
        v.rel_diff = abs(v.value - value_ocp) / size
    else:
        v.rel_diff = 0.0 if value_ocp == 0 else math.inf
    if not v.rel_diff <= tol:
        out.append(f"the objective differs by {units.ratio(v.rel_diff)} (replay_tol "
                   f"{units.ratio(tol)})")
    return out


def _joint_rate_problems(v: Verdict, settings: OCPSettings) -> list[str]:
    """The replay's peak joint rate above max_joint_rate_deg_s beyond JOINT_RATE_RTOL (sets
    ``joint_rate_ratio``); [] without the bound."""
    bound = settings.max_joint_rate_deg_s
    if bound is None:
        return []
    peak = max((max(p.joint_rate_deg_s) for p in v.peaks), default=math.nan)
    v.joint_rate_ratio = peak / bound
    if v.joint_rate_ratio <= 1 + JOINT_RATE_RTOL:
        return []
    return [f"the replayed joint rate reaches {units.significant(peak, 4)} deg/s, above "
            f"max_joint_rate_deg_s = {units.significant(bound)} deg/s (tolerance "
            f"{units.ratio(JOINT_RATE_RTOL)})"]
