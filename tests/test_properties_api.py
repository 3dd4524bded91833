"""Property-based tests (hypothesis) of the prescribed-angle simulator, the input signals and the
problem files (issue 6, part 1).

The number of examples per property comes from ``OCP_CRAWL_HYPOTHESIS_EXAMPLES`` (default 25, so
that the file runs in well under a minute); a large run::

    OCP_CRAWL_HYPOTHESIS_EXAMPLES=500 python -m pytest -q tests/test_properties_api.py --hypothesis-show-statistics

The statistics list the outcomes (``event``) of the random runs: success, failure status, input rejected.
Every assertion holds for every example, whatever the seed.
"""
from __future__ import annotations

import json
import math
import os
import re
import tomllib

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, event, given, note, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from ocp_crawl import (CallableSignal, FourierSeries, Harmonic, Mode, Model, PeriodicLinear, PeriodicPchip,
                       PeriodicSpline, ReferenceTorque, Robot, Status)
from ocp_crawl.sim.angles import TIE, simulate_angles
from ocp_crawl.problem import (SCHEMA, SECTIONS, Problem, ProblemError, problem_from_dict,
                               run_problem)
from ocp_crawl.problem.problem import MAX_STIFFNESS_RATIO
from ocp_crawl.status import STATUS_MESSAGES

EXAMPLES = int(os.environ.get("OCP_CRAWL_HYPOTHESIS_EXAMPLES", "25"))
#: expensive properties (one or more simulations per example)
#: (a small fixed set by default, as the README says, so that CI is deterministic; random with the variable set)
DERANDOMIZE = "OCP_CRAWL_HYPOTHESIS_EXAMPLES" not in os.environ
SIMS = settings(max_examples=EXAMPLES, deadline=None, derandomize=DERANDOMIZE,
                suppress_health_check=[HealthCheck.too_slow])
#: cheap properties (microseconds to milliseconds per example) get more examples for the same time
CHEAP = settings(max_examples=4 * EXAMPLES, deadline=None, derandomize=DERANDOMIZE,
                 suppress_health_check=[HealthCheck.too_slow])

EPS = np.finfo(float).eps
DEG = math.pi / 180


# ============================================================================================
# strategies: robots and periodic joint angles
# ============================================================================================
@st.composite
def robots(draw):
    """Physical robots: M 5 g - 5 kg, L 2 cm - 1 m, beta 0.2-5, k 0.05-100 M g L, mu 0.05-2, g 1-20."""
    M = draw(st.floats(0.005, 5.0))
    L = draw(st.floats(0.02, 1.0))
    beta = draw(st.floats(0.2, 5.0))
    g = draw(st.floats(1.0, 20.0))
    ratio = 10.0 ** draw(st.floats(math.log10(0.05), 2.0))
    mu1 = draw(st.floats(0.05, 2.0))
    mu2 = draw(st.one_of(st.just(mu1), st.floats(0.05, 2.0)))
    return Robot(M=M, L=L, beta=beta, k=ratio * M * g * L, mu1=mu1, mu2=mu2, g=g)


models = st.builds(Model, robots(), st.sampled_from(["physical", "paper"]))
gammas = st.floats(40.0, 175.0)  # nominal joint angle [deg]; pi = flat, legs down below it
amplitudes = st.floats(0.0, 50.0)  # [deg]


@st.composite
def harmonic_gaits(draw):
    g1 = draw(gammas)
    g2 = draw(st.one_of(st.just(g1), gammas))
    a1 = draw(amplitudes)
    a2 = draw(st.one_of(st.just(a1), amplitudes))
    psi = draw(st.one_of(st.floats(-180.0, 180.0), st.sampled_from([0.0, 45.0, -90.0, 180.0])))
    return Harmonic.from_degrees(psi_deg=psi, gamma1_deg=g1, gamma2_deg=g2, A1_deg=a1, A2_deg=a2)


@st.composite
def fourier_gaits(draw):
    order = draw(st.integers(1, 4))
    g = [draw(gammas), draw(gammas)]
    amp = draw(amplitudes) * DEG
    coef = st.floats(-1.0, 1.0)
    a = np.array([[draw(coef) * amp / n for n in range(1, order + 1)] for _ in range(2)])
    b = np.array([[draw(coef) * amp / n for n in range(1, order + 1)] for _ in range(2)])
    return FourierSeries(np.radians(g), a, b)


@st.composite
def knots(draw, n_min=3, n_max=9):
    """Strictly increasing knots in [0, 1), spacing at least 1/25 of a cycle."""
    n = draw(st.integers(n_min, n_max))
    w = np.array([draw(st.floats(0.2, 1.0)) for _ in range(n)])
    total = w.sum()
    t = np.concatenate([[0.0], np.cumsum(w[:-1])]) / total
    t0 = draw(st.floats(0.0, 0.999)) * w[-1] / total
    return t + t0


@st.composite
def sampled_gaits(draw):
    kind = draw(st.sampled_from([PeriodicSpline, PeriodicPchip, PeriodicLinear]))
    t = draw(knots())
    g = np.radians([draw(gammas), draw(gammas)])
    amp = draw(amplitudes) * DEG
    v = g[:, None] + amp * np.array([[draw(st.floats(-1.0, 1.0)) for _ in t] for _ in range(2)])
    return kind(t, v)


angle_signals = st.one_of(harmonic_gaits(), fourier_gaits(), sampled_gaits())


# ============================================================================================
# independent checks of a prescribed-angle result
# ============================================================================================
GUARDS = ("d", "fn1", "fn2", "zj1", "zj2")
#: fine grid for the independent checks (not a multiple of the simulator's scan of 512 phases)
FINE = 3000


def guard_scales(robot):
    return {"d": robot.L, "fn1": robot.M * robot.g, "fn2": robot.M * robot.g, "zj1": robot.L, "zj2": robot.L}


def valid_config(kin) -> np.ndarray:
    return np.all([kin[n] > 0 for n in GUARDS], axis=0)


def run_prescribed(model: Model, angles):
    """simulate_angles, or None when the input is rejected up front; a rejection must be justified."""
    try:
        return simulate_angles(model, angles)
    except ValueError as exc:
        msg = str(exc)
        assert "\n" not in msg and msg.startswith("prescribed configuration at t = 0:"), msg
        # documented rejection: the start configuration has a foot off the ground, a joint on it, or d <= 0
        assert not valid_config(model.kinematics(angles(0.0))), msg
        event("rejected: no valid start configuration")
        return None


