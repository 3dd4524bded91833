"""Periodic inputs that interpolate samples at knots (phases in [0, 1) of one period [cycles]).

* :class:`PeriodicSpline`: a periodic cubic spline through samples.
* :class:`PeriodicLinear`: periodic piecewise-linear interpolation of samples.
* :class:`PeriodicPchip`: periodic shape-preserving C1 cubic interpolation of samples.

Each is a :class:`~ocp_crawl.model.inputs.PeriodicSignal` of two joints; at most
:data:`MAX_KNOTS` knots, validated by one check (increasing, within one period).
"""
from __future__ import annotations

import numpy as np

from ocp_crawl.model.inputs import PeriodicSignal, _float_array


#: most samples (knots) of a sampled signal over one period.  Each knot of a piecewise-linear
#: input is a kink where the event-driven stepper ends a step (about 2 ms and 12 kB per knot and
#: cycle, measured: 20,000 knots took 51 s and 0.3 GB), and 1e-4 cycles resolve far finer than
#: any solver step or OCP node (<= 1000 nodes)
MAX_KNOTS = 10_000


def _check_samples(name: str, t_knots, values, min_knots: int,
                   rows: int | None = 2) -> tuple[np.ndarray, np.ndarray]:
    """Validated knots (increasing, in [0, 1)) and values of shape (rows, N) (any number of rows
    >= 1 for ``rows=None``).

    The knots cover one period: the first knot plus one closes it, so the last knot lies before
    t_knots[0] + 1 and must not repeat the first (give t in [0, 1), not the closing t = 1).
    """
    t = _float_array(name, "t_knots", t_knots)
    if t.ndim != 1 or not min_knots <= t.size <= MAX_KNOTS:
        raise ValueError(f"{name}: t_knots must be a 1-D array of {min_knots} to {MAX_KNOTS} "
                         f"phases (each knot is work of the solvers in every cycle), got shape "
                         f"{t.shape}")
    steps = np.diff(t)
    if np.any(steps <= 0):
        j = int(np.argmax(steps <= 0))
        raise ValueError(f"{name}: t_knots must be strictly increasing, got t_knots[{j}] = "
                         f"{t[j]!r} followed by {t[j + 1]!r}")
    if t[0] < 0 or t[-1] >= 1:
        raise ValueError(f"{name}: t_knots must lie in [0, 1) (one period; the closing knot "
                         f"t_knots[0] + 1 is implied), got {t[0]!r} ... {t[-1]!r}")
    v = _float_array(name, "values", values)
    if (v.ndim != 2 or v.shape[1] != t.size or v.shape[0] < 1
            or (rows is not None and v.shape[0] != rows)):
        want = "(m" if rows is None else f"({rows}"
        raise ValueError(f"{name}: values must have shape {want}, {t.size}) (one column per knot), "
                         f"got {v.shape}")
    return t, v


class _Sampled(PeriodicSignal):
    """Base of the signals interpolating samples at knots ``t_knots`` in [0, 1)."""

    t_knots: np.ndarray
    values: np.ndarray
    #: the rows the values must have (None: any number, the ``Joint*`` classes of a chain's joints)
    _rows: int | None = 2

    def __repr__(self) -> str:
        with np.printoptions(precision=17, threshold=10_000):
            return f"{type(self).__name__}(t_knots={self.t_knots!r}, values={self.values!r})"

    def _wrap(self, t):
        """Phases mapped into [t_knots[0], t_knots[0] + 1), the period the interpolant is
        built on."""
        return self.t_knots[0] + np.mod(np.asarray(t, float) - self.t_knots[0], 1.0)


