r"""Property-based tests (hypothesis) of the input signals: periodicity, derivatives, vectorised
evaluation, the Fourier fit and the rejection of invalid signals.

The number of examples per property comes from ``OCP_CRAWL_HYPOTHESIS_EXAMPLES`` (default 25, so
that the file runs in well under a minute); a large run::

    OCP_CRAWL_HYPOTHESIS_EXAMPLES=500 python -m pytest -q tests/test_properties_signals.py \
        --hypothesis-show-statistics

Every assertion holds for every example, whatever the seed.
"""
from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from ocp_crawl import (FourierSeries, Harmonic, PeriodicLinear, PeriodicPchip, PeriodicSpline,
                       ReferenceTorque)
from ocp_crawl.model.pulse import PULSE_RAMPS, Pulse

from _properties_common import BAD_NUMBERS, CHEAP, knots

EPS = np.finfo(float).eps


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
    st.builds(Harmonic, st.floats(-4, 4), st.floats(-4, 4), st.floats(0, 3), st.floats(0, 3),
              st.floats(-7, 7)),
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
        np.testing.assert_allclose(u.derivative(t + k), u.derivative(t), rtol=0,
                                   atol=1e-12 * (sdu + 1) + rounding * sddu)


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


@st.composite
def pulses(draw):
    rise = draw(st.floats(0.01, 0.5))
    c = st.floats(-3.0, 3.0)
    return Pulse(draw(c), draw(c), draw(st.floats(0, 3)), draw(st.floats(0, 3)),
                 draw(st.floats(-7, 7)), rise, draw(st.floats(0.0, 1.0)) * (1.0 - 2.0 * rise),
                 draw(st.sampled_from(PULSE_RAMPS)))


@CHEAP
@given(u=pulses(), ts=st.lists(st.floats(-3.0, 3.0), min_size=1, max_size=20),
       k=st.floats(1e-3, 1e3))
def test_pulse_at_one_phase_is_its_vectorised_value(u, ts, k):
    # the steppers call a pulse one float phase at a time (its own path, in floats): the same
    # numbers as the array path, to the last bit, for the pulse and the torque of its reference
    ts = np.array(ts, float)
    for f in (u, u.derivative, ReferenceTorque(u, k), ReferenceTorque(u, k).derivative):
        U = f(ts)
        for j, tj in enumerate(ts):
            for arg in (float(tj), np.float64(tj), np.array(tj)):
                np.testing.assert_array_equal(f(arg), U[:, j])
        corners = np.asarray(u.t_knots, float)  # at the kinks too
        for tj, v in zip(corners, f(corners).T):
            np.testing.assert_array_equal(f(float(tj)), v)


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
@given(n=st.integers(1, 12).map(lambda m: 2 * m + 1),
       v=st.lists(st.floats(-3, 3), min_size=50, max_size=50))
def test_fourier_fit_interpolates_odd_samples(n, v):
    """With N odd samples, the fit of order (N - 1)/2 passes through every sample (discrete Fourier
    interpolation), e.g. samples of a spline."""
    samples = np.array(v[:2 * n]).reshape(2, n)
    fit = FourierSeries.fit(samples, (n - 1) // 2)
    np.testing.assert_allclose(fit(np.arange(n) / n), samples, rtol=0,
                               atol=1e-12 * (1 + np.max(np.abs(samples))))


def _corrupt(draw, arr, value):
    arr = np.array(arr, float)
    idx = tuple(draw(st.integers(0, s - 1)) for s in arr.shape)
    arr[idx] = value
    return arr



@st.composite
def invalid_constructions(draw):
    """(constructor call, name of the argument the message must name)."""
    which = draw(st.sampled_from(["fourier_nan", "fourier_shape", "knots_nan", "knots_order",
                                  "knots_range",
                                  "knots_few", "values_nan", "values_shape", "harmonic",
                                  "torque_k"]))
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
        bad[arg] = np.ones(draw(st.sampled_from([(3,), (1,), (3, order), (2, order + 1),
                                                 (2, 2, order)])))
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
            # the period's end is the first knot again: not a knot
            tt[-1] = draw(st.floats(1.0, 2.0))
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
        value = draw(st.one_of(BAD_NUMBERS,
                               st.floats(-10, -1e-9) if arg.startswith("A") else BAD_NUMBERS))
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
