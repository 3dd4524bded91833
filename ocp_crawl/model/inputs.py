"""Periodic inputs as functions of the phase t (in cycles: one period is t in [0, 1)).

Quasistatic solutions are time-scalable, so only the phase matters: every signal here is
1-periodic in t and returns a 2-vector (joint 1, joint 2).  Derivatives are with respect to the
phase t (per cycle), not per second.

* :class:`Harmonic`: the paper's reference angles, eq. (ref),
  phi_ref,i = gamma_i + A_i sin(2 pi t +- psi/2).
* :class:`FourierSeries`: any truncated Fourier series.
* :class:`~ocp_crawl.model.sampled.PeriodicSpline`,
  :class:`~ocp_crawl.model.sampled.PeriodicLinear`, :class:`~ocp_crawl.model.sampled.PeriodicPchip`
  (``model/sampled.py``): periodic cubic spline, piecewise-linear and shape-preserving C1 cubic
  interpolation of samples.
* :class:`~ocp_crawl.model.pulse.Pulse` (``model/pulse.py``): trapezoidal (or cosine-edged) pulses
  of soft actuators, per-joint phase shift.
* :class:`CallableSignal`: any callable of phase (derivative by central differences if not given).
* :class:`ReferenceTorque`: the torque tau = k (phi_ref - pi) of eq. (tau) for any reference signal.
* :class:`TorqueReference`: its inverse, the reference angles phi_ref = pi + tau/k of a torque
  input.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ocp_crawl.checks import real

TWO_PI = 2.0 * math.pi


class PeriodicSignal:
    """Base class: a 1-periodic 2-vector signal of the phase t."""

    def __call__(self, t):
        """Value at phase t (scalar -> shape (2,), array of N -> shape (2, N))."""
        raise NotImplementedError

    def derivative(self, t):
        """d/dt of the value at phase t (same shapes as __call__)."""
        raise NotImplementedError

    def describe(self) -> dict:
        return {"type": type(self).__name__}


def _float_array(owner: str, name: str, value) -> np.ndarray:
    """``value`` as a float array whose entries are all finite, or ValueError naming ``owner``'s
    argument ``name``."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: {name} must be an array of real numbers, got "
                         f"{value!r:.60}") from None
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        idx = tuple(int(i) for i in bad[0])
        raise ValueError(f"{owner}: {name} must be finite, got {arr[idx]!r} at index {list(idx)}")
    return arr