def slip_weight(model: Model, kin) -> np.ndarray:
    """Share of d' taken by foot 1: 1 if its friction limit is the smaller, 0 if foot 2's, 1/2 for a tie."""
    r = model.robot
    h = (r.mu1 * kin["fn1"] - r.mu2 * kin["fn2"]) / (r.M * r.g)
    return np.where(np.abs(h) <= TIE, 0.5, np.where(h < 0, 1.0, 0.0))


def displacement_oracle(model: Model, angles, n: int = FINE) -> tuple[float, float]:
    """S = -integral of w dd (foot 1 moves by -dd when it slips) on a fine grid, and its error bound:
    |dd| of every interval in which the slipping foot changes (elsewhere the sum is exact)."""
    t = np.linspace(0.0, 1.0, 2 * n + 1)
    kin = model.kinematics(angles(t))
    w = slip_weight(model, kin)
    d = kin["d"]
    dd = d[2::2] - d[:-2:2]
    wm = w[1::2]
    switching = (w[:-2:2] != wm) | (w[2::2] != wm)
    return -float(np.sum(wm * dd)), float(np.sum(np.abs(dd[switching])))


def dissipation_oracle(model: Model, angles, n: int = FINE) -> tuple[float, float]:
    """Integral over the cycle of min(mu1 f_n1, mu2 f_n2) |d'| by Gauss-Legendre panels between
    the kinks (d' = 0, equal friction limits, knots of a sampled input) located here; the error
    estimate is the change from halving the panels."""
    r = model.robot

    def parts(t):
        t = np.atleast_1d(t)
        kin = model.kinematics(angles(t))
        dphi = angles.derivative(t).reshape(2, -1)
        ddot = kin["grad_d1"] * dphi[0] + kin["grad_d2"] * dphi[1]
        h = r.mu1 * kin["fn1"] - r.mu2 * kin["fn2"]
        return ddot, h, np.minimum(r.mu1 * kin["fn1"], r.mu2 * kin["fn2"]) * np.abs(ddot)

    t = np.linspace(0.0, 1.0, n + 1)
    ddot, h, _ = parts(t)
    kinks = list(np.asarray(getattr(angles, "t_knots", ()), float))
    for v, i in ((ddot, 0), (h, 1)):
        for j in np.nonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)[0]:
            kinks.append(brentq(lambda x: float(parts(x)[i][0]), t[j], t[j + 1], xtol=1e-15))
    edges = np.unique(np.concatenate([[0.0, 1.0], np.clip(kinks, 0.0, 1.0)]))

    def gauss(panels_per_cycle):
        x, w = np.polynomial.legendre.leggauss(8)
        nodes, weights = [], []
        for lo, hi in zip(edges[:-1], edges[1:]):
            e = np.linspace(lo, hi, max(1, int(np.ceil((hi - lo) * panels_per_cycle))) + 1)
            mid, half = 0.5 * (e[1:] + e[:-1])[:, None], 0.5 * (e[1:] - e[:-1])[:, None]
            nodes.append((mid + half * x).ravel())
            weights.append((half * w).ravel())
        return float(np.sum(np.concatenate(weights) * parts(np.concatenate(nodes))[2]))

    coarse, fine = gauss(64), gauss(128)
    return fine, abs(fine - coarse)


