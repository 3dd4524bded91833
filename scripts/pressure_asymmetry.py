"""The pressure-driven robot's psi curve with unequal joint stiffnesses k1, k2 = (1 +- r) k.

The paper's experiments move at psi = 0 (S/Smax 0.94) and best near psi = 10 deg, where the
symmetric three-link model does not move at small psi. This script simulates the three-link chain
(``simulate_chain_torque``) under the paper's pressure inputs (nominal p0 1.7 bar, amplitude A_p
(default 0.4 bar), the calibrated bending maps of Table I, flat rest shape) at the experiments'
phase differences for each asymmetry r, and prints S [mm], S/Smax and its RMS difference from the
experiment (with and without psi = 0).

Run: ``python scripts/pressure_asymmetry.py [--ratios 0 0.1 0.2 0.3 0.4] [--gravity physical]
[--amplitude 0.4]``.
"""
from __future__ import annotations

import argparse

import numpy as np

from ocp_crawl import Robot
from ocp_crawl.io.paper_data import read_paper_csv
from ocp_crawl.model import Chain, ChainModel
from ocp_crawl.model.pressure import PAPER_FORM_AMPLITUDE_BAR, pressure_torque
from ocp_crawl.sim import ChainReferenceTorque, simulate_chain_torque

P0_BAR = 1.7
FLAT_REST_DEG = 180.0


def psi_curve(r: float, psi_deg: np.ndarray, gravity: str,
              amplitude_bar: float = PAPER_FORM_AMPLITUDE_BAR) -> np.ndarray:
    """S [m] per cycle at each phase difference for the stiffness asymmetry r (NaN on failure)."""
    robot = Robot.paper()
    chain = Chain.from_robot(robot).replace(stiffness=((1 + r) * robot.k, (1 - r) * robot.k))
    model = ChainModel(chain, gravity=gravity)
    out = []
    for psi in psi_deg:
        signal = pressure_torque(robot, P0_BAR, float(psi), FLAT_REST_DEG,
                                 amplitude_bar=amplitude_bar)
        res = simulate_chain_torque(model, ChainReferenceTorque(signal.reference, chain))
        out.append(res.S if res.success else np.nan)
    return np.array(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ratios", type=float, nargs="+", default=[0.0, 0.1, 0.2, 0.25, 0.3, 0.4])
    ap.add_argument("--gravity", choices=("physical", "paper"), default="physical")
    ap.add_argument("--amplitude", type=float, default=PAPER_FORM_AMPLITUDE_BAR,
                    help="pressure amplitude A_p [bar] (default %(default)s)")
    args = ap.parse_args(argv)
    exp = read_paper_csv("fig_exp_psi_experiment.csv")
    psi, measured = exp["psi_deg"], exp["S_over_Smax"]
    print(f"psi [deg]: {psi.tolist()}\nexperiment S/Smax: {np.round(measured, 3).tolist()}")
    for r in args.ratios:
        S = psi_curve(r, psi, args.gravity, args.amplitude)
        progress = -S
        norm = progress / np.nanmax(progress)
        rms = float(np.sqrt(np.nanmean((norm - measured) ** 2)))
        rms_without_0 = float(np.sqrt(np.nanmean((norm[1:] - measured[1:]) ** 2)))
        print(f"r = {r:.2f} (k1/k = {1 + r:.2f}, k2/k = {1 - r:.2f}): S [mm] "
              f"{np.round(1e3 * S, 3).tolist()}, S/Smax {np.round(norm, 3).tolist()}, "
              f"RMS {rms:.3f} (without psi = 0: {rms_without_0:.3f}), "
              f"best psi {psi[int(np.nanargmax(progress))]:g} deg")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
