"""The figure of a fit: every measurement file's data with error bars against the fitted model, and
the residuals."""
from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ocp_crawl.fit.data import DISPLAY, INPUTS
from ocp_crawl.fit.forward import RowTask, evaluate_rows, row_tasks
from ocp_crawl.fit.solve import FitResult
from ocp_crawl.io.files import atomic_write

#: display unit and factor from SI of the operating-point columns
INPUT_DISPLAY = {"angle": ("deg", 180.0 / math.pi), "pressure": ("bar", 1e-5),
                 "torque": ("N m", 1.0), "dimensionless": ("-", 1.0)}
LABELS = {"S": "S per cycle", "S_norm": "S / S_ref", "phi": "edge angle phi"}
#: characters of a 10-point title line per inch of figure width (a little less than fits)
TITLE_CHARS_PER_INCH = 14
#: abscissae of the model curve of a segment, besides the data's own (each one simulation)
CURVE_POINTS = 24


def _value(name: str, unit: str, x: float, s: float) -> str:
    short = name.split(".", 1)[1]
    if math.isnan(s):
        return f"{short} = {x:.4g} {unit} (no uncertainty)"
    if not math.isfinite(s):
        return f"{short} = {x:.4g} {unit} (not identifiable)"
    return f"{short} = {x:.4g} +- {s:.2g} {unit}"


def _inputs(fit: FitResult) -> str:
    """The pressure input form of a fit with pressure rows (amplitude and rest angle), else
    empty."""
    c = fit.pressure
    if not any(f.data.kind == "pressure" for f in fit.files) or "amplitude_bar" not in c:
        return ""
    rest = f"rest angle {c['phi_rest_deg']:.4g} deg"
    if math.isnan(c["amplitude_bar"]):
        return f"\ninputs: raised sine from 0 to the peak p0, {rest}"
    return (f"\ninputs: paper's form p0 + A_p sin(2 pi t +- psi/2), A_p = {c['amplitude_bar']:.4g} "
            f"bar (unless a file gives A_p), {rest}")


def _packed(head: str, items: list[str], width: int) -> str:
    """``head`` and ``items`` joined by "; ", a new line before an item that would pass ``width``
    characters."""
    lines = [head]
    for item in items:
        if len(lines[-1]) + 2 + len(item) > width:
            lines[-1] += ";"
            lines.append(item)
        else:
            lines[-1] += ("; " if lines[-1] != head else " ") + item
    return "\n".join(lines)


def _title(fit: FitResult, width: int) -> str:
    values = _packed(f"fit ({fit.status.label}):", [_value(p.name, p.unit, x, s)
                                                    for p, x, s in zip(fit.parameters, fit.x,
                                                                       fit.sigma)], width)
    n = len(fit.unidentified)
    said = f"; {n} direction(s) not determined by the data (see the report)" if n else ""
    rank = (f"rank {fit.rank} of {len(fit.parameters)}{said}" if fit.singular_values.size
            else "the search did not run")
    return f"{values}\nchi2/dof = {fit.chi2_red:.3g} ({fit.dof} dof), {rank}{_inputs(fit)}"


