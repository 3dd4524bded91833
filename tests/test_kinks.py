"""Piecewise-linear torques in the event-driven stepper: slips that stop or reverse exactly at a
kink of the input.

The stepper ends a continuation step at every kink (a knot where tau' jumps) and decides the contact
mode after it by the rates after it (:mod:`ocp_crawl.sim.event_kinks`).  Independent checks: the
switch-exact MPCC time-stepping with the kinks on step boundaries, the limit of the same input with
its corners rounded (a Gaussian of width sigma -> 0, a smooth Fourier series that the stepper
follows without any kink handling), and the mirror symmetry of an in-phase gait.
"""
import math
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl import (FourierSeries, Harmonic, Model, PeriodicLinear, PeriodicPchip,
                       PeriodicSpline, ReferenceTorque, Robot, simulate, simulate_torque)
from ocp_crawl.model.pulse import Pulse
from ocp_crawl.sim.event_kinks import input_holds, input_kinks
from ocp_crawl.sim.timestepping import TimeSteppingOptions


def triangle(t, shift: float = 0.0) -> np.ndarray:
    """Triangle wave in [-1, 1] of period 1: -1 at t = shift, +1 half a cycle later."""
    u = np.mod(np.asarray(t, float) - shift, 1.0)
    return np.where(u < 0.5, -1 + 4 * u, 3 - 4 * u)


def triangle_gait(n: int, shift2: float, robot: Robot) -> ReferenceTorque:
    """Both reference angles a triangle wave between 60 and 120 deg, joint 2 shifted by ``shift2``
    cycles, linearly interpolated between n equally spaced samples (the turning points are
    samples)."""
    tk = np.arange(n) / n
    v = np.radians(90 + 30 * np.array([triangle(tk), triangle(tk, shift2)]))
    return ReferenceTorque(PeriodicLinear(tk, v), robot.k)


def rounded(torque: ReferenceTorque, sigma: float) -> ReferenceTorque:
    """The linear interpolant of equally spaced samples convolved with a Gaussian of standard
    deviation sigma [cycles]: its Fourier series (the hat functions' coefficients sinc^2 times the
    Gaussian's), cut where the Gaussian factor is below 1e-20."""
    lin = torque.reference
    n = lin.t_knots.size
    h = np.arange(int(math.ceil(1.6 / sigma)) + 1)
    c = ((np.fft.fft(lin.values, axis=1) / n)[:, h % n] * np.sinc(h / n) ** 2
         * np.exp(-2 * (math.pi * h * sigma) ** 2))
    return ReferenceTorque(FourierSeries(c[:, 0].real, 2 * c[:, 1:].real, -2 * c[:, 1:].imag),
                           torque.k)


def test_kinks_are_the_knots_where_the_rate_jumps():
    tk = np.arange(16) / 16
    harmonic = Harmonic.from_degrees(90, 30, 45)
    samples = harmonic(tk)
    assert np.array_equal(input_kinks(PeriodicLinear(tk, samples), tk)[0], tk)
    for smooth in (PeriodicSpline(tk, samples), PeriodicPchip(tk, samples)):
        assert input_kinks(smooth, tk)[0].size == 0, type(smooth).__name__
    collinear = PeriodicLinear([0.0, 0.25, 0.5, 0.75], [[1.0, 2.0, 3.0, 2.0], [0.0, 1.0, 2.0, 2.0]])
    # both straight at 0.25
    assert np.array_equal(input_kinks(collinear, collinear.t_knots)[0], [0.0, 0.5, 0.75])
    trapezoid = Pulse(1.5, 1.5, 0.5, 0.5, 0.0, 0.1, 0.2)
    assert np.array_equal(input_kinks(trapezoid, trapezoid.t_knots)[0], trapezoid.t_knots)
    cosine = Pulse(1.5, 1.5, 0.5, 0.5, 0.0, 0.1, 0.2, ramp="cosine")
    assert input_kinks(cosine, cosine.t_knots)[0].size == 0


