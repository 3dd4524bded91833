"""The waveform baselines (ocp/baseline.py, ocp/family.py, ocp/search.py) against independent grids
of gaits.

The grids are simulated here directly with the event-driven stepper, and the objectives are written
out here from their definitions (v = direction * S / T, CoT+ = W+/(M g |S|), T >= 2 pi max(A1, A2) /
R for a sine, 4 max(A1, A2) / R for a triangle wave), not taken from the modules under test.  The
dense grid (15 gamma x 8 A x 36 psi x 5 periods) is the slow test below; set
OCP_CRAWL_BASELINE_GRID="15,8,36" to run it at full size (default: a small grid).
"""
import json
import math
import os

import numpy as np
import pytest

from ocp_crawl import CallableSignal, Harmonic, Model, ReferenceTorque, Robot
from ocp_crawl.ocp.baseline import required_value, value_from
from ocp_crawl.ocp.family import BOX, WaveParams
from ocp_crawl.ocp.search import best_harmonic
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.sim.event import simulate_torque

GAMMA, A_MAX, RATE, DIRECTION = 90.0, 30.0, 180.0, -1
RTOL = 1e-9


def shipped_settings(**changes) -> OCPSettings:
    """The envelope and bandwidth of problems/ocp_max_speed.toml."""
    return OCPSettings(gamma_deg=GAMMA, A_max_deg=A_MAX, max_rate_deg_s=RATE, direction=DIRECTION,
                       **changes)


def grid(n_gamma: int, amps, psis, robots, periods=(1.0, 1.25, 2.0)) -> list[dict]:
    """Symmetric harmonic gaits (gamma1 = gamma2, A1 = A2) inside the envelope, simulated in every
    robot (scenario); each gait at several periods T >= 2 pi A / R (factors ``periods`` of that
    bound)."""
    rows = []
    for A in amps:
        for gamma in GAMMA + np.linspace(-1.0, 1.0, n_gamma) * (A_MAX - A):
            for psi in psis:
                gait = Harmonic.from_degrees(float(gamma), float(A), float(psi))
                sims = [simulate_torque(Model(r, gravity="physical"),
                                        ReferenceTorque(gait, r.k)) for r in robots]
                if not all(s.success for s in sims):
                    continue
                t_min = 2 * math.pi * A / RATE
                for f in periods:
                    T = f * t_min
                    v = [DIRECTION * s.S / T for s in sims]
                    cot = (sims[0].W_plus / (robots[0].M * robots[0].g * abs(sims[0].S))
                           if sims[0].S else math.inf)
                    rows.append({"gamma": gamma, "A": A, "psi": psi, "T": T, "v": v, "cot": cot})
    return rows


def check_choice(choice, settings: OCPSettings, robots) -> None:
    """The baseline's gait is in the envelope at the bandwidth's shortest period, and a fresh
    simulation of its parameters gives its S, W+ and speeds."""
    assert choice is not None
    for g, a in ((choice.gamma1_deg, choice.A1_deg), (choice.gamma2_deg, choice.A2_deg)):
        assert a >= 0 and abs(g - GAMMA) + a <= A_MAX * (1 + RTOL)
    assert choice.T == pytest.approx(2 * math.pi * max(choice.A1_deg, choice.A2_deg) / RATE,
                                     rel=1e-12)
    gait = Harmonic.from_degrees(psi_deg=choice.psi_deg, gamma1_deg=choice.gamma1_deg,
                                 gamma2_deg=choice.gamma2_deg, A1_deg=choice.A1_deg,
                                 A2_deg=choice.A2_deg)
    for j, r in enumerate(robots):
        sim = simulate_torque(Model(r, gravity="physical"), ReferenceTorque(gait, r.k))
        assert sim.success
        assert sim.S == pytest.approx(choice.S[j], rel=1e-12, abs=1e-15)
        assert sim.W_plus == pytest.approx(choice.W_plus[j], rel=1e-12)
        assert DIRECTION * sim.S / choice.T == pytest.approx(choice.v[j], rel=1e-12)
    json.dumps(choice.to_dict(), allow_nan=False)


def scenario_robots(ratios=(0.9, 1.0, 1.1)) -> list[Robot]:
    """The robust_speed scenarios mu1/mu2 = r at the same geometric-mean friction."""
    robot = Robot.paper()
    mu = math.sqrt(robot.mu1 * robot.mu2)
    return [robot.replace(mu1=mu * math.sqrt(r), mu2=mu / math.sqrt(r)) for r in ratios]


