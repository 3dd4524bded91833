"""How an optimum's displacement depends on the feet's friction ratio: its replay at mu1/mu2 moved
by a small asymmetry.

Which foot slips is decided by the feet's friction limits mu_i f_n,i.  Where a gait slips at the
tie of the two limits, friction that is never known exactly decides its displacement: the
mirror-symmetric harmonic gait of the paper robot (gamma 90, A 30, psi 0.01 deg) crawls 60.19 mm per
cycle at mu1 = mu2 and none at mu1/mu2 = 0.995 or 1.005.  A gait whose slips stay clear of the tie
changes its S by about the asymmetry, one whose slip phases end near the tie by several times it
(the paper robot's optima: docs/guide/optimal_gaits.md, "Friction uncertainty").  So every judged
optimum is replayed once more in each friction scenario with mu1/mu2 multiplied by 1 - delta and
by 1 + delta (the geometric mean sqrt(mu1 mu2) kept, as the friction set's scenarios are:
:meth:`OCPSettings.scenarios`), delta = :data:`ASYMMETRY` = 0.5 %, and the largest relative change
of S is reported.  A change of more than :data:`TIE_FACTOR` times delta means a friction tie
decides the slip; the message then says so and what to ask for instead (a friction set,
``mu_ratio_eps``, whose optimum holds its value at each ratio of the set).  It is a report, not a
rule: at exactly known friction the optimum is what the model gives.
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.io import units
from ocp_crawl.ocp.plant import Plant, as_plant, with_friction

#: the relative asymmetry of the friction ratio mu1/mu2 at which an optimum is replayed again [-]
ASYMMETRY = 0.005
#: a change of S larger than this many times the asymmetry is a friction tie's, not a smooth one's
TIE_FACTOR = 10.0


def asymmetric(plant: Plant, factor: float) -> Plant:
    """``plant``'s robot with mu1/mu2 multiplied by ``factor`` at the same sqrt(mu1 mu2)."""
    r = plant.robot
    root = math.sqrt(factor)
    return Plant(with_friction(r, r.mu1 * root, r.mu2 / root), plant.gravity)


def friction_asymmetry(plants: list[Plant], signal, S: list, delta: float = ASYMMETRY) -> dict:
    """Replay ``signal`` (a torque signal of the phase [N m]) in each friction scenario's plant at
    mu1/mu2 times 1 - ``delta`` and 1 + ``delta``.

    Parameters
    ----------
    plants : list of Plant
        One per friction scenario (the OCP's, in its order).
    signal : callable
        The optimum's torques tau(t) [N m] of the phase t [cycles]
        (:func:`~ocp_crawl.ocp.judge.replay_signal`).
    S : list of float
        The displacement per cycle [m] of each scenario's own replay.
    delta : float
        The relative asymmetry [-].

    Returns
    -------
    dict
        ``delta``; ``S_m``: per scenario [S at 1 - delta, S, S at 1 + delta] [m] (None where that
        simulation failed); ``change``: the largest |S' - S| / |S| over them [-] (1 where a
        simulation failed or S is 0: the gait's displacement is not defined by the ratio);
        ``messages``: the failed simulations' messages.
    """
    rows, changes, messages = [], [], []
    for plant, s in zip(plants, S):
        row: list[float | None] = []
        for factor in (1 - delta, 1 + delta):
            res = asymmetric(plant, factor).simulate(signal)
            row.append(float(res.S) if res.success else None)
            if not res.success:
                messages.append(f"mu1/mu2 x {factor:g}: {res.message}")
        rows.append([row[0], float(s), row[1]])
        for other in row:
            changes.append(1.0 if other is None or s == 0 else abs(other - s) / abs(s))
    return {"delta": delta, "S_m": rows, "change": max(changes, default=math.nan),
            "messages": messages}


def ties_decide(d: dict | None) -> bool:
    """Whether the report ``d`` of :func:`friction_asymmetry` shows a friction tie deciding the
    slip (a change of S of more than :data:`TIE_FACTOR` times the asymmetry)."""
    return bool(d) and not d["change"] <= TIE_FACTOR * d["delta"]


def check_friction_asymmetry(res, models: list) -> None:
    """Set ``res.friction_asymmetry`` of an OCPResult judged ``success`` (nothing otherwise) and,
    where a friction tie decides the slip, say so in its message with what to ask for instead."""
    from ocp_crawl.ocp.judge import replay_signal

    if not res.success:
        return
    N = res.tau.shape[1]
    plants = [as_plant(m) for m in models]
    d = friction_asymmetry(plants, replay_signal(np.arange(N) / N, res.tau), res.S_replay)
    res.friction_asymmetry = d
    if ties_decide(d):
        res.message += (f"; S changes by {_percent(d['change'])} at a "
                        f"{_percent(d['delta'])} friction asymmetry: a friction tie decides "
                        "which foot slips (a gait that holds over a set of friction ratios: "
                        "[ocp] mu_ratio_eps with robust = \"worst\")")


def asymmetry_text(d: dict | None) -> list[str]:
    """The text line of ``optimize``'s summary for its ``friction_asymmetry`` entry ([] without)."""
    if not d:
        return []
    pct = _percent(d["delta"])
    rows = "; ".join(", ".join("-" if s is None else units.distance(s) for s in row)
                     for row in d["S_m"])
    tie = "; a friction tie decides the slip" if ties_decide(d) else ""
    return [f"friction    S at mu1/mu2 x (1 - {pct}, 1, 1 + {pct}): {rows}; largest change "
            f"{_percent(d['change'])} ({d['change'] / d['delta']:.3g} times the asymmetry){tie}"]


def _percent(x: float) -> str:
    """A fraction [-] as an unsigned percentage, e.g. "0.5 %"."""
    return f"{100 * x:.3g} %"
