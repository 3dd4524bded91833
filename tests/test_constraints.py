"""Bounds on cycle quantities (``[[ocp.constraint]]``): one definition read three ways, in the NLP,
on simulated gaits and in text.

The profile quantities are checked against closed forms and adaptive quadrature (not the code's own
formula), the baseline against the bound it must meet, and the optimum's torques against the bound
by their own maximum.
"""
import math
from dataclasses import replace

import casadi as cs
import numpy as np
import pytest
from scipy.integrate import quad

from ocp_crawl import Robot
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.sampled import PeriodicLinear
from ocp_crawl.ocp import UserObjective, optimize_gait
from ocp_crawl.ocp.judge import scenario_labels
from ocp_crawl.ocp.quantities import (QUANTITIES, Constraint, Cycle, mean_square_nodes,
                                      profile_of_signal, shortfall)
from ocp_crawl.ocp.search import best_harmonic
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.status import Status

from conftest import COARSE

ROBOT = Robot.paper()
#: a peak torque below the envelope's 0.351 N m (phi_ref = 60 deg): the bound is active
PEAK = 0.30


def test_mean_square_of_the_linear_interpolant_is_its_integral():
    """The exact mean of tau_1^2 + tau_2^2 of the node interpolant equals adaptive quadrature of the
    interpolant itself, and the NLP's CasADi expression equals the numbers' formula."""
    rng = np.random.default_rng(3)
    tau = rng.uniform(-0.4, 0.1, size=(2, 7))
    sig = PeriodicLinear(np.arange(7) / 7, tau)
    brk = list(np.arange(8) / 7)
    direct = sum(quad(lambda t, i=i: float(sig(t)[i]) ** 2, 0.0, 1.0, points=brk, limit=200,
                      epsabs=1e-14, epsrel=1e-13)[0] for i in range(2))
    assert mean_square_nodes(tau) == pytest.approx(direct, rel=1e-12)
    T = cs.SX.sym("T", 2, 7)
    f = cs.Function("f", [T], [mean_square_nodes(T)])
    assert float(f(tau)) == pytest.approx(mean_square_nodes(tau), rel=1e-14)


def test_profile_of_a_harmonic_member_is_its_closed_form():
    """tau_i = k (gamma_i + A_i sin(...) - pi): peak max_i k (pi - gamma_i + A_i), mean square
    k^2 sum_i ((gamma_i - pi)^2 + A_i^2 / 2)."""
    g, A = np.radians([95.0, 88.0]), np.radians([20.0, 25.0])
    sig = ReferenceTorque(Harmonic.from_degrees(30.0, gamma1_deg=95.0, gamma2_deg=88.0, A1_deg=20.0,
                                                A2_deg=25.0), ROBOT.k)
    peak, mean_sq = profile_of_signal(sig)
    assert peak == pytest.approx(ROBOT.k * float(np.max(np.pi - g + A)), rel=1e-6)
    assert mean_sq == pytest.approx(ROBOT.k**2 * float(np.sum((g - np.pi) ** 2 + A**2 / 2)),
                                    rel=1e-6)


def test_constraint_text_table_and_shortfall():
    """A constraint reads back from its table, says what it bounds in words and units, and its
    shortfall is the relative miss of the worst value (0 when met, a mean over scenarios when
    asked)."""
    c = Constraint.of({"quantity": "speed", "min": 0.04, "over": "mean"})
    assert Constraint.of(c.to_dict()) == c
    assert c.text() == "speed >= 0.04 m/s on the mean of the scenarios"
    cycle = Cycle((-0.02, -0.018), (0.1, 0.1), (10.0, 11.0), 0.5, -1, math.nan, math.nan)
    assert shortfall(c, cycle) == pytest.approx((0.04 - 0.038) / 0.04)
    every = Constraint("speed", min=0.04)
    assert shortfall(every, cycle) == pytest.approx((0.04 - 0.036) / 0.04)
    assert shortfall(Constraint("speed", max=0.1), cycle) == 0.0
    assert Constraint("peak_torque", max=PEAK).text() == "peak_torque <= 0.3 N m"
    for name, q in QUANTITIES.items():
        if "min" not in q.bounds:
            with pytest.raises(ValueError, match="not available"):
                Constraint(name, min=1.0)


def test_friction_levels_scale_both_feet_and_name_their_scenarios():
    """mu_levels: every ratio at every level, both coefficients times the level; labels tell them
    apart."""
    s = OCPSettings(mu_levels=(1.0, 0.5), mu_ratio_eps=0.1)
    robots = s.scenarios(ROBOT.replace(mu1=0.4, mu2=0.4))
    assert len(robots) == 6 and s.friction_set
    assert robots[4].mu1 == pytest.approx(0.5 * 0.4) and robots[4].mu2 == pytest.approx(0.5 * 0.4)
    assert robots[3].mu1 / robots[3].mu2 == pytest.approx(0.9)
    assert scenario_labels(s)[3:] == ["0.9_level_0.5", "1_level_0.5", "1.1_level_0.5"]
    assert scenario_labels(OCPSettings(mu_ratio_eps=0.1)) == ["0.9", "1", "1.1"]


def test_levels_keep_an_unequal_robots_own_coefficients():
    """Without a ratio set, a level scales the robot's own mu1 and mu2 (not their geometric
    mean)."""
    s = OCPSettings(mu_levels=(1.0, 0.5))
    robots = s.scenarios(ROBOT.replace(mu1=0.35, mu2=0.43))
    assert [(r.mu1, r.mu2) for r in robots] == [(0.35, 0.43), (0.175, 0.215)]
    assert scenario_labels(s) == ["own_level_1", "own_level_0.5"]


