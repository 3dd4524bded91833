"""What a fit reports: the text summary, the JSON record, the fitted problem file and the residual
table."""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ocp_crawl.fit.data import DISPLAY
from ocp_crawl.fit.params import at_bound, pressure_defaults
from ocp_crawl.fit.solve import FitResult
from ocp_crawl.io.files import atomic_write, jsonable, write_json
from ocp_crawl.io.tables import write_table
from ocp_crawl.model.pressure import DEFAULT_FORM
from ocp_crawl.problem.overrides import toml_text
from ocp_crawl.problem.schema import SCHEMA

#: files written by :func:`write_fit` into its directory
FIT_FILES = {"problem": "fitted_problem.toml", "json": "fit.json", "residuals": "residuals.csv",
             "figure": "fit.png"}


def _num(v: float) -> str:
    return f"{v:.4g}" if math.isfinite(v) else ("inf" if v > 0 else "nan")


def identifiability_text(fit: FitResult) -> list[str]:
    """Lines saying the rank and every direction the data do not fix (empty list never: rank is
    always said)."""
    p = len(fit.parameters)
    if fit.singular_values.size == 0:
        return ["weighted Jacobian: none (the search did not run; no uncertainties)"]
    sv = ", ".join(f"{s:.3g}" for s in fit.singular_values)
    lines = [f"weighted Jacobian (relative parameters): rank {fit.rank} of {p}; singular values "
             f"{sv}"]
    for d in fit.unidentified:
        word = ("unidentifiable (rank-deficient)" if math.isinf(d.relative_sd)
                else "not determined (sd > 100 %)")
        lines.append(f"  {word}: {d.text()}")
    if not fit.unidentified:
        lines.append("  every parameter combination is determined by the data")
    return lines


def correlation_text(fit: FitResult) -> list[str]:
    """The correlation matrix, one row per parameter."""
    names = [p.name for p in fit.parameters]
    width = max(len(n) for n in names)
    rows = [" " * (width + 2) + " ".join(f"{j + 1:>6d}" for j in range(len(names)))]
    for i, n in enumerate(names):
        cells = " ".join(f"{c:+6.2f}" if math.isfinite(c) else "   nan" for c in fit.correlation[i])
        rows.append(f"{i + 1:d} {n:<{width}} {cells}")
    return rows


def fit_report(fit: FitResult) -> str:
    """The fit as text: status, parameters with uncertainties, chi-square, identifiability,
    correlations, files."""
    how = ("absolute sigmas: (J^T J)^-1" if fit.absolute_sigma
           else "sigmas as weights: s^2 (J^T J)^-1")
    lines = [f"fit        {fit.status.label}: {fit.message}",
             f"chi2       {fit.chi2:.4g} for {fit.dof} degrees of freedom (chi2/dof "
             f"{_num(fit.chi2_red)}); covariance from {how}"]
    if fit.scan is not None:
        lines.append(f"start      {fit.scan.text()}")
    for p, x, s in zip(fit.parameters, fit.x, fit.sigma):
        bound = "  AT A BOUND" if at_bound(p, x) else ""
        lines.append(f"  {p.name:<22} {x:12.6g} +- {_num(s):<10} {p.unit:<10} (start {p.x0:g}, "
                     f"bounds [{p.low:g}, {p.high:g}]){bound}")
    lines += identifiability_text(fit)
    if len(fit.parameters) > 1:
        lines += ["correlations"] + ["  " + r for r in correlation_text(fit)]
    for f in fit.files:
        unit, factor = DISPLAY[f.data.observable]
        finite = f.residuals[np.isfinite(f.residuals)]
        rms = float(np.sqrt(np.mean(finite ** 2))) if finite.size else math.nan
        failed = sum(s != "success" for s in f.statuses)
        lines.append(f"data       {f.data.path}: {len(f.data)} {f.data.kind} rows of "
                     f"{f.data.observable} [{unit}], RMS residual {rms:.3g} sigma"
                     + (f", {failed} failed" if failed else ""))
    return "\n".join(lines)


