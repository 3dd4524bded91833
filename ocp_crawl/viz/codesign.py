"""The figure of a co-design (:func:`codesign_figure`): the scanned designs with their best
harmonic gaits, the design the NLP started from and the design it chose."""
from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from ocp_crawl.io import units
from ocp_crawl.ocp.codesign import CodesignResult


def _unit(name: str) -> str:
    return "N m/rad" if name.startswith("stiffness") else "m"


def _shown(res: CodesignResult, value: float) -> float:
    """An objective value as plotted: a speed in mm/s, any other in its unit."""
    return value * 1e3 if res.unit == "m/s" else value


def _label(res: CodesignResult) -> str:
    """The plotted objective's name and unit."""
    if res.unit == "m/s":
        return "speed [mm/s]"
    return f"{'CoT+' if res.objective == 'min_cot' else res.objective} [{res.unit}]"


def codesign_figure(res: CodesignResult) -> Figure:
    """Left: the scanned designs in their first two variables (one variable: the value against
    it), coloured by their best harmonic gait's objective, with the given robot, the start and the
    chosen design marked; right: the objective of the given robot's best harmonic gait, of the
    best scanned design's, and of the co-design optimum by replay."""
    fig = Figure(figsize=(11.0, 4.6), constrained_layout=True)
    ax, bx = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.4, 1.0]})
    obj = res.objective
    label = _label(res)
    values = np.array([_shown(res, d.value) for d in res.scan])
    pts = np.array([d.values for d in res.scan])
    two = len(res.names) >= 2
    x = pts[:, 0]
    y = pts[:, 1] if two else values
    ok = np.isfinite(values)
    if two:
        sc = ax.scatter(x[ok], y[ok], c=values[ok], cmap="viridis", s=60,
                        label="scanned design (colour: its best harmonic gait)")
        fig.colorbar(sc, ax=ax, label=f"best harmonic gait's {label}")
    else:
        ax.plot(x[ok], y[ok], "o", color="tab:blue", label="scanned design, its best harmonic gait")
    if not ok.all():
        ax.plot(x[~ok], y[~ok] if two else np.zeros((~ok).sum()), "x", color="tab:red",
                label="scanned design without a harmonic gait")
    for i, line in enumerate((ax.axvline, ax.axhline)[:2 if two else 1]):
        for j, bound in enumerate((res.low[i], res.high[i])):
            line(bound, color="gray", ls="--", lw=0.8,
                 label="the design's bounds" if i == j == 0 else None)
    marks = [(0, "s", "the given robot")]
    if res.start is not None:
        marks.append((res.start, "^", "the start of the co-design NLP"))
    for i, marker, text in marks:
        ax.plot(x[i], y[i], marker, mfc="none", mec="k", ms=13, label=text)
    if res.chosen:
        cy = res.chosen[1] if two else _shown(res, res.value_replay)
        ax.plot(res.chosen[0], cy, "*", color="tab:red", ms=16,
                label="the chosen design" + ("" if two else ", its optimal gait (replay)"))
    for axis, name in ((ax.set_xscale, res.names[0]), (ax.set_yscale, res.names[1] if two else "")):
        if name.startswith("stiffness"):
            axis("log")
    ax.set_xlabel(f"{res.names[0]} [{_unit(res.names[0])}]")
    ax.set_ylabel(f"{res.names[1]} [{_unit(res.names[1])}]" if two else label)
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    best = res.best_scanned
    bars = [("given robot,\nbest harmonic", res.scan[0].value if res.scan else math.nan),
            ("best scanned\ndesign, best\nharmonic", best.value if best else math.nan),
            ("given robot,\noptimal gait\n(replay)",
             res.given.value_replay if res.given is not None else math.nan),
            ("co-design\noptimum\n(replay)", res.value_replay)]
    heights = [_shown(res, v) for _, v in bars]
    bx.bar(range(4), heights, color=["tab:gray", "tab:blue", "tab:olive", "tab:red"])
    bx.set_xticks(range(4), [t for t, _ in bars], fontsize=8)
    bx.set_ylabel(label)
    for i, h in enumerate(heights):
        if math.isfinite(h):
            bx.annotate(f"{h:.4g}", (i, h), ha="center", va="bottom", fontsize=9)
    bx.grid(axis="y", alpha=0.3)
    chosen = ", ".join(f"{n} {units.significant(v, 4)} {_unit(n)}"
                       for n, v in zip(res.names, res.chosen)) or "none"
    gains = res.gains()
    fig.suptitle(f"Co-design ({obj}, {res.status.label}): {chosen}\n"
                 f"{units.ratio(gains['over_given_optimum'])} over the given robot's optimal "
                 f"gait, {units.ratio(gains['over_scan'])} over the best of {len(res.scan)} "
                 "scanned designs' harmonic gaits", fontsize=10)
    return fig
