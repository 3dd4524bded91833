"""Numerical robustness of the event-driven stepper: grazing events, events closer
together than the step, many events per cycle (fast chattering inputs), the event cap."""
import numpy as np
import pytest

from ocp_crawl import (FourierSeries, Harmonic, HybridOptions, Model, ReferenceTorque, Robot,
                       Status, simulate_torque)
from ocp_crawl.sim.event import HybridStepper
from ocp_crawl.sim.event_kinks import input_step
from ocp_crawl.sim.event_guards import cubic_min

from conftest import paper_torque

REFINED = dict(max_step=1 / 2048)


def chattering(robot, n, amp):
    """The paper's gait with a fast ripple: harmonic n (per cycle) of amplitude amp [rad] in the
    reference."""
    base = Harmonic.from_degrees(90, 30, 45)
    t = np.arange(4 * n + 8) / (4 * n + 8)
    ripple = amp * np.vstack([np.sin(2 * np.pi * n * t), np.cos(2 * np.pi * n * t)])
    return ReferenceTorque(FourierSeries.fit(base(t) + ripple, order=n), robot.k)


def same_events(a, b, tol=1e-8):
    assert [e.kind for e in a] == [e.kind for e in b]
    assert [e.mode_after for e in a] == [e.mode_after for e in b]
    assert np.max(np.abs(np.array([e.t for e in a]) - np.array([e.t for e in b])),
                  initial=0.0) <= tol


def check_coulomb(res, robot, tol=1e-9):
    Mg = robot.M * robot.g
    lim = np.minimum(robot.mu1 * res.f_n1, robot.mu2 * res.f_n2)
    assert np.max(np.abs(res.f_t) - lim) <= tol * Mg


@pytest.mark.slow
def test_chattering_input_loses_no_event():
    """A ripple of 40 periods per cycle makes tens of events per cycle, some pairs closer together
    than the step: the default run finds the same events as a much finer one."""
    robot = Robot.paper()
    torque = chattering(robot, 40, 0.01)
    t_eval = np.linspace(0, 1, 2001)
    res = simulate_torque(Model(robot), torque, t_eval=t_eval)
    ref = simulate_torque(Model(robot), torque, HybridOptions(**REFINED, max_events_per_cycle=1000),
                          t_eval=t_eval)
    assert res.success and ref.success, (res.message, ref.message)
    assert len(res.steady_events()) >= 20
    same_events(res.steady_events(), ref.steady_events())
    assert res.S == pytest.approx(ref.S, rel=1e-9)
    assert res.W_plus == pytest.approx(ref.W_plus, rel=1e-7)
    check_coulomb(res, robot)  # on a grid 16x finer than the step: no slip hidden inside a step
    assert abs(res.energy["balance_residual"]) < 1e-8


def test_input_step_resolves_the_fastest_harmonic():
    robot = Robot.paper()
    assert input_step(paper_torque(robot)) == 0.125  # one harmonic: the default step (1/16) stays
    assert input_step(chattering(robot, 80, 0.01)) == pytest.approx(1 / 640)
    # a ripple far below the significance threshold does not shrink the step
    assert input_step(chattering(robot, 80, 1e-8)) == 0.125


def test_events_closer_than_the_step_are_located_inside_it():
    """The paper's robot at k = 1.3 M g L with an amplitude just above its slip threshold: the slip
    onset and the return to stick are much closer together than one step (1/16 cycle).  The
    threshold is found with an 8x finer step; the default run must find the same short slips
    (the guard is positive at both ends of the step that holds them)."""
    robot = Robot.paper().with_stiffness_ratio(1.3)
    model = Model(robot)
    fine = HybridOptions(max_step=1 / 512)

    def run(A, options=None):
        res = simulate_torque(model, ReferenceTorque(Harmonic.from_degrees(90, A, 45), robot.k),
                              options)
        assert res.success, res.message
        return res, [e for e in res.steady_events() if not e.kind.startswith("graze")]

    lo, hi = 2.0, 5.0
    assert not run(lo, fine)[1] and run(hi, fine)[1]
    for _ in range(20):  # bisection on "slips" with the fine step
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if not run(mid, fine)[1] else (lo, mid)
    ref, ref_ev = run(hi, fine)
    res, ev = run(hi)
    assert ev, "the event pair just above the threshold was lost"
    gaps = np.diff([e.t for e in ev])
    assert np.min(gaps) < 0.1 * HybridOptions().max_step  # much closer than one step
    same_events(ev, ref_ev)
    assert res.S == pytest.approx(ref.S, rel=1e-8, abs=1e-15)


