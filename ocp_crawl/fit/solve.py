"""Weighted least squares of chosen parameters on simulated measurements: :func:`fit_measurements`.

The residual of row j of a file is r_j = (model_j - y_j) / sigma_j (the normalising row of an
``S_norm`` file is left out: it is 1 - 1 = 0 whatever the parameters).
``scipy.optimize.least_squares`` (trust-region reflective, bounds) minimises sum r_j^2 over the
parameters, scaled by their start values so that every variable is of order 1 (its finite-difference
Jacobian then steps every parameter by about 1e-4 of its size, far above the simulations'
round-off).

Uncertainties.  J is the Jacobian of r at the solution (per unit of each parameter).  With
``absolute_sigma`` (default) the sigmas are taken as the data's standard uncertainties and the
covariance is (J^T J)^-1; otherwise it is scaled by the reduced chi-square s^2 = chi^2 / (n - p)
(the sigmas are then only relative weights).  Both are reported through ``chi2_red``.

Identifiability.  The singular values s_i of J D, D = diag(|x|) (a relative change of every
parameter), say what the data fix: along the right singular vector v_i, a relative change of
the parameters is determined to 1 / s_i.  Directions with s_i <= ``rcond`` s_max are numerically
unidentifiable (the rank is the number of the others); directions with 1 / s_i > 1 are fixed
to no better than 100 %.  Both are listed (:class:`Direction`), the parameters involved get an
infinite sigma, and the correlation matrix (from the covariance of the identifiable directions)
shows the trade-offs.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
from scipy.optimize import least_squares

from ocp_crawl.fit.checks import check_inputs
from ocp_crawl.fit.data import Measurements
from ocp_crawl.fit.forward import SUCCESS, evaluate_rows, model_values, row_tasks
from ocp_crawl.fit.params import Parameter, pressure_form, problem_pressure, split_values
from ocp_crawl.fit.starts import Scan, scan_starts
from ocp_crawl.model.pressure import DEFAULT_FORM
from ocp_crawl.problem import Problem
from ocp_crawl.status import Status
from ocp_crawl.workers import worker_pool

#: where the fit starts, in messages
START = "the start values"
#: residual (in sigmas) given to a row whose simulation failed during the search, to steer away from
#: it
FAILED_RESIDUAL = 1e3
#: singular values below RCOND * the largest are numerically zero (finite differences are good to
#: ~1e-6)
RCOND = 1e-4
#: a direction fixed to worse than this relative standard deviation is reported as not determined
POOR = 1.0
DIFF_STEP = 1e-4


@dataclass(frozen=True)
class FileFit:
    """Data and model of one measurement file at the fitted parameters."""

    data: Measurements = field(repr=False)
    model: np.ndarray
    """model values (SI, as the observable)"""
    statuses: tuple[str, ...]

    @property
    def residuals(self) -> np.ndarray:
        """(model - data) / sigma per row (0 at the normalising row)"""
        # an overflowing row is found (not finite) and reported by the caller
        with np.errstate(over="ignore"):
            return (self.model - self.data.y) / self.data.sigma


@dataclass(frozen=True)
class Direction:
    """A combination of relative parameter changes that the data do not fix."""

    singular_ratio: float
    """s_i / s_max"""
    relative_sd: float
    """1 / s_i: standard deviation of the relative change along this direction"""
    components: dict[str, float]
    """parameter -> component of the unit vector (in relative changes d x / x)"""

    def text(self) -> str:
        terms = " ".join(f"{c:+.2f} dlog({n})" for n, c in self.components.items()
                         if abs(c) >= 0.05)
        return f"{terms} (s/s_max = {self.singular_ratio:.1e}, relative sd {self.relative_sd:.2g})"


@dataclass(frozen=True)
class FitResult:
    """Outcome of :func:`fit_measurements`; values in problem-file units (angles in degrees)."""

    parameters: tuple[Parameter, ...]
    x: np.ndarray
    sigma: np.ndarray
    """standard uncertainties (inf: not identifiable)"""
    covariance: np.ndarray
    correlation: np.ndarray
    singular_values: np.ndarray
    """of J D (see the module docstring), largest first"""
    rank: int
    unidentified: tuple[Direction, ...]
    files: tuple[FileFit, ...]
    chi2: float
    dof: int
    nfev: int
    status: Status
    message: str
    absolute_sigma: bool
    problem: Problem = field(repr=False)
    """the input problem with the fitted problem keys"""
    pressure: dict[str, float] = field(default_factory=dict)
    """the pressure constants of the fit (fitted or not); empty when no row uses them"""
    form: str = DEFAULT_FORM
    """the pressure input form of the fit (:data:`~ocp_crawl.model.pressure.PRESSURE_FORMS`)"""
    scan: Scan | None = None
    """the sample evaluated for the search's start (``starts``), None without one"""

    @property
    def success(self) -> bool:
        return self.status == Status.SUCCESS

    @property
    def chi2_red(self) -> float:
        return self.chi2 / self.dof if self.dof > 0 else math.nan

    @property
    def identifiable(self) -> bool:
        return not self.unidentified

    def values(self) -> dict[str, float]:
        return {p.name: float(v) for p, v in zip(self.parameters, self.x)}


