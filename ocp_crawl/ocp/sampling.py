"""A waveform family's member as the OCP can hold it: sampled at the N node phases, linear between
them.

A member is a signal of the continuous phase (a triangle wave's corners anywhere); the transcription
holds a profile linear between N nodes, and the OCP is free in the phase of its cycle (whole-node
shifts are one profile: the phase pin).  Which sub-node phase the nodes sample decides which
corners they hold: a member is sampled at :data:`NODE_SHIFTS` phases a fraction of a node interval
apart and the best by replay is kept: what an optimum worse than a member is compared with
(:func:`~ocp_crawl.ocp.gains.measure_gains`), and a further tightened start of each family
(:func:`~ocp_crawl.ocp.starts.family_starts`).
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.ocp.baseline import value_from
from ocp_crawl.ocp.judge import is_better, replay_misses, replay_signal
from ocp_crawl.ocp.plant import as_plant
from ocp_crawl.ocp.settings import OCPSettings

#: a member sampled at the OCP's nodes: its phase shifted by j / NODE_SHIFTS of a node interval, j =
#: 0 .. NODE_SHIFTS - 1, the best kept
NODE_SHIFTS = 4


def best_sampling(settings: OCPSettings, models: list, choice) -> tuple[float, np.ndarray]:
    """The best node profile of a family member.

    Parameters
    ----------
    settings : OCPSettings
        The OCP's settings (its N nodes, objective and requirements).
    models : list of Plant, Model or ChainModel
        One per friction scenario, in the OCP's order.
    choice : WaveChoice or ChainWaveChoice
        The member, at its period ``choice.T`` [s].

    Returns
    -------
    (float, np.ndarray)
        The objective value (speeds [m/s], CoT+ [-]) of the member's torques sampled at the N node
        phases shifted by j / NODE_SHIFTS of a node interval and replayed linear between the nodes,
        the best over j; a profile that misses a requirement by more than replay_tol counts as
        infeasible (-inf for speeds, +inf for CoT+); NaN when every replay fails.  And that
        profile's torques (m, N) [N m] (the unshifted one's when every replay fails).
    """
    plants = [as_plant(m) for m in models]
    signal = choice.signal_for(plants[0].robot, settings)
    N = settings.nodes
    nodes = np.arange(N) / N
    best, best_tau = math.nan, None
    for j in range(NODE_SHIFTS):
        tau = np.asarray(signal(np.mod(nodes + j / (NODE_SHIFTS * N), 1.0)), float).reshape(-1, N)
        best_tau = tau if best_tau is None else best_tau
        runs = [p.simulate(replay_signal(nodes, tau)) for p in plants]
        if not all(r.success for r in runs):
            continue
        cycle, misses = replay_misses(settings, plants[0].robot, runs, choice.T, tau)
        value = value_from(settings, cycle.S, cycle.CoT_plus, choice.T, feasible=not misses,
                           cycle=cycle)
        if math.isnan(best) or is_better(settings.objective, value, best):
            best, best_tau = value, tau
    assert best_tau is not None
    return best, best_tau
