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
    """Left: the scanned designs in their first two free variables (one: the value against it),
    coloured by their best harmonic gait's objective, with the given robot, the start and the
    chosen design marked; right: the objective of the given robot's best harmonic gait, of the
    best scanned design's, of the given robot's optimal gait and of the co-design optimum by
    replay."""
    fig = Figure(figsize=(11.0, 5.4), constrained_layout=True)
    ax, bx = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.4, 1.0]})
    free = [i for i, (lo, hi) in enumerate(zip(res.low, res.high)) if lo < hi]
    if free:
        _scan_panel(fig, ax, res, free[:2])
    else:
        ax.set_axis_off()
    _value_bars(bx, res)
    chosen = ", ".join(f"{res.names[i]} {units.significant(res.chosen[i], 4)} "
                       f"{_unit(res.names[i])}" for i in free if res.chosen) or "none"
    gains = res.gains()
    fig.suptitle(f"Co-design ({res.objective}, {res.status.label}): {chosen}\n"
                 f"{units.ratio(gains['over_given_optimum'])} over the given robot's optimal "
                 f"gait, {units.ratio(gains['over_scan'])} over the best of {len(res.scan)} "
                 "scanned designs' harmonic gaits", fontsize=10)
    return fig


def _scan_panel(fig: Figure, ax, res: CodesignResult, axes: list[int]) -> None:
    """The scanned designs in the variables ``axes`` (one or two indices)."""
    label = _label(res)
    values = np.array([_shown(res, d.value) for d in res.scan])
    pts = np.array([d.values for d in res.scan])
    two = len(axes) == 2
    x = pts[:, axes[0]]
    y = pts[:, axes[1]] if two else values
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
    for k, line in enumerate((ax.axvline, ax.axhline)[:len(axes)]):
        for j, bound in enumerate((res.low[axes[k]], res.high[axes[k]])):
            line(bound, color="gray", ls="--", lw=0.8,
                 label="the design's bounds" if k == j == 0 else None)
    marks = [(0, "s", "the given robot")]
    if res.start is not None:
        marks.append((res.start, "^", "the start of the co-design NLP"))
    for i, marker, text in marks:
        ax.plot(x[i], y[i], marker, mfc="none", mec="k", ms=13, label=text)
    if res.chosen:
        cy = res.chosen[axes[1]] if two else _shown(res, res.value_replay)
        ax.plot(res.chosen[axes[0]], cy, "*", color="tab:red", ms=16,
                label="the chosen design" + ("" if two else ", its optimal gait (replay)"))
    names = [res.names[i] for i in axes]
    for axis, name in zip((ax.set_xscale, ax.set_yscale), names if two else names[:1]):
        if name.startswith("stiffness"):
            axis("log")
    ax.set_xlabel(f"{names[0]} [{_unit(names[0])}]")
    ax.set_ylabel(f"{names[1]} [{_unit(names[1])}]" if two else label)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    ax.grid(alpha=0.3)


def _value_bars(bx, res: CodesignResult) -> None:
    """The four objective values as bars."""
    label = _label(res)
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