@pytest.mark.parametrize("gravity", ["physical", "paper"])
def test_in_phase_triangle_stops_slipping_at_its_turning_points(gravity):
    """Equal triangle waves on a symmetric robot: both feet slip together (the tie of the friction
    limits) until the rate reverses at the turning points t = 0 and 1/2, where the slip stops
    exactly; the mirror symmetry gives S = 0.  (Located inside a step, the stop would fall a
    round-off before the kink and the stick-stick mode start there with the rates before it: "guard
    slip_1- does not leave zero".)"""
    robot = Robot.paper()
    res = simulate_torque(Model(robot, gravity=gravity), triangle_gait(24, 0.0, robot))
    assert res.success, res.message
    stops = [e for e in res.steady_events() if e.kind == "slip_to_stick"]
    assert sorted({(e.t - res.t0) % 1.0 for e in stops}) == [0.0, 0.5]  # exactly at the kinks
    assert all(e.mode_before.startswith("slip-slip")
               and e.mode_after == "stick-stick" for e in stops)
    assert abs(res.S) <= 1e-12 * robot.L


@pytest.fixture(scope="module")
def graze_case():
    """Triangles 150 deg apart (joint 2 shifted by -5/12 cycle): the stick-stick state reaches foot
    2's friction limit exactly at joint 1's turning point (by the gait's mirror-and-time-reversal
    symmetry) and leaves it after the kink (decided by the rates alone it would leave "2 consistent
    successor modes": stick-stick and a slip mode 0.4 deg away)."""
    robot = Robot.paper()
    model = Model(robot, gravity="physical")
    torque = triangle_gait(24, -5 / 12, robot)
    return model, torque, simulate_torque(model, torque)


def test_friction_limit_reached_at_a_kink_is_a_graze(graze_case):
    _, _, res = graze_case
    assert res.success, res.message
    graze = [e for e in res.steady_events() if e.kind.startswith("graze_")]
    # at joint 1's turning point, phase 0 of the cycle (the steady cycle's first or last instant)
    assert [(e.mode_after, e.guard_name) for e in graze] == [("stick-stick", "slip_2-")]
    assert min((graze[0].t - res.t0) % 1.0, -(graze[0].t - res.t0) % 1.0) < 1e-12
    assert abs(graze[0].guard) < 1e-12


@pytest.mark.slow
def test_kinked_gait_agrees_with_switch_exact_time_stepping(graze_case):
    """MPCC time-stepping with 48 steps: every kink (24 samples) on a step boundary, events split
    exactly."""
    model, torque, res = graze_case
    mpcc = simulate(model, torque, solver="mpcc", options=TimeSteppingOptions(steps=48))
    assert mpcc.success, mpcc.message
    assert mpcc.S == pytest.approx(res.S, rel=1e-7)  # (9.2e-9 measured; 3.4e-8 with 192 steps)


@pytest.mark.slow
def test_rounded_corners_converge_to_the_kinked_result(graze_case):
    """The input with its corners rounded over sigma = 4e-3, 2e-3, 1e-3 cycles (smooth: no kink
    handling) moves S by O(sigma); the second-order Richardson extrapolation of the three to sigma =
    0 is the kinked result."""
    model, torque, res = graze_case
    s = {}
    for sigma in (4e-3, 2e-3, 1e-3):
        smooth = simulate_torque(model, rounded(torque, sigma))
        assert smooth.success, smooth.message
        s[sigma] = smooth.S
    errors = [abs(s[sigma] - res.S) for sigma in (4e-3, 2e-3, 1e-3)]
    assert errors[0] > 1e-4 * abs(res.S)  # the rounding matters (7.1e-6 m, 8e-4 relative) ...
    # ... to first order in sigma
    assert 0.4 < errors[1] / errors[0] < 0.6 and 0.4 < errors[2] / errors[1] < 0.6
    # (errors c1 sigma + c2 sigma^2 cancel)
    extrapolated = (8 * s[1e-3] - 6 * s[2e-3] + s[4e-3]) / 3
    assert extrapolated == pytest.approx(res.S, rel=1e-5)  # (1.8e-6 measured)


