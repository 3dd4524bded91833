"""A global start for the least squares of a calibration: the best of a Latin hypercube sample of
the parameters' bounds (:class:`scipy.stats.qmc.LatinHypercube`) and the given start.

A local search needs a start in the right basin.  Some calibrations have none near the obvious
start: S at psi = 0 of the pressure robot is exactly 0 for the symmetric robot and for every small
asymmetry of its joints (the feet's friction limits tie, and the one foot that slips decides S),
so chi2 is flat around equal joints and jumps where a foot takes over; a search from equal joints
stays there.  The sample is uniform in each parameter's bounds (give bounds that span what is
plausible: a stiffness sampled in [k/10, 10 k] lands mostly near 10 k).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.stats import qmc

#: the sample's seed: the same fit gives the same starts
SEED = 0


@dataclass(frozen=True)
class Scan:
    """The sample evaluated before the search and where the search started."""

    points: int
    """points of the sample (the given start not counted)"""
    failed: int
    """points where a row's simulation failed (never chosen)"""
    chi2_start: float | None
    """chi2 at the given start values (None: a row failed there)"""
    chi2_best: float | None
    """chi2 where the search started (None: every point failed)"""
    best: tuple[float, ...] | None
    """the parameters where the search started (problem-file units; None: every point failed)"""
    from_start: bool
    """whether the search started at the given start values"""

    def text(self) -> str:
        failed = f", {self.failed} failed" if self.failed else ""
        at_start = ("a row fails there" if self.chi2_start is None
                    else f"chi2 {self.chi2_start:.4g}")
        if self.best is None:
            return (f"{self.points} Latin hypercube points in the bounds: a row fails at every one "
                    f"and at the start values")
        where = ("the given start values" if self.from_start
                 else "(" + ", ".join(f"{v:.6g}" for v in self.best) + ")")
        return (f"best of {self.points} Latin hypercube points in the bounds and the start "
                f"values: the search started at {where}, chi2 {self.chi2_best:.4g} (at the start "
                f"values: {at_start}){failed}")


def scan_starts(residuals: Callable[[np.ndarray], np.ndarray], z0: np.ndarray,
                r0: np.ndarray | None, lo: np.ndarray, hi: np.ndarray, points: int,
                scale: np.ndarray, failed_rows: Callable[[], bool]) -> tuple[np.ndarray, Scan]:
    """The start of the search: the point of least chi2 among ``z0`` (residuals ``r0``; None: a
    row failed there) and ``points`` Latin hypercube points in the box [lo, hi] (scaled
    parameters; ``scale`` turns them into problem-file units).  ``residuals(z)`` evaluates every
    row; ``failed_rows()`` says whether its last evaluation had a failed row (such points are never
    chosen).  Where every point fails, ``z0`` and a scan whose ``best`` is None."""
    sample = lo + qmc.LatinHypercube(d=z0.size, seed=SEED).random(points) * (hi - lo)
    chi2_start = None if r0 is None else float(np.sum(r0 ** 2))
    best, chi2_best, failed = None, chi2_start, 0
    for z in sample:
        chi2 = float(np.sum(residuals(z) ** 2))
        if failed_rows():
            failed += 1
        elif chi2_best is None or chi2 < chi2_best:
            best, chi2_best = z, chi2
    start = best if best is not None else z0
    shown = None if chi2_best is None else tuple(float(v) for v in start * scale)
    return start, Scan(points, failed, chi2_start, chi2_best, shown,
                       from_start=best is None and r0 is not None)