def model_curve(fit: FitResult, f, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """The model of file ``f`` over the rows ``rows`` (one segment, sorted by the abscissa) as a
    curve (abscissa, model, SI; and True): at the rows and at :data:`CURVE_POINTS` abscissae
    between their smallest and largest, the other inputs held at the rows' common values
    (simulated here), normalised as the file (``S_norm``).  Only the rows (and False) when the
    other inputs vary over them or the model failed at every row."""
    d = f.data
    name = d.abscissa
    x = np.asarray(d.table[name], float)[rows]
    at_rows = (x, np.asarray(f.model, float)[rows])
    fixed = {c: np.unique(np.asarray(d.table[c], float)[rows]) for c in d.inputs if c != name}
    if rows.size < 2 or fit.problem is None or any(v.size != 1 for v in fixed.values()) \
            or not np.isfinite(at_rows[1]).any():
        return (*at_rows, False)
    pj = json.dumps(fit.problem.to_dict(), sort_keys=True)
    pressure = tuple(sorted(fit.pressure.items()))
    grid = np.linspace(x.min(), x.max(), CURVE_POINTS)
    held = tuple((c, float(v[0])) for c, v in fixed.items())
    tasks = [RowTask(d.kind, pj, (), pressure, ((name, float(g)),) + held) for g in grid]
    ref = d.reference_row
    if ref is not None:   # the raw model S of the normalising row
        tasks.append(row_tasks(fit.problem, d, {}, fit.pressure)[ref])
    y = np.array([v for v, _ in evaluate_rows(tasks)], dtype=float)
    if ref is not None:
        y = y[:-1] / y[-1]
    xs = np.concatenate([x, grid])
    order = np.argsort(xs, kind="stable")
    return xs[order], np.concatenate([at_rows[1], y])[order], True


def fit_figure(fit: FitResult) -> Figure:
    """Data (error bars: one sigma) and model (fitted parameters; a curve, :func:`model_curve`)
    per file, residuals in sigmas below."""
    n = len(fit.files)
    fig = Figure(figsize=(5.2 * n, 5.6), constrained_layout=True)
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, n, squeeze=False, gridspec_kw={"height_ratios": [3, 1]}, sharex="col")
    for j, f in enumerate(fit.files):
        d = f.data
        name = d.abscissa
        xunit, xf = INPUT_DISPLAY[INPUTS[name]]
        yunit, yf = DISPLAY[d.observable]
        x = d.table[name] * xf
        order = np.argsort(x)
        ax, axr = axes[0, j], axes[1, j]
        ok = np.isfinite(f.model)
        segments = d.table["segment"] if "segment" in d.inputs else np.zeros(len(d))
        for i, seg in enumerate(np.unique(segments)):
            rows = order[segments[order] == seg]
            rows = rows[ok[rows]]
            which = f" (segment {seg:g})" if "segment" in d.inputs else ""
            ax.errorbar(x[segments == seg], d.y[segments == seg] * yf,
                        yerr=d.sigma[segments == seg] * yf, fmt="o",
                        color=("k", "tab:purple")[i % 2], ms=4, capsize=3,
                        label=f"data (+- 1 sigma){which}")
            xs, ys, dense = model_curve(fit, f, rows)
            at = "" if dense else ", at the rows"   # markers where the model is known only there
            ax.plot(xs * xf, ys * yf, "-" if dense else "-s", lw=1.6, ms=4, zorder=3,
                    color=("tab:blue", "tab:orange")[i % 2],
                    label=f"model at the fitted parameters{at}{which}")
        if (~ok).any():
            ax.plot(x[~ok], d.y[~ok] * yf, "x", color="tab:red", ms=9, mew=2,
                    label="simulation failed (data shown)")
        ref = d.reference_row
        if ref is not None:
            ax.plot(x[ref], d.y[ref] * yf, "o", mfc="none", mec="tab:red", ms=11, mew=1.5,
                    label="normalising row")
        others = [f"{c} = {v:g} {INPUT_DISPLAY[INPUTS[c]][0]}" for c in d.inputs if c != name
                  for v in [np.unique(np.round(d.table[c] * INPUT_DISPLAY[INPUTS[c]][1], 6))]
                  if v.size == 1 for v in [v[0]]]
        ax.set_title(f"{Path(d.path).name} ({d.kind}" + (", " + ", ".join(others) if others else "")
                     + ")", fontsize=9)
        ax.set_ylabel(f"{LABELS[d.observable]} [{yunit}]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        axr.axhline(0, color="0.5", lw=0.8)
        axr.plot(x, f.residuals, "o", color="tab:blue", ms=4, label="(model - data) / sigma")
        axr.set_xlabel(f"{name} [{xunit}]")
        axr.set_ylabel("residual [sigma]")
        axr.grid(alpha=0.3)
        axr.legend(fontsize=8)
    fig.suptitle(_title(fit, TITLE_CHARS_PER_INCH * int(5.2 * n)), fontsize=10)
    return fig


def plot_fit(fit: FitResult, path: str | os.PathLike) -> Path:
    """Save :func:`fit_figure` as a PNG at ``path`` (atomically); returns the path."""
    fig = fit_figure(fit)
    return atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=110))
