"""The checks of an n-link chain's incremental steps (:mod:`ocp_crawl.sim.chain_mpcc`): at a step's
end, its contacts (the joints above the ground, the feet apart, both normal forces positive) and the
stability of its equilibrium in its mode; between the steps' ends, the first zero of a contact guard
(:func:`~ocp_crawl.sim.step_dips.first_zero` on the chain's steps, the guards' rates from
:meth:`~ocp_crawl.model.chain_model.ChainModel.evaluate`, the chain solved inside a step by
:meth:`~ocp_crawl.sim.chain_mpcc.ChainStep.mode_solution`), which a contact lost inside a step
reaches first.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.chain_stability import chain_stability_margins
from ocp_crawl.sim.chain_torque_parts import mode_vector
from ocp_crawl.sim.result import Mode
from ocp_crawl.sim.step_dips import (CONTACT, dip_report, first_zero, guard_ends,
                                     step_probes)
from ocp_crawl.status import Status

if TYPE_CHECKING:
    from ocp_crawl.sim.chain_mpcc import ChainStep, ChainStepResult


class RunStop(Exception):
    """The end of a run by a failure status at phase t."""

    def __init__(self, status, t: float, mode: Mode, detail: str):
        super().__init__(detail)
        self.status, self.t, self.mode, self.detail = status, t, mode, detail


def check_contact(model: ChainModel, phi, mode: Mode, t: float) -> dict:
    """RunStop unless the chain at ``phi`` keeps the feet apart and every joint above the ground;
    returns its kinematics (:meth:`ChainModel.kinematics`)."""
    kin = model.kinematics(phi)
    if not float(kin["d"]) > 0:
        raise RunStop(Status.FEET_CROSSED, t, mode, f"feet distance {float(kin['d']):.4g} m")
    for j in range(1, model.chain.n_joints + 1):
        if not float(kin[f"zj{j}"]) > 0:
            raise RunStop(Status.JOINT_ON_GROUND, t, mode,
                          f"joint {j} at height {float(kin[f'zj{j}']):.4g} m")
    return kin


def check_step(model: ChainModel, row: tuple, t: float) -> None:
    """RunStop unless the equilibrium ``row`` (t, phi, x1, x2, f_t, f_n1, f_n2, d, mode) at the end
    of a step keeps its contacts (:func:`check_contact`) and is stable in its contact mode (the
    chain's stability margin, :mod:`ocp_crawl.model.chain_stability`, as the event-driven
    simulators require)."""
    phi, f_t, mode = row[1], row[4], row[8]
    kin = check_contact(model, phi, mode, t)
    X = np.append(np.asarray(phi, float), f_t / model.Mg).reshape(-1, 1)
    q = mode_vector(mode, float(kin["d"]))
    margin = float(np.ravel(chain_stability_margins(model, X, q))[0])
    if not margin > 0:
        raise RunStop(Status.UNSTABLE, t, mode, f"the {mode.label} equilibrium is unstable "
                      f"(stability margin {margin:.3g})")


def mode_row(step: "ChainStep", res: "ChainStepResult", mode: Mode, t: float) -> tuple | None:
    """The row of ``mode``'s solution at the end of a step without a consistent mode (its
    equilibrium, which may have lost a contact), or None when that mode's Newton failed."""
    cand = next((c for c in res.extra.get("candidates", ()) if c is not None
                 and c["mode"] == mode), None)
    if cand is None:
        return None
    z, nan = cand["z"], float("nan")
    d = float(step.model.kinematics(z[:step.m])["d"])
    return (t, z[:step.m], nan, nan, float(z[step.m] * step.Mg), float(cand["fn"][0]),
            float(cand["fn"][1]), d, mode)


def check_end(step: "ChainStep", torque, before: list, end: tuple, located: set,
              consistent: bool = True) -> None:
    """RunStop unless the row ``end`` at a step's end keeps its contacts and (when it is the step's
    ``consistent`` solution) is stable; a lost contact is placed where its guard first reaches
    zero inside the steps ``before`` + [end] (:func:`contact_dip`)."""
    t, mode = end[0], end[8]
    try:
        if min(end[5], end[6]) <= 0:
            raise RunStop(Status.LIFT_OFF, t, mode, f"step at t = {t:.6f}: the {mode.label} "
                          f"equilibrium's normal forces are {end[5]:.4g} and {end[6]:.4g} N")
        if consistent:
            check_step(step.model, end, t)
        else:
            check_contact(step.model, end[1], mode, t)
    except RunStop as stop:
        if stop.status in CONTACT:
            dip_stop(step, torque, [*before, end], located)
        raise


def dip_stop(step: "ChainStep", torque, rows: list, located: set) -> None:
    """RunStop at the first zero of a contact guard inside the steps ``rows``, if any."""
    dip = contact_dip(step, torque, rows, located)
    if dip is not None:
        raise RunStop(dip[1], dip[0], dip[2], dip[3])


def contact_dip(step, torque, rows: list, located: set) -> tuple | None:
    """The first contact guard that reaches zero inside a step of ``rows`` (the incremental steps'
    rows (t, phi, x1, x2, f_t, f_n1, f_n2, d, mode); ``located``: the phases of the events the
    steps located, each row there carrying the mode after it), as (phase [cycles], status, mode,
    message), or None when every guard stays positive."""
    # (a step is in its start row's mode: to its end row's, or to an event located at its end)
    idx = [i for i in range(1, len(rows)) if rows[i][0] > rows[i - 1][0]
           and (rows[i][8] == rows[i - 1][8] or rows[i][0] in located)]
    if not idx:
        return None
    a, b = [rows[i - 1] for i in idx], [rows[i] for i in idx]

    def solve(k: int, t: float) -> tuple | None:
        tau = np.asarray(torque(t), float).reshape(step.m)
        cand = step.mode_solution(a[k][8], a[k][1], tau, a[k][4])
        if cand is None:
            return None
        phi = cand["z"][:step.m]
        kin = step.model.kinematics(phi)
        guards = {"fn1": cand["fn"][0] / step.Mg, "fn2": cand["fn"][1] / step.Mg,
                  "d": float(kin["d"]) / step.L}
        guards.update({f"zj{j}": float(kin[f"zj{j}"]) / step.L for j in range(1, step.m + 1)})
        return phi, guards

    spans = [(r[0], s[0]) for r, s in zip(a, b)]
    x = np.array([np.append(r[1], r[4] / step.Mg) for r in a + b]).T
    q = np.array([mode_vector(r[8], r[7]) for r in a + a]).T
    ends = guard_ends(torque, a, b, x, q, step.model.evaluate, step.Mg, step.L)
    zero = first_zero(spans, ends, step.m, step_probes(solve, [r[1] for r in b], spans))
    if zero is None:
        return None
    t0, status, k, message = dip_report(zero, spans, step.m, step.Mg, step.L)
    return t0, status, a[k][8], message
