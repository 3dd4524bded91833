"""The harmonic-family baseline of the shipped OCP problems' robot for each objective, against the
earlier one-stroke scan (gamma = 90 deg, A1 = A2, psi only), both measured by the same objective
(run by hand).

    python scripts/harmonic_baseline.py            # max_speed, min_cot (speed_min = 0.6 v*), robust
                                                     mean/worst

The envelope and bandwidth are those of problems/ocp_max_speed.toml (paper robot, physical gravity,
gamma 90 deg, A_max 30 deg, 180 deg/s, direction -1).
"""
from __future__ import annotations

import sys
import time

import numpy as np

from ocp_crawl import Robot
from ocp_crawl.ocp.baseline import required_value, search_rank
from ocp_crawl.ocp.search import best_harmonic
from ocp_crawl.ocp.family import WaveFamily, WaveParams
from ocp_crawl.ocp.settings import OCPSettings

SHIPPED = {"gamma_deg": 90.0, "A_max_deg": 30.0, "max_rate_deg_s": 180.0, "direction": -1}


def old_scan(settings: OCPSettings):
    """The earlier baseline's gaits (gamma fixed, A1 = A2: A_max for speeds, 4 amplitudes for
    min_cot; 36 psi) at the shortest period: the best evaluation and the number of simulations."""
    fam = WaveFamily(Robot.paper(), "physical", settings)
    amps = np.linspace(settings.A_max_deg / 4, settings.A_max_deg, 4)
    amps = amps if settings.objective == "min_cot" else amps[-1:]
    evs = [fam.evaluate(WaveParams(settings.gamma_deg, settings.gamma_deg, float(A), float(A),
                                   float(psi)))
           for A in amps for psi in np.linspace(-180.0, 180.0, 37)[1:]]
    return min(evs, key=lambda ev: search_rank(settings, ev)), fam.evaluations


def report(name: str, settings: OCPSettings):
    """Print the family's best gait and the old scan's for ``settings``; return the choice."""
    t = time.perf_counter()
    c = best_harmonic(Robot.paper(), "physical", settings)
    dt = time.perf_counter() - t
    old, n_old = old_scan(settings)
    v_old = required_value(settings, old.S, old.CoT_plus, old.T)
    print(f"{name}: gamma {c.gamma1_deg:.4f}/{c.gamma2_deg:.4f} A {c.A1_deg:.4f}/{c.A2_deg:.4f} "
          f"psi {c.psi_deg:.3g} deg, T {c.T:.4f} s, S {np.round(np.array(c.S) * 1e3, 4)} mm, "
          f"W+ {np.round(np.array(c.W_plus) * 1e3, 3)} mJ, "
          f"CoT+ {np.round(c.CoT_plus, 4)}, v {np.round(np.array(c.v) * 1e3, 4)} mm/s; value "
          f"{c.value:.6g} ({c.evaluated} simulated gaits, {dt:.2f} s)")
    print(f"    one-stroke scan: A {old.params.A1_deg} psi {old.params.psi_deg:.0f} deg, value "
          f"{v_old:.6g} ({n_old} gaits); the family is better by "
          f"{abs(c.value / v_old - 1) * 100:.2f} %")
    return c


def main(argv: list[str] | None = None) -> int:
    best = report("max_speed", OCPSettings(objective="max_speed", **SHIPPED))
    report("min_cot (speed_min = 0.6 v*)",
           OCPSettings(objective="min_cot", speed_min=0.6 * best.value, **SHIPPED))
    report("robust_speed mean", OCPSettings(objective="robust_speed", **SHIPPED))
    report("robust_speed worst", OCPSettings(objective="robust_speed", robust="worst", **SHIPPED))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