@pytest.mark.parametrize("knot", [0, 12])
def test_a_hold_during_a_slip_changes_nothing(knot):
    """The triangle gait (joint 2 a quarter cycle behind) held still for 0.02 cycles at a knot
    inside a slip phase of foot 2 (knot 0) or foot 1 (knot 12), the hold's end point moved back by
    1e-9 of the next sample step (the round-off of an optimiser's hold: the slip stops and the
    stick-stick guard grows at 1e-9 of its usual rate): the same path, so a rate-independent
    (quasistatic) model must give the same S and W+.  Before the stepper let a mode hold at its
    limit while the input holds still, the stick-stick successor was refused (its guard did not
    leave zero within 1e-4 cycles) and the run ended as snap_through (knot 0) or energy_imbalance
    (knot 12)."""
    robot = Robot.paper()
    model = Model(robot, gravity="physical")
    base = triangle_gait(24, 0.25, robot)
    ref = simulate_torque(model, base)
    tk, v = base.reference.t_knots, base.reference.values
    assert ref.success, ref.message
    # (slip1-, slip2-: inside a slip phase)
    assert ref.mode[np.argmin(np.abs(ref.t - ref.t0 - tk[knot]))] in (2, 4)
    d = 0.02
    t_held = np.r_[tk[:knot + 1] * (1 - d), tk[knot] * (1 - d) + d, tk[knot + 1:] * (1 - d) + d]
    back = v[:,
             knot:knot + 1] - 1e-9 * (v[:, (knot + 1) % 24:(knot + 1) % 24 + 1]
                                      - v[:, knot:knot + 1])
    held = simulate_torque(model,
                           ReferenceTorque(PeriodicLinear(t_held, np.c_[v[:, :knot + 1], back,
                                                                        v[:, knot + 1:]]),
                                           robot.k))
    assert held.success, held.message
    assert held.S == pytest.approx(ref.S, rel=1e-12, abs=1e-15)
    # (the 1e-9 step back and forth: 6e-10 measured)
    assert held.W_plus == pytest.approx(ref.W_plus, rel=1e-8)


@pytest.mark.slow
@pytest.mark.parametrize("gravity", ["physical", "paper"])
def test_triangle_phase_sweep_is_antisymmetric(gravity):
    """Equal triangles with joint 2 shifted by j/24 cycle, j = 0..23 (the turning points on samples,
    so that slips stop at kinks; 8 of these 48 runs failed before): all succeed, and the mirror
    symmetry of the robot (swapping the joints is the shift -j/24, a time shift apart) reverses the
    step: S(j) = -S(24 - j), S(0) = S(12) = 0."""
    robot = Robot.paper()
    model = Model(robot, gravity=gravity)
    s = []
    for j in range(24):
        res = simulate_torque(model, triangle_gait(24, j / 24, robot))
        assert res.success, (j, res.message)
        s.append(res.S)
    assert abs(s[0]) <= 1e-12 * robot.L and abs(s[12]) <= 1e-12 * robot.L
    for j in range(1, 12):
        assert s[j] == pytest.approx(-s[24 - j], rel=1e-9, abs=1e-13 * robot.L), j
    assert max(np.abs(s)) > 0.01 * robot.L


