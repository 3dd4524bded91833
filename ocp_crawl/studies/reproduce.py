"""Reproduce the paper's figures and check its statements: ``ocp-crawl reproduce``.

Runs every study of :mod:`ocp_crawl.studies` in both gravity conventions (the statements table
needs both), draws the figures in the chosen convention (PNG and PDF), and writes ``report.md``:
each figure with the numbers behind it, the relative difference wherever the paper publishes a
number, every statement of the paper checked in both conventions, and every point the paper
publishes (Figs. CoT and exp) evaluated at its own abscissa in both conventions
(:mod:`~ocp_crawl.studies.paper_points`).  ``numbers.json`` holds the same numbers for scripts.

Nothing is lost when a run is killed: every file is written atomically
(:func:`ocp_crawl.io.files.atomic_write`: a temporary file renamed over the target, so a reader sees
the previous file or the new one, never a mix), and every grid is a journaled sweep under
``<out>/sweeps``.  ``resume`` (``--resume``) reuses the finished grid points there and recomputes
the rest (the single gaits, the bisection of the friction threshold and the pressure curves are not
journaled: they are recomputed); figures, ``report.md`` and ``numbers.json`` are always written
anew.  A resumed run gives the same numbers, report and figures as an uninterrupted one, apart from
the wall times (``elapsed_s`` in ``numbers.json``; the run time and the Timing section of
``report.md``).  Temporary files of a killed run are removed by the next run.

The grid sizes of the quick and the full run are the one table
:data:`~ocp_crawl.studies.suite.GRIDS`; the statements are :mod:`ocp_crawl.studies.statements`, the
report's text :mod:`ocp_crawl.studies.report`.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from ocp_crawl.io.files import atomic_write, remove_stale_temps, write_json
from ocp_crawl.model.statics import GRAVITY_CONVENTIONS
from ocp_crawl.studies.common import SweepOptions
from ocp_crawl.studies.gait_plots import (plot_configuration, plot_forces, plot_friction_band,
                                          plot_parametric)
from ocp_crawl.studies.plots import (plot_amplitude, plot_conventions, plot_higher_friction,
                                     plot_pressure, plot_stiffness)
from ocp_crawl.studies.paper_points import markdown as points_markdown, paper_points
from ocp_crawl.studies.report import numbers, report
from ocp_crawl.studies.statements import Statement, check_statements
from ocp_crawl.studies.suite import GRIDS, StudySet, run_studies
from ocp_crawl.viz.gait import save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class ReproduceResult:
    """What ``reproduce`` wrote and the numbers behind it."""

    out_dir: Path
    mode: str
    gravity: str
    files: tuple[Path, ...]
    report: Path
    studies: dict[str, StudySet]
    statements: tuple[Statement, ...]
    elapsed: float


#: figure stem -> (function of the chosen convention's studies and all sets)
FIGURES: dict[str, Callable[[StudySet, dict[str, StudySet]], Figure]] = {
    "simu_conf": lambda s, _: plot_configuration(s.gait),
    "simu_forces": lambda s, _: plot_forces(s.gait),
    "parametric": lambda s, _: plot_parametric(s.parametric),
    "d_mu": lambda s, _: plot_friction_band(s.band),
    "cot": lambda s, _: plot_amplitude(s.amplitude),
    "s_psi_mu": lambda s, _: plot_higher_friction(s.friction),
    "stiffness": lambda s, _: plot_stiffness(s.stiffness),
    "conventions": lambda _, sets: plot_conventions({g: x.stiffness for g, x in sets.items()},
                                                    {g: x.amplitude for g, x in sets.items()}),
    "exp": lambda s, _: plot_pressure(s.pressure),
}


def reproduce(out_dir: str | Path, quick: bool = False, gravity: str = "physical",
              sweep: SweepOptions | None = None,
              log: Callable[[str], None] | None = None) -> ReproduceResult:
    """Run every study in both conventions, write the figures of ``gravity`` and ``report.md`` to
    ``out_dir``.

    ``quick``: the coarse grids; ``gravity``: the convention of the figures, "physical" or "paper"
    (the paper's own figures; ``ocp-crawl reproduce`` passes "paper" by default).  ``sweep``: how
    grids are evaluated (workers, progress, journal); by default serially, with the sweeps journaled
    under ``out_dir/sweeps``.  ``log`` receives one line per step (the CLI prints it).  Returns a
    :class:`ReproduceResult` (the files written and the studies behind them).
    """
    if gravity not in GRAVITY_CONVENTIONS:
        raise ValueError(f"gravity must be one of {GRAVITY_CONVENTIONS}, got {gravity!r}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    # temporary files of a killed run (the sweeps clean their own directories)
    remove_stale_temps(out)
    sweep = sweep or SweepOptions(out_dir=out / "sweeps")
    mode = "quick" if quick else "full"
    grids = GRIDS[mode]
    say = log or (lambda msg: None)
    start = time.perf_counter()
    # the chosen convention first: its figures are the report's subject
    order = [gravity] + [g for g in GRAVITY_CONVENTIONS if g != gravity]
    sets = {g: run_studies(g, grids, sweep, say) for g in order}
    statements = check_statements(sets)
    say("every published point ...")
    points = {g: paper_points(g, sets[g].pressure.fit.curves.amplitude_psi_bar) for g in order}
    files: list[Path] = []
    say("figures ...")
    for stem, draw in FIGURES.items():
        fig = draw(sets[gravity], sets)
        for ext in ("png", "pdf"):
            files.append(save_figure(fig, out / f"{stem}.{ext}"))
    elapsed = time.perf_counter() - start
    text = report(sets, gravity, mode, statements, elapsed, sweep.jobs,
                  extra=points_markdown(points))
    report_md = atomic_write(out / "report.md", lambda fh: fh.write(text.encode("utf-8")))
    nums = {**numbers(sets, statements),
            "paper_points": {g: p.numbers() for g, p in points.items()}}
    files.append(write_json(out / "numbers.json", nums))
    files.append(report_md)
    say(f"done in {elapsed:.0f} s")
    return ReproduceResult(out, mode, gravity, tuple(files), report_md, sets, tuple(statements),
                           elapsed)


__all__ = ["ReproduceResult", "reproduce", "FIGURES"]
