"""The friction band: S against the friction coefficient, with the two feet's friction uncertain.

Real feet never have exactly the same friction.  For each friction level mu (the geometric mean of
the two feet), the paper's gait is run with mu1/mu2 = 0.9, 1 and 1.1 (mu1 = mu sqrt(r),
mu2 = mu / sqrt(r), so only the asymmetry changes, as in the paper's Fig. d_mu).  The plot shows S
[mm per cycle] at mu1 = mu2 and the band spanned by the +-10 % asymmetry; the title gives S and the
band's width at the paper's mu = 0.389.

Shows :meth:`Problem.with_values` (typed values, the problem files' keys and units) and
:func:`ocp_crawl.run_problem` in a loop; failed runs (status other than success) are reported and
left out of the band.

Run: ``python examples/04_friction_band.py [OUT_DIR]``; writes ``OUT_DIR/friction_band.png``.
"""
import math

import numpy as np
from _common import output_dir, save
from matplotlib.figure import Figure

from ocp_crawl import paper_problem, run_problem

MU = np.round(np.linspace(0.2, 0.8, 7), 3)   # friction levels sqrt(mu1 mu2) [-]
MU_PAPER = 0.389                            # Table I
RATIOS = (0.9, 1.0, 1.1)                    # mu1 / mu2 [-]


def S_of(mu: float, ratio: float) -> float:
    """S [m] of the paper's gait with feet mu1 = mu sqrt(ratio), mu2 = mu / sqrt(ratio); NaN if it
    failed."""
    problem = paper_problem().with_values({"robot.mu1": mu * math.sqrt(ratio),
                                           "robot.mu2": mu / math.sqrt(ratio)})
    result = run_problem(problem)
    if not result.success:
        print(f"mu = {mu:g}, mu1/mu2 = {ratio:g}: {result.status_name} ({result.message})")
    return result.S


def main() -> None:
    out = output_dir()
    levels = np.sort(np.append(MU, MU_PAPER))
    S = 1e3 * np.array([[S_of(mu, r) for mu in levels] for r in RATIOS])   # (ratio, mu) [mm]
    nominal = S[RATIOS.index(1.0)]
    low, high = np.nanmin(S, axis=0), np.nanmax(S, axis=0)
    for mu, s, lo, hi in zip(levels, nominal, low, high):
        print(f"mu = {mu:.3f}: S = {s:7.2f} mm per cycle, band [{lo:7.2f}, {hi:7.2f}] mm")

    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    ax = fig.subplots()
    ax.fill_between(levels, low, high, color="C0", alpha=0.25,
                    label=r"band: $\mu_1/\mu_2 \in [0.9, 1.1]$")
    for r, ls in zip(RATIOS, (":", "-", "--")):
        ax.plot(levels, S[RATIOS.index(r)], "C0" + ls, marker="o" if r == 1.0 else None, ms=4,
                label=rf"$\mu_1/\mu_2$ = {r:g}")
    ax.axvline(MU_PAPER, color="gray", lw=0.8, label=rf"paper's $\mu$ = {MU_PAPER}")
    ax.set(xlabel=r"friction coefficient $\mu = \sqrt{\mu_1 \mu_2}$ [-]",
           ylabel="S [mm per cycle] (< 0: towards foot 1)")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize="small", loc="center right")
    i = int(np.argmin(np.abs(levels - MU_PAPER)))
    ax.set_title(f"Paper gait: S = {nominal[i]:.1f} mm/cycle at mu = {MU_PAPER} (mu1 = mu2);\n"
                 f"+-10 % friction asymmetry between the feet: S in [{low[i]:.1f}, "
                 f"{high[i]:.1f}] mm/cycle",
                 fontsize="medium")
    save(fig, out / "friction_band.png")


if __name__ == "__main__":
    main()