def check_success(model: Model, angles, res) -> None:
    r = model.robot
    Mg, L = r.M * r.g, r.L
    torque_scale = r.MgL + r.k
    n = res.t.size
    # shapes and no NaN anywhere
    assert res.success and res.status == Status.SUCCESS and res.message
    assert res.phi.shape == (2, n) and res.tau.shape == (2, n)
    for name in ("theta", "d", "x1", "x2", "f_t", "f_n1", "f_n2", "mode"):
        assert getattr(res, name).shape == (n,), name
    for name, arr in res.arrays().items():
        assert np.all(np.isfinite(arr)), name
    for name in ("S", "W_plus", "periodicity_residual"):
        assert math.isfinite(getattr(res, name)), name
    assert np.all(np.isfinite(res.W_plus_joint))
    assert all(v is None or math.isfinite(v) for v in res.summary()["energy"].values())
    assert set(res.energy) >= {"input_work", "potential_change", "dissipation", "balance_residual"}
    assert all(math.isfinite(v) for v in res.energy.values())
    # the default output phases cover the cycle, switching instants included
    assert res.t[0] == 0.0 and res.t[-1] == 1.0 and np.all(np.diff(res.t) > 0)
    for ev in res.events:
        assert ev.kind in EVENT_KINDS and 0 <= ev.t <= 1
        assert np.min(np.abs(res.t - ev.t)) == 0.0
    # the angles are the prescribed ones
    np.testing.assert_allclose(res.phi, angles(res.t), rtol=0, atol=1e-14)
    kin = model.kinematics(res.phi)
    # contact: positive normal forces, joints above the ground, feet apart, at the samples ...
    for name in GUARDS:
        assert np.all(kin[name] > 0), name
    np.testing.assert_allclose(res.f_n1, kin["fn1"], rtol=1e-13, atol=1e-13 * Mg)
    np.testing.assert_allclose(res.d, kin["d"], rtol=1e-13, atol=1e-13 * L)
    # ... and on a fine grid of the whole cycle (a loss of contact between the scan phases is a failure)
    fine = model.kinematics(angles(np.linspace(0.0, 1.0, FINE + 1)))
    for name in GUARDS:
        assert np.min(fine[name]) > 0, f"{name} reaches {np.min(fine[name]):.3g} although the run succeeded"
    # joint equilibrium with the holding torques, residual relative to the torque scale
    for j in range(n):
        F = model.equilibrium_residual(res.phi[:, j], res.tau[:, j], res.f_t[j])
        assert np.max(np.abs(F)) <= 1e-11 * torque_scale, (j, F)
    # Coulomb: |f_t| on the friction limit of the slipping foot, which is the smaller limit
    lim1, lim2 = r.mu1 * res.f_n1, r.mu2 * res.f_n2
    # (with both feet slipping, |mu1 f_n1 - mu2 f_n2| <= TIE M g: a tie in the model's definition)
    tie = np.array([Mode(int(m)).foot == 3 for m in res.mode])
    tol = 1e-12 * np.maximum(Mg, np.maximum(lim1, lim2)) + np.where(tie, TIE * Mg, 0.0)
    assert np.all(np.abs(res.f_t) <= np.minimum(lim1, lim2) + tol)
    modes = [Mode(int(m)) for m in res.mode]
    slip = np.array([m.foot != 0 for m in modes])
    slip_lim = np.array([lim1[j] if m.foot in (1, 3) else lim2[j] for j, m in enumerate(modes)])
    assert np.all(np.abs(np.abs(res.f_t[slip]) - slip_lim[slip]) <= 1e-12 * np.maximum(Mg, slip_lim[slip]))
    # friction opposes the slip: f_t d' >= 0, d' from central differences of the kinematics
    h = 1e-7
    ddot = (model.kinematics(angles(res.t + h))["d"] - model.kinematics(angles(res.t - h))["d"]) / (2 * h)
    smooth = np.ones(n, bool)
    for knot in getattr(angles, "t_knots", ()):  # the derivative of a sampled input may jump at its knots
        smooth &= np.abs((res.t - knot + 0.5) % 1.0 - 0.5) > 2 * h
    clear = smooth & (np.abs(ddot) > 1e-5 * L * (1 + np.max(np.abs(ddot)) / L))
    sig = np.array([m.sigma for m in modes])
    assert np.all(sig[clear] == np.sign(ddot[clear]))
    # stick-stick only where the angles hold still (d' = 0 on a stretch)
    assert np.all(np.abs(ddot[~slip & smooth]) <= 1e-6 * L)
    assert np.all(res.f_t[clear] * ddot[clear] >= 0)
    # feet: x2 - x1 = d; the sticking foot stays; both feet advance by S over the cycle (periodic)
    np.testing.assert_allclose(res.x2 - res.x1, res.d, rtol=0, atol=1e-12 * L)
    assert res.d[-1] == pytest.approx(res.d[0], abs=1e-12 * L)
    assert res.x1[-1] - res.x1[0] == pytest.approx(res.S, abs=1e-12 * L)
    assert res.x2[-1] - res.x2[0] == pytest.approx(res.S, abs=1e-12 * L)
    for j in range(n - 1):
        if res.mode[j] == res.mode[j + 1] and modes[j].foot in (0, 1, 2):
            for stuck in [(res.x1, res.x2)[i] for i in (0, 1) if modes[j].foot != i + 1]:
                assert stuck[j + 1] == stuck[j]
    assert res.periodicity_residual <= 1e-12
    np.testing.assert_allclose(angles(1.0), angles(0.0), rtol=0, atol=1e-12)
    # S against an independent integration of the slipping foot's motion
    S, bound = displacement_oracle(model, angles)
    assert abs(res.S - S) <= bound + 1e-10 * L, (res.S, S, bound)
    # energy per cycle: W_in = Delta V + dissipation, Delta V = 0 (periodic), W+ >= W_in
    e = res.energy
    scale = max(abs(e["input_work"]), e["dissipation"], e["gross_work"], 1e-12 * r.MgL, 1e-300)
    assert e["gross_work"] >= abs(e["input_work"]) * (1 - 1e-12)
    assert abs(e["balance_residual"]) <= 1e-9, e
    assert e["balance_residual"] == pytest.approx(
        (e["input_work"] - e["potential_change"] - e["dissipation"]) / scale, rel=1e-9, abs=1e-15)
    assert abs(e["potential_change"]) <= 1e-12 * torque_scale
    assert e["dissipation"] >= 0
    assert np.all(res.W_plus_joint >= -1e-12 * scale)
    assert res.W_plus == pytest.approx(float(np.sum(res.W_plus_joint)), rel=1e-12, abs=1e-300)
    assert res.W_plus >= e["input_work"] - 1e-9 * scale
    diss, err = dissipation_oracle(model, angles)
    assert e["dissipation"] == pytest.approx(diss, rel=1e-9, abs=10 * err + 1e-12 * r.M * r.g * r.L)
    # cost of transport
    if abs(res.S) > 1e-12 * L:
        assert res.CoT_plus == pytest.approx(res.W_plus / (Mg * abs(res.S)), rel=1e-12)
    else:
        assert res.CoT_plus == math.inf


EVENT_KINDS = ("slip_reversal", "slip_switch", "slip_to_stick", "slip_onset_1", "slip_onset_2", "slip_onset_both")
FAILURE_KINDS = {Status.LIFT_OFF: ("lift_off_1", "lift_off_2"), Status.FEET_CROSSED: ("feet_crossed",),
                 Status.JOINT_ON_GROUND: ("joint_1_on_ground", "joint_2_on_ground")}


def check_failure(model: Model, angles, res) -> None:
    r = model.robot
    status = Status(res.status)
    assert not res.success and status in FAILURE_KINDS
    assert res.message.startswith(STATUS_MESSAGES[status]) and "phase" in res.message
    assert "\n" not in res.message
    tf = res.failure_t
    assert tf is not None and 0 < tf <= 1 and math.isfinite(tf)
    assert res.failure_mode in {m.label for m in Mode}
    kind = res.events[-1].kind
    assert kind in FAILURE_KINDS[status] and res.events[-1].t == tf
    json.dumps(res.summary(), allow_nan=False)  # a failure's summary is valid JSON too
    # the reported failure is real: its guard vanishes at the failure phase ...
    kin = model.kinematics(angles(tf))
    sc = guard_scales(r)
    if status == Status.LIFT_OFF:
        i = kind[-1]
        assert abs(kin[f"fn{i}"]) <= 1e-8 * sc["fn1"], kin[f"fn{i}"]
    elif status == Status.JOINT_ON_GROUND:
        i = kind.split("_")[1]
        assert abs(kin[f"zj{i}"]) <= 1e-8 * r.L, kin[f"zj{i}"]
    else:
        assert abs(kin["d"]) <= 1e-6 * r.L, kin["d"]
    # ... and it is the first one: the configuration is valid at every phase before it
    before = np.linspace(0.0, tf, FINE + 1)[:-1]
    before = before[before < tf - 1e-6]
    assert np.all(valid_config(model.kinematics(angles(before))))


def check_outcome(model: Model, angles, res) -> str:
    """Check a result (None: rejected input) and return its outcome name."""
    if res is None:
        return "rejected"
    note(repr(res))
    if res.success:
        check_success(model, angles, res)
    else:
        check_failure(model, angles, res)
    event(f"status: {res.status_name}")
    return res.status_name


