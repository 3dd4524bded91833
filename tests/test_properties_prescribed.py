r"""Property-based tests (hypothesis) of the prescribed-angle simulator, and the
regressions they found.

The number of examples per property comes from ``OCP_CRAWL_HYPOTHESIS_EXAMPLES`` (without it, a
fixed set of 10, so that the file runs in seconds); a large run::

    OCP_CRAWL_HYPOTHESIS_EXAMPLES=500 python -m pytest -q tests/test_properties_prescribed.py \
        --hypothesis-show-statistics

The statistics list the outcomes (``event``) of the random runs: success, failure status, input
rejected.  Every assertion holds for every example, whatever the seed.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ocp_crawl import (CallableSignal, FourierSeries, Harmonic, Mode, Model, PeriodicLinear,
                       PeriodicPchip, PeriodicSpline, Robot, Status)
from ocp_crawl.sim.angles import simulate_angles

from _properties_common import (SIMS, amplitudes, check_failure, check_outcome, check_success,
                                gammas, knots, run_prescribed)

DEG = math.pi / 180


# ============================================================================================
# strategies: robots and periodic joint angles
# ============================================================================================
@st.composite
def robots(draw):
    """Physical robots: M 5 g - 5 kg, L 2 cm - 1 m, beta 0.2-5, k 0.05-100 M g L, mu 0.05-2, g
    1-20."""
    M = draw(st.floats(0.005, 5.0))
    L = draw(st.floats(0.02, 1.0))
    beta = draw(st.floats(0.2, 5.0))
    g = draw(st.floats(1.0, 20.0))
    ratio = 10.0 ** draw(st.floats(math.log10(0.05), 2.0))
    mu1 = draw(st.floats(0.05, 2.0))
    mu2 = draw(st.one_of(st.just(mu1), st.floats(0.05, 2.0)))
    return Robot(M=M, L=L, beta=beta, k=ratio * M * g * L, mu1=mu1, mu2=mu2, g=g)


models = st.builds(Model, robots(), st.sampled_from(["physical", "paper"]))


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
def sampled_gaits(draw):
    kind = draw(st.sampled_from([PeriodicSpline, PeriodicPchip, PeriodicLinear]))
    t = draw(knots())
    g = np.radians([draw(gammas), draw(gammas)])
    amp = draw(amplitudes) * DEG
    v = g[:, None] + amp * np.array([[draw(st.floats(-1.0, 1.0)) for _ in t] for _ in range(2)])
    return kind(t, v)


angle_signals = st.one_of(harmonic_gaits(), fourier_gaits(), sampled_gaits())


# ============================================================================================
# 1. prescribed angles
# ============================================================================================
@pytest.mark.slow
@SIMS
@given(model=models, angles=angle_signals)
def test_prescribed_random_robots_and_gaits(model, angles):
    """Success with every invariant holding, a documented failure status, or a justified
    rejection."""
    check_outcome(model, angles, run_prescribed(model, angles))


def mirrored(model: Model, angles):
    """The mirror image: joints and feet swapped (x -> -x)."""
    r = model.robot
    m = Model(r.replace(mu1=r.mu2, mu2=r.mu1), gravity=model.gravity)
    if isinstance(angles, Harmonic):
        return m, Harmonic(angles.gamma2, angles.gamma1, angles.A2, angles.A1, -angles.psi)
    return m, FourierSeries(angles.a0[::-1], angles.a[::-1], angles.b[::-1])


def reversed_in_time(angles):
    """phi(-t), as the same kind of signal (a harmonic one half a cycle later, which changes no
    cycle total)."""
    if isinstance(angles, Harmonic):
        return Harmonic(angles.gamma1, angles.gamma2, angles.A1, angles.A2, -angles.psi)
    return FourierSeries(angles.a0, angles.a, -angles.b)


def shifted(angles: FourierSeries, s: float) -> FourierSeries:
    """phi(t + s)."""
    n = np.arange(1, angles.a.shape[1] + 1)
    c, sn = np.cos(2 * np.pi * n * s), np.sin(2 * np.pi * n * s)
    return FourierSeries(angles.a0, angles.a * c + angles.b * sn, angles.b * c - angles.a * sn)


@pytest.mark.slow
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


@pytest.mark.slow
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
    # Harmonic: sin(w + psi/2) for joint 1 and sin(w - psi/2) for joint 2: shift the phase by the
    # mean
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
# regressions found by the properties above
# ============================================================================================
def test_prescribed_hold_stretch_keeps_both_slip_directions():
    """A gait that holds still on a stretch (PCHIP through equal samples: d' = 0 there) and moves on
    the other way afterwards: the stretch is stick-stick, and S counts both directions (the scan
    once saw one sign change across the stretch and gave the whole segment one slip direction)."""
    model = Model(Robot.paper())
    angles = PeriodicPchip([0.0, 0.2, 0.45, 0.7],
                           np.radians([[80, 100, 100, 70], [100, 100, 100, 90]]))
    res = simulate_angles(model, angles)
    assert res.success, res.message
    kinds = [e.kind for e in res.events]
    assert "slip_to_stick" in kinds and any(k.startswith("slip_onset") for k in kinds)
    stick = res.mode == Mode.STICK
    assert np.all((res.t[stick] >= 0.2 - 1e-12) & (res.t[stick] <= 0.45 + 1e-12))
    # S against the independent integration (was +5.1 mm instead of 0)
    check_success(model, angles, res)


def test_prescribed_joint_touching_the_ground_is_a_failure():
    """Symmetric legs folding to phi = 0 at t = 3/4: the joints touch the ground without a sign
    change (was reported as feet crossing, with d = l (beta - 2) > 0 there)."""
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
