"""The waveform families' baselines (ocp/family.py, ocp/search.py) against gaits simulated here
directly.

The triangle waves of the independent grids are built here as piecewise-linear samples
(:class:`~ocp_crawl.model.inputs.PeriodicLinear`), not with the family's pulses, and the speeds are
written out here (v = direction * S / T, T = 4 max(A1, A2) / R for a triangle wave, 2 pi max(A1, A2)
/ R for a sine).  The asymmetric robot's dense grid runs by hand:
``OCP_CRAWL_ASYM_GRID="7,7,5,12" python -m pytest -q -s tests/test_waveform_baselines.py -k
asymmetric``.
"""
import math
import os
from dataclasses import replace

import numpy as np
import pytest

from ocp_crawl import Harmonic, Model, PeriodicLinear, ReferenceTorque, Robot
from ocp_crawl.ocp.family import SHAPES, WaveFamily, WaveParams, shape_box
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.search import best_baselines
from ocp_crawl.sim.event import simulate_torque

GAMMA, A_MAX, RATE, DIRECTION = 90.0, 30.0, 180.0, -1
#: the asymmetric robot of the audit: a sine of the family reaches 45.98 mm/s there
ASYM = Robot.paper().replace(mu1=0.30, mu2=0.45)
#: the triangle wave of the audit on the paper robot (gamma 87.5, A 27.5, psi 9 deg): 86.293 mm/s
AUDIT_TRIANGLE_SPEED = 0.086293


def settings(**changes) -> OCPSettings:
    """The envelope and bandwidth of problems/ocp_max_speed.toml."""
    return OCPSettings(gamma_deg=GAMMA, A_max_deg=A_MAX, max_rate_deg_s=RATE, direction=DIRECTION,
                       **changes)


def triangle(g1, g2, a1, a2, psi_deg, k) -> ReferenceTorque:
    """Triangle waves built here: joint i at gamma_i - A_i at phase -s_i, gamma_i + A_i half a cycle
    later, joint 1 leading by psi (s_1 = psi/720 cycles, s_2 = -psi/720), as piecewise-linear
    samples."""
    s = psi_deg / 720.0
    knots = np.unique(np.mod([-s, 0.5 - s, s, 0.5 + s], 1.0))

    def wave(t, g, a, shift):
        u = np.mod(t + shift, 1.0)
        return g + a * np.where(u < 0.5, 4 * u - 1, 3 - 4 * u)
    values = np.radians([wave(knots, g1, a1, s), wave(knots, g2, a2, -s)])
    return ReferenceTorque(PeriodicLinear(knots, values), k)


def speed(robot: Robot, torque, T: float) -> float:
    """direction * S / T [m/s] of a gait that simulates, else NaN."""
    r = simulate_torque(Model(robot, gravity="physical"), torque)
    if not r.success:
        return math.nan
    return DIRECTION * r.S / T


@pytest.mark.parametrize("shape", SHAPES)
def test_members_use_the_whole_bandwidth_inside_the_envelope(shape):
    """At its period, every member's fastest reference rate is R (finite differences of its angles)
    and its angles stay within gamma +- A_max."""
    st = settings()
    rng = np.random.default_rng(1)
    lo, hi = np.array(shape_box(shape)).T
    t = np.linspace(0.0, 1.0, 20001)
    for z in rng.uniform(lo, hi, size=(20, lo.size)):
        p = WaveParams.from_box(st, z, shape)
        if max(p.A1_deg, p.A2_deg) < 1e-3:
            continue
        phi = np.degrees(p.gait()(t))
        rate = np.max(np.abs(np.diff(phi, axis=1))) / (t[1] * p.period(st))
        assert rate == pytest.approx(RATE, rel=2e-3 if shape == "harmonic" else 1e-9)
        assert np.all(np.abs(phi - GAMMA) <= A_MAX * (1 + 1e-12))
        assert np.allclose(WaveParams.from_box(st, p.to_box(st), shape).as_dict()["A1_deg"],
                           p.A1_deg)