def assert_beats_speed(rows, objective: str, robust: str = "mean"):
    """best_harmonic for a speed objective is at least as fast as every grid row; returns (choice,
    margin)."""
    settings = shipped_settings(objective=objective, robust=robust)
    robots = scenario_robots() if objective == "robust_speed" else [Robot.paper()]
    choice = best_harmonic(Robot.paper(), "physical", settings)
    check_choice(choice, settings, robots)
    speed = ((lambda v: float(np.mean(v) if robust == "mean" else np.min(v)))
             if len(robots) > 1 else (lambda v: v[0]))
    assert choice.value == pytest.approx(speed(choice.v), rel=1e-12)
    grid_best = max(speed(r["v"]) for r in rows)
    assert choice.value >= grid_best * (1 - RTOL), (choice.to_dict(), grid_best)
    return choice, choice.value / grid_best - 1


def assert_beats_cot(rows, fraction: float = 0.5):
    """best_harmonic for min_cot (speed_min: met by some grid rows, not all) has a CoT+ at most
    every feasible grid row's; returns (choice, margin)."""
    speeds = sorted(r["v"][0] for r in rows if r["v"][0] > 0)
    speed_min = speeds[int(fraction * len(speeds))]
    feasible = [r for r in rows if r["v"][0] >= speed_min]
    assert 0 < len(feasible) < len(rows)
    settings = shipped_settings(objective="min_cot", speed_min=speed_min)
    choice = best_harmonic(Robot.paper(), "physical", settings)
    check_choice(choice, settings, [Robot.paper()])
    robot = Robot.paper()
    cot = choice.W_plus[0] / (robot.M * robot.g * abs(choice.S[0]))
    assert (choice.feasible and choice.v[0] >= speed_min
            and choice.value == pytest.approx(cot, rel=1e-12))
    grid_best = min(r["cot"] for r in feasible)
    assert choice.value <= grid_best * (1 + RTOL), (choice.to_dict(), grid_best)
    return choice, 1 - choice.value / grid_best


@pytest.fixture(scope="module")
def coarse_rows():
    """5 gamma x 3 A x 12 psi x 3 periods, independent of the baseline's own scan (A = 7.5, 15,
    22.5, 30; psi multiples of 10 deg)."""
    return grid(5, (5.0, 17.0, 29.0), np.linspace(-165.0, 165.0, 12), [Robot.paper()])


@pytest.mark.slow
def test_max_speed_beats_coarse_grid(coarse_rows):
    assert_beats_speed(coarse_rows, "max_speed")


@pytest.mark.slow
def test_min_cot_beats_coarse_grid(coarse_rows):
    assert_beats_cot(coarse_rows)


def dense_sizes() -> tuple[int, int, int]:
    text = os.environ.get("OCP_CRAWL_BASELINE_GRID", "5,3,12")
    n_gamma, n_a, n_psi = (int(v) for v in text.split(","))
    return n_gamma, n_a, n_psi


@pytest.mark.heavy
@pytest.mark.parametrize("objective", ["max_speed", "min_cot", "robust_speed"])
def test_beats_dense_grid(objective):
    """The dense grid (OCP_CRAWL_BASELINE_GRID="15,8,36": 15 gamma x 8 A x 36 psi x 5 periods) by
    hand; a small one by default.  Prints the margin of the baseline over the grid's best."""
    n_gamma, n_a, n_psi = dense_sizes()
    # off the baseline scan's amplitudes
    amps = np.linspace(A_MAX / n_a, A_MAX, n_a) - A_MAX / (4 * n_a)
    psis = np.linspace(-180.0, 180.0, n_psi + 1)[1:] - 180.0 / n_psi  # odd multiples of half a step
    robots = scenario_robots() if objective == "robust_speed" else [Robot.paper()]
    rows = grid(n_gamma, amps, psis, robots, periods=(1.0, 1.1, 1.5, 2.0, 3.0))
    if objective == "min_cot":
        choice, margin = assert_beats_cot(rows, fraction=0.4)
    else:
        choice, margin = assert_beats_speed(rows, objective)
    print(f"{objective}: {len(rows)} grid rows; baseline value {choice.value:.9g} better by "
          f"{margin:.3e} (relative); {choice.evaluated} evaluations in {choice.time_s:.2f} s")


def test_value_definitions():
    """value_from: mean speed v = direction S / T, robust mean/worst, CoT+ with the speed
    requirement."""
    S, cot, T = [-0.03, -0.02, 0.01], [20.0, 30.0, 40.0], 0.5
    assert value_from(shipped_settings(), S[:1], cot[:1], T) == pytest.approx(0.06)
    assert value_from(shipped_settings(objective="robust_speed"), S, cot,
                      T) == pytest.approx(0.04 / 3 * 2)
    assert value_from(shipped_settings(objective="robust_speed", robust="worst"), S, cot,
                      T) == pytest.approx(-0.02)
    need = shipped_settings(objective="min_cot", speed_min=0.07)
    assert value_from(need, S[:1], cot[:1], T) == 20.0
    assert required_value(need, S[:1], cot[:1], T) == math.inf
    # wrong way
    assert value_from(shipped_settings(objective="min_cot"), [0.03], [20.0], T) == math.inf


