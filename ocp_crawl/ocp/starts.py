"""The starts of the multi-start OCP: the harmonic baseline, a Fourier-order start and perturbed starts.

Every start is a node profile (torques at phases k/N) with a period chosen so that it lies inside the
envelope and within the bandwidth: the perturbed profiles are clipped to the envelope (clipping never
steepens a profile) and their period is the baseline's or, if the perturbation steepened the profile, the
shortest one that keeps |d tau_i/dt| <= k R for the linear interpolant.  The perturbations are drawn from a
seeded generator (:data:`START_SEED`): the same settings give the same starts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ocp_crawl.model.statics import Robot
from ocp_crawl.ocp.settings import OCPSettings

#: seed of the perturbed starts (start i uses the generator seeded with (START_SEED, i))
START_SEED = 13
#: largest perturbation of a perturbed start, relative to the envelope's half-width k A_max
PERTURBATION = 0.2
#: Fourier orders of the perturbations (smooth profiles: the OCP starts from gaits that simulate)
PERTURBATION_ORDERS = 3
#: amplitude of the second harmonic of the Fourier-order start, relative to each joint's half-range
SECOND_HARMONIC = 0.25


@dataclass(frozen=True)
class StartGuess:
    """One start of the OCP: a label, node torques and a period."""

    label: str
    tau: np.ndarray
    """torques [N m] at the node phases k/N, shape (2, N)"""
    T: float
    """period [s]"""


def feasible_period(settings: OCPSettings, robot: Robot, tau: np.ndarray, T: float) -> float:
    """The period [s] of the node profile ``tau`` (2, N) [N m]: ``T`` [s], or longer when the profile's linear
    interpolant would exceed the bandwidth k R at ``T`` (max |tau_k - tau_k-1| N / T <= k R)."""
    steps = np.abs(np.diff(np.c_[tau, tau[:, :1]], axis=1))
    return max(T, float(np.max(steps)) * tau.shape[1] / settings.rate_bound(robot))


def _profile(settings: OCPSettings, robot: Robot, label: str, tau: np.ndarray, T: float) -> StartGuess:
    """The profile clipped to the envelope, with the period that keeps it within the bandwidth."""
    lo, hi = settings.torque_bounds(robot)
    tau = np.clip(tau, lo, hi)
    return StartGuess(label, tau, feasible_period(settings, robot, tau, T))


def second_harmonic_start(settings: OCPSettings, robot: Robot, base: np.ndarray, T: float) -> StartGuess:
    """The baseline plus a second harmonic: each joint's profile plus SECOND_HARMONIC times its half-range
    times sin(4 pi t) (clipped to the envelope, the period lengthened if the bandwidth requires)."""
    N = base.shape[1]
    half = 0.5 * (base.max(axis=1) - base.min(axis=1))
    wave = np.sin(4 * math.pi * np.arange(N) / N)
    return _profile(settings, robot, "second harmonic", base + SECOND_HARMONIC * half[:, None] * wave, T)


def perturbed_start(settings: OCPSettings, robot: Robot, base: np.ndarray, T: float, i: int) -> StartGuess:
    """The baseline plus a smooth random perturbation (Fourier orders 1..PERTURBATION_ORDERS, random
    coefficients of the generator seeded with (START_SEED, i)), scaled to at most PERTURBATION times the
    envelope's half-width k A_max, clipped to the envelope, the period lengthened if the bandwidth requires."""
    N = base.shape[1]
    rng = np.random.default_rng((START_SEED, i))
    t = np.arange(N) / N
    n = np.arange(1, PERTURBATION_ORDERS + 1)[:, None]
    coef = rng.normal(size=(2, 2, PERTURBATION_ORDERS)) / n.T  # (joint, cos/sin, order), decaying with order
    delta = coef[:, 0] @ np.cos(2 * math.pi * n * t) + coef[:, 1] @ np.sin(2 * math.pi * n * t)
    half_width = robot.k * math.radians(settings.A_max_deg)
    delta *= PERTURBATION * half_width / np.max(np.abs(delta))
    return _profile(settings, robot, f"perturbed {i}", base + delta, T)


def start_guesses(settings: OCPSettings, robot: Robot, base: np.ndarray, T: float) -> list[StartGuess]:
    """The ``settings.starts`` starts of the multi-start OCP.

    Parameters
    ----------
    settings : OCPSettings
        Number of starts, envelope and bandwidth.
    robot : Robot
        The robot (stiffness k).
    base : array_like, shape (2, N)
        The harmonic baseline's torques [N m] at the node phases k/N.
    T : float
        The baseline's period [s].

    Returns
    -------
    list of StartGuess
        The baseline first, then (if starts >= 2) the Fourier-order start (second harmonic), then perturbed
        starts 1, 2, ... up to ``settings.starts`` in all.
    """
    base = np.asarray(base, float)
    out = [StartGuess("harmonic baseline", base, T)]
    if settings.starts >= 2:
        out.append(second_harmonic_start(settings, robot, base, T))
    out += [perturbed_start(settings, robot, base, T, i) for i in range(1, settings.starts - 1)]
    return out
