"""Events are located to 1e-13 of a cycle: the stepper's safeguarded Newton on the guard against an
independent root finder (scipy's Brent method, xtol 1e-15) on the same guard of the solved
branch."""
import numpy as np
import pytest
from scipy.optimize import brentq

from ocp_crawl import Harmonic, Model, ReferenceTorque, Robot
from ocp_crawl.sim.event import HybridStepper
from ocp_crawl.sim.result import Mode

CASES = [("paper", 90, 30, 45, 2.74), ("physical", 90, 30, 45, 2.74), ("paper", 80, 40, -60, 0.6),
         ("physical", 100, 20, 120, 5.0), ("paper", 90, 30, 45, 1e4)]


@pytest.mark.parametrize("gravity, gamma, amp, psi, ratio", CASES)
def test_event_phases_match_an_independent_brent_root(gravity, gamma, amp, psi, ratio):
    robot = Robot.paper().with_stiffness_ratio(ratio)
    stepper = HybridStepper(Model(robot, gravity=gravity),
                            ReferenceTorque(Harmonic.from_degrees(gamma, amp, psi), robot.k))
    res = stepper.run()
    assert res.success, res.message
    labels = {m.label: m for m in Mode}
    worst = 0.0
    for ev in res.events:
        before = labels[ev.mode_before]
        seg = [s for s in stepper.segments
               if s.mode == before and s.points[0].t <= ev.t <= s.points[-1].t + 1e-12]
        assert seg, ev
        seg = seg[-1]
        p = min(seg.points, key=lambda pt: abs(pt.t - ev.t))

        def guard(t):
            pt = stepper.solver.solve(t, p.x, seg.q)
            return stepper.guards.values(before, pt.aux)[ev.guard_name]

        lo, hi = ev.t - 1e-9, ev.t + 1e-9
        assert guard(lo) > 0 > guard(hi), ev
        t_ref = brentq(guard, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)
        worst = max(worst, abs(t_ref - ev.t))
    # measured: <= 4e-15 at k/(M g L) <= 5, 3e-14 at 1e4 (the guards' round-off grows with k/(M g
    # L)); with event_xtol = 1e-8 the same check reads 7e-12 to 6e-10
    assert worst <= 1e-13, worst


def test_the_steppers_scalar_torque_is_the_signals_own():
    """sim/event_state.torque_pair re-states the harmonic torque k (phi_ref - pi) in scalar
    arithmetic for speed: it must give the signal's own value and rate bit for bit, and its
    curvature the same as the generic path."""
    import numpy as np

    from ocp_crawl import Harmonic, ReferenceTorque
    from ocp_crawl.sim.event_state import torque_curvature, torque_pair

    signal = ReferenceTorque(Harmonic.from_degrees(87.0, 31.0, 52.0, gamma2_deg=93.0, A2_deg=24.0),
                             0.1677)
    fast = torque_pair(signal)
    assert hasattr(fast, "rate")  # the specialised path is the one under test
    generic = lambda t: (signal(t), signal.derivative(t))  # noqa: E731
    for t in np.random.default_rng(7).uniform(-2.0, 3.0, 2000):
        t = float(t)
        (a, da), (b, db) = fast(t), generic(t)
        assert a.tolist() == b.tolist() and da.tolist() == db.tolist()
        assert torque_curvature(fast, t) == torque_curvature(generic, t)
