"""The search for a contact lost between the incremental steps' ends
(:mod:`ocp_crawl.sim.step_dips`) on guards given in closed form: their zeros are known exactly."""
import numpy as np
import pytest

from ocp_crawl.sim.step_dips import dip_report, first_zero, step_probes
from ocp_crawl.status import Status

#: the contact guards of a robot with no joints (m = 0) and their rates, closed forms of the phase
HEALTHY = {"fn1": (lambda t: 1.0 + 0 * t, lambda t: 0 * t),
           "fn2": (lambda t: 1.0 + 0 * t, lambda t: 0 * t),
           "d": (lambda t: 1.0 + 0 * t, lambda t: 0 * t)}
RATE = {"fn1": "dfn1", "fn2": "dfn2", "d": "ddot"}


def _search(guards: dict, span=(0.0, 1.0)):
    """first_zero on one step ``span`` with the guards ``guards`` (name -> (g, g'))."""
    ends = {}
    for name, (g, dg) in {**HEALTHY, **guards}.items():
        ends[name] = np.array([g(span[0]), g(span[1])])
        ends[RATE[name]] = np.array([dg(span[0]), dg(span[1])])
    funcs = {name: g for name, (g, _) in {**HEALTHY, **guards}.items()}
    return first_zero([span], ends, 0, lambda k, name: funcs[name])


def test_a_dip_between_positive_ends_is_found_at_its_first_zero():
    zero = _search({"d": (lambda t: (t - 0.5) ** 2 - 1e-4, lambda t: 2 * (t - 0.5))})
    assert zero is not None and zero[2] == "d"
    assert zero[0] == pytest.approx(0.49, abs=1e-10)
    t0, status, k, message = dip_report(zero, [(0.0, 1.0)], 0, 2.0, 0.5)
    assert status is Status.FEET_CROSSED and k == 0 and "the feet's distance" in message


def test_a_guard_that_stays_positive_is_no_zero():
    assert _search({"d": (lambda t: (t - 0.5) ** 2 + 1e-4, lambda t: 2 * (t - 0.5))}) is None


def test_of_two_guards_in_one_step_the_earlier_zero_ends_the_run():
    """foot 1's force crosses at 0.3 and stays below (listed at the step's end); the distance dips
    over 0.7 to 0.9 (listed at its cubic's minimum, before the step's end)."""
    zero = _search({"fn1": (lambda t: 0.3 - t, lambda t: -1.0 + 0 * t),
                    "d": (lambda t: (t - 0.8) ** 2 - 0.01, lambda t: 2 * (t - 0.8))})
    assert zero[2] == "fn1" and zero[0] == pytest.approx(0.3, abs=1e-10)


def test_a_failed_solve_inside_the_step_is_no_zero():
    def g(t):
        return np.nan if 0.2 < t < 0.8 else (t - 0.5) ** 2 - 1e-4
    ends = {name: np.array([1.0, 1.0]) for name in ("fn1", "fn2")}
    ends.update({RATE[n]: np.zeros(2) for n in ("fn1", "fn2")})
    ends["d"], ends["ddot"] = np.array([g(0.0), g(1.0)]), np.array([-1.0, 1.0])
    funcs = {"fn1": lambda t: 1.0, "fn2": lambda t: 1.0, "d": g}
    assert first_zero([(0.0, 1.0)], ends, 0, lambda k, name: funcs[name]) is None


def test_a_step_whose_mode_does_not_reach_its_end_is_not_looked_into():
    """The mode's solution at the step's end differs from the step's end (another branch or a
    mode change the step did not locate): its probe is nan everywhere."""
    def solve(k, t):
        return np.array([t, 0.0]), {"d": (t - 0.5) ** 2 - 1e-4}
    ends_phi = [np.array([1.0, 0.0]), np.array([1.0, 0.5])]
    probe = step_probes(solve, ends_phi, [(0.0, 1.0), (0.0, 1.0)])
    assert probe(0, "d")(0.5) == pytest.approx(-1e-4)
    assert np.isnan(probe(1, "d")(0.5))
