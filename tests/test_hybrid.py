"""Event-driven hybrid-quasistatic stepper: invariants, events, limits, folds, published CoT+."""
import csv
import math
import os
import re

import numpy as np
import pytest

from ocp_crawl import (CallableSignal, FourierSeries, Harmonic, HybridOptions, Mode, Model,
                       PeriodicLinear,
                       PeriodicSpline, ReferenceTorque, Robot, Status, simulate_torque)
from ocp_crawl.sim.event import HybridStepper
from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.angles import simulate_angles

from conftest import PAPER_DATA, paper_torque


def check_samples(model, res, atol_res=1e-9):
    """Equilibrium, Coulomb and positive normal forces at every output sample."""
    r = model.robot
    assert res.t.size > 50
    for j in range(res.t.size):
        F = model.equilibrium_residual(res.phi[:, j], res.tau[:, j], res.f_t[j])
        assert np.max(np.abs(F)) < atol_res, (j, F)
    slack = 1e-10 * r.M * r.g
    assert np.all(res.f_n1 > 0) and np.all(res.f_n2 > 0)
    assert np.all(np.abs(res.f_t) <= r.mu1 * res.f_n1 + slack)
    assert np.all(np.abs(res.f_t) <= r.mu2 * res.f_n2 + slack)
    # slipping samples sit on the friction limit of the slipping foot
    for code, foot in ((Mode.SLIP1_POS, 1), (Mode.SLIP1_NEG, 1), (Mode.SLIP2_POS, 2),
                       (Mode.SLIP2_NEG, 2)):
        sel = res.mode == int(code)
        lim = (r.mu1 * res.f_n1 if foot == 1 else r.mu2 * res.f_n2)[sel]
        np.testing.assert_allclose(np.abs(res.f_t[sel]), lim, rtol=0, atol=slack)


@pytest.mark.parametrize("mu1,mu2", [(0.389, 0.389), (0.35, 0.43)])
def test_invariants_and_energy_balance_every_cycle(gravity, mu1, mu2):
    robot = Robot.paper(mu1=mu1, mu2=mu2)
    model = Model(robot, gravity=gravity)
    stepper = HybridStepper(model, paper_torque(robot))
    res = stepper.run()
    assert res.success, res.message
    assert res.cycles >= 2
    check_samples(model, res)
    for c in range(res.cycles):
        e = stepper.cycle_energy(c)
        assert e["dissipation"] > 0
        assert abs(e["balance_residual"]) < 1e-6, (c, e)
    assert abs(res.energy["balance_residual"]) < 1e-6
    assert res.periodicity_residual < 1e-8
    # the steady cycle moves: stick-stick and slip phases of both feet
    modes = set(res.mode.tolist())
    assert int(Mode.STICK) in modes and len(modes) >= 3
    assert res.S < 0  # phi1 leads (psi > 0): motion towards foot 1 (MODEL_NOTES)
    assert res.CoT_plus == pytest.approx(res.W_plus / (robot.M * robot.g * abs(res.S)), rel=1e-14)


def test_events_are_located_on_their_guards(gravity):
    robot = Robot.paper(mu1=0.36, mu2=0.41)
    model = Model(robot, gravity=gravity)
    stepper = HybridStepper(model, paper_torque(robot))
    res = stepper.run()
    assert res.success, res.message
    events = res.steady_events()
    kinds = {e.kind for e in events}
    assert "slip_to_stick" in kinds and any(k.startswith("slip_onset_") for k in kinds)
    Mg, L = robot.M * robot.g, robot.L
    for ev in events:
        assert abs(ev.guard) < 1e-9, ev
        before = {m.label: m for m in Mode}[ev.mode_before]
        # the guard of the mode before the event changes sign across it (bracket of 2e-10 in phase)
        seg = [s for s in stepper.segments
               if s.mode == before and s.points[0].t <= ev.t <= s.points[-1].t + 1e-12]
        assert seg, ev
        p = min(seg[-1].points, key=lambda pt: abs(pt.t - ev.t))
        vals = []
        for dt in (-1e-10, 1e-10):
            pt = stepper.solver.solve(ev.t + dt, p.x, seg[-1].q)
            vals.append(stepper.guards.values(before, pt.aux)[ev.guard_name])
        assert vals[0] > 0 > vals[1] or (abs(vals[0]) < 1e-9 and abs(vals[1]) < 1e-9), (ev, vals)
        # independent check of the physical guard at the event state
        pt = stepper.solver.solve(ev.t, p.x, seg[-1].q)
        ft, fn1, fn2 = pt.aux[AUX["ft"]], pt.aux[AUX["fn1"]], pt.aux[AUX["fn2"]]
        if ev.kind.startswith("slip_onset_"):
            i = int(ev.kind[-1])
            assert abs(abs(ft) - (robot.mu1 * fn1 if i == 1 else robot.mu2 * fn2)) < 1e-9 * Mg
        elif ev.kind == "slip_to_stick":
            # d has a stationary point: central difference of d along the slip branch
            h = 1e-5
            d = [stepper.solver.solve(ev.t + s * h, p.x, seg[-1].q).aux[AUX["d"]] for s in (-1, 1)]
            assert abs((d[1] - d[0]) / (2 * h)) < 1e-7 * L
        elif ev.kind == "slip_switch":
            assert abs(robot.mu1 * fn1 - robot.mu2 * fn2) < 1e-9 * Mg


