"""A chain of n >= 3 links in a problem file: ``[robot] lengths, masses, stiffness`` (with ``com``
and ``rest_deg``) instead of the symmetric three-link shorthand ``M, L, beta, k``.

The robot is a :class:`~ocp_crawl.model.chain.Chain`; its gait is the harmonic waveform of every
joint, ``phi_j = gamma_j + A_j sin(2 pi t + psi ((m - 1)/2 - (j - 1)))`` for the m = n - 1 joints
(``psi_deg`` the phase lead of each joint over the next one; m = 2 is the paper's eq. (ref)),
``gamma_deg`` and ``A_deg`` for every joint, or ``gamma_joints_deg`` and ``A_joints_deg`` one per
joint; or pulses with those centres, half swings and phase leads (``waveform = "pulse"``, with
``rise``, ``hold`` and ``ramp`` as for the three-link robot's pulses); or samples of one cycle
from a CSV file with a column per joint (``waveform = "samples"``, ``file``: ``phase [-]`` and
``phi1_ref .. phi<m>_ref [deg]`` or ``tau1 .. tau<m> [N m]``, interpolated as ``interpolation``
says).  The torque drive is ``tau_j = k_j (phi_ref_j - pi - rest_j)``; torque samples stand for
the reference angles ``pi + rest_j + tau_j / k_j``, the same torques (each interpolation
commutes with that increasing affine map of the samples).  A chain also takes the pressure
actuator of the paper's robot (``waveform = "pressure"`` and its ``[pressure]`` section): a
segment per joint on three links, so that its joints, legs and rest bends may differ; on more
links ``[pressure] segments`` gives the segment of each joint, and the joints of a segment share
its bend equally (the segment bent as an arc of hinges).
"""
from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_inputs import JointFourier
from ocp_crawl.model.inputs import PeriodicSignal
from ocp_crawl.model.pressure import SegmentJoints
from ocp_crawl.model.pulse import JointPulse
from ocp_crawl.problem.keys import ProblemError
from ocp_crawl.problem.messages import format_value
from ocp_crawl.problem.values import Context
from ocp_crawl.problem.waveforms import (JOINT_INTERPOLANTS, check_pulse_fits, driven_samples,
                                         file_samples, pressure_reference)

#: the [robot] keys of a chain (``lengths`` marks a chain; ``masses`` and ``stiffness`` go with it)
CHAIN_KEYS = ("lengths", "masses", "stiffness", "com", "rest_deg")
#: the [robot] keys of the three-link shorthand, which a chain replaces
THREE_LINK_KEYS = ("M", "L", "beta", "k")
#: the [gait] keys of the three-link robot's two joints, replaced by lists for a chain
TWO_JOINT_KEYS = ("gamma1_deg", "gamma2_deg", "A1_deg", "A2_deg")
#: the [gait] keys of a chain's joints, one entry per joint
JOINT_KEYS = ("gamma_joints_deg", "A_joints_deg")
#: the waveforms of a chain's joints
CHAIN_WAVEFORMS = ("harmonic", "pulse", "samples", "pressure")
#: the [gait] keys of the three-link robot's inline samples (a chain's samples come from a file)
INLINE_SAMPLE_KEYS = ("phase", "phi1_ref_deg", "phi2_ref_deg", "tau1", "tau2")


def is_chain(robot: Mapping[str, Any]) -> bool:
    """Whether the validated ``[robot]`` values describe a chain (``lengths`` given)."""
    return "lengths" in robot