def fit_dict(fit: FitResult) -> dict[str, Any]:
    """The fit as a JSON-ready dict (values in problem-file units; SI in the per-row model
    values)."""
    return jsonable({
        "status": fit.status.label, "message": fit.message, "success": fit.success,
        "parameters": [{"name": p.name, "unit": p.unit, "value": float(x), "sigma": float(s),
                        "start": p.x0, "bounds": [p.low, p.high],
                        "at_bound": at_bound(p, x)} for p, x, s in zip(fit.parameters, fit.x,
                                                                       fit.sigma)],
        "covariance": fit.covariance.tolist(), "correlation": fit.correlation.tolist(),
        "covariance_from": "absolute_sigma" if fit.absolute_sigma else "scaled_by_chi2_red",
        "chi2": fit.chi2, "dof": fit.dof, "chi2_red": fit.chi2_red, "nfev": fit.nfev,
        "rank": fit.rank, "singular_values": fit.singular_values.tolist(),
        "unidentified": [{"singular_ratio": d.singular_ratio, "relative_sd": d.relative_sd,
                          "components": d.components} for d in fit.unidentified],
        "pressure": fit.pressure, "form": fit.form,
        "scan": None if fit.scan is None else {
            "points": fit.scan.points, "failed": fit.scan.failed,
            "chi2_start": fit.scan.chi2_start, "chi2_best": fit.scan.chi2_best,
            "search_start": None if fit.scan.best is None else list(fit.scan.best),
            "from_start": fit.scan.from_start},
        "files": [{"path": f.data.path, "kind": f.data.kind, "observable": f.data.observable,
                   "lines": f.data.table.lines.tolist(), "data_si": f.data.y.tolist(),
                   "sigma_si": f.data.sigma.tolist(),
                   "model_si": f.model.tolist(), "residuals": f.residuals.tolist(),
                   "statuses": list(f.statuses)}
                  for f in fit.files],
    })


def problem_toml(fit: FitResult) -> str:
    """The fitted problem as a problem file: the keys the input problem was given (no defaults
    added), the fitted values as keys (``pressure.*`` in ``[pressure]``, with
    :func:`pressure_keys`), the uncertainties in comments.  Simulating it at a row's operating point
    gives the model of that row."""
    head = [f"Fitted by ocp-crawl fit ({fit.status.label}; chi2/dof {_num(fit.chi2_red)}).",
            *[f"{n} = {v:.10g} +- {_num(s)} "
              f"{p.unit}" for (n, v), s, p in zip(fit.values().items(), fit.sigma,
                                                  fit.parameters)]]
    sections = fit.problem.given_dict()
    pressure = pressure_keys(fit, sections.get("pressure", {}))
    if pressure:
        sections["pressure"] = pressure
    return toml_text(sections, head)


def pressure_keys(fit: FitResult, given: Mapping[str, Any]) -> dict[str, Any]:
    """The ``[pressure]`` section of the fitted problem file: the keys the input gave, the fitted
    constants, and, when rows used the pressure constants, the form and every constant the fit used
    that differs from the form's default (``--pressure``, ``--form``), so that the file alone gives
    the fitted model."""
    out = dict(given)
    if fit.pressure:
        defaults = pressure_defaults(fit.problem.gravity, fit.form)
        if fit.form != DEFAULT_FORM or "form" in out:
            out["form"] = fit.form
        for key, value in fit.pressure.items():
            if math.isfinite(value) and (key in out or value != defaults[key]):
                out[key] = float(value)
    for name, value in fit.values().items():
        section, key = name.split(".", 1)
        if section == "pressure":
            out[key] = value
    order = [k.name for k in SCHEMA["pressure"].keys]
    return {k: out[k] for k in sorted(out, key=order.index)}


def residual_columns(fit: FitResult) -> list[tuple[str, str, list[float]]]:
    """Columns of the residual table: file index, file line, data, sigma, model (display units),
    residual."""
    cols: dict[str, list[float]] = {"file": [], "line": [], "data": [], "sigma": [], "model": [],
                                    "residual": []}
    for i, f in enumerate(fit.files):
        _, factor = DISPLAY[f.data.observable]
        cols["file"] += [i + 1] * len(f.data)
        cols["line"] += f.data.table.lines.tolist()
        cols["data"] += (f.data.y * factor).tolist()
        cols["sigma"] += (f.data.sigma * factor).tolist()
        cols["model"] += (f.model * factor).tolist()
        cols["residual"] += f.residuals.tolist()
    units = {"file": "-", "line": "-", "residual": "-"}
    only = {DISPLAY[f.data.observable][0] for f in fit.files}
    unit = only.pop() if len(only) == 1 else "-"
    return [(n, units.get(n, unit), v) for n, v in cols.items()]


def write_fit(fit: FitResult, out_dir: str | Path, figure: bool = True) -> list[Path]:
    """Write the fitted problem file, fit.json, residuals.csv and (``figure``) fit.png into
    ``out_dir``, atomically.

    Returns the paths written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    text = problem_toml(fit).encode("utf-8")
    paths = [atomic_write(out / FIT_FILES["problem"], lambda f: f.write(text)),
             write_json(out / FIT_FILES["json"], fit_dict(fit))]
    only = {DISPLAY[f.data.observable][0] for f in fit.files}
    comments = ["residual = (model - data) / sigma; file = index in: "
                f"{', '.join(f.data.path for f in fit.files)}"]
    if len(only) > 1:
        comments.append("data, sigma, model in mm (S), deg (phi) or - (S_norm) per file")
    paths.append(write_table(out / FIT_FILES["residuals"], residual_columns(fit), comments))
    if figure:
        from ocp_crawl.fit.plot import plot_fit
        paths.append(plot_fit(fit, out / FIT_FILES["figure"]))
    return paths