def test_value_over_a_friction_set():
    """Every objective over a friction set: max_speed's is robust_speed's (mean or worst speed);
    min_cot's the mean or the largest CoT+, +inf when one scenario misses speed_min or moves the
    wrong way."""
    S, cot, T = [-0.03, -0.02, -0.025], [20.0, 30.0, 40.0], 0.5
    for robust in ("mean", "worst"):
        own = shipped_settings(objective="max_speed", mu_ratio_eps=0.05, robust=robust)
        assert own.friction_ratios == (0.95, 1.0, 1.05) and own.friction_set
        assert value_from(own, S, cot, T) == value_from(
            shipped_settings(objective="robust_speed", robust=robust), S, cot, T)
    assert value_from(shipped_settings(objective="min_cot", mu_ratio_eps=0.05), S, cot, T) == 30.0
    worst = shipped_settings(objective="min_cot", mu_ratio_eps=0.05, robust="worst",
                             speed_min=0.045)
    assert value_from(worst, S, cot, T) == 40.0
    assert required_value(worst, S, cot, T) == math.inf  # 0.04 m/s in scenario 2
    assert value_from(worst, [-0.03, 0.001, -0.03], cot, T) == math.inf  # the wrong way in one
    assert not shipped_settings().friction_set and shipped_settings().friction_ratios == (1.0,)
    assert shipped_settings(objective="robust_speed").friction_ratios == (0.9, 1.0, 1.1)


def test_family_box_is_the_envelope():
    """Every box point maps into the envelope (gamma_i +- A_i within gamma +- A_max), corners reach
    its edges, and to_box inverts from_box."""
    settings = shipped_settings()
    rng = np.random.default_rng(0)
    lo, hi = np.array(BOX).T
    for z in rng.uniform(lo, hi, size=(200, 5)):
        p = WaveParams.from_box(settings, z)
        assert p.in_envelope(settings, rtol=0.0)
        assert np.allclose(p.to_box(settings), z, atol=1e-12) or p.psi_deg == 180.0
    edge = WaveParams.from_box(settings, (1, -1, 0.5, -0.6, 0.1))
    assert edge.gamma1_deg + edge.A1_deg == pytest.approx(GAMMA + A_MAX)
    assert edge.gamma2_deg - edge.A2_deg == pytest.approx(GAMMA - A_MAX)
    assert (edge.A1_deg, edge.A2_deg) == pytest.approx((0.4 * 0.5 * A_MAX, 0.5 * A_MAX))


def test_min_cot_unreachable_speed_gives_a_fallback():
    """A speed requirement above every harmonic gait's speed: value +inf, not feasible, but a gait
    (the fastest found) is returned as initial guess."""
    settings = shipped_settings(objective="min_cot", speed_min=1.0, harmonic_A=2, harmonic_psi=8,
                                baseline_samples=8)
    choice = best_harmonic(Robot.paper(), "physical", settings, local_starts=1, maxfev=40)
    assert choice is not None and not choice.feasible and choice.value == math.inf
    assert 0.04 < choice.v[0] < 1.0
    assert choice.torque_signal(Robot.paper().k)(0.0).shape == (2,)


@pytest.mark.parametrize("objective", ["max_speed", "min_cot"])
def test_twice_per_cycle_has_the_same_value(objective):
    """A harmonic gait run twice per cycle at twice the period: S and W+ double, and value_from is
    unchanged (v = direction S / T and CoT+ are both invariant), as the OCP's free period
    requires."""
    robot = Robot.paper()
    model = Model(robot, gravity="physical")
    once = ReferenceTorque(Harmonic.from_degrees(psi_deg=30.0, gamma1_deg=100.0, gamma2_deg=96.0,
                                                 A1_deg=12.0, A2_deg=15.0), robot.k)
    twice = CallableSignal(lambda t: once((2.0 * t) % 1.0),
                           lambda t: 2.0 * once.derivative((2.0 * t) % 1.0))
    r1, r2 = simulate_torque(model, once), simulate_torque(model, twice)
    assert r1.success and r2.success
    assert r2.S == pytest.approx(2 * r1.S, rel=1e-9) and r2.W_plus == pytest.approx(2 * r1.W_plus,
                                                                                    rel=1e-9)
    settings = shipped_settings(objective=objective, speed_min=0.01)
    T = 2 * math.pi * 15.0 / RATE
    v1 = required_value(settings, [r1.S], [r1.CoT_plus], T)
    v2 = required_value(settings, [r2.S], [r2.CoT_plus], 2 * T)
    assert math.isfinite(v1) and v2 == pytest.approx(v1, rel=1e-9)


