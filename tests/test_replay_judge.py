"""Replay is the judge: given an honest claim it agrees, given a tampered one it says so.

The claims are made independently of the judge: a triangle-wave profile whose envelope and bandwidth
margins are known in closed form, its "OCP" numbers computed by the other simulator (the MPCC
time-stepping, not the event-driven replay the judge runs).  The judge computes its own numbers from
the torques and the period alone, so a claim changed beyond replay_tol, a torque moved out of the
envelope or a period shortened beyond the bandwidth must be flagged.
"""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from ocp_crawl import Robot
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.sampled import PeriodicLinear
from ocp_crawl.model.statics import Model
from ocp_crawl.ocp import judge
from ocp_crawl.ocp.baseline import value_from
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.sim import simulate
from ocp_crawl.status import Status

N = 40
ROBOT = Robot.paper()
MODEL = Model(ROBOT, gravity="physical")


def triangle(settings):
    """Triangle waves between the envelope's torque bounds at N nodes (tau2 a quarter cycle behind
    tau1, tau1 largest at node 0) and the shortest period of the bandwidth in closed form: every
    step is
    |d tau| = 2 (hi - lo) / N = 4 k A_max / N, so the rate 4 k A_max / T equals k R at T = 4 A_max /
    R."""
    lo, hi = settings.torque_bounds(ROBOT)
    j = np.arange(N)
    tri = lambda i: lo + (hi - lo) * (1 - np.abs(((i % N) - N / 2) / (N / 2)))  # noqa: E731
    return np.vstack([tri(j + N // 2),
                      tri(j + N // 4)]), 4 * settings.A_max_deg / settings.max_rate_deg_s


@pytest.fixture(scope="module")
def claim():
    """The triangle gait's numbers by the MPCC time-stepping (the independent "OCP")."""
    tau, T = triangle(OCPSettings())
    res = simulate(MODEL, PeriodicLinear(np.arange(N) / N, tau), "mpcc")
    assert res.success, res.message
    return tau, T, res


def settings_for(res, **kw):
    return OCPSettings(direction=int(np.sign(res.S)), **kw)


@pytest.mark.slow
def test_honest_claim_is_confirmed_with_the_replays_own_numbers(claim):
    tau, T, ts = claim
    st = settings_for(ts)
    value = value_from(st, [ts.S], [ts.CoT_plus], T)
    v = judge.judge_replay([MODEL], st, tau, T, value, [ts.S])
    assert v.status == Status.SUCCESS, v.message
    # the judge's numbers are its own replay's: they agree with the other simulator, not by
    # construction
    assert v.S[0] == pytest.approx(ts.S, rel=1e-6) and v.S[0] != ts.S
    assert v.speed[0] == pytest.approx(abs(ts.S) / T, rel=1e-6)
    assert v.rel_diff <= 1e-6
    # the triangle touches the envelope and runs at the bandwidth (closed form)
    assert abs(v.envelope_excess) <= 1e-12 and v.rate_ratio == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("objective", ["max_speed", "min_cot"])
def test_claim_changed_beyond_replay_tol_is_a_mismatch(claim, objective):
    tau, T, ts = claim
    st = settings_for(ts, objective=objective)
    value = value_from(st, [ts.S], [ts.CoT_plus], T)
    ok = judge.judge_replay([MODEL], st, tau, T, value * (1 + 0.5 * st.replay_tol))
    assert ok.status == Status.SUCCESS, ok.message
    forged = value * (1 + 2 * st.replay_tol)
    v = judge.judge_replay([MODEL], st, tau, T, forged, [ts.S])
    assert v.status == Status.REPLAY_MISMATCH and not v.ok
    assert v.message.startswith(Status.REPLAY_MISMATCH.text)
    # both sets of numbers: the claimed value and the replayed one
    assert (judge.value_text(objective, forged) in v.message
            and judge.value_text(objective, v.value) in v.message)
    assert "objective differs by" in v.message
    assert "leave the envelope" not in v.message and "times the bandwidth" not in v.message


def test_torque_outside_the_envelope_is_a_mismatch(claim):
    tau, T, ts = claim
    st = settings_for(ts)
    T = 1.01 * T  # 1 % slower than the bandwidth allows: only the envelope is at stake
    value = value_from(st, [ts.S], [ts.CoT_plus], T)
    lo, hi = st.torque_bounds(ROBOT)
    bumped = tau.copy()
    # node 0 is tau1's peak: 1e-7 of the half-width outside
    bumped[0, 0] = hi + 1e-7 * (hi - lo) / 2
    v = judge.judge_replay([MODEL], st, bumped, T, value)
    assert v.status == Status.REPLAY_MISMATCH and "leave the envelope" in v.message, v.message
    assert v.envelope_excess == pytest.approx(1e-7, rel=1e-6) and v.rate_ratio < 1
    assert "times the bandwidth" not in v.message and "objective differs" not in v.message


@pytest.mark.parametrize("shrink, flagged", [(1e-7, True), (1e-11, False)])
def test_period_shorter_than_the_bandwidth_allows_is_a_mismatch(claim, shrink, flagged):
    """The bandwidth is checked to 1e-9 relative: 1e-7 too fast is flagged, 1e-11 (round-off) is
    not."""
    tau, T, ts = claim
    st = settings_for(ts)
    Tx = T * (1 - shrink)
    value = value_from(st, [ts.S], [ts.CoT_plus], Tx)
    v = judge.judge_replay([MODEL], st, tau, Tx, value)
    assert v.rate_ratio == pytest.approx(1 / (1 - shrink), rel=1e-12)
    assert (v.status == Status.REPLAY_MISMATCH) == flagged, v.message
    assert ("times the bandwidth" in v.message) == flagged


@pytest.mark.parametrize("change, flagged", [(-1e-7, True), (1e-7, False)])
def test_second_difference_beyond_max_accel_is_a_mismatch(claim, change, flagged):
    """With the optional max_accel_deg_s2 = a: the triangle's second difference, 2 |d tau| = 16 k
    A_max / N at its peaks (zero elsewhere), against k a (T/N)^2 at T = 4 A_max / R: met exactly by
    a* = N R^2 / (2 A_max)."""
    tau, T, ts = claim
    st0 = OCPSettings()
    a_star = N * st0.max_rate_deg_s ** 2 / (2 * st0.A_max_deg)
    st = settings_for(ts, max_accel_deg_s2=a_star * (1 + change))
    value = value_from(st, [ts.S], [ts.CoT_plus], T)
    v = judge.judge_replay([MODEL], st, tau, T, value)
    assert v.accel_ratio == pytest.approx(1 / (1 + change), rel=1e-12)
    assert (v.status == Status.REPLAY_MISMATCH) == flagged, v.message
    assert ("max_accel_deg_s2" in v.message) == flagged
    assert math.isnan(judge.judge_replay([MODEL], settings_for(ts), tau, T, value).accel_ratio)


@pytest.mark.parametrize("factor, flagged", [(1 + 2 * 5e-3, True), (1 + 0.5 * 5e-3, False)])
def test_speed_requirement_missed_by_the_replay_is_a_mismatch(claim, factor, flagged):
    tau, T, ts = claim
    v_true = abs(ts.S) / T  # the independent simulator's mean speed [m/s]
    st = settings_for(ts, objective="min_cot", speed_min=v_true * factor, replay_tol=5e-3)
    value = value_from(st, [ts.S], [ts.CoT_plus], T)
    v = judge.judge_replay([MODEL], st, tau, T, value)
    assert (v.status == Status.REPLAY_MISMATCH) == flagged, v.message
    assert ("misses speed >=" in v.message) == flagged


@pytest.mark.parametrize("factor, flagged", [(1 - 2 * 5e-3, True), (1 - 0.5 * 5e-3, False)])
def test_a_bound_on_a_cycle_quantity_missed_by_the_replay_is_a_mismatch(claim, factor, flagged):
    """peak |tau| <= b: the triangle's peak is its envelope's edge, |lo|; a bound below it by more
    than replay_tol is flagged, within it is not."""
    tau, T, ts = claim
    peak = float(np.max(np.abs(tau)))
    st = settings_for(ts, constraints=({"quantity": "peak_torque", "max": peak * factor},))
    v = judge.judge_replay([MODEL], st, tau, T, value_from(st, [ts.S], [ts.CoT_plus], T))
    assert (v.status == Status.REPLAY_MISMATCH) == flagged, v.message
    assert ("misses peak_torque <=" in v.message) == flagged


def test_failed_replay_is_replay_failed(claim):
    """A profile the robot cannot follow (joint 2 driven far outside the envelope, until it reaches
    the ground) is not judged on its numbers: REPLAY_FAILED with the simulator's reason."""
    tau, T, ts = claim
    st = settings_for(ts)
    wild = tau.copy()
    wild[1] = -3.0 * tau[1]
    v = judge.judge_replay([MODEL], st, wild, T * 100, 0.01)
    assert v.status == Status.REPLAY_FAILED, v.message
    assert (v.message.startswith(Status.REPLAY_FAILED.text)
            and "a joint reaches the ground" in v.message)
    assert math.isnan(v.value) and v.S == []


@pytest.mark.parametrize("objective, value, base, gain", [
    ("max_speed", 0.012, 0.010, 0.2), ("min_cot", 12.0, 15.0, 0.2), ("min_cot", 15.0, 12.0, -0.25),
    ("robust_speed", 0.010, 0.010, 0.0), ("max_speed", 0.01, 0.0, math.nan)])
def test_gain_over_the_baseline(objective, value, base, gain):
    got = judge.gain_over(objective, value, base)
    assert (math.isnan(got) and math.isnan(gain)) or got == pytest.approx(gain, rel=1e-12)
    if math.isfinite(gain) and gain != 0:
        assert judge.is_better(objective, value, base) == (gain > 0)


@pytest.mark.slow
def test_the_transcription_on_a_fixed_profile_is_confirmed_and_a_forged_result_is_not():
    """The real path: the transcription with its torques and period fixed to a harmonic gait's (it
    then only simulates the profile, by its own sub-steps) is judged by the event-driven replay:
    confirmed; the same result with its objective or its period forged beyond the tolerances is not,
    nor one worse than a given harmonic baseline beyond replay_tol (WORSE_THAN_BASELINE)."""
    import dataclasses

    from ocp_crawl.ocp import solve
    from ocp_crawl.ocp.solver import GaitSolver
    from ocp_crawl.ocp.transcription import GaitOCP

    st = OCPSettings(nodes=N, starts=1)
    # tau1 peaks at t = 1/8: node N/8 (the phase pin: node 0)
    gait = Harmonic.from_degrees(90.0, 30.0, 90.0)
    tt = np.arange(N) / N
    start = PeriodicLinear(tt, ReferenceTorque(gait, ROBOT.k)(tt + 0.125))
    T = st.min_period(30.0, 30.0)
    ocp = GaitOCP(ROBOT, "physical", st)
    solver = GaitSolver(ocp)
    x, hist, failed, status = solver.solve(ocp.initial_guess(start, T), fix_profile=True)
    res = solve.OCPResult(success=False, status=Status.SOLVER_FAILURE, message="",
                          objective=st.objective, settings=st)
    assert solve._accept(res, solver, x, failed, status), res.message
    assert res.T_ocp == pytest.approx(T, rel=1e-12)
    honest = dataclasses.replace(res)
    solve._judge(honest, [MODEL])
    assert honest.status == Status.SUCCESS and honest.rel_diff_replay <= 1e-6, honest.message
    assert honest.S_replay[0] == pytest.approx(res.S_ocp[0], rel=1e-6)
    forged = dataclasses.replace(res, value_ocp=res.value_ocp * (1 + 2 * st.replay_tol))
    solve._judge(forged, [MODEL])
    assert (forged.status == Status.REPLAY_MISMATCH and not forged.success
            and "objective differs" in forged.message)
    # the same strokes 10 % faster: beyond the bandwidth
    faster = dataclasses.replace(res, T_ocp=0.9 * res.T_ocp)
    solve._judge(faster, [MODEL])
    assert faster.status == Status.REPLAY_MISMATCH and "times the bandwidth" in faster.message
    # a confirmed profile against a harmonic baseline better than it beyond replay_tol is not an
    # optimum; within the tolerance (either side) it stands
    value, tol = honest.value_replay, st.replay_tol
    for excess, status in ((2.0, Status.WORSE_THAN_BASELINE), (0.5, Status.SUCCESS),
                           (-0.5, Status.SUCCESS)):
        base = value + excess * tol * abs(value)
        judged = dataclasses.replace(res, harmonic=SimpleNamespace(value=base))
        solve._judge(judged, [MODEL])
        assert (judged.status == status
                and judged.success == (status == Status.SUCCESS)), judged.message
        assert judged.gain == pytest.approx((value - base) / abs(base), rel=1e-9)