@dataclass(frozen=True)
class Harmonic(PeriodicSignal):
    """Reference angles of eq. (ref) [rad]: phi_1 = gamma1 + A1 sin(2 pi t + psi/2), phi_2 =
    gamma2 + A2 sin(2 pi t - psi/2).

    Parameters
    ----------
    gamma1, gamma2 : float
        Nominal angles of joints 1 and 2 [rad] (pi/2: the upright Pi shape; pi: flat).
    A1, A2 : float
        Amplitudes [rad] (>= 0).
    psi : float
        Phase difference [rad], joint 1 leading for psi > 0.

    Called with a phase t [cycles] it returns the angles, shape (2,) (or (2, N) for N phases).
    :meth:`from_degrees` takes the same values in degrees.
    """

    gamma1: float = math.pi / 2
    """nominal angle of joint 1 [rad]"""
    gamma2: float = math.pi / 2
    """nominal angle of joint 2 [rad]"""
    A1: float = math.pi / 6
    """amplitude of joint 1 [rad]"""
    A2: float = math.pi / 6
    """amplitude of joint 2 [rad]"""
    psi: float = math.pi / 4
    """phase difference, joint 1 leading for psi > 0 [rad]"""

    def __post_init__(self) -> None:
        for name in ("gamma1", "gamma2", "A1", "A2", "psi"):
            object.__setattr__(self, name,
                               real(name, getattr(self, name), nonneg=name in ("A1", "A2")))

    @classmethod
    def from_degrees(cls, gamma_deg=90.0, A_deg=30.0, psi_deg=45.0, *, gamma1_deg=None,
                     gamma2_deg=None, A1_deg=None, A2_deg=None) -> "Harmonic":
        """The harmonic reference from angles in degrees, as in the problem files' ``[gait]``
        section.

        Parameters
        ----------
        gamma_deg, A_deg, psi_deg : float
            Nominal angle, amplitude and phase lead of joint 1 over joint 2 [deg] (the paper's gait:
            90, 30, 45).
        gamma1_deg, gamma2_deg, A1_deg, A2_deg : float, optional
            Per-joint values [deg] that override ``gamma_deg`` / ``A_deg``.

        Returns
        -------
        Harmonic
        """
        g1 = gamma_deg if gamma1_deg is None else gamma1_deg
        g2 = gamma_deg if gamma2_deg is None else gamma2_deg
        a1 = A_deg if A1_deg is None else A1_deg
        a2 = A_deg if A2_deg is None else A2_deg
        return cls(math.radians(g1), math.radians(g2), math.radians(a1), math.radians(a2),
                   math.radians(psi_deg))

    def __call__(self, t):
        # the steppers' hot path: scalar phases, math is ~5x faster than numpy
        if isinstance(t, float):
            w = TWO_PI * t
            return np.array([self.gamma1 + self.A1 * math.sin(w + self.psi / 2),
                             self.gamma2 + self.A2 * math.sin(w - self.psi / 2)])
        t = np.asarray(t, dtype=float)
        w = TWO_PI * t
        return np.array([self.gamma1 + self.A1 * np.sin(w + self.psi / 2),
                         self.gamma2 + self.A2 * np.sin(w - self.psi / 2)])

    def derivative(self, t):
        if isinstance(t, float):
            w = TWO_PI * t
            return np.array([TWO_PI * self.A1 * math.cos(w + self.psi / 2),
                             TWO_PI * self.A2 * math.cos(w - self.psi / 2)])
        t = np.asarray(t, dtype=float)
        w = TWO_PI * t
        return np.array([TWO_PI * self.A1 * np.cos(w + self.psi / 2),
                         TWO_PI * self.A2 * np.cos(w - self.psi / 2)])

    def describe(self) -> dict:
        return {"type": "Harmonic", "gamma1_deg": math.degrees(self.gamma1),
                "gamma2_deg": math.degrees(self.gamma2),
                "A1_deg": math.degrees(self.A1), "A2_deg": math.degrees(self.A2),
                "psi_deg": math.degrees(self.psi)}