class _Objective:
    """r(z) of the scaled parameters z = x / scale, with the last evaluation kept (statuses,
    failures)."""

    def __init__(self, problem, datasets, params, executor, pressure, form):
        self.problem, self.datasets, self.params, self.executor = (problem, datasets, params,
                                                                   executor)
        self.form = pressure_form(problem, form)
        self.constants = {**problem_pressure(problem, form), **pressure}
        self.scale = np.array([abs(p.x0) or 1.0 for p in params])
        self.failed_evaluations = self.calls = 0
        self.last: tuple[np.ndarray, list] | None = None
        self.residual = np.empty(0)
        """the residuals of the last evaluation (failed rows: FAILED_RESIDUAL)"""

    def evaluate(self, x: np.ndarray) -> list[tuple[np.ndarray, tuple[str, ...]]]:
        keys, pressure = split_values(self.params, x)
        constants = {**self.constants, **pressure}
        tasks = [row_tasks(self.problem, d, keys, constants) for d in self.datasets]
        flat = evaluate_rows([t for ts in tasks for t in ts], self.executor)
        out, start = [], 0
        for d in self.datasets:
            rows = flat[start:start + len(d)]
            start += len(d)
            out.append((model_values(d, rows), tuple(r[1] for r in rows)))
        return out

    def __call__(self, z: np.ndarray) -> np.ndarray:
        per_file = self.evaluate(z * self.scale)
        self.last = (np.array(z, copy=True), per_file)
        parts = []
        for d, (model, _) in zip(self.datasets, per_file):
            # an overflowing residual is replaced below, its row reported
            with np.errstate(over="ignore"):
                res = (model - d.y) / d.sigma
            keep = np.arange(len(d)) != (d.reference_row if d.reference_row is not None else -1)
            parts.append(res[keep])
        r = np.concatenate(parts)
        bad = ~np.isfinite(r)
        if bad.any():
            self.failed_evaluations += 1
            r[bad] = FAILED_RESIDUAL
        self.calls += 1
        self.residual = r
        return r

    def files(self) -> list[FileFit]:
        """Data and model of every file at the last evaluation."""
        assert self.last is not None  # called after an evaluation
        return [FileFit(d, m, s) for d, (m, s) in zip(self.datasets, self.last[1])]


