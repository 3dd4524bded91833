"""A :class:`CrawlResult` is frozen: every simulator builds it once, and assigning to one of its
attributes raises; a physical check or an error estimate gives a derived result
(``dataclasses.replace``) and leaves the one it started from as it is."""
import dataclasses

import numpy as np
import pytest

from ocp_crawl import MujocoOptions, Model, simulate, simulate_torque
from ocp_crawl.problem import paper_problem
from ocp_crawl.sim.angles import simulate_angles
from ocp_crawl.sim.assemble import balance_metrics, demote, energy_gate, new_result
from ocp_crawl.sim.discretisation import error_gate
from ocp_crawl.sim.result import CrawlResult
from ocp_crawl.sim.timestepping import TimeSteppingOptions, simulate_mpcc
from ocp_crawl.status import Status

FIELDS = [f.name for f in dataclasses.fields(CrawlResult)]


def _assert_frozen(res: CrawlResult) -> None:
    """Every field refuses assignment and deletion; the values stay."""
    before = res.summary()
    for name in FIELDS:
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(res, name, getattr(res, name))
        with pytest.raises(dataclasses.FrozenInstanceError):
            delattr(res, name)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.not_a_field = 1  # type: ignore[attr-defined]
    assert res.summary() == before


def test_event_result_is_frozen():
    pr = paper_problem()
    res = simulate_torque(pr.model, pr.torque)
    assert res.success, res.message
    _assert_frozen(res)


def test_a_result_is_hashable_and_equal_only_to_itself():
    """Identity equality and hash: a result can key a dict or a cache, and comparing it with a copy
    neither raises (its arrays have no truth value) nor claims equal arrays equal."""
    pr = paper_problem()
    res = simulate_torque(pr.model, pr.torque)
    copy = dataclasses.replace(res)
    assert {res: 1, copy: 2}[res] == 1 and hash(res) != hash(copy)
    assert res == res and res != copy and copy.S == res.S


def test_mpcc_result_is_frozen():
    """One cycle of 12 MPCC steps, without the check run of S's error."""
    pr = paper_problem()
    res = simulate_mpcc(pr.model, pr.torque, steps=12, cycles=1,
                        options=TimeSteppingOptions(s_error_tol=0.0))
    assert res.success, res.message
    _assert_frozen(res)


@pytest.mark.slow
def test_mpcc_result_with_its_error_estimate_is_frozen():
    """One cycle of 12 MPCC steps and the check run of S's error (a derived result)."""
    pr = paper_problem()
    res = simulate_mpcc(pr.model, pr.torque, steps=12, cycles=1)
    assert res.success, res.message
    assert np.isfinite(res.S_error) and "S_error_bound" in res.extra
    _assert_frozen(res)


def test_mpcc_gated_results_are_frozen():
    """The ENERGY_IMBALANCE failure of the energy gate (no check run of S's error)."""
    pr = paper_problem()
    res = simulate_mpcc(pr.model, pr.torque, steps=12, cycles=1,
                        options=TimeSteppingOptions(energy_tol_n2=1e-12, s_error_tol=0.0))
    assert res.status == Status.ENERGY_IMBALANCE, res.message
    _assert_frozen(res)


def test_angles_result_is_frozen():
    pr = paper_problem(["gait.drive=angles"])
    res = simulate_angles(pr.model, pr.signal)
    assert res.success, res.message
    _assert_frozen(res)


def test_mujoco_result_is_frozen():
    pytest.importorskip("mujoco")
    pr = paper_problem()
    res = simulate(pr.model, pr.torque, "mujoco", MujocoOptions(period=2.0))
    assert res.cycles >= 1 and res.t.size, res.message
    _assert_frozen(res)


def test_a_gate_returns_a_derived_result():
    """energy_gate on a constructed result: a failing balance gives a new ENERGY_IMBALANCE result
    (S, W+, CoT+ NaN; energy kept), the original untouched; a closing balance gives the result
    itself."""
    m = Model(paper_problem().robot)
    for residual, ok in ((1e-3, False), (1e-8, True)):
        # input work 1 J, potential change 0, dissipation 1 - residual: the balance misses
        # `residual`
        res = new_result(m, "torque", Status.SUCCESS,
                         **balance_metrics(m.robot, -0.05, np.array([0.5, 0.5]), 1.0, 0.0,
                                           1.0 - residual, 1.0))
        gated = energy_gate(res, 1e-6, "tol")
        assert res.success and res.S == -0.05
        assert gated.energy["balance_residual"] == pytest.approx(residual)
        if ok:
            assert gated is res
            continue
        assert gated.status == Status.ENERGY_IMBALANCE and not gated.success
        assert np.isnan(gated.S) and np.isnan(gated.CoT_plus) and gated.energy == res.energy
        assert gated.failure_mode == "steady cycle" and "tol" in gated.message
        _assert_frozen(gated)


def test_demote_and_error_gate_leave_their_input():
    m = Model(paper_problem().robot)
    res = new_result(m, "torque", Status.SUCCESS, "found", S=-0.05, extra={"a": 1})
    bad = demote(res, Status.UNSTABLE, "margin", 0.5, "stick-stick")
    assert (bad.status, bad.failure_t, bad.failure_mode) == (Status.UNSTABLE, 0.5, "stick-stick")
    assert res.success and res.message == "found" and res.S == -0.05
    check = {"S_check": -0.04, "steps": 8, "steps_check": 17, "check_failure": ""}
    coarse = error_gate(res, check, m.robot.L, 1e-3)
    assert coarse.status == Status.COARSE_STEPS and coarse.S_error == pytest.approx(0.01)
    bound = 1e-3 * (0.05 + 1e-3 * m.robot.L)
    assert coarse.extra == {"a": 1, "S_error_bound": pytest.approx(bound), "S_coarse": -0.05}
    assert res.extra == {"a": 1} and np.isnan(res.S_error)
    assert error_gate(res, None, m.robot.L, 1e-3) is res
    # a check run that ends at a lost contact ends the run there (not a matter of the steps' size)
    lost = {**check, "S_check": float("nan"), "check_failure": "lift_off at phase 0.250000 (f)",
            "check_status": "lift_off", "check_t": 0.25, "check_mode": "slip1+"}
    ended = error_gate(dataclasses.replace(res, t0=2.0), lost, m.robot.L, 1e-3)
    assert (ended.status, ended.failure_t, ended.failure_mode) == (Status.LIFT_OFF, 2.25, "slip1+")
    assert "found by the check run at 17 steps per cycle: lift_off at phase 0.25" in ended.message