def test_triangle_member_is_the_triangle_wave():
    """The family's triangle member simulates as the triangle wave built here (S and W+ to 1e-9)."""
    robot = Robot.paper()
    p = WaveParams(87.5, 92.0, 27.5, 20.0, 35.0, "triangle")
    ours = simulate_torque(Model(robot), p.torque(robot.k))
    here = simulate_torque(Model(robot), triangle(87.5, 92.0, 27.5, 20.0, 35.0, robot.k))
    assert ours.success and here.success
    assert ours.S == pytest.approx(here.S, rel=1e-9) and ours.W_plus == pytest.approx(here.W_plus,
                                                                                      rel=1e-9)
    assert p.period(settings()) == pytest.approx(4 * 27.5 / RATE, rel=1e-15)


def test_members_linear_between_kinks_are_simulated_in_whole_pieces():
    """Triangle and linear pulses are linear between their kinks (cosine pulses and sines are not),
    and their default runs, which take those pieces whole, give the S and W+ of runs in steps of
    1/1024 cycle (what the input's Fourier content would ask for), in a fifth of the steps or fewer;
    so does a triangle wave whose corners at phases 0 and 1, shifted by psi/2 and wrapped, differ by
    round-off (psi = -140 deg), which must not leave a piece of round-off length."""
    from ocp_crawl.model.pulse import Pulse
    from ocp_crawl.sim.event import HybridOptions
    from ocp_crawl.sim.event_kinks import linear_pieces

    robot = Robot.paper()
    linear = Pulse(1.5, 1.6, 0.4, 0.3, 0.6, 0.2, 0.3)
    assert linear_pieces(linear, linear.t_knots)
    assert not linear_pieces(Pulse(1.5, 1.6, 0.4, 0.3, 0.6, 0.2, 0.3, "cosine"), linear.t_knots)
    assert not linear_pieces(Harmonic.from_degrees(90.0, 30.0, 45.0), np.zeros(0))
    for p in (WaveParams(87.5, 87.5, 27.5, 27.5, 9.0, "triangle"),
              WaveParams(67.5, 67.5, 7.5, 7.5, -140.0, "triangle"),
              WaveParams(80.0, 95.0, 10.0, 20.0, 60.0, "pulse", 0.1, 0.3)):
        fine = HybridOptions(max_step=1 / 1024)
        whole, capped = (simulate_torque(Model(robot), p.torque(robot.k),
                                         opt) for opt in (None, fine))
        assert whole.success and capped.success
        assert 5 * whole.nsteps <= capped.nsteps, (whole.nsteps, capped.nsteps)
        assert whole.S == pytest.approx(capped.S, rel=1e-12, abs=1e-15)
        assert whole.W_plus == pytest.approx(capped.W_plus, rel=1e-12)


@pytest.mark.heavy
def test_paper_robot_triangle_baseline_beats_an_independent_grid():
    """max_speed on the paper robot: the triangle family's best is at least the best of a grid of
    triangle waves built here, and within 0.1 % of the audit's 86.293 mm/s or above it."""
    robot = Robot.paper()
    st = settings(harmonic_psi=12, harmonic_A=4, baseline_samples=16, baseline_starts=2,
                  baseline_evaluations=250)
    choice = best_baselines(robot, "physical", st, shapes=("triangle",)).choices["triangle"]
    rows = [speed(robot, triangle(g, g, a, a, psi, robot.k), 4 * a / RATE)
            for a in (25.0, 27.5, 30.0) for g in (GAMMA - (A_MAX - a),
                                                  GAMMA) for psi in (6.0, 9.0, 12.0, 20.0)]
    grid_best = np.nanmax(rows)
    assert choice.value >= grid_best * (1 - 1e-9), (choice.to_dict(), grid_best)
    assert choice.value >= AUDIT_TRIANGLE_SPEED * (1 - 1e-3)
    print(f"triangle baseline {choice.value * 1e3:.3f} mm/s, grid best {grid_best * 1e3:.3f} mm/s "
          f"({choice.evaluated} members)")
    assert choice.T == pytest.approx(4 * max(choice.A1_deg, choice.A2_deg) / RATE, rel=1e-12)


def asym_grid_sizes() -> tuple[int, int, int, int]:
    text = os.environ.get("OCP_CRAWL_ASYM_GRID", "4,4,3,6")
    return tuple(int(v) for v in text.split(","))


