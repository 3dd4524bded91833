"""Physical checks of a problem at load time: the stiffness within the reach of double precision,
and both feet on the ground where the gait starts (over the whole cycle for prescribed angles),
for the three-link robot and for a chain.  Each failure is bad input naming the keys."""
from __future__ import annotations

from typing import Mapping

import numpy as np

from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.inputs import PeriodicSignal
from ocp_crawl.model.statics import Model, Robot
from ocp_crawl.problem.messages import format_value
from ocp_crawl.problem.values import Context

#: phases at which a prescribed-angle gait is checked for contact validity before simulating
CONTACT_GRID = 721

#: largest nondimensional stiffness k/(M g L) of the torque drive: the joint balance subtracts
#: spring torques of order k from inputs of order k, so round-off in the contact forces grows like
#: 1e-16 k/(M g L) (M g); at 1e10 that is 1e-6 M g, the solvers' force tolerance.  The stiff limit
#: is the prescribed-angle gait (gait.drive = "angles"), which S approaches as M g L/k
#: (tests/test_scaling.py measures the first order up to 1e8).
MAX_STIFFNESS_RATIO = 1e10


def check_stiffness_ratio(ctx: Context, robot: Robot | Chain, drive: str) -> None:
    """k/(M g L) (a chain: its stiffest joint's) above :data:`MAX_STIFFNESS_RATIO` is bad input for
    the torque drive, naming the keys."""
    if isinstance(robot, Chain):
        ratio = max(robot.stiffness) / robot.MgL
        keys = (f"stiffness = {format_value(list(robot.stiffness))} with masses = "
                f"{format_value(list(robot.masses))}, lengths = "
                f"{format_value(list(robot.lengths))}")
        what = "max k_j/(M g L)"
    else:
        ratio = robot.k / robot.MgL
        keys = (f"k = {format_value(robot.k)} with M = {format_value(robot.M)}, L = "
                f"{format_value(robot.L)}")
        what = "k/(M g L)"
    if drive == "torque" and not ratio <= MAX_STIFFNESS_RATIO:
        raise ctx.error(f"[robot] {keys}, g = {format_value(robot.g)} is invalid: {what} = "
                        f"{ratio:.3g} exceeds {MAX_STIFFNESS_RATIO:g}, beyond which round-off in "
                        "double precision swamps the contact forces; the stiff limit is the "
                        "prescribed-angle gait: set gait.drive = \"angles\"")


def _blame(values: Mapping, robot_key: str) -> str:
    """The ``[gait]`` keys given (and the robot's key that shapes it) as a message names them."""
    gait_keys = [k for k in values["gait"] if k not in ("drive", "waveform", "interpolation")]
    blame = ", ".join(f"{k} = {format_value(values['gait'][k])}" for k in gait_keys)
    return (f"[gait] {blame} (with [robot] {robot_key} = "
            f"{format_value(values['robot'][robot_key])})")


def check_contact(ctx: Context, model: Model, gait: PeriodicSignal, drive: str,
                  values: Mapping) -> None:
    """A starting configuration (or, prescribed, any phase) with a foot off the ground is bad
    input."""
    blame = _blame(values, "beta")
    try:
        model.check_contact(gait(0.0), where="reference angles at phase 0")
    except ValueError as exc:
        raise ctx.error(f"{blame} are invalid: {exc}") from None
    if drive != "angles":
        return
    t = np.linspace(0.0, 1.0, CONTACT_GRID)
    j = _first_lost(model.kinematics(gait(t)))
    if j is not None:
        try:
            model.check_contact(gait(t[j]), where=f"prescribed angles at phase {t[j]:.4f}")
            detail = f"prescribed angles at phase {t[j]:.4f}: contact lost"
        except ValueError as exc:
            detail = str(exc)
        raise ctx.error(f"{blame} are invalid for the angles drive: {detail} (both feet must stay "
                        "on the ground over the whole cycle)")


def check_chain_contact(ctx: Context, model: ChainModel, gait: PeriodicSignal, drive: str,
                        values: Mapping) -> None:
    """Both feet of a chain on the ground with every joint above it at phase 0 (and, for the angles
    drive, over the cycle on :data:`CONTACT_GRID` phases); bad input naming the gait otherwise."""
    from ocp_crawl.sim.chain_angles import ChainGait, check_start

    blame = _blame(values, "lengths")
    try:
        check_start(ChainGait(model, gait))
    except ValueError as exc:
        raise ctx.error(f"{blame} are invalid: {exc}") from None
    if drive != "angles":
        return
    t = np.linspace(0.0, 1.0, CONTACT_GRID)
    j = _first_lost(model.kinematics(gait(t)), model.chain.n_joints)
    if j is not None:
        raise ctx.error(f"{blame} are invalid for the angles drive: contact lost at phase "
                        f"{t[j]:.4f} (both feet must stay on the ground, every joint above it, "
                        "over the whole cycle)")


def _first_lost(kin: Mapping, joints: int = 0) -> int | None:
    """The first phase of the kinematics ``kin`` (columns over phases) where the feet cross or
    meet, a normal force is not positive or, of the first ``joints`` joints, one is not above the
    ground; None if there is none."""
    ok = (kin["d"] > 0) & (kin["fn1"] > 0) & (kin["fn2"] > 0)
    for j in range(1, joints + 1):
        ok &= kin[f"zj{j}"] > 0
    bad = np.nonzero(~ok)[0]
    return int(bad[0]) if bad.size else None
