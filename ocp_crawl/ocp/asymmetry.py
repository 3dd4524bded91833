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
rule: at exactly known friction the optimum is what the model gives.  A replay that fails at the
moved ratio (the gait cannot go on under the asymmetry) is reported with its message, and S = 0
has no relative change: neither is called a tie.
"""
from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ocp_crawl.io import units
from ocp_crawl.ocp.judge import replay_misses, replay_signal, scenario_labels
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


def friction_asymmetry(plants: list[Plant], signal, S: list, delta: float = ASYMMETRY,
                       labels: list[str] | None = None,
                       misses: Callable[[list], list[str]] | None = None) -> dict:
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
        The displacement per cycle [m] of each scenario's own replay, as many as ``plants``.
    delta : float
        The relative asymmetry [-].
    labels : list of str, optional
        The scenarios' labels (:func:`~ocp_crawl.ocp.judge.scenario_labels`; None: one scenario).
    misses : callable, optional
        The requirements a gait misses, as texts, given its replays (CrawlResult) in every scenario
        at one moved ratio; asked at each ratio where every scenario's replay succeeded.

    Returns
    -------
    dict
        ``delta``; ``labels``; ``S_m``: per scenario [S at 1 - delta, S, S at 1 + delta] [m] (None
        where that simulation failed); ``change``: the largest |S' - S| / |S| [-] over the
        successful ones (None where none has a relative change: every one failed, or S = 0);
        ``messages``: the failed simulations' messages; ``missed``: what ``misses`` found, each
        text preceded by its ratio's factor ("at mu1/mu2 x 0.995, ...").
    """
    if len(plants) != len(S):
        raise ValueError(f"friction_asymmetry: {len(plants)} scenarios but {len(S)} values of S")
    factors = (1 - delta, 1 + delta)
    runs = {f: [asymmetric(plant, f).simulate(signal) for plant in plants] for f in factors}
    rows, changes, messages, found = [], [], [], []
    for i, s in enumerate(S):
        for f in factors:
            res = runs[f][i]
            if not res.success:
                where = f"{labels[i]}, " if labels else ""
                messages.append(f"{where}mu1/mu2 x {f:g}: {res.message}")
            elif s != 0:
                changes.append(abs(float(res.S) - s) / abs(s))
        rows.append([_S(runs[factors[0]][i]), float(s), _S(runs[factors[1]][i])])
    for f in factors:
        if misses is not None and all(r.success for r in runs[f]):
            found += [f"at mu1/mu2 x {f:g}, {text}" for text in misses(runs[f])]
    return {"delta": delta, "labels": labels, "S_m": rows,
            "change": max(changes) if changes else None, "messages": messages, "missed": found}


def _S(res) -> float | None:
    """A replay's S [m], None where it failed."""
    return float(res.S) if res.success else None


def ties_decide(d: dict | None) -> bool:
    """Whether the report ``d`` of :func:`friction_asymmetry` shows a friction tie deciding the
    slip: every replay succeeded and S changed by more than :data:`TIE_FACTOR` times the
    asymmetry."""
    if not d or d["messages"] or d["change"] is None:
        return False
    return bool(d["change"] > TIE_FACTOR * d["delta"])


def _remedy(settings) -> str:
    """What to ask for instead of a gait that a friction tie decides, for these settings."""
    if settings.ratio_set:
        return "a wider set of friction ratios, [ocp] mu_ratio_eps"
    ask = "a gait that holds over a set of friction ratios: [ocp] mu_ratio_eps"
    # robust = "worst" exists for the named speed and CoT+ objectives only (objectives.py)
    return ask + ' with robust = "worst"' if settings.objective in ("max_speed", "min_cot") else ask


def check_friction_asymmetry(res, models: list) -> None:
    """Report how a friction asymmetry moves a confirmed optimum.

    Parameters
    ----------
    res : OCPResult
        An optimum judged by replay; nothing is done unless ``res.success`` with a replay in every
        scenario (an optimum solved without replay has none).  Sets
        ``res.friction_asymmetry`` (:func:`friction_asymmetry`) and, where a friction tie decides
        the slip or a replay at the moved ratio fails, says so in ``res.message``.
    models : list of Plant, Model or ChainModel
        One per friction scenario, in the OCP's order.
    """
    if not res.success or len(res.S_replay) != len(models):
        return
    s, N = res.settings, res.tau.shape[1]
    plants = [as_plant(m) for m in models]

    def misses(runs: list) -> list[str]:
        return replay_misses(s, plants[0].robot, runs, res.T_ocp, res.tau)[1]

    labels = scenario_labels(s) if len(models) > 1 else None
    d = friction_asymmetry(plants, replay_signal(np.arange(N) / N, res.tau), res.S_replay,
                           labels=labels, misses=misses)
    res.friction_asymmetry = d
    pct = _percent(d["delta"])
    if d["messages"]:
        res.message += (f"; at a {pct} friction asymmetry the replay fails "
                        f"({'; '.join(d['messages'])})")
    elif ties_decide(d):
        res.message += (f"; S changes by {_percent(d['change'])} at a {pct} friction asymmetry: a "
                        f"friction tie decides which foot slips ({_remedy(s)})")
    if d["missed"]:
        res.message += (f"; under a {pct} friction asymmetry the replay misses its requirements "
                        f"({'; '.join(d['missed'])}; {_remedy(s)})")


def asymmetry_text(d: dict | None) -> list[str]:
    """The text lines of ``optimize``'s summary for its ``friction_asymmetry`` entry ([] without):
    one, or one per labelled scenario, then the verdict."""
    if not d:
        return []
    pct = _percent(d["delta"])
    rows = [", ".join("-" if s is None else units.distance(s) for s in row) for row in d["S_m"]]
    labels = d.get("labels") or [""] * len(rows)
    lines = [f"friction    S at mu1/mu2 x (1 - {pct}, 1, 1 + {pct}): "
             + ("" if len(rows) > 1 else rows[0])]
    lines += [f"            scenario {label}: {row}" for label, row in zip(labels, rows)
              if len(rows) > 1]
    change = d["change"]
    verdict = ("-" if change is None
               else f"{_percent(change)} ({change / d['delta']:.3g} times the asymmetry)")
    if d["messages"]:
        verdict += f"; failed: {'; '.join(d['messages'])}"
    elif ties_decide(d):
        verdict += "; a friction tie decides the slip"
    if d.get("missed"):
        verdict += f"; misses {'; '.join(d['missed'])}"
    return lines + [f"            largest change {verdict}"]


def _percent(x: float) -> str:
    """A fraction [-] as an unsigned percentage, e.g. "0.5 %"."""
    return f"{100 * x:.3g} %"