# ============================================================================================
# 1. prescribed angles
# ============================================================================================
@SIMS
@given(model=models, angles=angle_signals)
def test_prescribed_random_robots_and_gaits(model, angles):
    """Success with every invariant holding, a documented failure status, or a justified rejection."""
    check_outcome(model, angles, run_prescribed(model, angles))


def mirrored(model: Model, angles):
    """The mirror image: joints and feet swapped (x -> -x)."""
    r = model.robot
    m = Model(r.replace(mu1=r.mu2, mu2=r.mu1), gravity=model.gravity)
    if isinstance(angles, Harmonic):
        return m, Harmonic(angles.gamma2, angles.gamma1, angles.A2, angles.A1, -angles.psi)
    return m, FourierSeries(angles.a0[::-1], angles.a[::-1], angles.b[::-1])


def reversed_in_time(angles):
    """phi(-t), as the same kind of signal (a harmonic one half a cycle later, which changes no cycle total)."""
    if isinstance(angles, Harmonic):
        return Harmonic(angles.gamma1, angles.gamma2, angles.A1, angles.A2, -angles.psi)
    return FourierSeries(angles.a0, angles.a, -angles.b)


def shifted(angles: FourierSeries, s: float) -> FourierSeries:
    """phi(t + s)."""
    n = np.arange(1, angles.a.shape[1] + 1)
    c, sn = np.cos(2 * np.pi * n * s), np.sin(2 * np.pi * n * s)
    return FourierSeries(angles.a0, angles.a * c + angles.b * sn, angles.b * c - angles.a * sn)


@SIMS
@given(model=models, angles=st.one_of(harmonic_gaits(), fourier_gaits()))
def test_prescribed_mirror_and_time_reversal(model, angles):
    """Mirror image: S -> -S with the same status and failure phase (foot and joint labels swapped).
    Time reversal (for the harmonic gait: psi -> -psi): S -> -S, the slipping foot depends on the
    configuration only; the gait fails or not together (the same configurations are visited)."""
    L = model.robot.L
    res = run_prescribed(model, angles)
    check_outcome(model, angles, res)
    mm, ma = mirrored(model, angles)
    mir = run_prescribed(mm, ma)
    assert (mir is None) == (res is None)
    if res is not None:
        check_outcome(mm, ma, mir)
        assert mir.status == res.status
        if res.success:
            assert mir.S == pytest.approx(-res.S, abs=1e-10 * L)
            assert mir.W_plus == pytest.approx(res.W_plus, rel=1e-8, abs=1e-12 * model.robot.MgL)
        else:
            assert mir.failure_t == pytest.approx(res.failure_t, abs=1e-8)
            swap = str.maketrans("12", "21")
            t = np.linspace(0.0, 1.0, 65)
            own_mirror = mm == model and np.array_equal(ma(t), angles(t))
            if not own_mirror:  # a mirror-symmetric problem is its own mirror: no label to swap
                assert mir.events[-1].kind == res.events[-1].kind.translate(swap)
    ra = reversed_in_time(angles)
    rev = run_prescribed(model, ra)
    if res is not None and rev is not None:
        assert rev.success == res.success
        if res.success:
            assert rev.S == pytest.approx(-res.S, abs=1e-10 * L)
    elif res is not None or rev is not None:
        # one start configuration is invalid: it lies on the other run's cycle, which cannot succeed
        assert not (res or rev).success


@SIMS
@given(model=models, angles=fourier_gaits(), s=st.floats(0.0, 1.0))
def test_prescribed_phase_shift_and_harmonic_equivalence(model, angles, s):
    """S per cycle does not depend on where the cycle starts; a Fourier series equal to a harmonic
    gait gives the harmonic gait's result."""
    res = run_prescribed(model, angles)
    sh = shifted(angles, s)
    res_s = run_prescribed(model, sh)
    if res is not None and res_s is not None:
        assert res_s.success == res.success
        if res.success:
            assert res_s.S == pytest.approx(res.S, abs=1e-10 * model.robot.L)
            assert res_s.W_plus == pytest.approx(res.W_plus, rel=1e-8, abs=1e-12 * model.robot.MgL)
    # first harmonic only: the same gait written as a Harmonic
    a, b = angles.a[:, 0], angles.b[:, 0]
    A = np.hypot(a, b)
    ph = np.arctan2(a, b)  # a cos + b sin = A sin(w + ph)
    first = FourierSeries(angles.a0, angles.a[:, :1], angles.b[:, :1])
    # Harmonic: sin(w + psi/2) for joint 1 and sin(w - psi/2) for joint 2: shift the phase by the mean
    shift = 0.5 * (ph[0] + ph[1]) / (2 * np.pi)
    harm = Harmonic(angles.a0[0], angles.a0[1], A[0], A[1], ph[0] - ph[1])
    rf = run_prescribed(model, shifted(first, -shift))
    rh = run_prescribed(model, harm)
    if rf is not None and rh is not None:
        assert rf.status == rh.status
        if rh.success:
            assert rf.S == pytest.approx(rh.S, abs=1e-10 * model.robot.L)
            np.testing.assert_allclose(rf.phi, rh.phi, rtol=0, atol=1e-12)
        else:
            assert rf.failure_t == pytest.approx(rh.failure_t, abs=1e-8)


# ============================================================================================
# 2. input signals
# ============================================================================================
@st.composite
def fourier_series(draw, max_order=5):
    order = draw(st.integers(0, max_order))
    c = st.floats(-3.0, 3.0)
    a0 = [draw(c), draw(c)]
    a = [[draw(c) for _ in range(order)] for _ in range(2)]
    b = [[draw(c) for _ in range(order)] for _ in range(2)]
    return FourierSeries(a0, np.array(a).reshape(2, order), np.array(b).reshape(2, order))


@st.composite
def sampled_signals(draw):
    kind = draw(st.sampled_from([PeriodicSpline, PeriodicPchip, PeriodicLinear]))
    t = draw(knots(3, 12))
    v = np.array([[draw(st.floats(-3.0, 3.0)) for _ in t] for _ in range(2)])
    return kind(t, v)


plain_signals = st.one_of(
    st.builds(Harmonic, st.floats(-4, 4), st.floats(-4, 4), st.floats(0, 3), st.floats(0, 3), st.floats(-7, 7)),
    fourier_series(), sampled_signals())