class PeriodicSpline(_Sampled):
    """Periodic cubic spline through samples at phases ``t_knots`` in [0, 1) (values shape (2, N)).

    Parameters
    ----------
    t_knots : array_like, shape (N,)
        Strictly increasing phases [cycles] in [0, 1), N >= 3 (the closing knot t_knots[0] + 1 is
        implied).
    values : array_like, shape (2, N)
        The two joints' values at the knots, in the signal's unit (angles [rad] or torques [N m]).
    """

    def __init__(self, t_knots, values):
        # scipy only when a spline is built (start-up time)
        from scipy.interpolate import CubicSpline

        t, v = _check_samples(type(self).__name__, t_knots, values, min_knots=3,
                              rows=self._rows)
        tt = np.append(t, t[0] + 1.0)
        vv = np.concatenate([v, v[:, :1]], axis=1)
        self._spline = CubicSpline(tt, vv, axis=1, bc_type="periodic")
        self._dspline = self._spline.derivative()
        self.t_knots, self.values = t, v

    def __call__(self, t):
        return self._spline(self._wrap(t))

    def derivative(self, t):
        return self._dspline(self._wrap(t))

    def describe(self) -> dict:
        return {"type": type(self).__name__, "knots": int(self.t_knots.size)}


class PeriodicLinear(_Sampled):
    """Periodic piecewise-linear interpolation of samples at phases ``t_knots`` in [0, 1)
    (values (2, N)).

    It keeps every bound and rate limit that the samples satisfy (a cubic spline may overshoot);
    the derivative is piecewise constant (the simulators split their quadrature at the knots,
    ``t_knots``).

    Parameters
    ----------
    t_knots, values : array_like, shapes (N,) and (2, N)
        Phases [cycles] and values as for :class:`PeriodicSpline`, with N >= 2.
    """

    def __init__(self, t_knots, values):
        t, v = _check_samples(type(self).__name__, t_knots, values, min_knots=2, rows=self._rows)
        self.t_knots, self.values = t, v
        self._tt = np.append(t, t[0] + 1.0)
        self._vv = np.concatenate([v, v[:, :1]], axis=1)
        self._slope = np.diff(self._vv, axis=1) / np.diff(self._tt)

    def __call__(self, t):
        tw = self._wrap(t)
        return np.array([np.interp(tw, self._tt, row) for row in self._vv])

    def derivative(self, t):
        tw = self._wrap(t)
        k = np.clip(np.searchsorted(self._tt, tw, side="right") - 1, 0, self.t_knots.size - 1)
        return self._slope[:, k]

    def describe(self) -> dict:
        return {"type": type(self).__name__, "knots": int(self.t_knots.size)}


class JointLinear(PeriodicLinear):
    """:class:`PeriodicLinear` with any number of rows: the m joints of an n-link chain
    (values (m, N)), in the signal's unit (angles [rad] or torques [N m])."""

    _rows = None


class PeriodicPchip(_Sampled):
    """Periodic shape-preserving cubic (PCHIP) interpolation of samples at phases
    ``t_knots`` in [0, 1).

    C1 (continuous derivative, unlike :class:`PeriodicLinear`) and without overshoot: it stays
    within the range of neighbouring samples, so bounds the samples satisfy hold between them too.
    The optimal-control replay uses it.

    Parameters
    ----------
    t_knots, values : array_like, shapes (N,) and (2, N)
        Phases [cycles] and values as for :class:`PeriodicSpline`, with N >= 3.
    """

    def __init__(self, t_knots, values):
        # scipy only when a PCHIP is built (start-up time)
        from scipy.interpolate import PchipInterpolator

        t, v = _check_samples(type(self).__name__, t_knots, values, min_knots=3,
                              rows=self._rows)
        self.t_knots, self.values = t, v
        # three periods, so that the interpolant of the middle one sees its periodic neighbours
        tt = np.concatenate([t - 1.0, t, t + 1.0])
        vv = np.concatenate([v, v, v], axis=1)
        self._f = PchipInterpolator(tt, vv, axis=1)
        self._df = self._f.derivative()


    def __call__(self, t):
        return self._f(self._wrap(t))

    def derivative(self, t):
        return self._df(self._wrap(t))

    def describe(self) -> dict:
        return {"type": type(self).__name__, "knots": int(self.t_knots.size)}


class JointSpline(PeriodicSpline):
    """:class:`PeriodicSpline` with any number of rows: the m joints of an n-link chain."""

    _rows = None


class JointPchip(PeriodicPchip):
    """:class:`PeriodicPchip` with any number of rows: the m joints of an n-link chain."""

    _rows = None
