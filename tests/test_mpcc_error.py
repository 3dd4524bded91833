"""The MPCC time-stepping's estimate of the discretisation error of S (sim/discretisation.py).

A successful run re-runs its steady cycle with 2 N + 1 steps; |S_N - S_2N+1| is ``S_error`` [m], and
above ``s_error_tol (|S| + 1e-3 L)`` the run is ``coarse_steps``. Checked here: a soft robot driven
by linear pulses whose S at N = 50 is 2.4 % off the event-driven S (found by a seeded random search
over soft robots, unequal friction and linear pulses at N = 50) is flagged with a message naming the
estimate and the steps to try; the paper gait at N = 50 stays a success with a small estimate; and
on random robots and inputs every success at N = 50..100 is within its own bound of the event-driven
S.

The property test is a fuzz run, by hand
(``OCP_CRAWL_HEAVY=1 python -m pytest -q -m heavy tests/test_mpcc_error.py``; its example count is
ten times ``OCP_CRAWL_HYPOTHESIS_EXAMPLES``, 100 without it).
"""
import math
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, note, settings
from hypothesis import strategies as st

from ocp_crawl import Harmonic, Model, ReferenceTorque, Robot, Status, simulate
from ocp_crawl.model.pulse import Pulse
from ocp_crawl.problem import load_problem, run_problem
from ocp_crawl.sim.discretisation import error_bound
from ocp_crawl.sim.timestepping import TimeSteppingOptions

REPO = Path(__file__).resolve().parents[1]

#: the soft robot (k = 0.70 M g L, mu1 != mu2) and linear pulse input of the search (seed 1, draw
#: 16)
SOFT = Robot(M=0.02075439451995801, L=0.44771255477828364, beta=0.6892316690517694,
             k=0.06375305597671202, mu1=0.20962118112455327, mu2=0.18453364880901799, g=9.81)
PULSE = Pulse(gamma1=1.5761910957427558, gamma2=1.5371503517637386, A1=0.14579345021629847,
              A2=0.10733215550996626, psi=-2.0430685706986047, rise=0.1004010062567402,
              hold=0.5733220397838336, ramp="linear")
#: the event-driven S of that case [m]
S_EVENT_SOFT = 0.009843120573007735


@pytest.mark.slow
def test_coarse_steps_on_a_soft_robot_with_linear_pulses():
    """N = 50 misses a slip-to-stick after the end of a hold (S 2.4 % off the event-driven S): the
    estimate sees it, and the message names the estimate and a steps value."""
    signal = ReferenceTorque(PULSE, SOFT.k)
    res = simulate(Model(SOFT), signal, "mpcc", TimeSteppingOptions(steps=50))
    assert res.status == Status.COARSE_STEPS and not res.success
    assert math.isnan(res.S)
    S_coarse = res.extra["S_coarse"]
    assert abs(S_coarse / S_EVENT_SOFT - 1) > 0.01  # the error the estimate is about
    assert res.S_error > error_bound(S_coarse, SOFT.L, 1e-3)
    # the right size, not only above the bound
    assert res.S_error > 0.3 * abs(S_coarse - S_EVENT_SOFT)
    assert "S error estimate" in res.message and "use steps >= 200" in res.message
    assert res.extra["steps_check"] == 101 and res.summary()["S_error"] == res.S_error


@pytest.mark.slow
def test_paper_gait_at_50_steps_is_a_success_with_a_small_estimate():
    problem = load_problem(REPO / "problems" / "paper_gait.toml").with_values(
        {"simulation.solver": "mpcc", "simulation.steps": 50})
    res = run_problem(problem)
    assert res.status == Status.SUCCESS, res.message
    bound = res.extra["S_error_bound"]
    assert bound == pytest.approx(1e-3 * (abs(res.S) + 1e-3 * problem.robot.L))
    assert 0 <= res.S_error < 1e-3 * bound


def test_zero_tolerance_skips_the_estimate():
    problem = load_problem(REPO / "problems" / "paper_gait.toml").with_values(
        {"simulation.solver": "mpcc", "simulation.steps": 20, "simulation.s_error_tol": 0.0})
    res = run_problem(problem)
    assert res.success and math.isnan(res.S_error) and "steps_check" not in res.extra


def log_uniform(lo, hi):
    return st.floats(math.log(lo), math.log(hi)).map(math.exp)


@st.composite
def cases(draw):
    """A robot (stiffness 0.3-20 M g L, mu1 != mu2) and a torque input: a harmonic reference or a
    linear or cosine pulse, at N = 50..100 steps."""
    mu1 = draw(log_uniform(0.2, 0.8))
    ratio = draw(log_uniform(1.05, 1.6)) ** draw(st.sampled_from([-1, 1]))
    robot = Robot(M=draw(log_uniform(0.01, 1.0)), L=draw(log_uniform(0.05, 0.5)),
                  beta=draw(log_uniform(0.5, 4.0)), k=1.0, mu1=mu1, mu2=mu1 * ratio,
                  g=9.81).with_stiffness_ratio(draw(log_uniform(0.3, 20.0)))
    gamma = math.radians(draw(st.floats(75.0, 105.0)))
    gamma2 = gamma + math.radians(draw(st.floats(-5.0, 5.0)))
    A1, A2 = (math.radians(draw(st.floats(5.0, 30.0))) for _ in range(2))
    psi = math.radians(draw(st.floats(-180.0, 180.0)))
    kind = draw(st.sampled_from(["harmonic", "linear", "cosine"]))
    if kind == "harmonic":
        gait = Harmonic(gamma, gamma2, A1, A2, psi)
    else:
        rise = draw(st.floats(0.05, 0.4))
        hold = draw(st.floats(0.0, 1.0)) * (1 - 2 * rise)
        gait = Pulse(gamma, gamma2, A1, A2, psi, rise, hold, kind)
    return robot, gait, draw(st.integers(50, 100))


def check_success_within_its_bound(case):
    robot, gait, steps = case
    note(f"{robot!r}, {gait!r}, steps = {steps}")
    model, signal = Model(robot), ReferenceTorque(gait, robot.k)
    ev = simulate(model, signal)
    if not ev.success:
        event(f"event: {ev.status_name}")
        return
    res = simulate(model, signal, "mpcc", TimeSteppingOptions(steps=steps))
    event(f"mpcc: {res.status_name}")
    if not res.success:
        return
    bound = res.extra["S_error_bound"]
    note(f"S_event {ev.S!r}, S_mpcc {res.S!r}, estimate {res.S_error!r}, bound {bound!r}")
    assert res.S_error <= bound
    assert abs(res.S - ev.S) <= bound


EXAMPLES = int(os.environ.get("OCP_CRAWL_HYPOTHESIS_EXAMPLES", "10"))
HEAVY = settings(max_examples=10 * EXAMPLES, deadline=None, database=None,
                 derandomize="OCP_CRAWL_HYPOTHESIS_EXAMPLES" not in os.environ,
                 suppress_health_check=[HealthCheck.too_slow])


@pytest.mark.heavy
@HEAVY
@given(cases())
def test_mpcc_successes_are_within_their_error_bound_heavy(case):
    check_success_within_its_bound(case)