def uncertainty(jac: np.ndarray, x: np.ndarray, names: Sequence[str], scale2: float = 1.0,
                rcond: float = RCOND) -> tuple[np.ndarray, np.ndarray, np.ndarray, int,
                                               tuple[Direction, ...]]:
    """Covariance, correlation, singular values, rank and undetermined directions of a weighted
    Jacobian.

    Parameters
    ----------
    jac : numpy.ndarray
        d r / d x of the weighted residuals r = (model - y) / sigma, per unit of each parameter (a
        row per residual, a column per parameter).
    x : numpy.ndarray
        The parameter values, one per parameter (the relative scale D = diag(|x|); 1 where x = 0).
    names : sequence of str
        Parameter names, for the directions.
    scale2 : float
        Factor of the covariance: 1 for absolute sigmas, the reduced chi-square otherwise.
    rcond : float
        Singular values <= rcond * the largest are zero.

    Returns
    -------
    covariance (p, p), correlation (p, p), singular values of J D (largest first), rank, directions
    not determined (numerically zero, or relative sd > 1).  A parameter with a component >= 0.05 on
    a zero direction has infinite variance and NaN correlations.
    """
    d = np.where(x != 0, np.abs(x), 1.0)
    _, s, vt = np.linalg.svd(jac * d, full_matrices=False)
    smax = s[0] if s.size and s[0] > 0 else 1.0
    zero = s <= rcond * smax
    rank = int(np.sum(~zero))
    inv2 = np.where(zero, 0.0, 1.0 / np.where(zero, 1.0, s) ** 2) * scale2
    cov_rel = (vt.T * inv2) @ vt
    cov = cov_rel * np.outer(d, d)
    lost = np.any(np.abs(vt[zero]) >= 0.05, axis=0) if zero.any() else np.zeros(len(x), bool)
    sd = np.sqrt(np.diag(cov))
    with np.errstate(all="ignore"):
        corr = cov / np.outer(sd, sd)
    corr[lost, :] = corr[:, lost] = np.nan
    np.fill_diagonal(corr, 1.0)
    cov[lost, :] = cov[:, lost] = np.inf
    dirs = tuple(Direction(float(si / smax), math.inf if z else float(math.sqrt(scale2) / si),
                           {n: float(c)
                            for n, c in zip(names, v * np.sign(v[np.argmax(np.abs(v))]))})
                 for si, v, z in zip(s, vt, zero) if z or math.sqrt(scale2) / si > POOR)
    return cov, corr, s, rank, dirs


def _final_status(files: Sequence[FileFit], ls_status: int, nfev: int,
                  where: str = "the fitted parameters" ) -> tuple[Status, str]:
    """The first failing row's status; NO_CONVERGENCE for a file normalised at a row where the
    model does not move, for a row whose weighted residual is not finite although its model is
    (it overflows), or for a search that did not converge; else SUCCESS."""
    failed = [(f.data.table.line_of(j), f.data.path,
               s) for f in files for j, s in enumerate(f.statuses)
              if s != SUCCESS]
    if failed:
        line, path, text = failed[0]
        label = text.split(":", 1)[0]
        try:
            status = Status.from_label(label)
        except (KeyError, ValueError):
            status = Status.ERROR
        return status, (f"{len(failed)} point(s) fail at {where}; the first, {path}:{line}: "
                        f"{' '.join(text.split())}")
    still = [(f, ref) for f in files if (ref := f.data.reference_row) is not None
             and not np.isfinite(f.model[ref])]
    if still:
        f, ref = still[0]
        return Status.NO_CONVERGENCE, (
            f"the model does not move at the normalising row {f.data.path}:"
            f"{f.data.table.line_of(ref)} (S = 0 there) at {where}, so its "
            "S_norm is not defined; start elsewhere (--start, --starts)"
            + ("; the search did not run, no uncertainties" if where == START else ""))
    overflow = [(f, j) for f in files for j in np.flatnonzero(~np.isfinite(f.residuals))]
    if overflow:
        f, j = overflow[0]
        return Status.NO_CONVERGENCE, (
            "the weighted residual (model - data) / sigma of "
            f"{f.data.path}:{f.data.table.line_of(int(j))} is not finite at {where} (model "
            f"{f.model[j]:.3g}, data {f.data.y[j]:.3g}, sigma {f.data.sigma[j]:.3g}, SI): it "
            "overflows"
            + ("; the search did not run, no uncertainties" if where == START else ""))
    if ls_status <= 0:
        return (Status.NO_CONVERGENCE,
                f"least squares stopped after {nfev} evaluations without converging")
    return Status.SUCCESS, f"converged after {nfev} evaluations"