signals = st.one_of(plain_signals, st.builds(ReferenceTorque, plain_signals, st.floats(1e-3, 1e3)))


def signal_scales(u):
    """Largest |u|, |u'| and (finite differences of u') |u''| on a grid of the cycle."""
    t = np.linspace(0.0, 1.0, 4001)
    du = u.derivative(t)
    return (float(np.max(np.abs(u(t)))) + 1.0, float(np.max(np.abs(du))),
            float(np.max(np.abs(np.diff(du, axis=1)))) * 4000)


def near_knot(u, t, dist) -> bool:
    """t within dist of a knot of a piecewise-linear input (where its derivative jumps)."""
    sampled = getattr(u, "reference", u)
    if not isinstance(sampled, PeriodicLinear):
        return False
    return bool(np.min(np.abs((t - sampled.t_knots + 0.5) % 1.0 - 0.5)) <= dist)


@CHEAP
@given(u=signals, t=st.floats(-5.0, 5.0), k=st.integers(-3, 3))
def test_signal_periodic(u, t, k):
    su, sdu, sddu = signal_scales(u)
    rounding = 8 * EPS * (abs(t) + abs(k) + 2)  # round-off of the phase t + k
    np.testing.assert_allclose(u(t + k), u(t), rtol=0, atol=1e-12 * su + rounding * sdu)
    if not near_knot(u, t, 1e-9):
        np.testing.assert_allclose(u.derivative(t + k), u.derivative(t), rtol=0, atol=1e-12 * (sdu + 1) + rounding * sddu)


@CHEAP
@given(u=signals, t=st.floats(0.0, 1.0))
def test_signal_derivative_matches_finite_differences(u, t):
    su, sdu, sddu = signal_scales(u)
    h = 1e-6
    # piecewise linear: the derivative is exact between knots, undefined at them
    assume(not near_knot(u, t, 2 * h))
    fd = (u(t + h) - u(t - h)) / (2 * h)
    # central differences: h^2/6 |u'''| for smooth signals, h |u''| across a knot of a C1 spline
    tol = 2 * h * sddu + 10 * EPS * su / h + 1e-9 * sdu
    np.testing.assert_allclose(u.derivative(t), fd, rtol=0, atol=tol)


@CHEAP
@given(u=signals, ts=st.lists(st.floats(-3.0, 3.0), min_size=0, max_size=20))
def test_signal_vectorised_equals_scalar(u, ts):
    ts = np.array(ts, float)
    su, sdu, _ = signal_scales(u)
    for f, scale in ((u, su), (u.derivative, sdu + 1)):
        U = f(ts)
        assert U.shape == (2, ts.size)
        for j, tj in enumerate(ts):
            for arg in (float(tj), np.float64(tj), np.array(tj)):
                v = f(arg)
                assert np.shape(v) == (2,)
                np.testing.assert_allclose(v, U[:, j], rtol=0, atol=4 * EPS * scale)
    assert u(0).shape == (2,) and u(np.array([0.0, 0.5])).shape == (2, 2)


