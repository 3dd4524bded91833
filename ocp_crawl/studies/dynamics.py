"""Is it still quasistatic? S, W+ and CoT+ of a gait against its period T, in MuJoCo.

:func:`dynamics_scan` runs the dynamic solver at each period (``"mujoco"``, or
``"mujoco_angles"`` for a problem of the angles drive) and the quasistatic solver of the drive
once (``"event"`` or ``"angles"``: the limit T -> infinity); :class:`DynamicsScan` holds both,
the relative deviations, the highest frequency at which each quantity stays within a tolerance
of the quasistatic value, a
CSV table and a figure (:func:`plot_dynamics`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ocp_crawl.io.tables import write_table
from ocp_crawl.problem.problem import Problem, solver_options
from ocp_crawl.sim import simulate
from ocp_crawl.sim.dynamic import MujocoOptions

#: the quantities compared, with their attribute, unit and scale to that unit
QUANTITIES = (("S", "S", "mm", 1e3), ("W+", "W_plus", "mJ", 1e3), ("CoT+", "CoT_plus", "-", 1.0))
#: default periods [s] of ``ocp-crawl dynamics``
DEFAULT_PERIODS = (1.0, 2.0, 5.0, 10.0, 20.0)
#: default tolerance of "still quasistatic" [-]
TOLERANCE = 0.05
#: the quasistatic and the dynamic solver of each drive
DRIVE_SOLVERS = {"torque": ("event", "mujoco"), "angles": ("angles", "mujoco_angles")}


@dataclass
class DynamicsScan:
    """The dynamic solver's S [m], W+ [J], CoT+ [-] at each period [s], and the quasistatic
    values."""

    source: str
    periods: np.ndarray
    values: dict[str, np.ndarray]
    """quantity name ("S", "W+", "CoT+") -> values at each period (NaN where a run failed)"""
    quasistatic: dict[str, float]
    statuses: list[str]
    tolerance: float = TOLERANCE
    messages: list[str] = field(default_factory=list)
    period: float | None = None
    """the gait's own period [s] (``[gait] period``, e.g. an optimum's), one of ``periods``; None
    if the problem gives none"""
    quasistatic_solver: str = "event"
    """the solver of the quasistatic values (``"event"``; ``"angles"`` for the angles drive)"""

    def at_period(self, name: str) -> float | None:
        """Relative deviation of ``name`` at the gait's own period [-]; None without one."""
        if self.period is None:
            return None
        return float(self.deviation(name)[int(np.argmin(abs(self.periods - self.period)))])

    def at_period_text(self, name: str, fmt: str = "+.2%") -> str:
        """:meth:`at_period` as text, or the run's status where it failed."""
        dev = self.at_period(name)
        if dev is not None and math.isfinite(dev):
            return format(dev, fmt)
        return self.statuses[int(np.argmin(abs(self.periods - self.period)))]

    def deviation(self, name: str) -> np.ndarray:
        """Relative deviation of ``name`` from its quasistatic value at each period [-]."""
        return self.values[name] / self.quasistatic[name] - 1.0

    def highest_frequency(self, name: str) -> float | None:
        """The highest frequency 1/T [Hz] at which ``name`` is within the tolerance of its
        quasistatic value there and at every longer period scanned; None if at none."""
        order = np.argsort(self.periods)[::-1]  # (longest period first)
        best = None
        for i in order:
            if not abs(self.deviation(name)[i]) <= self.tolerance:
                break
            best = 1.0 / float(self.periods[i])
        return best

    def summary(self) -> dict:
        """JSON-safe numbers: periods [s], each quantity's values and deviations, the
        frequencies [Hz]."""
        def num(x):
            return float(x) if math.isfinite(x) else None
        return {"problem": self.source, "periods_s": [float(t) for t in self.periods],
                "status": list(self.statuses), "tolerance": self.tolerance,
                "units": {name: unit for name, _, unit, _ in QUANTITIES},
                "quasistatic": {n: num(v) for n, v in self.quasistatic.items()},
                "values": {n: [num(x) for x in v] for n, v in self.values.items()},
                "deviation": {n: [num(x) for x in self.deviation(n)] for n in self.values},
                "highest_frequency_hz": {n: self.highest_frequency(n) for n in self.values},
                "gait_period_s": self.period,
                "deviation_at_gait_period": {n: self.at_period(n) for n in self.values}}

    def table(self) -> str:
        """The scan as text: one row per period, the quasistatic row last, then the frequencies."""
        head = f"{'T [s]':>8} {'f [Hz]':>8} " + " ".join(
            f"{name + ' [' + unit + ']':>12} {'dev':>8}" for name, _, unit, _ in QUANTITIES)
        rows = [head]
        for i, t in enumerate(self.periods):
            cells = " ".join(f"{self.values[n][i] * k:12.4f} {self.deviation(n)[i]:+8.2%}"
                             for n, _, _, k in QUANTITIES)
            rows.append(f"{t:8.3g} {1 / t:8.3g} {cells}  {self.statuses[i]}")
        rows.append(f"{'quasistatic':>17} " + " ".join(
            f"{self.quasistatic[n] * k:12.4f} {'':8}" for n, _, _, k in QUANTITIES))
        for n, _, _, _ in QUANTITIES:
            f = self.highest_frequency(n)
            text = ("at none of the periods" if f is None
                    else f"up to {f:.3g} Hz (T = {1 / f:.3g} s)")
            rows.append(f"{n} within {self.tolerance:.0%} of quasistatic {text}")
        if self.period is not None:
            rows.append(f"at the gait's own period T = {self.period:.4g} s: " + ", ".join(
                f"{n} {self.at_period_text(n)}" for n, _, _, _ in QUANTITIES))
        return "\n".join(rows)

    def write_csv(self, path: str | Path) -> Path:
        """The scan as a CSV table of the package's convention (units in the header)."""
        columns = [("period", "s", self.periods), ("frequency", "Hz", 1.0 / self.periods)]
        for name, _, unit, k in QUANTITIES:
            columns.append((name, unit, self.values[name] * k))
            columns.append((f"{name} quasistatic", unit, np.full(len(self.periods),
                                                                 self.quasistatic[name] * k)))
        write_table(path, columns, comments=[f"problem {self.source}; dynamic solver mujoco"])
        return Path(path)