def fit_measurements(problem: Problem, datasets: Sequence[Measurements],
                     params: Sequence[Parameter], *, pressure: Mapping[str, float] | None = None,
                     absolute_sigma: bool = True, max_nfev: int = 100, jobs: int = 1,
                     rcond: float = RCOND, form: str | None = None,
                     starts: int = 0) -> FitResult:
    """Fit ``params`` to the measurements by weighted least squares on simulations.

    Parameters
    ----------
    problem : Problem
        The robot, gait, gravity convention and solver options of every simulation.
    datasets : sequence of Measurements
        The measurement files (:func:`ocp_crawl.fit.data.read_measurements`).
    params : sequence of Parameter
        What to fit, with start values and bounds (:func:`ocp_crawl.fit.params.resolve_parameters`).
    pressure : mapping of str to float, optional
        Pressure constants held fixed (``a1``, ``a2``, ``b1``, ``b2`` [rad/bar^2, rad/bar],
        ``phi_rest_deg`` [deg], ``amplitude_bar`` [bar]); default the problem's ``[pressure]``
        values as given, else Table I and the constants of ``form``
        (:func:`ocp_crawl.fit.params.problem_pressure`).
    absolute_sigma : bool
        True: the sigmas are standard uncertainties, covariance (J^T J)^-1; False: relative weights,
        covariance scaled by the reduced chi-square.
    max_nfev : int
        Most evaluations of all rows by the least-squares search (finite differences excluded).
    jobs : int
        Worker processes evaluating the rows (1: this process).
    rcond : float
        Relative singular value below which a direction is unidentifiable.
    form : str, optional
        The pressure input form (:data:`ocp_crawl.model.pressure.PRESSURE_FORMS`): "paper" (as the
        pressure study), the paper's form (ref) with nominal p0, amplitude 0.4 bar and rest angle
        180 deg; "raised", the raised sine from 0 to the peak p0 with the stored fitted rest angle;
        None (default): the problem's ``[pressure] form``, "paper" when it gives none
        (:func:`ocp_crawl.fit.params.pressure_form`).
    starts : int
        Latin hypercube points of the bounds evaluated first; the search starts at the best of
        them and the start values where no row fails (:mod:`ocp_crawl.fit.starts`; 0: at the
        start values).

    Returns
    -------
    FitResult
        Its ``status`` is ``success``, ``no_convergence``, or the status of the first point whose
        simulation fails at the fitted (or, if the start fails, the start) parameters: never raised.
        ``no_convergence`` also when the search did not run or failed (a weighted residual that
        overflows), or the weighted Jacobian is not finite or zero (rank 0), or the covariance is
        NaN: never ``success``.

    Raises
    ------
    TableError, ProblemError
        Bad input, before any simulation (:func:`~ocp_crawl.fit.checks.check_inputs`): fewer
        measurements than parameters + 1, a fitted gait key that a file sets, a pressure constant
        both fitted and fixed, stiffness rows on a chain, a row the model rejects at the start
        values (naming the file and row).
    ValueError
        ``starts`` not an integer >= 0.
    """
    if isinstance(starts, bool) or not isinstance(starts, int) or starts < 0:
        raise ValueError(f"fit_measurements: starts must be an integer >= 0, got {starts!r}")
    check_inputs(problem, datasets, params, pressure, form)
    executor = worker_pool(jobs) if jobs > 1 else None
    try:
        obj = _Objective(problem, datasets, params, executor, dict(pressure or {}), form)
        return _search(obj, max_nfev, starts, absolute_sigma, rcond)
    finally:
        if executor is not None:
            executor.shutdown(cancel_futures=True)


def _search(obj: _Objective, max_nfev: int, starts: int, absolute_sigma: bool,
            rcond: float) -> FitResult:
    """The start's evaluation, the sample of ``starts`` points (the search starts at the best
    point without a failed row), the least squares and the result; a failure at the start (and at
    every point of the sample) is the fit's status."""
    z0 = np.array([p.x0 for p in obj.params]) / obj.scale
    r0 = obj(z0)
    start_failed, start_files = obj.failed_evaluations > 0, obj.files()
    lo = np.array([p.low for p in obj.params]) / obj.scale
    hi = np.array([p.high for p in obj.params]) / obj.scale
    scan = None
    if starts:
        z, scan = scan_starts(obj, z0, None if start_failed else r0, lo, hi, starts, obj.scale,
                              lambda: bool(np.any(obj.residual == FAILED_RESIDUAL)))
    if start_failed and (scan is None or scan.best is None):
        status, msg = _final_status(start_files, 1, 1, START)
        if scan is not None:
            msg += f"; a row fails at every one of the {starts} sampled points too"
        fit = _result(obj, z0, None, r0, start_files, status, msg, 1, absolute_sigma, rcond)
        return dataclasses.replace(fit, scan=scan)
    if scan is not None:
        z0 = z
    before = obj.calls
    try:
        res = least_squares(obj, z0, bounds=(lo, hi), diff_step=DIFF_STEP, max_nfev=max_nfev,
                            method="trf", x_scale=1.0)
    except ValueError as exc:  # scipy refuses a Jacobian that is not finite
        fit = _refused_search(obj, exc, absolute_sigma, rcond, obj.calls - before)
        return dataclasses.replace(fit, scan=scan)
    if obj.last is None or not np.array_equal(obj.last[0], res.x):
        obj(res.x)
    files = obj.files()
    status, msg = _final_status(files, res.status, res.nfev)
    fit = _result(obj, res.x, res.jac / obj.scale, res.fun, files, status, msg, res.nfev,
                  absolute_sigma, rcond)
    return dataclasses.replace(fit, scan=scan)