@dataclass(frozen=True)
class FourierSeries(PeriodicSignal):
    """u_i(t) = a0_i + sum_n (a_n,i cos(2 pi n t) + b_n,i sin(2 pi n t)).

    Parameters
    ----------
    a0 : array_like, shape (2,)
        Mean of each joint's signal, in the signal's unit (angles [rad] or torques [N m]).
    a, b : array_like, shape (2, N)
        Cosine and sine coefficients of the harmonics n = 1..N (same unit); t is the phase [cycles].

    :meth:`fit` builds the series from equally spaced samples.
    """

    a0: np.ndarray
    a: np.ndarray
    b: np.ndarray

    def __post_init__(self) -> None:
        a0 = _float_array("FourierSeries", "a0", self.a0)
        if a0.shape != (2,):
            raise ValueError(f"FourierSeries: a0 must have shape (2,), got {a0.shape}")
        a = _float_array("FourierSeries", "a", self.a)
        b = _float_array("FourierSeries", "b", self.b)
        for name, arr in (("a", a), ("b", b)):
            if arr.ndim != 2 or arr.shape[0] != 2:
                raise ValueError(f"FourierSeries: {name} must have shape (2, N) for N harmonics, "
                                 f"got {arr.shape}")
        if a.shape != b.shape:
            raise ValueError("FourierSeries: a and b must have the same shape (2, N), got a "
                             f"{a.shape} and b {b.shape}")
        object.__setattr__(self, "a0", a0)
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "b", b)

    @classmethod
    def fit(cls, samples, order: int) -> "FourierSeries":
        """Least-squares series of the given order through equally spaced samples
        (shape (2, N), t = j/N).

        The order is capped at (N - 1) // 2; with N odd and that order the series interpolates the
        samples.
        """
        s = _float_array("FourierSeries.fit", "samples", samples)
        if s.ndim != 2 or s.shape[0] != 2 or s.shape[1] < 1:
            raise ValueError("FourierSeries.fit: samples must have shape (2, N) with N >= 1, got "
                             f"{s.shape}")
        if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 0:
            raise ValueError(f"FourierSeries.fit: order must be an integer >= 0, got {order!r}")
        n = s.shape[1]
        c = np.fft.rfft(s, axis=1) / n
        order = min(order, (n - 1) // 2)
        return cls(c[:, 0].real, 2 * c[:, 1:order + 1].real, -2 * c[:, 1:order + 1].imag)

    def _n(self):
        return np.arange(1, self.a.shape[1] + 1)

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        w = TWO_PI * np.multiply.outer(t, self._n())  # (..., N)
        out = self.a0.reshape((2,) + (1,) * t.ndim) \
            + np.einsum("in,...n->i...", self.a, np.cos(w)) \
            + np.einsum("in,...n->i...", self.b, np.sin(w))
        return out

    def derivative(self, t):
        t = np.asarray(t, dtype=float)
        n = self._n()
        w = TWO_PI * np.multiply.outer(t, n)
        return np.einsum("in,...n->i...", self.b * TWO_PI * n, np.cos(w)) \
            - np.einsum("in,...n->i...", self.a * TWO_PI * n, np.sin(w))

    def describe(self) -> dict:
        return {"type": "FourierSeries", "order": int(self.a.shape[1]), "a0": self.a0.tolist(),
                "a": self.a.tolist(), "b": self.b.tolist()}


#: knots of an input closer than this [cycles] (across the wrap too) are one knot
KNOT_GAP = 1e-12


def merged_knots(t_knots) -> np.ndarray:
    """The phases in [0, 1) of an input's knots ``t_knots`` [cycles], sorted, those within
    :data:`KNOT_GAP` of another (across the wrap too) merged into one: knots that coincide up to
    round-off (a triangle wave's corners at phases 0 and 1, shifted by psi/2 and wrapped into
    [0, 1)) would leave a piece of round-off length, on which neither the one-sided rates of a
    kink nor a test for linear pieces mean anything (the event-driven stepper would fall back to
    steps of 1/1024 cycle on the triangle waves of about half of the phases)."""
    b = np.sort(np.mod(np.asarray(t_knots, float).ravel(), 1.0))
    if b.size == 0:
        return b
    b = b[np.append(True, np.diff(b) > KNOT_GAP)]
    if b.size > 1 and b[0] + 1.0 - b[-1] <= KNOT_GAP:
        b = b[:-1]
    return b


class CallableSignal(PeriodicSignal):
    """Any callable ``f(t) -> (2,)`` of the phase, assumed 1-periodic; derivative by central
    differences (step ``h`` = 1e-6: round-off error ~1e-10 relative to |f|) unless ``df`` is
    given."""

    def __init__(self, f: Callable, df: Callable | None = None, h: float = 1e-6):
        if not callable(f):
            raise TypeError(f"CallableSignal needs a callable, got {type(f).__name__}")
        if df is not None and not callable(df):
            raise TypeError(f"CallableSignal: df must be callable or None, got {type(df).__name__}")
        h = real("CallableSignal.h", h)
        if not 0 < h < 0.5:
            raise ValueError(f"CallableSignal: h must be in (0, 0.5), got {h!r}")
        self.f, self.df, self.h = f, df, h

    @staticmethod
    def _one(g, t: float) -> np.ndarray:
        v = np.asarray(g(t), float)
        if v.size != 2:
            raise ValueError("CallableSignal: the function must return 2 values "
                             f"(joint 1, joint 2), got shape {v.shape} at t = {t!r}")
        return v.reshape(2)

    def _eval(self, g, t):
        t = np.asarray(t, float)
        if t.ndim == 0:
            return self._one(g, float(t))
        if t.size == 0:
            return np.zeros((2,) + t.shape)
        return (np.stack([self._one(g, float(ti)) for ti in t.ravel()], axis=1)
                .reshape((2,) + t.shape))

    def __call__(self, t):
        return self._eval(self.f, t)

    def derivative(self, t):
        if self.df is not None:
            return self._eval(self.df, t)
        t = np.asarray(t, float)
        return (self(t + self.h) - self(t - self.h)) / (2 * self.h)


@dataclass(frozen=True)
class ReferenceTorque(PeriodicSignal):
    """Torque input of eq. (tau): tau_i = k (phi_ref,i(t) - pi) [N m], i.e. a spring whose rest
    angle is phi_ref.

    Parameters
    ----------
    reference : PeriodicSignal
        The reference angles phi_ref(t) [rad] (e.g. :class:`Harmonic`, or a sampled signal of
        angles).
    k : float
        Joint stiffness [N m/rad] (> 0), normally the robot's ``k``.
    """

    reference: PeriodicSignal
    k: float
    """joint stiffness [N m/rad]"""

    def __post_init__(self) -> None:
        if not isinstance(self.reference, PeriodicSignal):
            raise TypeError("ReferenceTorque.reference must be a PeriodicSignal, got "
                            f"{type(self.reference).__name__}")
        object.__setattr__(self, "k", real("ReferenceTorque.k", self.k, positive=True))

    def __call__(self, t):
        return self.k * (self.reference(t) - math.pi)

    def derivative(self, t):
        return self.k * self.reference.derivative(t)

    def describe(self) -> dict:
        return {"type": "ReferenceTorque", "k": self.k, "reference": self.reference.describe()}


def input_knots(signal) -> np.ndarray:
    """The phases in [0, 1) where ``signal`` may have a kink: the knots of a sampled, triangle or
    pulse signal (of the reference angles of a :class:`ReferenceTorque`, or of a chain's torques
    of reference angles, whichever signal holds them as ``reference``), merged as
    :func:`merged_knots` merges them; none for a smooth signal."""
    reference = getattr(signal, "reference", None)
    source = reference if isinstance(reference, PeriodicSignal) else signal
    return merged_knots(getattr(source, "t_knots", np.zeros(0)))


@dataclass(frozen=True)
class TorqueReference(PeriodicSignal):
    """Reference angles phi_ref,i = pi + tau_i(t)/k [rad] of a torque input: the inverse of
    :class:`ReferenceTorque` (the spring rest angles that a given torque profile stands for; for
    figures and geometry checks)."""

    torque: PeriodicSignal
    """joint torques [N m]"""
    k: float
    """joint stiffness [N m/rad]"""

    def __post_init__(self) -> None:
        if not isinstance(self.torque, PeriodicSignal):
            raise TypeError("TorqueReference.torque must be a PeriodicSignal, got "
                            f"{type(self.torque).__name__}")
        object.__setattr__(self, "k", real("TorqueReference.k", self.k, positive=True))

    def __call__(self, t):
        return math.pi + self.torque(t) / self.k

    def derivative(self, t):
        return self.torque.derivative(t) / self.k

    def describe(self) -> dict:
        return {"type": "TorqueReference", "k": self.k, "torque": self.torque.describe()}


def as_signal(u) -> PeriodicSignal:
    """Accept a PeriodicSignal or any callable of phase.

    Parameters
    ----------
    u : PeriodicSignal or callable
        A signal, or a function ``f(t) -> (2,)`` of the phase t [cycles], assumed 1-periodic.

    Returns
    -------
    PeriodicSignal
        ``u`` itself, or a :class:`CallableSignal` wrapping it (derivative by central differences).

    Raises
    ------
    TypeError
        If ``u`` is neither.
    """
    if isinstance(u, PeriodicSignal):
        return u
    if callable(u):
        return CallableSignal(u)
    raise TypeError("an input must be a PeriodicSignal or a callable of phase, got "
                    f"{type(u).__name__}")