def dynamics_scan(problem: Problem, periods=DEFAULT_PERIODS, options: MujocoOptions | None = None,
                  tolerance: float = TOLERANCE) -> DynamicsScan:
    """Simulate ``problem`` in MuJoCo at each period [s], and with the quasistatic solver of its
    drive (the event solver for the torque drive, the angles solver for prescribed angles).

    Parameters
    ----------
    problem : Problem
        A problem of either drive with physical gravity.
    periods : sequence of float
        Periods T [s] of one cycle; the problem's ``[gait] period`` (the gait's own, e.g. in the
        ``optimal_gait.toml`` of ``optimize --out``) is added when it gives one.
    options : MujocoOptions, optional
        Time step, cone and cycle options (its period is replaced); None: the problem's
        ``[simulation]`` values.
    tolerance : float
        Relative tolerance [-] of "within the quasistatic value".

    Returns
    -------
    DynamicsScan
    """
    if options is None:
        options = solver_options("mujoco", problem.sections.get("simulation", {}))
    own = problem.sections.get("gait", {}).get("period")
    periods = sorted({float(t) for t in periods} | ({float(own)} if own else set()))
    signal = problem.torque if problem.drive == "torque" else problem.gait
    quasi_solver, dynamic = DRIVE_SOLVERS[problem.drive]
    event = simulate(problem.model, signal, quasi_solver)
    if not event.success:
        raise ValueError(f"{problem.source}: the quasistatic gait failed: {event.message}")
    quasi = {name: float(getattr(event, attr)) for name, attr, _, _ in QUANTITIES}
    values = {name: np.full(len(periods), np.nan) for name, _, _, _ in QUANTITIES}
    statuses, messages = [], []
    for i, period in enumerate(periods):
        res = simulate(problem.model, signal, dynamic,
                       dataclasses.replace(options, period=float(period)))
        statuses.append(res.status_name)
        messages.append(res.message)
        for name, attr, _, _ in QUANTITIES:
            values[name][i] = getattr(res, attr)
    return DynamicsScan(problem.source, np.asarray(periods, float), values, quasi, statuses,
                        tolerance, messages, float(own) if own else None, quasi_solver)


def plot_dynamics(scan: DynamicsScan, path: str | Path) -> Path:
    """Figure of S [mm], W+ [mJ] and CoT+ [-] against the frequency 1/T [Hz], with the quasistatic
    values as lines, their tolerance bands and the highest frequency within it; written to
    ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    freq = 1.0 / scan.periods
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), constrained_layout=True)
    for ax, (name, _, unit, k) in zip(axes, QUANTITIES):
        q = scan.quasistatic[name] * k
        ax.plot(freq, scan.values[name] * k, "o-", label="MuJoCo (dynamic)")
        ax.axhline(q, color="k", ls="--", label=f"quasistatic ({scan.quasistatic_solver} solver)")
        ax.axhspan(q * (1 - scan.tolerance), q * (1 + scan.tolerance), color="0.85",
                   label=f"quasistatic ± {scan.tolerance:.0%}")
        f = scan.highest_frequency(name)
        if f is not None:
            ax.axvline(f, color="tab:red", ls=":",
                       label=f"within {scan.tolerance:.0%} up to {f:.3g} Hz")
        if scan.period is not None:
            ax.axvline(1.0 / scan.period, color="tab:green", ls="-.", label=f"the gait's period "
                       f"T = {scan.period:.3g} s ({scan.at_period_text(name, '+.1%')})")
        ax.set_xscale("log")
        ax.set_xticks(freq, [f"{v:.3g}" for v in freq])   # the scanned frequencies, not decades
        ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
        ax.set_xlabel("frequency 1/T [Hz]")
        ax.set_ylabel(f"{name} [{unit}]")
        ax.legend(fontsize=8)
    f_s = scan.highest_frequency("S")
    at = np.argmax(scan.periods)
    upto = ("at none of the periods" if f_s is None else f"up to {f_s:.3g} Hz")
    drive = " (angles drive)" if scan.quasistatic_solver == "angles" else ""
    fig.suptitle(f"{Path(scan.source).name}{drive}: S = {scan.quasistatic['S'] * 1e3:.2f} mm "
                 "quasistatic, "
                 f"{scan.values['S'][at] * 1e3:.2f} mm at T = {scan.periods[at]:g} s; S within "
                 f"{scan.tolerance:.0%} {upto}")
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)