def test_grazing_guard_keeps_the_mode_and_the_answer_is_continuous():
    """Just below the slip threshold a friction guard touches zero without crossing: the run stays
    in stick-stick (S = 0, possibly recording a graze); just above, S is small and continuous."""
    robot = Robot.paper().with_stiffness_ratio(1.3)
    model = Model(robot)

    def run(A):
        return simulate_torque(model, ReferenceTorque(Harmonic.from_degrees(90, A, 45), robot.k))

    lo, hi = 2.0, 5.0
    for _ in range(30):  # bisection on "slips"
        mid = 0.5 * (lo + hi)
        res = run(mid)
        assert res.success, res.message
        if any(not e.kind.startswith("graze") for e in res.steady_events()):
            hi = mid
        else:
            lo = mid
    below, above = run(lo), run(hi)
    assert below.success and above.success
    assert all(e.kind.startswith("graze") for e in below.steady_events())
    assert abs(below.S) <= 1e-12 * robot.L
    assert abs(above.S) <= 1e-6 * robot.L  # continuity in A across the threshold
    for ev in below.steady_events():
        assert ev.mode_before == ev.mode_after == "stick-stick" and abs(ev.guard) < 1e-9


def test_event_cap_ends_the_run_with_a_clear_status():
    robot = Robot.paper()
    res = simulate_torque(Model(robot), chattering(robot, 80, 0.01),
                          HybridOptions(max_events_per_cycle=10))
    assert res.status == Status.TOO_MANY_EVENTS and not res.success
    assert "more than 10 events in cycle 1" in res.message
    assert len(res.events) == 11 and np.isnan(res.S)


@pytest.mark.parametrize("bad", [0, -1, 2.5, True])
def test_event_cap_is_validated(bad):
    with pytest.raises(ValueError, match="max_events_per_cycle"):
        HybridOptions(max_events_per_cycle=bad)


def test_stepper_terminates_on_an_input_faster_than_it_can_follow():
    """A ripple at 500 periods per cycle with the step limit switched off and a small event cap:
    the run ends (with success or a documented status), it does not loop."""
    robot = Robot.paper()
    stepper = HybridStepper(Model(robot), chattering(robot, 500, 0.005),
                            HybridOptions(resolve_input=False, max_events_per_cycle=50))
    res = stepper.run()
    assert res.status in {Status.SUCCESS, Status.TOO_MANY_EVENTS, Status.NO_CONSISTENT_MODE}
    assert res.message


@pytest.mark.parametrize("g0, g1, m0, m1, dips", [
    (1.0, 1.0, -6.0, 6.0, True),     # a symmetric dip below zero (minimum 1 - 6/4)
    (1.0, 1.0, -1.0, 1.0, False),    # dips, but stays positive
    (1.0, 2.0, 1.0, 1.0, False),     # monotone
    (0.1, 0.1, -0.5, 0.5, True),
])
def test_cubic_minimum(g0, g1, m0, m1, dips):
    s, v = cubic_min(g0, g1, m0, m1)
    grid = np.linspace(0, 1, 100001)
    a, b = 2 * (g0 - g1) + m0 + m1, 3 * (g1 - g0) - 2 * m0 - m1
    values = ((a * grid + b) * grid + m0) * grid + g0
    assert (np.min(values) < 0) == dips
    if np.isfinite(s):
        assert v == pytest.approx(np.min(values), abs=1e-9)