@pytest.mark.slow
def test_asymmetric_robot_sine_baseline_beats_an_independent_grid():
    """mu1 = 0.30, mu2 = 0.45, max_speed: the harmonic family's best reaches 45.9 mm/s (a sine of
    the family reaches 45.98) and beats a grid of sines with unequal centres simulated here (gamma1,
    gamma2, A, psi; 4 x 4 x 3 x 6 by default, OCP_CRAWL_ASYM_GRID by hand)."""
    n1, n2, na, npsi = asym_grid_sizes()
    st = settings()
    choice = best_baselines(ASYM, "physical", st, shapes=("harmonic",)).choices["harmonic"]
    rows = []
    for a in np.linspace(6.0, 12.0, na):
        for g1 in np.linspace(GAMMA - (A_MAX - a), GAMMA, n1):
            for g2 in np.linspace(GAMMA - (A_MAX - a) / 2, GAMMA + (A_MAX - a) / 2, n2):
                for psi in np.linspace(40.0, 75.0, npsi):
                    gait = Harmonic.from_degrees(psi_deg=psi, gamma1_deg=g1, gamma2_deg=g2,
                                                 A1_deg=a, A2_deg=a)
                    rows.append(speed(ASYM, ReferenceTorque(gait, ASYM.k), 2 * math.pi * a / RATE))
    grid_best = np.nanmax(rows)
    print(f"asymmetric robot: {len(rows)} grid gaits, best {grid_best * 1e3:.3f} mm/s; baseline "
          f"{choice.value * 1e3:.3f} mm/s ({choice.evaluated} members)")
    assert choice.value >= grid_best * (1 - 1e-9)
    assert choice.value >= 0.0459


@pytest.mark.slow
def test_asymmetric_robot_min_cot_finds_a_feasible_sine():
    """min_cot at speed_min 40 mm/s on the asymmetric robot: a sine meets it (CoT+ 19.99 at 40.05
    mm/s in the audit); the baseline is feasible with CoT+ <= 20.0, confirmed by a fresh
    simulation."""
    st = settings(objective="min_cot", speed_min=0.040)
    choice = best_baselines(ASYM, "physical", st, shapes=("harmonic",)).choices["harmonic"]
    assert choice.feasible and choice.value <= 20.0, choice.to_dict()
    r = simulate_torque(Model(ASYM), choice.torque_signal(ASYM.k))
    assert DIRECTION * r.S / choice.T >= 0.040 * (1 - 1e-12)
    assert r.W_plus / (ASYM.M * ASYM.g * abs(r.S)) == pytest.approx(choice.value, rel=1e-12)


@pytest.mark.slow
def test_every_family_is_searched_and_the_best_is_their_best():
    """best_baselines with every family (small search): a choice per family, each confirmed by a
    fresh simulation of its member, and ``best`` the fastest of them."""
    robot = Robot.paper()
    st = settings(harmonic_psi=8, harmonic_A=2, baseline_samples=8, baseline_starts=1,
                  baseline_evaluations=30)
    base = best_baselines(robot, "physical", st, jobs=1)
    assert list(base.choices) == list(SHAPES)
    for shape, c in base.choices.items():
        assert c is not None and c.shape == shape
        fam = WaveFamily(robot, "physical", st, shape)
        ev = fam.evaluate(c.params)
        assert ev.success and DIRECTION * ev.S[0] / ev.T == pytest.approx(c.value, rel=1e-12)
    assert base.best.value == max(c.value for c in base.choices.values())
    # a triangle is a pulse (rise 0.5): the pulse search goes on from the triangle's best
    assert base.choices["pulse"].value >= base.choices["triangle"].value
    assert len(base.choices["pulse"].starts) == len(base.choices["triangle"].starts) + 1
    table = base.table()
    assert [row["shape"] for row in table] == list(SHAPES)


