"""The gains of a replayed optimum over the best member of each waveform family, and the verdict
on an optimum worse than the harmonic baseline it started from (WORSE_THAN_BASELINE)."""
from __future__ import annotations

import math

from ocp_crawl.io import units
from ocp_crawl.ocp.baseline import WaveChoice
from ocp_crawl.ocp.chain_search import ChainWaveChoice
from ocp_crawl.ocp.judge import gain_over, value_text
from ocp_crawl.ocp.plant import as_plant
from ocp_crawl.ocp.rates import JOINT_RATE_RTOL, signal_peaks
from ocp_crawl.ocp.result import OCPResult
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
        note = (f"; the best {best.shape} gait is better ({value_text(objective, best.value)}, "
                f"gain {units.ratio(res.gain)}): the resolution of N = {res.settings.nodes} nodes "
                "or a local optimum")
        if note not in res.message:  # (measured once by the start's judge, again over the starts)
            res.message += note


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