@pytest.mark.parametrize("hold, switch_at", [(False, 0.98), (True, 0.985)])
def test_slipping_foot_changes_at_a_knot_where_the_limits_tie(hold, switch_at):
    """robust_speed's optimum at N = 200 (tests/data/tie_at_a_knot.csv): in the scenario mu1/mu2 =
    1.1 the friction limits of the slipping foot 1 and of foot 2 tie exactly at the knot t = 0.98,
    and after it foot 2's is the lower: the slip passes to foot 2 there.  The guard switch_to_2 was
    zero to round-off at the kink, seen from the right rates, and negative after it; the stepper
    looked for it to rise first and failed ("does not leave zero after the transition into slip1-",
    a physically ambiguous tie).  ``hold``: the torques held at the tie for one sample (nothing
    moves while they hold; the slip passes to foot 2 when they move again, at 0.985).  Independent
    check: moving the tie's sample by +-1e-9 N m (the tie then a little off the knot, located by the
    ordinary crossing) moves S by O(1e-9) only."""
    tau = np.loadtxt(Path(__file__).parent / "data" / "tie_at_a_knot.csv", delimiter=",").T
    if hold:
        tau[:, 197] = tau[:, 196]
    robot = Robot.paper()
    ratio = math.sqrt(1.1)
    model = Model(robot.replace(mu1=robot.mu1 * ratio, mu2=robot.mu2 / ratio), gravity="physical")
    phase = np.arange(200) / 200
    res = simulate_torque(model, PeriodicLinear(phase, tau))
    assert res.success, res.message
    switch = [e for e in res.steady_events() if e.kind == "slip_switch"]
    assert [(round(e.t - res.t0, 12), e.mode_before,
             e.mode_after) for e in switch] == [(switch_at, "slip1-", "slip2+")]
    for d in (1e-9, -1e-9):
        moved = tau.copy()
        moved[0, 196] += d
        near = simulate_torque(model, PeriodicLinear(phase, moved))
        assert near.success, near.message
        # (8.7e-9 and 2.4e-8 measured without the hold)
        assert abs(near.S - res.S) <= 1e-7 * abs(res.S)


@pytest.mark.slow
@pytest.mark.parametrize("shift", [0.0, -5.9916710482000624e-11])
def test_slip_that_stops_just_before_a_knot_resumes_at_it(shift):
    """The replay of an OCP optimum (tests/data/slip_stops_just_before_a_knot.csv, ocp_robust.toml
    at mu = 0.3 and N = 100, the scenario mu1/mu2 = 0.9) whose switch-exact transcription put the
    stop of foot 2's slip at the node t = 0.51: with the rates of the piece before that knot the
    slip stops 2.3e-8 cycles before it, the stick-stick friction guard of foot 2 then grows only
    quadratically (at zero to round-off at the knot), and with the rates after the knot it falls
    (the slip resumes, until t = 0.515).  The trial steps of the successor test crossed the kink:
    stick-stick was refused by the rates after it and slip2- by those before it ("0 consistent
    successor modes").  ``shift``: the knot's sample moved by -6e-11 N m (bisected), so that the
    slip stops 1e-9 cycles before the knot; the trial steps then accepted slip2- (a graze, by the
    rates after the kink), whose guard is negative up to the kink ("guard stick does not leave zero
    after the transition into slip2-").  Now stick-stick holds up to the knot and the slip of foot 2
    resumes exactly there.  Independent checks: moving the knot's sample by a further +-1e-9 N m
    (the +1e-9 runs failed the same way, the -1e-9 ones did not) moves S by O(1e-9) only, and the
    switch-exact MPCC time-stepping (the knots on step boundaries) gives the same S."""
    tau = np.loadtxt(Path(__file__).parent / "data" / "slip_stops_just_before_a_knot.csv",
                     delimiter=",").T
    tau[:, 51] += shift
    robot = Robot(M=0.052, L=0.12, beta=2.0, k=0.1677, mu1=0.2846049894151541,
                  mu2=0.31622776601683794, g=9.81)
    model = Model(robot, gravity="physical")
    phase = np.arange(100) / 100
    res = simulate_torque(model, PeriodicLinear(phase, tau))
    assert res.success, res.message
    ev = [(e.t - res.t0, e.kind, e.mode_before, e.mode_after) for e in res.steady_events()
          if 0.5 < e.t - res.t0 < 0.52]
    assert [e[1:] for e in ev] == [("slip_to_stick", "slip2-", "stick-stick"),
                                   ("slip_onset_2", "stick-stick", "slip2-"),
                                   ("slip_to_stick", "slip2-", "stick-stick")]
    assert 0 < 0.51 - ev[0][0] < 1e-7 and round(ev[1][0], 12) == 0.51 and ev[2][0] > 0.514
    for d in (1e-9, -1e-9):
        moved = tau.copy()
        moved[:, 51] += d
        near = simulate_torque(model, PeriodicLinear(phase, moved))
        assert near.success, near.message
        assert abs(near.S - res.S) <= 1e-7 * abs(res.S)  # (5.0e-9 measured, each)
    mpcc = simulate(model, PeriodicLinear(phase, tau), solver="mpcc",
                    options=TimeSteppingOptions(steps=100))
    assert mpcc.success, mpcc.message
    assert mpcc.S == pytest.approx(res.S, rel=1e-6)  # (1.2e-8 measured; 2.4e-8 with 200 steps)


