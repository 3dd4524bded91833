"""A study from Python into pandas.

Runs a small sweep of the paper's gait over the amplitude A and the phase difference psi with
:func:`ocp_crawl.sweep.run_sweep` and hands its rows (one per grid point: the grid keys, then
S [m], W_plus [J], CoT_plus [-], status, message) to a :class:`pandas.DataFrame` with
:meth:`~ocp_crawl.sweep.SweepResult.to_pandas` (units in ``df.attrs["units"]``), where the usual
tools apply: units converted in columns, the failed points counted by status, the best psi per
amplitude found with ``groupby``, a pivot table plotted.  The sweep's ``results.csv`` carries the
units in its header (``S [m]``, ``gait.psi_deg [deg]``; text columns bare), as the package's input
tables do: ``pandas.read_csv`` reads the same rows, and ``study.csv`` is written the same way.
Needs pandas (``pip install 'ocp-crawl[examples]'``).

Run: ``python examples/07_study_to_pandas.py [OUT_DIR]``; writes ``OUT_DIR/sweep/results.csv``,
``OUT_DIR/study.csv`` and ``OUT_DIR/study.png``.
"""
import numpy as np
import pandas as pd
from _common import output_dir, save
from matplotlib.figure import Figure

from ocp_crawl import paper_problem
from ocp_crawl.sweep import run_sweep

GRID = {"gait.A_deg": [10.0, 20.0, 30.0], "gait.psi_deg": list(np.linspace(0.0, 120.0, 9))}


def main() -> None:
    out = output_dir()
    sweep = run_sweep(paper_problem(), GRID, out_dir=out / "sweep", jobs=1, force=True)
    df = sweep.to_pandas()
    assert df.attrs["units"]["S"] == "m" and df.attrs["units"]["W_plus"] == "J"
    # the file holds the same rows; its header cells are "name [unit]" (e.g. "S [m]") or bare names
    table = pd.read_csv(out / "sweep" / "results.csv")
    table = table.rename(columns={cell: cell.split(" [")[0] for cell in table.columns})
    numbers = ["S", "W_plus", "CoT_plus"]
    assert table[numbers].equals(df[numbers])
    df["S_mm"] = 1e3 * df["S"]                    # [mm per cycle]
    df["W_plus_mJ"] = 1e3 * df["W_plus"]          # [mJ per cycle]
    unit = dict(df.attrs["units"], S_mm="mm", W_plus_mJ="mJ")   # study.csv: the same convention
    header = [f"{c} [{unit[c]}]" if c in unit else c for c in df.columns]
    df.to_csv(out / "study.csv", index=False, header=header)
    print(f"wrote {out / 'study.csv'}")
    print(df.groupby("status").size().rename("points").to_string())
    ok = df[df["status"] == "success"]
    best = ok.loc[ok.groupby("gait.A_deg")["S_mm"].idxmin(),
                  ["gait.A_deg", "gait.psi_deg", "S_mm", "CoT_plus"]]
    print("fastest psi per amplitude (largest progress towards foot 1):")
    print(best.to_string(index=False, float_format=lambda x: f"{x:.3g}"))

    # NaN where a point failed
    table = df.pivot(index="gait.psi_deg", columns="gait.A_deg", values="S_mm")
    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    ax = fig.subplots()
    for A, color in zip(table.columns, ("C0", "C1", "C2")):
        ax.plot(table.index, table[A], color + "-o", ms=4, label=f"A = {A:g} deg")
        row = best[best["gait.A_deg"] == A]
        ax.plot(row["gait.psi_deg"], row["S_mm"], color + "*", ms=12, clip_on=False)
    ax.plot([], [], "k*", ms=10, label="fastest psi of each A")
    ax.set(xlabel=r"phase difference $\psi$ [deg]", ylabel="S [mm per cycle] (< 0: towards foot 1)")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize="small")
    top = best.loc[best["S_mm"].idxmin()]
    ax.set_title(f"Paper robot: S over psi for three amplitudes ({len(ok)} of {len(df)} points "
                 f"succeeded)\nfastest: S = {top['S_mm']:.1f} mm/cycle at "
                 f"A = {top['gait.A_deg']:g} deg, psi = {top['gait.psi_deg']:g} deg",
                 fontsize="medium")
    save(fig, out / "study.png")


if __name__ == "__main__":
    main()