@CHEAP
@given(u=fourier_series(), extra=st.integers(0, 6))
def test_fourier_fit_reproduces_a_sampled_series(u, extra):
    order = u.a.shape[1]
    n = 2 * order + 1 + extra
    samples = u(np.arange(n) / n)
    fit = FourierSeries.fit(samples, order)
    scale = 1.0 + np.max(np.abs(np.concatenate([u.a0, u.a.ravel(), u.b.ravel()])))
    np.testing.assert_allclose(fit.a0, u.a0, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(fit.a, u.a, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(fit.b, u.b, rtol=0, atol=1e-12 * scale)
    t = np.linspace(-1, 2, 37)
    np.testing.assert_allclose(fit(t), u(t), rtol=0, atol=1e-11 * scale)


@CHEAP
@given(n=st.integers(1, 12).map(lambda m: 2 * m + 1), v=st.lists(st.floats(-3, 3), min_size=50, max_size=50))
def test_fourier_fit_interpolates_odd_samples(n, v):
    """With N odd samples, the fit of order (N - 1)/2 passes through every sample (discrete Fourier
    interpolation), e.g. samples of a spline."""
    samples = np.array(v[:2 * n]).reshape(2, n)
    fit = FourierSeries.fit(samples, (n - 1) // 2)
    np.testing.assert_allclose(fit(np.arange(n) / n), samples, rtol=0, atol=1e-12 * (1 + np.max(np.abs(samples))))


def _corrupt(draw, arr, value):
    arr = np.array(arr, float)
    idx = tuple(draw(st.integers(0, s - 1)) for s in arr.shape)
    arr[idx] = value
    return arr


BAD_NUMBERS = st.sampled_from([math.nan, math.inf, -math.inf])


@st.composite
def invalid_constructions(draw):
    """(constructor call, name of the argument the message must name)."""
    which = draw(st.sampled_from(["fourier_nan", "fourier_shape", "knots_nan", "knots_order", "knots_range",
                                  "knots_few", "values_nan", "values_shape", "harmonic", "torque_k"]))
    order = draw(st.integers(1, 3))
    a0, a, b = np.zeros(2), np.ones((2, order)), np.ones((2, order))
    kind = draw(st.sampled_from([PeriodicSpline, PeriodicPchip, PeriodicLinear]))
    t = np.array([0.0, 0.25, 0.5, 0.75])
    v = np.ones((2, 4))
    if which == "fourier_nan":
        arg = draw(st.sampled_from(["a0", "a", "b"]))
        bad = {"a0": a0, "a": a, "b": b}
        bad[arg] = _corrupt(draw, bad[arg], draw(BAD_NUMBERS))
        return (lambda: FourierSeries(**bad)), arg
    if which == "fourier_shape":
        arg = draw(st.sampled_from(["a0", "a", "b"]))
        bad = {"a0": a0, "a": a, "b": b}
        bad[arg] = np.ones(draw(st.sampled_from([(3,), (1,), (3, order), (2, order + 1), (2, 2, order)])))
        if arg == "a0" and bad[arg].size == 2:
            bad[arg] = np.ones(3)
        return (lambda: FourierSeries(**bad)), arg
    if which == "knots_nan":
        return (lambda: kind(_corrupt(draw, t, draw(BAD_NUMBERS)), v)), "t_knots"
    if which == "knots_order":
        i = draw(st.integers(0, 2))
        tt = t.copy()
        tt[i], tt[i + 1] = tt[i + 1], (tt[i] if draw(st.booleans()) else tt[i + 1])
        return (lambda: kind(tt, v)), "t_knots"
    if which == "knots_range":
        tt = t.copy()
        if draw(st.booleans()):
            tt[-1] = draw(st.floats(1.0, 2.0))  # the period's end is the first knot again: not a knot
        else:
            tt[0] = draw(st.floats(-1.0, -1e-9))
        return (lambda: kind(tt, v)), "t_knots"
    if which == "knots_few":
        n = 2 if kind is not PeriodicLinear else 1
        return (lambda: kind(t[:n], v[:, :n])), "t_knots"
    if which == "values_nan":
        return (lambda: kind(t, _corrupt(draw, v, draw(BAD_NUMBERS)))), "values"
    if which == "values_shape":
        shape = draw(st.sampled_from([(2, 3), (2, 5), (3, 4), (4,), (2, 4, 1)]))
        return (lambda: kind(t, np.ones(shape))), "values"
    if which == "harmonic":
        arg = draw(st.sampled_from(["gamma1", "gamma2", "A1", "A2", "psi"]))
        value = draw(st.one_of(BAD_NUMBERS, st.floats(-10, -1e-9) if arg.startswith("A") else BAD_NUMBERS))
        return (lambda: Harmonic(**{arg: value})), arg
    k = draw(st.one_of(BAD_NUMBERS, st.floats(-10, 0)))
    return (lambda: ReferenceTorque(Harmonic(), k)), "k"


@CHEAP
@given(case=invalid_constructions())
def test_invalid_signals_raise_value_error_naming_the_argument(case):
    build, arg = case
    with pytest.raises(ValueError) as info:
        build()
    msg = str(info.value)
    assert "\n" not in msg
    assert re.search(rf"\b{re.escape(arg)}\b", msg), msg


# ============================================================================================
# 3. problem files: strategies driven by the schema
# ============================================================================================
#: physically sensible ranges where the schema's rule alone allows configurations without contact
#: (the rule is still applied on top)
PLAUSIBLE = {
    ("robot", "beta"): st.floats(1.0, 5.0),
    ("gait", "gamma_deg"): st.floats(70.0, 120.0), ("gait", "gamma1_deg"): st.floats(70.0, 120.0),
    ("gait", "gamma2_deg"): st.floats(70.0, 120.0),
    ("gait", "A_deg"): st.floats(0.0, 20.0), ("gait", "A1_deg"): st.floats(0.0, 20.0),
    ("gait", "A2_deg"): st.floats(0.0, 20.0),
}
_NUM = r"(-?[0-9.]+(?:e-?[0-9]+)?)"


def rule_bounds(key):
    """(low, high, low open, high open, listed values) from the rule's text, e.g. "> 0", "in (0, 0.25]", "-1 or 1"."""
    text = key.valid_text
    if m := re.fullmatch(rf"(>=|>) {_NUM}", text):
        return float(m[2]), None, m[1] == ">", False, None
    if m := re.fullmatch(rf"in ([\[(]){_NUM}, {_NUM}([\])])", text):
        return float(m[2]), float(m[3]), m[1] == "(", m[4] == ")", None
    if m := re.fullmatch(rf"{_NUM} or {_NUM}", text):
        return None, None, False, False, [key.type(m[1]), key.type(m[2])]
    if text == "any finite number":
        return None, None, False, False, None
    raise AssertionError(f"the property tests do not know the rule {text!r} of key {key.name}: extend rule_bounds")


def valid_values(section: str, key, ranges=None):
    """Values the schema accepts for a key (the key's own rule filters them)."""
    ranges = PLAUSIBLE if ranges is None else ranges
    if key.choices:
        return st.sampled_from(key.choices)
    lo, hi, lo_open, hi_open, listed = rule_bounds(key)
    if listed is not None:
        base = st.sampled_from(listed)
    elif (section, key.name) in ranges:
        base = ranges[(section, key.name)]
    elif key.type is int:
        lo_i = -100 if lo is None else math.floor(lo)
        base = st.integers(lo_i, lo_i + 200 if hi is None else math.ceil(hi))
    else:
        lo_f = -1e3 if lo is None else lo
        hi_f = (abs(lo_f) * 10 + 10 if hi is None else hi)
        base = st.floats(lo_f, hi_f, exclude_min=lo_open, exclude_max=hi_open)
        if key.type is float:
            base = st.one_of(base, base.map(lambda v: v)).filter(math.isfinite)
    return base.filter(lambda v: key.rule is None or key.rule.test(v))


def invalid_values(key):
    """Values the schema must reject for a numeric key: non-finite, outside the rule, wrong type."""
    wrong_type = st.sampled_from(["1.0", True, False, [1.0], {"x": 1.0}])
    out = [BAD_NUMBERS, wrong_type]
    if key.type is int:
        out.append(st.floats(-50.5, 50.5).filter(lambda v: v != int(v)))
    if key.rule is not None:
        lo, hi, lo_open, hi_open, listed = rule_bounds(key)
        if listed is not None:
            out.append(st.integers(-5, 5).filter(lambda v: v not in listed))
        else:
            cands = []
            if lo is not None:
                cands += [lo - 1.0, lo - 1e-6] + ([lo] if lo_open else [])
            if hi is not None:
                cands += [hi + 1.0, hi + 1e-3] + ([hi] if hi_open else [])
            cands = [key.type(c) if key.type is float else int(c) for c in cands if key.type is float or c == int(c)]
            cands = [c for c in cands if not key.rule.test(c)]
            if cands:
                out.append(st.sampled_from(cands))
    return st.one_of(out)


#: a physical robot for the runs (the schema alone admits e.g. L = 1e-302 m, where M g L S underflows)
PHYSICAL = {**PLAUSIBLE, ("robot", "M"): st.floats(0.005, 5.0), ("robot", "L"): st.floats(0.02, 1.0),
            ("robot", "k"): st.floats(1e-3, 100.0), ("robot", "g"): st.floats(1.0, 20.0),
            ("robot", "mu"): st.floats(0.05, 2.0), ("robot", "mu1"): st.floats(0.05, 2.0),
            ("robot", "mu2"): st.floats(0.05, 2.0), ("robot", "beta"): st.floats(0.2, 5.0),
            **{("gait", f"gamma{i}_deg"): gammas for i in ("", "1", "2")},
            **{("gait", f"A{i}_deg"): amplitudes for i in ("", "1", "2")}}


@st.composite
def section_values(draw, section, ranges=None):
    """A valid set of keys for one section: required keys, a random choice of optional ones, pairing rules kept
    (the default waveform's keys: the other waveforms have their own tests, tests/test_waveforms.py)."""
    keys = section.key_map
    given = set()
    for key in default_variant_keys(section):
        if key.required:
            if key.required_unless and draw(st.booleans()):
                given |= set(key.required_unless)
                if not key.exclusive_with and draw(st.booleans()):
                    given.add(key.name)
            else:
                given.add(key.name)
        elif draw(st.booleans()):
            given.add(key.name)
    changed = True
    while changed:  # pairing rules: exclusive keys leave, required partners join
        changed = False
        for name in sorted(given):
            key = keys[name]
            if name in given and any(o in given for o in key.exclusive_with):
                drop = set(key.exclusive_with) if key.required else {name}
                given -= drop
                changed = True
            if name in given and any(r not in given for r in key.requires):
                given |= set(key.requires)
                changed = True
    if section.name == "simulation":
        # the solver choice is covered by tests/test_problem.py; here every problem runs the default
        # solver of its drive (an MPCC run per example would be slow, and angles + mpcc is bad input)
        given -= {"solver", "steps"}
    return {name: draw(valid_values(section.name, keys[name], ranges)) for name in (k.name for k in section.keys)
            if name in given}


@st.composite
def problem_dicts(draw, ranges=None):
    data = {}
    for section in SECTIONS:
        if section.required or draw(st.booleans()):
            data[section.name] = draw(section_values(section, ranges))
    return data


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf else repr(v))
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + "}"
    return repr(v)


def to_toml(data: dict) -> str:
    return "\n".join(f"[{s}]\n" + "\n".join(f"{k} = {toml_value(v)}" for k, v in keys.items()) for s, keys in data.items())


def load_or_contact_error(data: dict, source: str = "<dict>", overrides=()):
    """The problem, or None when the only fault is a gait without contact (then the message says so)."""
    try:
        return problem_from_dict(data, source=source, overrides=overrides)
    except ProblemError as exc:
        msg = str(exc)
        if msg.startswith(f"{source}: [robot] k = ") and "k/(M g L)" in msg and not overrides:
            # the torque drive's documented bound on the nondimensional stiffness, recomputed from the data
            r = data["robot"]
            assert r["k"] / (r["M"] * r.get("g", Robot.paper().g) * r["L"]) > MAX_STIFFNESS_RATIO, msg
            assert "\n" not in msg
            return None
        assert "\n" not in msg and msg.startswith(f"{source}: [gait] ") and " are invalid" in msg, msg
        return None


def edited(data: dict, section: str, name: str, value) -> dict:
    """The dict edit that ``--set section.name=value`` documents: set the key; mu and mu1/mu2 replace each other,
    and one foot's friction set on a robot given one mu leaves the other foot at mu."""
    out = {s: dict(v) for s, v in data.items()}
    sec = out.setdefault(section, {})
    key = SCHEMA[section].key_map[name]
    for other in key.exclusive_with:
        sec.pop(other, None)
    if section == "robot" and name in ("mu1", "mu2") and "mu" in sec:
        sec.setdefault("mu2" if name == "mu1" else "mu1", sec["mu"])
    for k in SCHEMA[section].keys:
        if name in k.exclusive_with:
            sec.pop(k.name, None)
    sec[name] = value
    return out


def default_variant_keys(section):
    """The keys of a section with its selector (``[gait] waveform``) at its default, the selector left out."""
    if section.selector is None:
        return list(section.keys)
    default = section.key_map[section.selector].default
    return [k for k in section.keys if k.name != section.selector and section.applies(k, default)]


def schema_keys(numeric_only=False):
    return [(s.name, k) for s in SECTIONS for k in default_variant_keys(s) if not numeric_only or k.type in (int, float)]


@CHEAP
@given(data=problem_dicts())
def test_problem_round_trip(data):
    """problem_from_dict(p.to_dict()) == p, directly and through TOML text; the values are the ones given."""
    p = load_or_contact_error(data)
    assume(p is not None)
    assert problem_from_dict(p.to_dict()) == p
    assert problem_from_dict(tomllib.loads(to_toml(p.to_dict()))) == p
    assert problem_from_dict(p.to_dict()).to_dict() == p.to_dict()
    r = data["robot"]
    assert (p.robot.M, p.robot.L, p.robot.k) == (r["M"], r["L"], r["k"])
    assert (p.robot.mu1, p.robot.mu2) == ((r["mu"], r["mu"]) if "mu" in r else (r["mu1"], r["mu2"]))
    g = data["gait"]
    assert p.gait.psi == math.radians(g["psi_deg"])
    assert p.gait.gamma1 == math.radians(g.get("gamma1_deg", g.get("gamma_deg")))
    assert p.gait.A2 == math.radians(g.get("A2_deg", g.get("A_deg")))
    assert p.drive == g.get("drive", "torque") and p.gravity == data.get("model", {}).get("gravity", "physical")
    for name, value in data.get("simulation", {}).items():
        assert getattr(p.hybrid, name) == value
    for section, keys in data.items():
        for name, value in keys.items():
            assert p.sections[section][name] == value


@CHEAP
@given(data=problem_dicts(), st_key=st.sampled_from(schema_keys()), st_data=st.data())
def test_set_override_equals_dict_edit(data, st_key, st_data):
    """--set SECTION.KEY=VALUE gives the same problem as editing the dict, or the same error (marked "from --set")."""
    section, key = st_key
    value = st_data.draw(st.one_of(valid_values(section, key), invalid_values(key)) if key.type is not str
                         else st.one_of(valid_values(section, key), st.sampled_from(["walk", "", "Physical"])))
    text = f"{section}.{key.name}={toml_value(value)}"
    try:
        via_set = problem_from_dict(data, source="f.toml", overrides=[text])
    except ProblemError as exc:
        via_set = exc
    try:
        via_dict = problem_from_dict(edited(data, section, key.name, value), source="f.toml")
    except ProblemError as exc:
        via_dict = exc
    if isinstance(via_dict, Problem):
        assert via_set == via_dict
    else:
        assert isinstance(via_set, ProblemError), via_set
        assert str(via_set).replace(" (from --set)", "") == str(via_dict)
        event("both rejected")
    # a bare word is accepted for string keys
    if key.type is str and re.fullmatch(r"[A-Za-z_]+", value) and value not in ("true", "false", "inf", "nan"):
        try:
            bare = problem_from_dict(data, source="f.toml", overrides=[f"{section}.{key.name}={value}"])
        except ProblemError as exc:
            bare = exc
        assert str(bare) == str(via_set) if isinstance(bare, ProblemError) else bare == via_set


@CHEAP
@given(data=problem_dicts(), st_key=st.sampled_from(schema_keys(numeric_only=True)), st_data=st.data())
def test_invalid_numeric_values_name_the_key_and_value(data, st_key, st_data):
    """Every numeric key of the schema rejects NaN, infinities, values outside its rule and wrong types
    with a one-line ProblemError naming the file, the key and the value; from --set too."""
    section, key = st_key
    value = st_data.draw(invalid_values(key))
    assume(not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
                and key.rule is not None and key.rule.test(value) and not (key.type is int and value != int(value))))
    bad = edited(data, section, key.name, value)
    with pytest.raises(ProblemError) as info:
        problem_from_dict(bad, source="problems/x.toml")
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith("problems/x.toml: ")
    assert f"[{section}] {key.name} = {toml_value(value)} is invalid" in msg, msg
    with pytest.raises(ProblemError) as info:
        problem_from_dict(data, source="problems/x.toml", overrides=[f"{section}.{key.name}={toml_value(value)}"])
    assert f"[{section}] {key.name} = {toml_value(value)} (from --set) is invalid" in str(info.value), str(info.value)
    assert isinstance(info.value, ValueError)


@CHEAP
@given(data=problem_dicts(), st_key=st.sampled_from([(s.name, k) for s in SECTIONS if s.required
                                                     for k in default_variant_keys(s) if k.required]))
def test_missing_required_key_is_named(data, st_key):
    section, key = st_key
    bad = {s: dict(v) for s, v in data.items()}
    bad[section].pop(key.name, None)
    for alt in key.required_unless:  # the alternatives would stand in for the key
        bad[section].pop(alt, None)
    for k in SCHEMA[section].keys:  # so would keys that need it
        if key.name in k.requires:
            bad[section].pop(k.name, None)
    with pytest.raises(ProblemError) as info:
        problem_from_dict(bad, source="p.toml")
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith("p.toml: ")
    assert f"[{section}] {key.name} is missing" in msg, msg


@SIMS
@given(data=problem_dicts(PHYSICAL), model_gravity=st.sampled_from(["physical", "paper"]))
def test_run_problem_with_prescribed_angles(data, model_gravity):
    """gait.drive = "angles" through the problem layer: the same result as simulate_angles; a gait
    rejected for losing contact does lose it (the simulator cannot succeed on it)."""
    data = edited(data, "gait", "drive", "angles")
    data = edited(data, "model", "gravity", model_gravity)
    p = load_or_contact_error(data)
    if p is None:
        event("rejected as bad input")
        try:  # the torque drive checks the start configuration only
            q = problem_from_dict(edited(data, "gait", "drive", "torque"))
        except ProblemError:
            return  # no contact at phase 0: simulate_angles rejects it as well (test_prescribed_random_...)
        res = run_prescribed(q.model, q.gait)
        assert res is not None and not res.success
        return
    res = run_problem(p)
    assert res.drive == "angles" and res.gravity == model_gravity
    direct = simulate_angles(p.model, p.gait)
    assert res.status == direct.status and (not res.success or res.S == direct.S)
    check_outcome(p.model, p.gait, res)


# ============================================================================================
# regressions found by the properties above
# ============================================================================================
def test_prescribed_hold_stretch_keeps_both_slip_directions():
    """A gait that holds still on a stretch (PCHIP through equal samples: d' = 0 there) and moves on
    the other way afterwards: the stretch is stick-stick, and S counts both directions (the scan
    once saw one sign change across the stretch and gave the whole segment one slip direction)."""
    model = Model(Robot.paper())
    angles = PeriodicPchip([0.0, 0.2, 0.45, 0.7], np.radians([[80, 100, 100, 70], [100, 100, 100, 90]]))
    res = simulate_angles(model, angles)
    assert res.success, res.message
    kinds = [e.kind for e in res.events]
    assert "slip_to_stick" in kinds and any(k.startswith("slip_onset") for k in kinds)
    stick = res.mode == Mode.STICK
    assert np.all((res.t[stick] >= 0.2 - 1e-12) & (res.t[stick] <= 0.45 + 1e-12))
    check_success(model, angles, res)  # S against the independent integration (was +5.1 mm instead of 0)


def test_prescribed_joint_touching_the_ground_is_a_failure():
    """Symmetric legs folding to phi = 0 at t = 3/4: the joints touch the ground without a sign change
    (was reported as feet crossing, with d = l (beta - 2) > 0 there)."""
    model = Model(Robot.paper(beta=3.0))
    angles = Harmonic.from_degrees(40, 40, 0)
    res = simulate_angles(model, angles)
    assert res.status == Status.JOINT_ON_GROUND
    assert res.failure_t == pytest.approx(0.75, abs=1e-6)
    check_failure(model, angles, res)


@pytest.mark.parametrize("kwargs, match", [
    (dict(t_eval=[0.0, math.nan]), "t_eval"),
    (dict(t_eval=[]), "t_eval"),
    (dict(t_eval=[0.5, 1.5]), "t_eval"),
    (dict(n_scan=4), "n_scan"),
    (dict(n_scan=100.0), "n_scan"),
    (dict(angles=CallableSignal(lambda t: [math.pi / 2 + 0.1 * t, math.pi / 2])), "1-periodic"),
    (dict(angles=CallableSignal(lambda t: [math.nan, math.pi / 2])), "not finite"),
    (dict(angles=CallableSignal(lambda t: [1.0, 1.0, 1.0])), "2 values"),
])
def test_prescribed_bad_arguments_raise_value_error(kwargs, match):
    args = dict(model=Model(Robot.paper()), angles=Harmonic())
    args.update(kwargs)
    with pytest.raises(ValueError, match=match) as info:
        simulate_angles(**args)
    assert "\n" not in str(info.value)
    with pytest.raises(TypeError, match="Model"):
        simulate_angles(Robot.paper(), Harmonic())