@pytest.mark.slow
def test_worker_processes_change_nothing_but_the_time():
    """The scan and the local searches on two worker processes give the serial search's choice,
    field by field (the simulations are deterministic), and ``meanwhile`` runs once; a worker pool
    that breaks falls back to the serial search; jobs < 1 is refused by name."""
    import ocp_crawl.ocp.search as search
    from concurrent.futures.process import BrokenProcessPool
    from dataclasses import asdict

    settings = shipped_settings(objective="max_speed", harmonic_A=2, harmonic_psi=8,
                                baseline_samples=16)
    called = []
    runs = [asdict(best_harmonic(Robot.paper(), "physical", settings, local_starts=2, maxfev=30,
                                 jobs=j, meanwhile=lambda: called.append(j))) for j in (1, 2)]
    assert called == [1, 2]  # once each, with and without workers
    for run in runs:
        run.pop("time_s")
    assert runs[0] == runs[1] and len(runs[0]["starts"]) == 2

    calls = []

    def broken(robot, gravity, s, shapes, jobs):
        calls.append(jobs)
        if jobs > 1:
            raise BrokenProcessPool("a worker died")
        return real_pool(robot, gravity, s, shapes, jobs)

    real_pool, search._pool = search._pool, broken
    try:
        again = asdict(best_harmonic(Robot.paper(), "physical", settings, local_starts=2, maxfev=30,
                                     jobs=2))
    finally:
        search._pool = real_pool
    assert calls == [2, 1]
    again.pop("time_s")
    assert again == runs[0]
    with pytest.raises(ValueError, match="jobs"):
        best_harmonic(Robot.paper(), "physical", settings, jobs=0)


def test_a_local_search_ends_the_same_whatever_the_cache_holds():
    """A local search's budget counts the members it asks for beyond the scan, not the family
    cache's misses: run again on the same family (every member cached) or on a family that knows
    the scan alone, it takes the same path to the same end, with the same count."""
    from ocp_crawl.ocp.family import WaveFamily
    from ocp_crawl.ocp.search import local_search, scan_points, seeds
    from ocp_crawl.ocp.baseline import search_rank

    settings = shipped_settings(objective="max_speed", harmonic_A=2, harmonic_psi=8,
                                baseline_samples=0)
    fam = WaveFamily(Robot.paper(), "physical", settings, "harmonic")
    points = scan_points(settings)
    scan = [fam.evaluate(fam.member(z)) for z in points]
    keys = frozenset(fam.key(ev.params) for ev in scan)
    z0 = seeds([(search_rank(settings, ev), z) for ev, z in zip(scan, points)], 1, 0.5)[0]
    first, asked = local_search(fam, z0, 30, scan)
    again, asked_again = local_search(fam, z0, 30, scan)
    fresh = WaveFamily(Robot.paper(), "physical", settings, "harmonic")
    fresh.absorb(scan)
    third, asked_third = local_search(fresh, z0, 30, scan)
    assert first == again == third and 0 < first["evaluations"] <= 30
    assert [ev.params for ev in asked] == [ev.params for ev in asked_again] == \
        [ev.params for ev in asked_third]
    # the counted members, each simulated once
    assert fresh.evaluations - len(keys) == first["evaluations"]


@pytest.mark.slow
def test_every_family_on_workers_is_the_serial_search():
    """Every family's scan and local searches on worker processes (whose caches keep what earlier
    searches simulated), the pulse search from the triangle's best sent as soon as the triangle's
    searches end, give the serial search's choices field by field, each local search's summary
    included, on a robot of unequal feet (asymmetric members)."""
    from dataclasses import asdict

    from ocp_crawl.ocp.search import best_baselines

    settings = shipped_settings(objective="max_speed", harmonic_A=2, harmonic_psi=8,
                                baseline_samples=16, baseline_starts=2)
    robot = Robot.paper(mu1=0.30, mu2=0.45)

    def choices(j):
        found = best_baselines(robot, "physical", settings, ("harmonic", "triangle", "pulse"),
                               maxfev=40, jobs=j).choices
        out = {}
        for shape, choice in found.items():
            d = asdict(choice)
            d.pop("time_s")
            out[shape] = d
        return out
    serial, parallel = choices(1), choices(2)
    assert serial == parallel
    assert [len(serial[s]["starts"]) for s in ("harmonic", "triangle", "pulse")] == [2, 2, 3]