def test_very_stiff_joints_reproduce_prescribed_angles(gravity):
    gait = Harmonic.from_degrees(90, 30, 45)
    robot = Robot.paper().with_stiffness_ratio(1e4)
    model = Model(robot, gravity=gravity)
    ref = simulate_angles(model, gait)
    res = simulate_torque(model, ReferenceTorque(gait, robot.k))
    assert ref.success and res.success, (ref.message, res.message)
    assert res.S == pytest.approx(ref.S, rel=1e-3)


def test_below_friction_threshold_nothing_moves_in_paper_convention():
    robot = Robot.paper().with_stiffness_ratio(0.05)
    res = simulate_torque(Model(robot, gravity="paper"), paper_torque(robot))
    assert res.success, res.message
    assert abs(res.S) < 1e-12 * robot.L
    assert res.events == [] and np.all(res.mode == int(Mode.STICK))


def test_below_friction_threshold_physical_robot_cannot_stand():
    """With the physical sign gravity destabilises the Pi shape: at k = 0.05 M g L no equilibrium
    near the reference posture keeps both joints above the ground, so the released start is rejected
    (MODEL_NOTES)."""
    robot = Robot.paper().with_stiffness_ratio(0.05)
    res = simulate_torque(Model(robot, gravity="physical"), paper_torque(robot))
    assert not res.success and res.status_name == "no_start"
    assert re.search("starting configuration: joint . at or below the ground",
                     res.message), res.message
    assert np.isnan(res.S) and res.events == [] and res.t.size == 0


def test_fold_is_reported_with_phase_mode_and_singular_jacobian():
    robot = Robot.paper().with_stiffness_ratio(0.3)
    model = Model(robot, gravity="physical")
    stepper = HybridStepper(model, paper_torque(robot))
    res = stepper.run()
    assert not res.success
    assert res.status == Status.FOLD
    assert "phase" in res.message and res.failure_mode in res.message
    assert res.events[-1].kind == "fold" and res.events[-1].t == res.failure_t
    assert res.failure_t is not None and 0 < res.failure_t
    x = np.array(res.extra["fold_x"])
    mode = {m.label: m for m in Mode}[res.failure_mode]
    seg = stepper.segments[-1]
    assert seg.mode == mode
    G, J = model.sym.system(x, stepper.ctx.torque(res.failure_t), seg.q, model.p)
    assert np.max(np.abs(np.asarray(G))) < 1e-10  # the fold point is an equilibrium ...
    s = np.linalg.svd(np.asarray(J), compute_uv=False)
    assert s[-1] / s[0] < 1e-8  # ... with a singular Jacobian
    # just before the fold the branch exists and its Jacobian is regular
    last = seg.points[-1]
    assert last.t < res.failure_t
    _, J0 = model.sym.system(last.x, stepper.ctx.torque(last.t), seg.q, model.p)
    s0 = np.linalg.svd(np.asarray(J0), compute_uv=False)
    assert s0[-1] / s0[0] > s[-1] / s[0]


