"""The starts of the multi-start OCP: the harmonic baseline, a Fourier-order start and perturbed
starts.

Every start is a node profile (torques at phases k/N, shifted by whole nodes so that node 0 is where
tau_1 is largest: the OCP's phase pin) with a period chosen so that it lies inside the envelope and
within the bandwidth: the perturbed profiles are clipped to the envelope (clipping never
steepens a profile) and their period is the baseline's or, if the perturbation steepened the
profile, the shortest one that keeps |d tau_i/dt| <= k R for the linear interpolant.  The
perturbations are drawn from a seeded generator (:data:`START_SEED`): the same settings give the
same starts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from ocp_crawl.ocp.baseline import Baselines
from ocp_crawl.ocp.plant import AnyRobot, joint_rate_bounds, joint_torque_bounds, stiffness_of
from ocp_crawl.ocp.sampling import best_sampling
from ocp_crawl.ocp.settings import OCPSettings

#: seed of the perturbed starts (start i uses the generator seeded with (START_SEED, i))
START_SEED = 13
#: largest perturbation of a perturbed start, relative to the envelope's half-width k A_max
PERTURBATION = 0.2
#: Fourier orders of the perturbations (smooth profiles: the OCP starts from gaits that simulate)
PERTURBATION_ORDERS = 3
#: amplitude of the second harmonic of the Fourier-order start, relative to each joint's half-range
SECOND_HARMONIC = 0.25
#: draws of a start the simulator does not follow (each with half the amplitude of the previous one)
ATTEMPTS = 4


@dataclass(frozen=True)
class StartGuess:
    """One start of the OCP: a label, node torques and a period."""

    label: str
    tau: np.ndarray
    """torques [N m] at the node phases k/N, shape (m, N) of the m joints"""
    T: float
    """period [s]"""
    family: str | None = None
    """the waveform family whose best member the start is (:func:`family_starts`), else None"""


def feasible_period(settings: OCPSettings, robot: AnyRobot, tau: np.ndarray, T: float) -> float:
    """The period [s] of the node profile ``tau`` (m, N) [N m]: ``T`` [s], or longer when the
    profile's linear interpolant would exceed the bandwidth k_i R of a joint at ``T``
    (max |tau_k - tau_k-1| N / T <= k_i R)."""
    steps = np.abs(np.diff(np.c_[tau, tau[:, :1]], axis=1))
    bound = joint_rate_bounds(settings, robot)
    return max(T, float(np.max(np.max(steps, axis=1) * tau.shape[1] / bound)))


def pinned(tau: np.ndarray) -> np.ndarray:
    """The node profile (m, N) shifted by whole nodes so that node 0 is where tau_1 is largest (the
    OCP's phase pin, tau_1,k <= tau_1,0): the same periodic gait, started at another phase."""
    return np.roll(tau, -int(np.argmax(tau[0])), axis=1)


def _profile(settings: OCPSettings, robot: AnyRobot, label: str, tau: np.ndarray,
             T: float) -> StartGuess:
    """The profile clipped to the envelope and pinned, with the period that keeps it within the
    bandwidth."""
    lo, hi = joint_torque_bounds(settings, robot)
    tau = pinned(np.clip(tau, lo[:, None], hi[:, None]))
    return StartGuess(label, tau, feasible_period(settings, robot, tau, T))


def given_start(settings: OCPSettings, robot: AnyRobot, tau: np.ndarray, T: float,
                label: str = "given start") -> StartGuess:
    """A start of the user's: node torques ``tau`` (m, N) [N m] and a period ``T`` [s] (e.g. a
    previous optimum, or a waveform family's best member), clipped to the envelope, pinned, the
    period lengthened if the bandwidth requires."""
    return _profile(settings, robot, label, np.asarray(tau, float), T)


def second_harmonic_start(settings: OCPSettings, robot: AnyRobot, base: np.ndarray, T: float,
                          attempt: int = 0) -> StartGuess:
    """The baseline plus a second harmonic: each joint's profile plus SECOND_HARMONIC / 2^attempt
    times its half-range times sin(4 pi t) (clipped to the envelope, the period lengthened if the
    bandwidth requires)."""
    N = base.shape[1]
    half = 0.5 * (base.max(axis=1) - base.min(axis=1)) * SECOND_HARMONIC / 2**attempt
    wave = np.sin(4 * math.pi * np.arange(N) / N)
    return _profile(settings, robot, "second harmonic", base + half[:, None] * wave, T)


def perturbed_start(settings: OCPSettings, robot: AnyRobot, base: np.ndarray, T: float, i: int,
                    attempt: int = 0) -> StartGuess:
    """The baseline plus a smooth random perturbation (Fourier orders 1..PERTURBATION_ORDERS, random
    coefficients of the generator seeded with (START_SEED, i, attempt)), scaled to at most
    PERTURBATION / 2^attempt times the envelope's half-width k A_max, clipped to the envelope, the
    period lengthened if the bandwidth requires."""
    N = base.shape[1]
    rng = np.random.default_rng((START_SEED, i, attempt))
    t = np.arange(N) / N
    n = np.arange(1, PERTURBATION_ORDERS + 1)[:, None]
    # (joint, cos/sin, order), decaying with order
    coef = rng.normal(size=(base.shape[0], 2, PERTURBATION_ORDERS)) / n.T
    delta = coef[:, 0] @ np.cos(2 * math.pi * n * t) + coef[:, 1] @ np.sin(2 * math.pi * n * t)
    half_width = stiffness_of(robot)[:, None] * math.radians(settings.A_max_deg)
    delta *= PERTURBATION / 2**attempt * half_width / np.max(np.abs(delta))
    return _profile(settings, robot, f"perturbed {i}", base + delta, T)


def start_guesses(settings: OCPSettings, robot: AnyRobot, base: np.ndarray, T: float,
                  follows: Callable[[np.ndarray], bool] | None = None) -> list[StartGuess]:
    """The ``settings.starts`` starts of the multi-start OCP.

    Parameters
    ----------
    settings : OCPSettings
        Number of starts, envelope and bandwidth.
    robot : Robot or Chain
        The robot (its joints' stiffnesses).
    base : array_like, shape (m, N)
        The harmonic baseline's torques [N m] at the node phases k/N.
    T : float
        The baseline's period [s].
    follows : callable, optional
        ``follows(tau)``: whether the simulator follows the node profile tau (m, N) [N m] (the OCP's
        initial guess simulates its start).  A start it does not follow is drawn again, up to
        ATTEMPTS times, each with half the amplitude (perturbed starts: a new draw of their
        generator); the last is kept if none is followed.  None: the first draw.

    Returns
    -------
    list of StartGuess
        The baseline first, then (if starts >= 2) the Fourier-order start (second harmonic), then
        perturbed starts 1, 2, ... up to ``settings.starts`` in all; each pinned (node 0 where tau_1
        is largest).
    """
    base = pinned(np.asarray(base, float))
    makers = [lambda a: second_harmonic_start(settings, robot, base, T,
                                              a)] if settings.starts >= 2 else []
    makers += [lambda a, i=i: perturbed_start(settings, robot, base, T, i,
                                              a) for i in range(1, settings.starts - 1)]
    out = [StartGuess("harmonic baseline", base, T)]
    for make in makers:
        for attempt in range(ATTEMPTS if follows is not None else 1):
            guess = make(attempt)
            if follows is None or follows(guess.tau):
                break
        out.append(guess)
    return out


def family_starts(base: Baselines, settings: OCPSettings, robot: AnyRobot,
                  skip: tuple[str, ...] = (), models: list | None = None) -> list[StartGuess]:
    """The best member of each searched waveform family of ``base`` (but the shapes ``skip``) as a
    start: its torques at the node phases k/N, pinned, with its period; labelled "SHAPE baseline,
    tightened" (they are solved by the tightened NLP, :attr:`OCPSettings.start_solve`).  With the
    friction scenarios' ``models``, also the member sampled at its best sub-node phase
    (:func:`~ocp_crawl.ocp.sampling.best_sampling`, "SHAPE baseline, best node phase, tightened")
    where that is another profile: which of its corners the nodes hold decides where the solve
    starts (robust_speed: 69.89 mm/s from it, 68.82 by the homotopy).  A start whose node profile
    and period equal an earlier one's is left out (the pulse family's best is often the
    triangle's: a pulse of rise 0.5)."""
    phase = np.arange(settings.nodes) / settings.nodes
    out: list[StartGuess] = []
    for shape, choice in base.choices.items():
        if choice is None or shape in skip:
            continue
        tau = np.asarray(choice.signal_for(robot, settings)(phase), float).reshape(-1, phase.size)
        profiles = [(tau, f"{shape} baseline, tightened")]
        if models is not None:
            profiles.append((best_sampling(settings, models, choice)[1],
                             f"{shape} baseline, best node phase, tightened"))
        for nodes, label in profiles:
            guess = replace(given_start(settings, robot, nodes, choice.T, label), family=shape)
            # equal up to round-off: a pulse of rise 0.5 is the triangle
            atol = 1e-12 * float(np.max(np.abs(guess.tau)))
            if not any(np.allclose(guess.tau, o.tau, rtol=0.0, atol=atol)
                       and math.isclose(guess.T, o.T, rel_tol=1e-12) for o in out):
                out.append(guess)
    return out