def test_a_gait_moving_backwards_misses_zero_bounds_and_cot_bounds():
    """speed >= 0 is missed by a backward gait relative to the quantity's size (not in m/s), and
    CoT+ of a backward scenario is +inf for a CoT+ bound."""
    from ocp_crawl.ocp.quantities import missed, reference_sizes

    s = OCPSettings()
    cycle = Cycle((0.004,), (0.1,), (10.0,), 1.0, -1, math.nan, math.nan)   # 4 mm/s the wrong way
    sizes = reference_sizes(ROBOT.M, ROBOT.g, ROBOT.L, s.period_ref())
    assert missed([Constraint("speed", min=0.0)], cycle, 5e-3, sizes)
    assert not missed([Constraint("speed", min=0.0)], cycle, 5e-3)   # in m/s: 4e-3 < 5e-3
    assert shortfall(Constraint("CoT_plus", max=50.0), cycle) == math.inf


def test_bounds_a_quantity_cannot_meet_are_refused():
    """A positive quantity's bound must be > 0; speed_min and a speed constraint both: give one."""
    for q in ("peak_torque", "W_plus", "CoT_plus", "period"):
        with pytest.raises(ValueError, match="must be > 0"):
            Constraint(q, max=-0.1)
    with pytest.raises(ValueError, match="give one"):
        OCPSettings(objective="min_cot", speed_min=0.04,
                    constraints=({"quantity": "speed", "min": 0.05},))


def test_a_period_bound_slows_the_baselines_members():
    """period >= 1.5 s: a member is evaluated at 1.5 s (S does not depend on T), not at its
    shortest."""
    from ocp_crawl.ocp.family import WaveFamily, WaveParams

    s = OCPSettings(direction=-1, constraints=({"quantity": "period", "min": 1.5},))
    member = WaveParams(90.0, 90.0, 25.0, 25.0, 30.0)
    ev = WaveFamily(ROBOT, "physical", s).evaluate(member)
    assert member.period(s) < 1.0 and ev.T == 1.5 and ev.success


def _search(settings):
    return best_harmonic(ROBOT, "physical", settings, local_starts=1, maxfev=60)


@pytest.mark.slow
def test_the_baseline_meets_a_peak_torque_bound_that_binds():
    """The best harmonic member under peak |tau| <= 0.3 N m meets it by its closed-form peak, and
    the unconstrained search's best breaks it (so the bound decides the baseline)."""
    base = dict(direction=-1, harmonic_A=2, harmonic_psi=8, baseline_samples=0)
    free = _search(OCPSettings(**base))
    held = _search(OCPSettings(**base, constraints=({"quantity": "peak_torque", "max": PEAK},)))

    def peak(c):
        return ROBOT.k * max(math.pi - math.radians(g - a) for g, a in
                             ((c.gamma1_deg, c.A1_deg), (c.gamma2_deg, c.A2_deg)))
    assert held.feasible and peak(held) <= PEAK * (1 + 1e-12)
    assert peak(free) > PEAK * 1.05 and free.value > held.value > 0


@pytest.mark.slow
def test_the_optimum_under_a_peak_torque_bound_meets_it_and_beats_its_baseline():
    """max_speed with peak |tau| <= 0.3 N m (N = 16): success, the optimum's largest node torque is
    the bound (active), the replay's requirement value is it, and the optimum beats the constrained
    harmonic baseline."""
    s = OCPSettings(nodes=16, starts=1, direction=-1, baselines="harmonic", baseline_samples=0,
                    harmonic_A=2, harmonic_psi=8,
                    constraints=({"quantity": "peak_torque", "max": PEAK},))
    res = optimize_gait(ROBOT, "physical", s, jobs=1)
    assert res.status == Status.SUCCESS, res.message
    assert float(np.max(np.abs(res.tau))) == pytest.approx(PEAK, rel=1e-6)
    assert float(np.max(np.abs(res.tau))) <= PEAK * (1 + 1e-9)
    (req,) = res.requirements
    assert req["replay"] == [pytest.approx(PEAK, rel=1e-6)] and req["constraint"]["max"] == PEAK
    assert res.value_replay > res.harmonic.value and res.harmonic.feasible


def _speed_nlp(q):
    return q.direction * q.S[0] / q.T


def _speed_value(cycle):
    return cycle.direction * cycle.S[0] / cycle.T


@pytest.mark.slow
def test_a_user_objective_that_restates_max_speed_finds_its_optimum(coarse_max_speed):
    """The hook with the mean speed direction S / T, scaled as the named objective scales it (L over
    the reference period), is the max_speed NLP: the same replayed optimum (N = 16), reported under
    the user's label and compared with the same baseline."""
    # a short search: both solves share its start and their baseline (not its quality) is compared
    named = coarse_max_speed
    assert named.settings.objective == "max_speed" and ROBOT == Robot.paper()
    scale = ROBOT.L / COARSE.period_ref()
    user = UserObjective("speed", _speed_nlp, _speed_value, sense="max", unit="m/s", scale=scale)
    mine = optimize_gait(ROBOT, "physical", replace(COARSE, user_objective=user), jobs=1)
    assert named.success and mine.success, (named.message, mine.message)
    assert mine.objective == "max:speed" and mine.settings.minimises is False
    assert mine.value_replay == pytest.approx(named.value_replay, rel=1e-7)
    assert mine.harmonic.value == pytest.approx(named.harmonic.value, rel=1e-12)
    assert mine.gains["harmonic"] == pytest.approx(named.gains["harmonic"], rel=1e-6)
