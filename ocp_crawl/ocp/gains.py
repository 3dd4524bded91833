"""The gains of a replayed optimum over the best member of each waveform family, and the verdict
on an optimum worse than the harmonic baseline it started from (WORSE_THAN_BASELINE).

Where another family's member beats the optimum, that member sampled at the nodes
(:mod:`ocp_crawl.ocp.sampling`) tells why: if that profile (a point of the OCP) is no better than
the optimum, the nodes cannot hold the member's corners (refine N); if it is better, the solver's
path ended in a local optimum (other starts).
"""
from __future__ import annotations

import math

from ocp_crawl.io import units
from ocp_crawl.ocp.baseline import WaveChoice
from ocp_crawl.ocp.chain_search import ChainWaveChoice
from ocp_crawl.ocp.judge import gain_over, is_better, value_text
from ocp_crawl.ocp.plant import as_plant
from ocp_crawl.ocp.rates import JOINT_RATE_RTOL, signal_peaks
from ocp_crawl.ocp.result import OCPResult
from ocp_crawl.ocp.sampling import best_sampling
from ocp_crawl.status import Status


def measure_gains(res: OCPResult, models: list) -> None:
    """The gains by replay over each family's best member and over the best of them; an optimum
    significantly worse than the harmonic baseline (its first start) is not one
    (WORSE_THAN_BASELINE); one worse than another family's best says so in its message (a local
    optimum: that gait is a start to try)."""
    objective = res.settings.objective
    best: WaveChoice | ChainWaveChoice | None
    if res.baselines is not None:
        res.gains = res.baselines.gains(res.value_replay, gain_over)
        best = res.baselines.best
    else:
        best = res.harmonic
        res.gains = {"harmonic": math.nan if best is None else
                     gain_over(objective, res.value_replay, best.value)}
    if best is None:
        return
    # NaN for an infeasible one's +inf
    res.gain = gain_over(objective, res.value_replay, best.value)
    h_gain, tol = res.gains.get("harmonic", math.nan), res.settings.replay_tol
    if res.success and h_gain < -tol and _baseline_within(res, models, h_gain):
        _worse_than_baseline(res, h_gain)
    elif res.success and res.gain < -tol and best is not res.harmonic:
        _better_member(res, models, best)


def _better_member(res: OCPResult, models: list, best) -> None:
    """A confirmed optimum worse than another family's best member ``best``: that member sampled at
    the nodes (:func:`~ocp_crawl.ocp.sampling.best_sampling`, in ``res.baseline_at_nodes``) and
    what it means, in the message."""
    s, objective, N = res.settings, res.settings.objective, res.settings.nodes
    peak = _rate_beyond_bound(res, models, best)
    if peak is not None:
        note = (f"; the best {best.shape} gait reaches {value_text(objective, best.value)} (gain "
                f"{units.ratio(res.gain)}), but its joint rate reaches "
                f"{units.significant(peak, 4)} deg/s, beyond max_joint_rate_deg_s: no gait of "
                f"this problem")
        if note not in res.message:
            res.message += note
        return
    if res.baseline_at_nodes is None or res.baseline_at_nodes["shape"] != best.shape:
        res.baseline_at_nodes = {"shape": best.shape, "nodes": N,
                                 "value": best_sampling(s, models, best)[0]}
    at_nodes = res.baseline_at_nodes["value"]
    note = (f"; the best {best.shape} gait is better ({value_text(objective, best.value)}, gain "
            f"{units.ratio(res.gain)}); sampled at the N = {N} nodes it reaches "
            f"{value_text(objective, at_nodes)}")
    if is_better(objective, at_nodes, res.value_replay):
        note += (", better than the optimum: a local optimum of the solver's path (other starts: "
                 "optimize --start with that gait, or start_solve = \"both\")")
    else:
        note += ": the nodes cannot hold its corners (raise ocp.nodes)"
    if note not in res.message:  # (measured once by the start's judge, again over the starts)
        res.message += note


def _rate_beyond_bound(res: OCPResult, models: list, member) -> float | None:
    """The peak actual joint rate [deg/s] of ``member`` over the scenarios when it exceeds the
    optional max_joint_rate_deg_s (the members are searched within the bandwidth and the envelope
    only), else None."""
    bound = res.settings.max_joint_rate_deg_s
    if bound is None:
        return None
    signal = member.signal_for(as_plant(models[0]).robot, res.settings)
    peak = max(max(signal_peaks(m, signal, member.T).joint_rate_deg_s) for m in models)
    return peak if peak > bound * (1 + JOINT_RATE_RTOL) else None


def harmonic_peaks(res: OCPResult, models: list) -> None:
    """The harmonic baseline's peak joint rates and foot sliding speeds (its replay in every
    scenario), unless measured already or there is no baseline."""
    if res.harmonic is None or res.harmonic_peak_joint_rate_deg_s:
        return
    signal = res.harmonic.signal_for(as_plant(models[0]).robot, res.settings)
    peaks = [signal_peaks(m, signal, res.harmonic.T) for m in models]
    res.harmonic_peak_joint_rate_deg_s = [list(p.joint_rate_deg_s) for p in peaks]
    res.harmonic_peak_slip_speed_m_s = [list(p.slip_speed_m_s) for p in peaks]


def _baseline_within(res: OCPResult, models: list, gain: float) -> bool:
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
    note = (f"; worse than the harmonic baseline by replay ({units.ratio(gain)}), whose joint rate "
            f"reaches {units.significant(peak, 4)} deg/s, beyond max_joint_rate_deg_s")
    if note not in res.message:  # (measured once by the start's judge, again over the starts)
        res.message += note
    return False


def _worse_than_baseline(res: OCPResult, gain: float) -> None:
    """A profile confirmed by replay but worse than the harmonic baseline (a gait inside the same
    envelope and bandwidth, and the first start) is not an optimum: WORSE_THAN_BASELINE with both
    values."""
    objective = res.settings.objective
    assert res.harmonic is not None  # a gain over the baseline is measured
    res.success = False
    res.status = Status.WORSE_THAN_BASELINE
    res.message = (f"{Status.WORSE_THAN_BASELINE.text}: replay "
                   f"{value_text(objective, res.value_replay)} against the harmonic baseline's "
                   f"{value_text(objective, res.harmonic.value)} (gain {units.ratio(gain)}, "
                   f"replay_tol {units.ratio(res.settings.replay_tol)})")
