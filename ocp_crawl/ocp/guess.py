"""The initial guess of the periodic-gait OCP from event-driven simulations of a torque input: the
transcription's variables sampled from one simulation per friction scenario, the interior points at
the simulated changes of the slipping foot."""
from __future__ import annotations

import numpy as np

from ocp_crawl.model.step_equations import StepRows
from ocp_crawl.ocp.judge import replay_signal
from ocp_crawl.ocp.layout import fourier_basis
from ocp_crawl.ocp.substeps import (THETA_GUESS, guess_block, sample_phases,
                                    substep_torques, switch_fractions)

#  the initial guess's phase shift puts node 0 at the largest tau_1 on a grid this many times finer
# than the nodes
PIN_GRID = 16


def simulated_guess(ocp, torque_signal, period: float, switches: bool = True) -> np.ndarray:
    """The variables of the transcription ``ocp`` (a :class:`~ocp_crawl.ocp.transcription.GaitOCP`)
    sampled from event-driven simulations (one per scenario) of a torque input.

    Parameters
    ----------
    torque_signal : callable
        ``torque_signal(t)`` [N m] (shape (m, n), m joints) at phases t [cycles], e.g. the best
        harmonic gait of the baseline; it is sampled at the N nodes, shifted in phase so that node 0
        is where tau_1 is largest (the phase pin, on a grid PIN_GRID times finer), and simulated as
        the transcription sees it, linear in phase between the nodes (its interior points at the
        simulated foot switches, else mid-interval).
    period : float
        The gait's period T [s].
    switches : bool
        Place the interior points at the simulated changes of the slipping foot (default); False:
        every interior point mid-interval (a guess that the solve must correct where a foot switch
        falls).

    Returns
    -------
    np.ndarray
        The NLP's variable vector (scaled).
    """
    s, r, m = ocp.settings, ocp.robot, ocp.n_joints
    N, R = s.nodes, StepRows(ocp.n_joints)
    MgL = r.M * r.g * r.L
    x = np.zeros(ocp.nx)
    t_nodes = np.arange(N) / N
    fine = np.arange(PIN_GRID * N) / (PIN_GRID * N)
    # the phase pin
    shift = fine[np.argmax(np.asarray(torque_signal(fine), float).reshape(m, -1)[0])]
    tau_nodes = np.asarray(torque_signal((shift + t_nodes) % 1.0), float).reshape(m, N)
    if s.parametrization == "free":
        x[ocp.slices["tau"]] = (tau_nodes / MgL).ravel(order="F")
    else:
        basis = fourier_basis(N, s.fourier_order)
        coef, *_ = np.linalg.lstsq(basis.T, tau_nodes.T / MgL, rcond=None)
        x[ocp.slices["tau"]] = coef.T.ravel(order="F")
    x[ocp.slices["T_hat"]] = period / s.period_ref()
    signal = replay_signal(t_nodes, tau_nodes)
    speeds, cots = [], []
    for j, plant in enumerate(ocp.scen):
        theta = (switch_fractions(plant.simulate(signal), N) if switches
                 else np.full(N, THETA_GUESS))
        res = plant.simulate(signal, t_eval=sample_phases(theta))
        blk = guess_block(res, plant, N)
        speeds.append(s.direction * blk["S"] / x[ocp.slices["T_hat"]][0])
        for name in ("phi0", "ft0"):
            x[ocp.slices[f"{name}_{j}"]] = blk[name]
        x[ocp.slices[f"Sc_{j}"]] = np.cumsum(blk["w"][R.s1p] - blk["w"][R.s1p + 1])
        x[ocp.slices[f"w_{j}"]] = blk["w"].ravel(order="F")
        x[ocp.slices[f"theta_{j}"]] = theta
        if f"v_{j}" in ocp.slices:
            tau_sub = substep_torques(tau_nodes, theta) / MgL
            tau_mid = 0.5 * (tau_sub + np.roll(tau_sub, 1, axis=1))
            V = np.maximum(tau_mid * np.diff(np.c_[blk["phi0"], blk["w"][R.phi]], axis=1), 0.0)
            x[ocp.slices[f"v_{j}"]] = V.ravel(order="F")
            x[ocp.slices[f"Wc_{j}"]] = np.cumsum(V.sum(axis=0))
            cots.append(V.sum() / max(s.direction * blk["S"], 1e-9))
    if "zeta" in ocp.slices:  # the worst scenario's CoT+ (min_cot) or speed
        x[ocp.slices["zeta"]] = max(cots) if s.objective == "min_cot" else min(speeds)
    return x