@pytest.mark.parametrize("N", [20, 50])
def test_a_member_sampled_at_the_nodes_is_the_profile_the_ocp_can_hold(N):
    """best_sampling: the audit's triangle wave sampled at N node phases (shifted by a quarter of a
    node interval at a time) and replayed linear between the nodes, against the independent triangle
    wave sampled the same way here and simulated directly: the best of the shifts, at most the
    wave's own speed (the nodes cut its corners unless a shift puts them on nodes)."""
    from ocp_crawl.ocp.baseline import WaveChoice
    from ocp_crawl.ocp.sampling import NODE_SHIFTS, best_sampling

    robot, st = Robot.paper(), settings(nodes=N)
    T = 4 * 27.5 / RATE
    wave = triangle(87.5, 87.5, 27.5, 27.5, 9.0, robot.k)
    choice = WaveChoice(87.5, 87.5, 27.5, 27.5, 9.0, T, [], [], [], [], math.nan, True,
                        "max_speed", shape="triangle")
    nodes = np.arange(N) / N
    direct = [speed(robot, PeriodicLinear(nodes, np.asarray(
        wave(np.mod(nodes + j / (NODE_SHIFTS * N), 1.0)), float).reshape(2, N)), T)
        for j in range(NODE_SHIFTS)]
    value, tau = best_sampling(st, [Model(robot, gravity="physical")], choice)
    assert value == pytest.approx(max(direct), rel=1e-9)
    assert speed(robot, PeriodicLinear(nodes, tau), T) == value
    assert value <= speed(robot, wave, T) * (1 + 1e-9)


#: the best triangle wave of problems/ocp_max_speed.toml over its friction set (the worst of
#: mu1/mu2 = 0.95, 1, 1.05): gamma, A [deg] per joint, psi [deg]
SET_TRIANGLE = (82.91864402563719, 83.08186189182614, 22.896660587780147, 22.89613070117422,
                22.271909603966897)


def test_an_optimum_below_a_member_says_whether_the_nodes_or_the_path_decide():
    """An optimum worse than the best triangle wave over a friction set: its message compares it
    with the triangle wave sampled at its N = 50 nodes (computed here by direct simulation in each
    scenario, the worst, the best of the shifts): below that profile the solver's path ended in a
    local optimum, above it the nodes cannot hold the wave's corners (they sit on the set's edge,
    where the speed falls)."""
    from ocp_crawl.ocp import OCPResult
    from ocp_crawl.ocp.baseline import Baselines, WaveChoice
    from ocp_crawl.ocp.gains import measure_gains
    from ocp_crawl.ocp.sampling import NODE_SHIFTS
    from ocp_crawl.status import Status

    N = 50
    st = settings(nodes=N, mu_ratio_eps=0.05, robust="worst")
    robots = st.scenarios(Robot.paper())
    g1, g2, a1, a2, psi = SET_TRIANGLE
    T = 4 * max(a1, a2) / RATE
    wave = triangle(g1, g2, a1, a2, psi, robots[0].k)
    full = min(speed(r, wave, T) for r in robots)
    choice = WaveChoice(g1, g2, a1, a2, psi, T, [], [], [], [], full, True, "max_speed",
                        shape="triangle")
    nodes = np.arange(N) / N
    sampled = max(min(speed(r, PeriodicLinear(nodes, np.asarray(
        wave(np.mod(nodes + j / (NODE_SHIFTS * N), 1.0)), float).reshape(2, N)), T)
        for r in robots) for j in range(NODE_SHIFTS))
    # the premise: the nodes cut the corners by more than replay_tol
    assert sampled < full * (1 - 1.5 * st.replay_tol)
    for value, why in ((sampled + 0.1 * (full - sampled), "the nodes cannot hold its corners"),
                       (0.99 * sampled, "a local optimum of the solver's path")):
        res = OCPResult(success=True, status=Status.SUCCESS, message="confirmed",
                        objective="max_speed", settings=st, value_replay=value,
                        baselines=Baselines("max_speed", {"triangle": choice}))
        measure_gains(res, [Model(r, gravity="physical") for r in robots])
        assert why in res.message, res.message
        assert res.baseline_at_nodes["value"] == pytest.approx(sampled, rel=1e-9)
        assert res.gain == pytest.approx(value / full - 1, rel=1e-9)
    # under a bound on the actual joint rates that the wave exceeds (its joints reach about 190
    # deg/s), the wave is no gait of the problem: the message says so instead
    bounded = replace(st, max_joint_rate_deg_s=180.0)
    res = OCPResult(success=True, status=Status.SUCCESS, message="confirmed",
                    objective="max_speed", settings=bounded, value_replay=0.99 * sampled,
                    baselines=Baselines("max_speed", {"triangle": choice}))
    measure_gains(res, [Model(r, gravity="physical") for r in robots])
    peak = float(res.message.split("its joint rate reaches ")[1].split(" deg/s")[0])
    assert peak > 180.0 * 1.01 and "beyond max_joint_rate_deg_s" in res.message, res.message
    assert res.baseline_at_nodes is None
