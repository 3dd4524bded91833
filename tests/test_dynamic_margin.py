"""The judge's dynamic-margin rule ([ocp] dynamic_margin) on a stand-in for MuJoCo: S(T) [m] of
a known law, so that the shortest period within 5 % is known exactly (T_min = 0.5/sqrt(0.05) s)."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from ocp_crawl.ocp import dynamic_margin as dm
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.solve import OCPResult
from ocp_crawl.status import Status

S_QS = -0.01
T_MIN = 0.5 / math.sqrt(0.05)


def _stand_in(model, signal, options):
    """S = S_qs (1 - (0.5 s / T)^2): within 5 % of S_qs from T_MIN = 2.236 s."""
    return SimpleNamespace(success=True, S=S_QS * (1 - (0.5 / options.period) ** 2),
                           status_name="success")


def _judged(monkeypatch, T, factor):
    pytest.importorskip("mujoco")
    real = dm.margin_check
    monkeypatch.setattr(dm, "margin_check", lambda *a, **k: real(*a, simulate=_stand_in, **k))
    settings = OCPSettings(dynamic_margin=factor)
    res = OCPResult(success=True, status=Status.SUCCESS, message="confirmed", objective="max_speed",
                    settings=settings, tau=np.zeros((2, 8)), T_ocp=T, S_replay=[S_QS])
    dm.check_dynamic_margin(res, [SimpleNamespace(gravity="physical")])
    return res


def test_an_optimum_played_too_fast_is_refused(monkeypatch):
    res = _judged(monkeypatch, 4.0, 2.0)   # S at T/c = 2 s is 6.25 % short
    assert not res.success and res.status == Status.REPLAY_MISMATCH
    assert "not quasistatic at its period" in res.message and "max_rate_deg_s" in res.message
    d = res.summary()["dynamic_margin"]
    assert not d["ok"] and len(d["runs"]) <= dm.MAX_RUNS
    assert d["T_out_s"] < T_MIN <= d["T_min_s"] < dm.BRACKET * d["T_out_s"]


def test_a_slow_enough_optimum_is_accepted(monkeypatch):
    res = _judged(monkeypatch, 5.0, 2.0)   # T/c = 2.5 s: within
    assert res.success and res.status == Status.SUCCESS, res.message
    d = res.dynamic_margin
    assert d["ok"] and d["runs"][0]["period_s"] == 2.5 and d["period_s"] == 5.0
    assert d["T_out_s"] < T_MIN <= d["T_min_s"] and d["f_5pct_Hz"] == 1 / d["T_min_s"]
    assert "quasistatic in MuJoCo" in res.message
    assert dm.margin_text(d)[0].startswith("dynamic     MuJoCo: S within 5 %")


def test_without_the_setting_nothing_is_run():
    res = OCPResult(success=True, status=Status.SUCCESS, message="", objective="max_speed",
                    settings=OCPSettings())
    dm.check_dynamic_margin(res, [])
    assert res.dynamic_margin is None and res.summary()["dynamic_margin"] is None


@pytest.mark.parametrize("value", [0.5, 25.0])
def test_the_factor_is_bounded(value):
    with pytest.raises(ValueError, match="dynamic_margin must be in"):
        OCPSettings(dynamic_margin=value)