def test_lift_off_is_a_status_not_an_exception(gravity):
    robot = Robot.paper().with_stiffness_ratio(10.0)
    res = simulate_torque(Model(robot, gravity=gravity), paper_torque(robot, A=60))
    assert res.status == Status.LIFT_OFF and not res.success
    assert "phase" in res.message and "lift off 2" in res.message
    assert math.isnan(res.S)
    last = res.events[-1]
    assert last.kind == "lift_off_2" and last.t == pytest.approx(res.failure_t, abs=0)
    assert abs(last.guard) < 1e-9  # f_n2/(M g) at the located lift-off
    # output runs up to the lift-off ...
    assert res.t[-1] == pytest.approx(res.failure_t, abs=1e-15)
    assert np.all(res.f_n2[:-1] > 0)  # ... through valid states
    assert abs(res.f_n2[-1]) < 1e-9 * robot.M * robot.g


def test_fold_location_does_not_depend_on_the_step():
    robot = Robot.paper().with_stiffness_ratio(0.3)
    model = Model(robot, gravity="physical")
    t_fold = []
    for h in (1 / 32, 1 / 64, 1 / 128):
        res = simulate_torque(model, paper_torque(robot), HybridOptions(max_step=h))
        assert res.status == Status.FOLD, res.message
        t_fold.append(res.failure_t)
    assert max(t_fold) - min(t_fold) < 1e-10


def _cot_reference():
    path = os.path.join(PAPER_DATA, "fig_cot_vs_amplitude.csv")
    if not os.path.exists(path):
        pytest.skip(f"paper data not found at {path}")
    with open(path) as fh:
        return list(csv.DictReader(fh))


@pytest.mark.parametrize("column,ratio,tol",
                         [("CoT_plus_large_k", 5.0, 0.03), ("CoT_plus_realistic_k", 2.74, 0.03),
                          ("CoT_plus_low_k", 0.3, 0.05)])
@pytest.mark.parametrize("amplitude", [20.0, 50.0])
def test_cot_matches_published_curve_in_paper_convention(column, ratio, tol, amplitude):
    rows = _cot_reference()
    A = np.array([float(r["A_deg"]) for r in rows])
    j = int(np.argmin(np.abs(A - amplitude)))
    published = float(rows[j][column])
    robot = Robot.paper().with_stiffness_ratio(ratio)
    res = simulate_torque(Model(robot, gravity="paper"), paper_torque(robot, A=A[j]))
    assert res.success, res.message
    assert res.CoT_plus == pytest.approx(published, rel=tol)


def test_reversing_psi_reverses_S_and_psi_zero_does_not_move(gravity):
    robot = Robot.paper()
    model = Model(robot, gravity=gravity)
    fwd = simulate_torque(model, paper_torque(robot, psi=45))
    bwd = simulate_torque(model, paper_torque(robot, psi=-45))
    sym = simulate_torque(model, paper_torque(robot, psi=0))
    assert fwd.success and bwd.success and sym.success
    assert abs(fwd.S) > 1e-3 * robot.L
    assert bwd.S == pytest.approx(-fwd.S, rel=1e-9)
    assert abs(sym.S) < 1e-12 * robot.L


def test_S_does_not_depend_on_output_grid_or_event_tolerance():
    robot = Robot.paper()
    model = Model(robot)
    torque = paper_torque(robot)
    base = simulate_torque(model, torque)
    grid = simulate_torque(model, torque, t_eval=np.linspace(0, 1, 1001))
    fine = simulate_torque(model, torque, HybridOptions(max_step=1 / 200, event_xtol=1e-14))
    assert base.success and grid.success and fine.success
    assert grid.t.size == 1001
    assert grid.S == pytest.approx(base.S, rel=1e-8)
    assert fine.S == pytest.approx(base.S, rel=1e-8)
    assert fine.W_plus == pytest.approx(base.W_plus, rel=1e-6)
    for a, b in zip(base.steady_events(), fine.steady_events()):
        assert a.kind == b.kind and a.t == pytest.approx(b.t, abs=1e-10)


def test_general_periodic_inputs_are_accepted():
    robot = Robot.paper()
    model = Model(robot)
    harmonic = paper_torque(robot)
    base = simulate_torque(model, harmonic)
    n = 512
    tk = np.arange(n) / n
    samples = harmonic(tk)
    fourier = FourierSeries.fit(samples, order=3)
    spline = PeriodicSpline(tk, samples)
    plain = CallableSignal(lambda t: robot.k * (Harmonic.from_degrees(90, 30, 45)(t) - math.pi))
    linear = PeriodicLinear(tk, samples)
    np.testing.assert_allclose(linear(tk + 0.5 / n), 0.5 * (samples + np.roll(samples, -1, axis=1)),
                               atol=1e-15)
    for u, tol in ((fourier, 1e-10), (spline, 1e-7), (plain, 1e-8), (linear, 1e-4)):
        res = simulate_torque(model, u)
        assert res.success, res.message
        assert res.S == pytest.approx(base.S, rel=tol), type(u).__name__


