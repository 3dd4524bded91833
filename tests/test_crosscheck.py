"""Cross-check of the MPCC time-stepping against the event-driven stepper: convergence of S and the report."""
import json

import numpy as np
import pytest

from ocp_crawl import Model, Robot
from ocp_crawl.sim.crosscheck import CrossCheckTolerances, convergence_order, crosscheck

from conftest import paper_torque

STEPS = (50, 100, 200, 400)
REL_S_AT_400 = 5e-3
"""the issue's requirement: |S_mpcc/S_event - 1| <= 0.5 % at N = 400"""


@pytest.fixture(scope="module", params=[("physical", 45.0), ("physical", 90.0), ("paper", 90.0)],
                ids=["paper-gait", "psi90", "psi90-paper-gravity"])
def checked(request):
    gravity, psi = request.param
    robot = Robot.paper()
    return crosscheck(Model(robot, gravity=gravity), paper_torque(robot, psi=psi), steps=STEPS)


def test_s_converges_to_the_event_driven_value(checked):
    rows = checked.rows
    assert checked.event.success, checked.event.message
    assert all(r.success for r in rows), [r.message for r in rows]
    assert [r.steps for r in rows] == list(STEPS)
    errors = np.array([abs(r.S - checked.event.S) for r in rows])
    assert checked.finest.rel_diff_S <= REL_S_AT_400
    assert errors[-1] < errors[0]
    # order recomputed here from the rows, by the least-squares slope of log error against log N
    slope = np.polyfit(np.log(STEPS), np.log(errors), 1)[0]
    assert checked.order == pytest.approx(-slope, rel=1e-12)
    assert checked.order >= 1.0


def test_crosscheck_report(checked):
    s = checked.summary()
    text = json.dumps(s)  # JSON-able
    for key in ("S_event", "S_mpcc", "rel_diff_S", "steps", "order", "passed", "W_plus_event", "W_plus_mpcc",
                "rel_diff_W_plus", "CoT_plus_event", "CoT_plus_mpcc", "rel_diff_CoT_plus", "max_phi_dev",
                "modes_event", "per_steps", "checks"):
        assert key in s, key
    assert json.loads(text)["steps"] == list(STEPS)
    assert s["S_event"] == checked.event.S and s["S_mpcc"] == checked.finest.S
    assert s["rel_diff_S"] == pytest.approx(abs(s["S_mpcc"] / s["S_event"] - 1), rel=1e-12)
    assert s["passed"] is True and all(c["passed"] for c in s["checks"].values())
    # every event of the event-driven cycle has a mode change of the time-stepping within the lag window
    lo, hi = checked.tolerances.event_lag_steps
    for lag in s["per_steps"][-1]["event_lags"]:
        assert lag["step_phase"] is not None and lo <= lag["lag_steps"] <= hi
    table = checked.table()
    assert "overall: PASS" in table and "[FAIL]" not in table
    assert f"{checked.finest.steps:>6d}" in table


def test_crosscheck_can_fail():
    robot = Robot.paper()
    tight = CrossCheckTolerances(rel_S=1e-12, max_phi_dev=1e-12)
    cc = crosscheck(Model(robot), paper_torque(robot), steps=(8, 16), tolerances=tight)
    assert cc.finest.rel_diff_S > 1e-12
    assert not cc.passed and cc.summary()["passed"] is False
    assert "overall: FAIL" in cc.table() and "[FAIL] rel diff S" in cc.table()


def test_convergence_order_of_synthetic_errors():
    n = np.array([50, 100, 200, 400])
    assert convergence_order(n, 3.0 * n ** -2.0) == pytest.approx(2.0, rel=1e-12)
    assert convergence_order(n, 0.1 / n) == pytest.approx(1.0, rel=1e-12)
    # exact (zero) errors carry no information and are left out
    assert convergence_order(n, [1e-3, 0.0, 6.25e-5, 0.0]) == pytest.approx(2.0, rel=1e-12)
    assert np.isnan(convergence_order(n, [1e-3, 0.0, 0.0, 0.0]))


@pytest.mark.parametrize("kwargs,exc,match", [
    ({"steps": (100,)}, ValueError, "steps"),
    ({"steps": (100, 50)}, ValueError, "steps"),
    ({"tolerances": {"rel_S": 1e-3}}, TypeError, "tolerances"),
])
def test_bad_crosscheck_input_raises(kwargs, exc, match):
    robot = Robot.paper()
    with pytest.raises(exc, match=match):
        crosscheck(Model(robot), paper_torque(robot), **kwargs)


def test_bad_tolerances_raise():
    with pytest.raises(ValueError, match="rel_S"):
        CrossCheckTolerances(rel_S=0.0)
    with pytest.raises(ValueError, match="event_lag_steps"):
        CrossCheckTolerances(event_lag_steps=(2.0, 1.0))
