"""Periodic joint-angle inputs of an n-link chain: signals of the phase t [cycles] with n - 1 rows.

The signals of :mod:`ocp_crawl.model.inputs` have two rows (the three-link robot); these have any
number, one per joint, and are :class:`~ocp_crawl.model.inputs.PeriodicSignal` objects too: called
with a phase t (scalar -> shape (m,), N phases -> (m, N)), ``derivative`` per cycle.

* :class:`JointFourier`: a truncated Fourier series per joint (:meth:`JointFourier.harmonic`: one
  sine per joint with its own mean, amplitude and phase).
* :class:`JointSamples`: a periodic cubic spline through equally spaced samples of one cycle.
* :class:`~ocp_crawl.model.sampled.JointLinear`, :class:`~ocp_crawl.model.sampled.JointPchip`,
  :class:`~ocp_crawl.model.sampled.JointSpline`: the interpolants of samples at any knots (the
  linear one with kinks and holds, as the OCP's profiles and soft actuators' tables have them).
* :class:`JointCallable`: any callable of the phase (derivative by central differences if not
  given).

:func:`as_joint_signal` turns what a user gives (a signal, a callable, a sampled array) into one;
:class:`ChainReferenceTorque` makes the joints' torques of reference angles.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Callable

import numpy as np

from ocp_crawl.checks import real
from ocp_crawl.model.inputs import TWO_PI, PeriodicSignal, _float_array

if TYPE_CHECKING:
    from ocp_crawl.model.chain import Chain

#: most samples of one cycle in a :class:`JointSamples` (that of the two-joint sampled signals)
MAX_SAMPLES = 10_000


class JointFourier(PeriodicSignal):
    """``phi_j(t) = a0_j + sum_k (a_jk cos(2 pi k t) + b_jk sin(2 pi k t))`` for m joints.

    Parameters
    ----------
    a0 : array_like, shape (m,)
        Mean of each joint's signal (angles [rad]).
    a, b : array_like, shape (m, H)
        Cosine and sine coefficients of the harmonics k = 1..H [rad].
    """

    def __init__(self, a0, a, b):
        a0 = _float_array("JointFourier", "a0", a0)
        a = _float_array("JointFourier", "a", a)
        b = _float_array("JointFourier", "b", b)
        if a0.ndim != 1 or a.ndim != 2 or a.shape != b.shape or a.shape[0] != a0.size:
            raise ValueError("JointFourier: a0 must have shape (m,) and a, b the same shape "
                             f"(m, H), got {a0.shape}, {a.shape}, {b.shape}")
        self.a0, self.a, self.b = a0, a, b
        self._k = np.arange(1, a.shape[1] + 1)
        # the derivative's coefficients, once (the steppers evaluate a signal thousands of times)
        self._da, self._db = self.a * TWO_PI * self._k, self.b * TWO_PI * self._k

    def __eq__(self, other) -> bool:
        """The same coefficients (as the three-link signals, compared by value)."""
        if type(other) is not type(self):
            return NotImplemented
        return all(np.array_equal(x, y) for x, y in zip((self.a0, self.a, self.b),
                                                        (other.a0, other.a, other.b)))

    def __hash__(self) -> int:
        # (the shape alone: equal coefficients may differ in the sign of a zero)
        return hash(self.a.shape)

    @classmethod
    def harmonic(cls, mean, amplitude, phase) -> "JointFourier":
        """``phi_j(t) = mean_j + amplitude_j sin(2 pi t + phase_j)`` [rad] (phases [rad], each
        argument of shape (m,))."""
        mean, amp, ph = (np.asarray(v, float).ravel() for v in (mean, amplitude, phase))
        return cls(mean, (amp * np.sin(ph))[:, None], (amp * np.cos(ph))[:, None])

    def __call__(self, t):
        if isinstance(t, float):   # (a phase: the steppers' many calls; the same operations)
            w = TWO_PI * (t * self._k)
            return self.a0 + self.a @ np.cos(w) + self.b @ np.sin(w)
        t = np.asarray(t, float)
        if t.ndim <= 1:   # (a phase or a row of phases: products of matrices, the fast path)
            w = TWO_PI * np.multiply.outer(t, self._k)
            return ((self.a0 if t.ndim == 0 else self.a0[:, None])
                    + self.a @ np.cos(w).T + self.b @ np.sin(w).T)
        w = TWO_PI * np.multiply.outer(t, self._k)
        return (self.a0.reshape((-1,) + (1,) * (w.ndim - 1))
                + np.einsum("jk,...k->j...", self.a, np.cos(w))
                + np.einsum("jk,...k->j...", self.b, np.sin(w)))

    def derivative(self, t):
        if isinstance(t, float):
            w = TWO_PI * (t * self._k)
            return self._db @ np.cos(w) - self._da @ np.sin(w)
        t = np.asarray(t, float)
        w = TWO_PI * np.multiply.outer(t, self._k)
        if t.ndim <= 1:
            return self._db @ np.cos(w).T - self._da @ np.sin(w).T
        return (np.einsum("jk,...k->j...", self._db, np.cos(w))
                - np.einsum("jk,...k->j...", self._da, np.sin(w)))

    def describe(self) -> dict:
        return {"type": "JointFourier", "a0": self.a0.tolist(), "a": self.a.tolist(),
                "b": self.b.tolist()}


class JointSamples(PeriodicSignal):
    """Periodic cubic spline through samples ``values`` (m, K) at the phases ``j/K``, j = 0..K-1
    (one cycle; the closing sample at t = 1 is the first one), K >= 3 [rad]."""

    def __init__(self, values):
        from scipy.interpolate import CubicSpline  # scipy only where used (start-up time)

        v = _float_array("JointSamples", "values", values)
        if v.ndim != 2 or not 3 <= v.shape[1] <= MAX_SAMPLES:
            raise ValueError(f"JointSamples: values must have shape (m, K) with 3 <= K <= "
                             f"{MAX_SAMPLES} samples of one cycle, got {v.shape}")
        self.values = v
        self.t_knots = np.arange(v.shape[1]) / v.shape[1]
        self._spline = CubicSpline(np.append(self.t_knots, 1.0),
                                   np.concatenate([v, v[:, :1]], axis=1), axis=1,
                                   bc_type="periodic")
        self._dspline = self._spline.derivative()

    def __call__(self, t):
        return self._spline(np.mod(np.asarray(t, float), 1.0))

    def derivative(self, t):
        return self._dspline(np.mod(np.asarray(t, float), 1.0))

    def describe(self) -> dict:
        return {"type": "JointSamples", "samples": int(self.values.shape[1])}


class JointCallable(PeriodicSignal):
    """Any callable ``f(t) -> (m,)`` of the phase [rad], assumed 1-periodic; derivative ``df`` or,
    without it, central differences of step ``h`` [cycles].

    A callable that accepts an array of N phases and returns (m, N) is called once per array;
    any other is called phase by phase.
    """

    def __init__(self, f: Callable, df: Callable | None = None, h: float = 1e-6):
        if not callable(f) or (df is not None and not callable(df)):
            raise TypeError("JointCallable needs a callable f (and df callable or None), got "
                            f"{type(f).__name__}, {type(df).__name__}")
        h = real("JointCallable.h", h)
        if not 0 < h < 0.5:
            raise ValueError(f"JointCallable: h must be in (0, 0.5), got {h!r}")
        self.f, self.df, self.h = f, df, h

    @staticmethod
    def _eval(g, t):
        t = np.asarray(t, float)
        if t.ndim == 0:
            return np.asarray(g(float(t)), float).ravel()
        first = np.asarray(g(float(t.ravel()[0])), float).ravel()
        try:
            out = np.asarray(g(t), float)
        except (TypeError, ValueError):
            out = None
        if out is not None and out.shape == first.shape + t.shape:
            return out
        cols = [np.asarray(g(float(ti)), float).ravel() for ti in t.ravel()]
        return np.stack(cols, axis=1).reshape((-1,) + t.shape)

    def __call__(self, t):
        return self._eval(self.f, t)

    def derivative(self, t):
        if self.df is not None:
            return self._eval(self.df, t)
        t = np.asarray(t, float)
        return (self(t + self.h) - self(t - self.h)) / (2 * self.h)


def as_joint_signal(u, n_joints: int) -> PeriodicSignal:
    """The joint-angle signal of ``u`` for ``n_joints`` joints.

    Parameters
    ----------
    u : PeriodicSignal, callable or array_like
        A signal (kept as it is), a callable ``f(t) -> (m,)`` of the phase t [cycles]
        (:class:`JointCallable`) or samples (m, K) of one cycle at t = j/K
        (:class:`JointSamples`) [rad].
    n_joints : int
        The number m of joints: the rows the signal must have.

    Returns
    -------
    PeriodicSignal

    Raises
    ------
    TypeError
        For anything else; ValueError when the signal's value at t = 0 does not have m rows.
    """
    if isinstance(u, PeriodicSignal):
        sig = u
    elif callable(u):
        sig = JointCallable(u)
    elif isinstance(u, (np.ndarray, list, tuple)):
        sig = JointSamples(u)
    else:
        raise TypeError("joint angles must be a PeriodicSignal, a callable of the phase or an "
                        f"array of samples (joints, K), got {type(u).__name__}")
    shape = np.shape(sig(0.0))
    if shape != (n_joints,):
        raise ValueError(f"joint angles must have {n_joints} rows (one per joint), got shape "
                         f"{shape} at t = 0")
    return sig


class ChainReferenceTorque(PeriodicSignal):
    """Joint torques of reference angles: ``tau_j = k_j (phi_ref_j(t) - pi - rest_j)`` [N m].

    Parameters
    ----------
    reference : PeriodicSignal
        Reference joint angles phi_ref(t) [rad] with m rows.
    chain : Chain
        The chain whose stiffnesses k_j [N m/rad] and rest bends rest_j [rad] are used.
    """

    def __init__(self, reference: PeriodicSignal, chain: Chain):
        self.reference = as_joint_signal(reference, chain.n_joints)
        self.k = np.asarray(chain.stiffness, float)
        self.rest = np.asarray(chain.rest, float)

    def _col(self, v, t):
        return v.reshape((-1,) + (1,) * np.ndim(t))

    def __call__(self, t):
        if isinstance(t, float) or np.ndim(t) == 0:   # (a phase: the steppers' many calls)
            return self.k * (self.reference(t) - math.pi - self.rest)
        return self._col(self.k, t) * (self.reference(t) - math.pi - self._col(self.rest, t))

    def derivative(self, t):
        if isinstance(t, float) or np.ndim(t) == 0:
            return self.k * self.reference.derivative(t)
        return self._col(self.k, t) * self.reference.derivative(t)

    def describe(self) -> dict:
        return {"type": "ChainReferenceTorque", "k": self.k.tolist(), "rest": self.rest.tolist(),
                "reference": self.reference.describe()}