def _ocp_start(index: int, n: int = 40):
    """The OCP's start ``index`` at ``n`` nodes (linear between its nodes) on the paper robot."""
    from ocp_crawl.ocp.settings import OCPSettings
    from ocp_crawl.ocp.starts import start_guesses

    robot = Robot.paper()
    settings = OCPSettings(starts=4, nodes=n, direction=-1)
    harmonic = ReferenceTorque(Harmonic.from_degrees(settings.gamma_deg, settings.A_max_deg, 45.0),
                               robot.k)
    start = start_guesses(settings, robot, harmonic(np.arange(n) / n),
                          settings.min_period(settings.A_max_deg, settings.A_max_deg))[index]
    return PeriodicLinear(np.arange(n) / n, start.tau)


@pytest.mark.slow
@pytest.mark.parametrize("index,kinds", [
    # a slip of foot 1 that a kink stops at a step's end; a slip of foot 2 whose input holds still
    # for a step and then turns
    (2, ("slip_to_stick", "slip_to_stick")),
    # a hold ending a slip; foot 2's slip handed over to foot 1 at a node (both feet at their
    # limits there: the step's one-step problem could share the slip out between the feet)
    (1, ("slip_to_stick", "slip_to_stick", "slip_switch"))])
def test_events_at_the_inputs_nodes_are_where_the_event_driven_stepper_puts_them(index, kinds):
    """The OCP's second and third starts at 40 nodes, every node a step boundary at 40 steps: the
    switch-exact time-stepping reads the slip rate on the step's side of a kink, places a guard
    that turns at a kink at that kink, holds the mode while the input holds and decides it where
    the hold ends, and keeps a step in its starting mode when its solution ends with both feet
    slipping at a tie: every event of the event-driven stepper's steady cycle, of the same kind at
    the same phase, and S to the solvers' tolerance (a central difference across a kink sends the
    third start's cycle on another branch, S 1.9e-3 off)."""
    n, model = 40, Model(Robot.paper(), gravity="physical")
    torque = _ocp_start(index, n)
    ref = simulate_torque(model, torque)
    assert ref.success, ref.message
    steady = [(e.kind, (e.t - ref.t0) % 1.0) for e in ref.steady_events() if e.t < ref.t0 + 1.0]
    # the premises: events of these kinds at nodes, and a hold of the input that ends at one
    at_nodes = sorted(k for k, t in steady if abs(t * n - round(t * n)) < 1e-9)
    assert at_nodes == sorted(kinds), steady
    holds = input_holds(torque, np.arange(n) / n)
    assert any(abs(end % 1.0 - t) < 1e-9 for _, end in holds for _, t in steady), (holds, steady)

    mpcc = simulate(model, torque, solver="mpcc",
                    options=TimeSteppingOptions(steps=n, s_error_tol=0.0))
    assert mpcc.success, mpcc.message
    assert mpcc.S == pytest.approx(ref.S, rel=1e-7)   # (8e-10 and 2.6e-9 measured)
    stepped = [(e.kind, (e.t - mpcc.t0) % 1.0) for e in mpcc.events
               if mpcc.t0 <= e.t < mpcc.t0 + 1.0]
    assert len(stepped) == len(steady), (stepped, steady)
    for kind, t in steady:
        assert any(k == kind and min(abs(s - t), 1 - abs(s - t)) < 1e-6 for k, s in stepped), \
            (kind, t, stepped)