def test_bad_starting_configuration_is_rejected():
    robot = Robot.paper()
    torque = ReferenceTorque(Harmonic.from_degrees(30, 5, 45, gamma2_deg=45), robot.k)
    res = simulate_torque(Model(robot), torque)
    assert res.status == Status.NO_START and "starting configuration" in res.message


def test_grazing_friction_limit_keeps_the_mode():
    """psi = 180 deg, gamma = 80 deg (physical): in stick-stick f_t touches foot 2's friction limit
    and turns back; the stepper must stay in stick-stick (a graze event), not report an
    inconsistency."""
    robot = Robot.paper()
    stepper = HybridStepper(Model(robot), paper_torque(robot, gamma=80, psi=180))
    res = stepper.run(t_eval=np.linspace(0, 1, 20001))
    assert res.success, res.message
    Mg = robot.M * robot.g
    margin = np.minimum(robot.mu1 * res.f_n1, robot.mu2 * res.f_n2) - np.abs(res.f_t)
    assert -1e-9 * Mg <= margin.min() < 1e-6 * Mg  # the friction limit is touched, not crossed
    assert np.all(res.mode == int(Mode.STICK))
    for ev in res.steady_events():  # a touch that round-off shows as a crossing is a graze
        assert ev.kind.startswith("graze_") and ev.mode_before == ev.mode_after == "stick-stick"
        assert abs(ev.guard) < 1e-9
    assert abs(res.S) < 1e-12 * robot.L  # the paper: S vanishes as psi -> 180 deg


def test_output_phases_go_to_the_first_segment_that_holds_them():
    """The one-search assignment of sorted output phases to consecutive segments
    (event_state.phase_owners) against the rule itself, phase by phase: the first segment whose
    [first, last] point phases hold it (boundaries, phases on no segment, one-point segments and
    unsorted phases included)."""
    from types import SimpleNamespace

    from ocp_crawl.sim.event_state import phase_owners

    rng = np.random.default_rng(7)
    for _ in range(200):
        cuts = np.sort(rng.choice(np.linspace(0, 2, 41), size=rng.integers(2, 8), replace=False))
        segs = [SimpleNamespace(points=[SimpleNamespace(t=float(a)), SimpleNamespace(t=float(b))])
                for a, b in zip(cuts[:-1], cuts[1:])]
        # a one-point segment at a boundary (an event followed by another at once)
        if rng.random() < 0.3:
            k = int(rng.integers(0, len(segs)))
            segs.insert(k, SimpleNamespace(points=[segs[k].points[0]]))
        te = np.unique(np.concatenate([rng.uniform(-0.2, 2.2, 30), rng.choice(cuts, 3)]))
        for phases in (te, rng.permutation(te)):
            got = {id(seg): ts.tolist() for seg, ts in phase_owners(segs, phases)}
            want = {}
            for t in phases.tolist():
                seg = next((s for s in segs if s.points[0].t <= t <= s.points[-1].t), None)
                if seg is not None:
                    want.setdefault(id(seg), []).append(t)
            assert got == want


def test_cycle_ending_a_rounding_error_short_of_its_phase():
    """A gait whose steady cycle ends 2e-16 before t = 2 (an event found at 1.9999999999999998)
    reports its metrics (it raised IndexError), and they continue those of a neighbouring psi (a
    limit, not a stored value)."""
    model = Model(Robot.paper(), gravity="physical")
    kw = dict(gamma1_deg=91.6456826619305, gamma2_deg=90.44124551349091, A1_deg=27.92683794884863,
              A2_deg=29.296200647806213)
    res = simulate_torque(model,
                          ReferenceTorque(Harmonic.from_degrees(psi_deg=180, **kw), model.robot.k))
    near = simulate_torque(model,
                           ReferenceTorque(Harmonic.from_degrees(psi_deg=179.999, **kw),
                                           model.robot.k))
    assert res.success and near.success, (res.message, near.message)
    assert abs(res.W_plus - near.W_plus) <= 1e-5 * abs(near.W_plus)
    assert abs(res.S - near.S) <= 1e-5 * abs(near.S)