def _refused_search(obj: _Objective, exc: ValueError, absolute_sigma: bool, rcond: float,
                    calls: int) -> FitResult:
    """The result of a search that scipy refused (``exc``: a weighted Jacobian that is not finite,
    the residuals overflowing when differenced) after ``calls`` evaluations, at the last one: the
    status of its first failed point, else NO_CONVERGENCE; no uncertainties."""
    status, msg = _final_status(obj.files(), 1, calls, "the last evaluation")
    if status == Status.SUCCESS:
        status, msg = Status.NO_CONVERGENCE, (f"least squares failed after {calls} "
                                              f"evaluations: {exc} (the weighted residuals "
                                              "overflow); no uncertainties")
    assert obj.last is not None  # obj.files() above needs an evaluation
    return _result(obj, obj.last[0], None, obj.residual, obj.files(), status, msg, calls,
                   absolute_sigma, rcond)


def _trusted(status: Status, message: str, jac: np.ndarray | None, cov: np.ndarray,
             rank: int) -> tuple[Status, str]:
    """SUCCESS only for a search that ran, with a finite Jacobian, a covariance without NaN and rank
    >= 1 (a rank-deficient fit keeps its infinite sigmas: the directions are reported); else
    NO_CONVERGENCE, saying why."""
    if status != Status.SUCCESS:
        return status, message
    if jac is None:
        why = "the search did not run (no Jacobian)"
    elif not np.all(np.isfinite(jac)):
        why = ("the weighted Jacobian at the fitted parameters is not finite (the residuals "
               "overflow)")
    elif np.isnan(cov).any():
        why = "the covariance is not finite (NaN)"
    elif rank == 0:
        why = ("the weighted Jacobian is zero (rank 0): the data do not depend on any fitted "
               "parameter")
    else:
        return status, message
    return (Status.NO_CONVERGENCE,
            f"not a fit ({message}): {why}; nothing is determined, no uncertainties")


def _result(obj: _Objective, z, jac, r, files, status, message, nfev, absolute_sigma,
            rcond) -> FitResult:
    x = z * obj.scale
    # a failed (or overflowing) row's residual is a penalty, not a misfit: no chi-square then
    failed = (any(s != SUCCESS for f in files for s in f.statuses)
              or not all(np.isfinite(f.residuals).all() for f in files))
    with np.errstate(over="ignore"):
        chi2 = math.nan if failed else float(np.sum(np.asarray(r) ** 2))
    dof = len(r) - len(x)
    scale2 = 1.0 if absolute_sigma or dof <= 0 else chi2 / dof
    names = [p.name for p in obj.params]
    # no (usable) Jacobian: nothing known about the uncertainties
    dirs: tuple[Direction, ...]
    if jac is None or not np.all(np.isfinite(jac)):
        nan = np.full((len(x), len(x)), np.nan)
        cov, corr, s, rank, dirs = nan, nan.copy(), np.empty(0), 0, ()
    else:
        cov, corr, s, rank, dirs = uncertainty(np.asarray(jac), x, names, scale2, rcond)
    status, message = _trusted(status, message, jac, cov, rank)
    keys, pressure = split_values(obj.params, x)
    fitted = obj.problem.with_values(keys) if keys else obj.problem
    uses = any(d.kind in ("pressure", "bending") for d in obj.datasets)
    constants = {**obj.constants, **pressure} if uses else {}
    return FitResult(tuple(obj.params), x, np.sqrt(np.diag(cov)), cov, corr, s, rank, dirs,
                     tuple(files), chi2, dof,
                     nfev, status, message, absolute_sigma, fitted, constants, obj.form)