def chain_robot(ctx: Context, robot: Mapping[str, Any], given: Mapping[str, Any]) -> Chain:
    """The :class:`Chain` of the validated ``[robot]`` values; ProblemError naming the key whose
    value the chain rejects (a count that does not match the links, a length ratio)."""
    for name in THREE_LINK_KEYS:
        if name in given:
            raise ProblemError(f"{ctx.at('robot', name, given[name])} and lengths = "
                               f"{format_value(given['lengths'])} are mutually exclusive: a chain "
                               "([robot] lengths, masses, stiffness) has no three-link shorthand")
    for name in ("com", "rest_deg"):   # (absent: the defaults; given: one value each)
        if name in robot and len(robot[name]) == 0:
            raise ProblemError(f"{ctx.at('robot', name, robot[name])} is invalid: give a value per "
                               f"{'link' if name == 'com' else 'joint'}, or leave the key out for "
                               "the default")
    rest = [math.radians(r) for r in robot.get("rest_deg", ())]
    try:
        return Chain(lengths=robot["lengths"], masses=robot["masses"],
                     stiffness=robot["stiffness"], mu=feet_friction(robot),
                     com=robot.get("com"), rest=rest or None, g=robot["g"])
    except ValueError as exc:
        text = str(exc)
        # the key the chain's message names first ("total mass sum(masses) ...": masses)
        named = [(text.find(k.removesuffix("_deg")), k) for k in CHAIN_KEYS
                 if k in robot and k.removesuffix("_deg") in text]
        name = min(named)[1] if named else "lengths"
        raise ProblemError(f"{ctx.at('robot', name, robot[name])} is invalid: {text}") from None


def feet_friction(robot: Mapping[str, Any]) -> tuple[float, float]:
    """(mu1, mu2) of the validated ``[robot]`` values: ``mu`` for both feet, or ``mu1``, ``mu2``."""
    return (robot["mu"], robot["mu"]) if "mu" in robot else (robot["mu1"], robot["mu2"])


def _per_joint(ctx: Context, gait: Mapping[str, Any], name: str, common: str, m: int) -> list:
    values = gait.get(name)
    if values is None:
        return [gait[common]] * m   # (the schema asks for one of the two)
    if len(values) != m:
        raise ProblemError(f"{ctx.at('gait', name, values)} is invalid: the chain has {m} joints, "
                           f"one value each")
    return list(values)


def chain_waveform(ctx: Context, gait: Mapping[str, Any]) -> None:
    """ProblemError for a chain's ``[gait]`` of a waveform its joints do not take (checked on the
    keys as given, before that waveform's own keys are asked for)."""
    waveform = gait.get("waveform", "harmonic")
    if waveform not in CHAIN_WAVEFORMS:
        raise ProblemError(f"{ctx.at('gait', 'waveform', waveform)} is invalid with a chain "
                           "([robot] lengths): its joints take the waveforms "
                           f"{', '.join(map(format_value, CHAIN_WAVEFORMS))} (samples from a file "
                           "with a column per joint)")


def chain_gait(ctx: Context, gait: Mapping[str, Any], chain: Chain,
               pressure: Mapping[str, Any], gravity: str) -> tuple[PeriodicSignal, dict]:
    """The reference angles [rad] of a chain's ``[gait]`` (one row per joint) and the section's
    values (a sample file's name resolved, its period); ``pressure``: the validated ``[pressure]``
    values, ``gravity``: the convention (the pressure waveform's rest angle depends on it)."""
    for name in TWO_JOINT_KEYS:
        if name in gait:
            raise ProblemError(f"{ctx.at('gait', name, gait[name])} is a key of the three-link "
                               "robot's two joints: a chain ([robot] lengths) gives "
                               f"{' and '.join(JOINT_KEYS)}, one value per joint")
    if gait["waveform"] == "samples":
        return _chain_samples(ctx, gait, chain)
    m = chain.n_joints
    if gait["waveform"] == "pressure":
        return _chain_pressure(ctx, gait, chain, pressure, gravity), dict(gait)
    gamma = np.radians(_per_joint(ctx, gait, "gamma_joints_deg", "gamma_deg", m))
    amplitude = np.radians(_per_joint(ctx, gait, "A_joints_deg", "A_deg", m))
    lead = np.radians([gait["psi_deg"] * ((m - 1) / 2 - j) for j in range(m)])
    if gait["waveform"] == "pulse":
        check_pulse_fits(gait, ctx.at)
        pulse = JointPulse(gamma, amplitude, lead, gait["rise"], gait["hold"], gait["ramp"])
        return pulse, dict(gait)
    return JointFourier.harmonic(gamma, amplitude, lead), dict(gait)


def _chain_pressure(ctx: Context, gait: Mapping[str, Any], chain: Chain,
                    pressure: Mapping[str, Any], gravity: str) -> PeriodicSignal:
    """The reference angles [rad] of a chain driven by the pressure actuator: its two segments'
    (:func:`pressure_reference`) on a chain of three links, else shared by the joints of each
    segment as ``[pressure] segments`` assigns them (:class:`SegmentJoints`)."""
    reference = pressure_reference(gait, pressure, gravity, ctx.at)
    segments, m = pressure.get("segments"), chain.n_joints
    if segments is None:
        if m == 2:
            return reference
        example = [1] * (m // 2) + [2] * (m - m // 2)
        raise ProblemError(f"{ctx.at('gait', 'waveform', 'pressure')} with a chain of {chain.n} "
                           f"links needs [pressure] segments, the segment (1 or 2) of each of its "
                           f"{m} joints (e.g. segments = {format_value(example)})")
    segments = _whole(segments)
    if len(segments) != m or segments != sorted(segments) or set(segments) != {1, 2}:
        raise ProblemError(f"{ctx.at('pressure', 'segments', segments)} is invalid with a "
                           f"chain of {chain.n} links: give the segment (1 or 2) of each of its "
                           f"{m} joints, segment 1's first, each segment at least one")
    return SegmentJoints(reference, tuple(int(s) - 1 for s in segments))


def _whole(segments) -> list:
    """The segment numbers as the file writes them (the schema reads arrays as floats; each entry
    has passed its rule, 1 or 2)."""
    return [int(s) for s in segments]


def _chain_samples(ctx: Context, gait: Mapping[str, Any],
                   chain: Chain) -> tuple[PeriodicSignal, dict]:
    """The reference angles [rad] of a chain's sample file (torques as the reference angles that
    stand for them) and the section's values."""
    if "file" not in gait:
        given = [k for k in INLINE_SAMPLE_KEYS if k in gait]
        key = given[0] if given else "waveform"
        raise ProblemError(f"{ctx.at('gait', key, gait[key])} is invalid with a chain ([robot] "
                           "lengths): its samples come from a file, [gait] file, with 'phase [-]' "
                           "and a column per joint")
    values = dict(gait)
    samples = file_samples(gait, ctx.at, ctx.base, values, chain.n_joints)
    t, v = driven_samples(samples, gait["interpolation"], gait["drive"], ctx.at)
    if samples.torque:
        v = (math.pi + np.asarray(chain.rest)[:, None]
             + v / np.asarray(chain.stiffness)[:, None])
    return JOINT_INTERPOLANTS[gait["interpolation"]](t, v), values


def segments_of_a_chain(ctx: Context, pressure: Mapping[str, Any]) -> None:
    """ProblemError for ``[pressure] segments`` given to the three-link robot."""
    if "segments" in pressure:
        raise ProblemError(f"{ctx.at('pressure', 'segments', _whole(pressure['segments']))} is a "
                           "key of a chain ([robot] lengths): the three-link robot has one joint "
                           "per segment")


def joint_keys_of_a_chain(ctx: Context, gait: Mapping[str, Any]) -> None:
    """ProblemError for a chain's per-joint key in the ``[gait]`` of the three-link robot."""
    for name in JOINT_KEYS:
        if name in gait:
            raise ProblemError(f"{ctx.at('gait', name, gait[name])} is a key of a chain ([robot] "
                               "lengths, masses, stiffness): the three-link robot's joints take "
                               "gamma1_deg, gamma2_deg, A1_deg, A2_deg")
