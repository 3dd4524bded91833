"""Dynamic simulation of the crawler in MuJoCo: the quasistatic gait played at a period T [s].

The robot of :mod:`ocp_crawl.sim.mujoco_model` is driven by the input signal at the phase t / T
(in cycles): the joint torques tau(t / T) [N m] of the torque drive, or the joint angles
phi(t / T) [rad] of the angles drive, which position servos make the hinges follow (see
:func:`drive_controls`).  After a settling time :data:`SETTLE_TIME` [s] at the input of phase 0
it runs cycle after cycle until the displacement per cycle S converges (relative change between
two successive cycles at most ``MujocoOptions.s_tol``).  The result is a
:class:`CrawlResult` as the quasistatic solvers give: S [m] (foot 1's displacement over the
steady cycle), W+ [J] (per actuator, the integral of max(tau_i phi_i', 0) over the cycle, tau_i
the actuator's torque as MuJoCo's sensor reads it, as the event and angles solvers define it; see
:data:`W_PLUS_WINDOW`), CoT+, samples, and the contact modes and
events from the feet's sliding (see :func:`sample_cycle`).  The energy balance is not closed
(``energy`` holds the input and gross work only): friction, contact and joint damping are not
separated.

MuJoCo is an optional dependency (``pip install 'ocp-crawl[dynamic]'``); it is imported when a
run starts (:func:`require_mujoco`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ocp_crawl.checks import real
from ocp_crawl.model.statics import Model
from ocp_crawl.sim.assemble import (
    cycle_metrics,
    failure_message,
    new_result,
    sample_fields,
    success_message,
)
from ocp_crawl.sim.mujoco_model import (
    DRIVES,
    FOOT_RADIUS,
    crawler_mjcf,
    foot_forces,
    foot_positions,
    joint_heights,
    place_on_ground,
    servo_controls,
)
from ocp_crawl.sim.options import MAX_CYCLES_BOUNDS, count
from ocp_crawl.sim.result import CrawlResult, Event, Mode, mode_change_kind
from ocp_crawl.status import Status

#: the command that installs the optional dependency
INSTALL = "pip install 'ocp-crawl[dynamic]'"
#: time [s] the robot stands at the torque of phase 0 before the first cycle (its ringing dies out)
SETTLE_TIME = 0.5
#: friction cones of MuJoCo
CONES = ("elliptic", "pyramidal")
#: output samples per cycle when no phases are asked for
SAMPLES = 200
#: W+ is summed over windows of W_PLUS_WINDOW [s] (at most 1/200 of the period): the joint angle
#: increment of a window times the mean torque in it, clipped at zero: the quasistatic motion is
#: smooth on a window, and a contact that lets a sliding foot chatter (hops of a few um every few
#: ms: a contact hard up to the surface) would add work on single steps;
#: ``extra["W_plus_steps"]`` is the sum over single steps (on the paper gait within 2e-4 of it)
W_PLUS_WINDOW = 0.02
#: a foot slides when it moves faster than SLIP_SPEED L / T (averaged between output samples) and
#: faster than SLIP_SHARE times the other foot (the sticking foot of a slip creeps at about 1 % of
#: the slipping foot's speed, and a slip that starts kicks it for a moment)
SLIP_SPEED = 0.05
SLIP_SHARE = 0.25
#: a foot has lifted off when its sphere's centre rises LIFT_HEIGHT l above its resting height
LIFT_HEIGHT = 0.02


def require_mujoco():
    """The ``mujoco`` module; ImportError naming the install command when it cannot be imported."""
    try:
        import mujoco
    except ImportError as exc:
        raise ImportError(
            f"the mujoco solver needs MuJoCo (not importable: {exc}); install it with {INSTALL}"
        ) from None
    return mujoco


def mujoco_available() -> bool:
    """True when MuJoCo can be imported."""
    try:
        require_mujoco()
    except ImportError:
        return False
    return True


@dataclass(frozen=True)
class MujocoOptions:
    """Options of the dynamic (MuJoCo) solver."""

    period: float = 20.0
    """period T of one cycle of the input [s]; the quasistatic model is the limit T -> infinity"""
    timestep: float = 5e-4
    """integration step [s]; the contact time constant is 5 steps (``mujoco_model.SOLREF_STEPS``)"""
    cone: str = "elliptic"
    """friction cone: "elliptic" (Coulomb's) or "pyramidal" (its 4-sided approximation)"""
    max_cycles: int = 12
    """cycles to run before declaring the gait non-periodic"""
    s_tol: float = 1e-3
    """periodicity: |S_n - S_(n-1)| <= s_tol max(|S_n|, 1e-3 L) for two successive cycles [-]"""

    def __post_init__(self) -> None:
        period = real("MujocoOptions.period", self.period, positive=True)
        step = real("MujocoOptions.timestep", self.timestep, low=1e-6, high=1e-2)
        if period / step > 1e6:
            raise ValueError(
                "MujocoOptions.period / timestep must be at most 1e6 steps per cycle (88 MB of "
                f"states), got {period / step:.3g}"
            )
        if self.cone not in CONES:
            raise ValueError(
                f"MujocoOptions.cone must be one of {', '.join(CONES)}, got {self.cone!r}"
            )
        object.__setattr__(self, "period", period)
        object.__setattr__(self, "timestep", step)
        object.__setattr__(
            self,
            "max_cycles",
            count("MujocoOptions.max_cycles", self.max_cycles, *MAX_CYCLES_BOUNDS),
        )
        object.__setattr__(self, "s_tol", real("MujocoOptions.s_tol", self.s_tol, positive=True))


@lru_cache(maxsize=8)
def _compiled(robot, timestep: float, cone: str, drive: str):
    mujoco = require_mujoco()
    return mujoco.MjModel.from_xml_string(crawler_mjcf(robot, timestep, cone, drive))


def drive_controls(robot, signal, drive: str, period: float, timestep: float, phases) -> np.ndarray:
    """The actuator controls at ``phases`` [cycles], shape (len(phases), 2): the torques
    tau [N m] of the torque drive; for the angles drive the set points [rad] of the position
    servos that hold the hinge angles phi - pi of the signal moving at phi' / T
    (:func:`~ocp_crawl.sim.mujoco_model.servo_controls`)."""
    phases = np.atleast_1d(np.asarray(phases, float))
    values = np.asarray(signal(phases), float).reshape(2, -1)
    if drive == "torque":
        return np.ascontiguousarray(values.T)
    rate = np.asarray(signal.derivative(phases), float).reshape(2, -1) / period
    return np.ascontiguousarray(servo_controls(robot, timestep, values - math.pi, rate).T)


@dataclass
class _Cycle:
    """One simulated cycle: the state before it and after each of its n steps, (n + 1, nq + nv)."""

    qpos: np.ndarray
    qvel: np.ndarray
    tau: np.ndarray
    """the actuators' torques [N m] in each step, (n, 2)"""
    S: float
    w_plus: np.ndarray
    w_plus_steps: np.ndarray
    input_work: float
    gross_work: float


def windowed_positive_work(controls: np.ndarray, dphi: np.ndarray, window: int) -> np.ndarray:
    """Positive work [J] of each actuator over windows of ``window`` steps: the sum over windows
    of max(mean tau [N m] x joint angle increment [rad], 0); ``controls`` and ``dphi``: (n, 2)."""
    n = len(dphi)
    edges = np.arange(0, n, max(1, window))
    dq = np.add.reduceat(dphi, edges, axis=0)
    tau = np.add.reduceat(controls * 1.0, edges, axis=0) / np.diff(np.append(edges, n))[:, None]
    return np.maximum(tau * dq, 0.0).sum(axis=0)


def _run_cycle(mujoco, mjm, data, controls: np.ndarray, robot) -> _Cycle:
    """Step ``data`` through one cycle of ``controls`` (n, 2), one per step (MuJoCo's rollout);
    the torques are the actuators' as their sensors read them at the start of each step."""
    from mujoco import rollout

    nq, nv = mjm.nq, mjm.nv
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.empty(mujoco.mj_stateSize(mjm, spec))
    mujoco.mj_getState(mjm, data, state0, spec)
    states, sensors = rollout.rollout(mjm, data, state0[None], controls[None])
    tau = np.ascontiguousarray(sensors[0][:, :2])
    states = np.vstack([state0[None], states[0]])
    qpos, qvel = states[:, 1 : 1 + nq], states[:, 1 + nq : 1 + nq + nv]
    mujoco.mj_setState(mjm, data, states[-1], spec)
    mujoco.mj_forward(mjm, data)
    dphi = np.diff(qpos[:, 3:5], axis=0)  # (the joint angle increments of the steps [rad])
    power = tau * dphi  # [J] per step
    x1 = foot_positions(robot, qpos[[0, -1]])[0][:, 0]
    n, step = len(controls), mjm.opt.timestep
    window = int(min(max(1.0, round(W_PLUS_WINDOW / step)), max(1, n // 200)))
    return _Cycle(
        qpos,
        qvel,
        tau,
        float(x1[1] - x1[0]),
        windowed_positive_work(tau, dphi, window),
        np.maximum(power, 0.0).sum(axis=0),
        float(power.sum()),
        float(np.abs(power).sum()),
    )


def _failure(model, status, detail, cycle, drive="torque", **fields) -> CrawlResult:
    return new_result(
        model,
        drive,
        status,
        failure_message(status, detail),
        failure_t=float(cycle),
        failure_mode="dynamic",
        **fields,
    )


def _geometry_failure(model, cyc: _Cycle, cycle: int, drive: str) -> CrawlResult | None:
    """LIFT_OFF, JOINT_ON_GROUND or FEET_CROSSED if a step of ``cyc`` shows it, else None."""
    r = model.robot
    (f1, f2), joints = foot_positions(r, cyc.qpos), joint_heights(r, cyc.qpos)
    rest = FOOT_RADIUS * r.l
    n = len(cyc.qpos) - 1
    checks = (
        (
            Status.LIFT_OFF,
            np.maximum(f1[:, 1], f2[:, 1]) - rest > LIFT_HEIGHT * r.l,
            f"a foot rises more than {LIFT_HEIGHT:g} l above the ground",
        ),
        (Status.JOINT_ON_GROUND, joints.min(axis=1) < 0.0, "a joint is below the ground"),
        (Status.FEET_CROSSED, f2[:, 0] - f1[:, 0] <= 0.0, "the feet meet"),
    )
    for status, bad, text in checks:
        if np.any(bad):
            t = cycle + int(np.argmax(bad)) / n
            return _failure(model, status, f"{text} at t = {t:.4f} cycles", t, drive)
    return None


def _cycles(model: Model, signal, options: MujocoOptions, drive: str):
    """Run cycles until S converges; returns (the steady cycle, cycles run, the S of each cycle,
    the MuJoCo objects at the start of the steady cycle, controls) or a failure result."""
    mujoco = require_mujoco()
    r, step = model.robot, options.timestep
    mjm = _compiled(r, step, options.cone, drive)
    data = mujoco.MjData(mjm)
    start = np.asarray(signal(0.0), float).ravel()
    place_on_ground(mujoco, mjm, data, math.pi + start / r.k if drive == "torque" else start)
    data.ctrl[:] = drive_controls(r, signal, drive, options.period, step, [0.0])[0]
    mujoco.mj_step(mjm, data, nstep=max(1, int(round(SETTLE_TIME / step))))
    n = max(4, int(round(options.period / step)))
    controls = drive_controls(r, signal, drive, options.period, step, (np.arange(n) + 0.5) / n)
    history: list[float] = []
    for cycle in range(options.max_cycles):
        cyc = _run_cycle(mujoco, mjm, data, controls, r)
        if not (np.all(np.isfinite(cyc.qpos)) and np.all(np.isfinite(cyc.qvel))):
            return _failure(
                model,
                Status.SOLVER_FAILURE,
                f"the MuJoCo state is not finite in cycle {cycle + 1}",
                cycle,
                drive,
            )
        fail = _geometry_failure(model, cyc, cycle, drive)
        if fail is not None:
            return fail
        history.append(cyc.S)
        if cycle >= 1 and abs(cyc.S - history[-2]) <= options.s_tol * max(abs(cyc.S), 1e-3 * r.L):
            return cyc, cycle + 1, history, (mujoco, mjm, data), controls
    return _failure(
        model,
        Status.NOT_PERIODIC,
        f"S of the last cycles {history[-3:]} [m] changes by more than "
        f"s_tol = {options.s_tol:g} after {options.max_cycles} cycles",
        options.max_cycles,
        drive,
        extra={"S_cycles": history},
    )


def simulate_mujoco(
    model: Model, signal, options: MujocoOptions | None = None, t_eval=None, drive: str = "torque"
) -> CrawlResult:
    """Simulate the crawler dynamically in MuJoCo, the input played at a period T [s].

    Parameters
    ----------
    model : Model
        robot; its gravity convention must be ``"physical"`` (MuJoCo has no other).
    signal : PeriodicSignal
        joint torques tau(phase) [N m] (torque drive) or joint angles phi(phase) [rad] with their
        derivative (angles drive), phase in cycles.
    options : MujocoOptions, optional
        period [s], time step [s], friction cone, cycles and periodicity tolerance.
    t_eval : array_like, optional
        output phases [cycles] in [0, 1] of the steady cycle; None: :data:`SAMPLES` + 1 equal steps.
    drive : str
        ``"torque"`` (torque motors) or ``"angles"`` (the angles prescribed by position servos).

    Returns
    -------
    CrawlResult
        S [m], W+ [J], CoT+ [-] of the steady cycle, the samples, the modes and events from the
        feet's sliding; a failure status (``lift_off``, ``joint_on_ground``, ``feet_crossed``,
        ``not_periodic``,         ``solver_failure``) with its message otherwise.
    """
    options = MujocoOptions() if options is None else options
    if drive not in DRIVES:
        raise ValueError(f"drive must be one of {', '.join(DRIVES)}, got {drive!r}")
    if model.gravity != "physical":
        raise ValueError(
            f"the mujoco solver simulates physical gravity only, got gravity = {model.gravity!r}"
        )
    out = _cycles(model, signal, options, drive)
    if isinstance(out, CrawlResult):
        return out
    cyc, cycles, history, engine, controls = out
    t0 = float(cycles - 1)
    phases = np.linspace(0.0, 1.0, SAMPLES + 1) if t_eval is None else np.asarray(t_eval, float)
    return new_result(
        model,
        drive,
        Status.SUCCESS,
        success_message(
            cycles, t0, f" of {len(controls)} MuJoCo steps at T = {options.period:g} s"
        ),
        cycles=cycles,
        t0=t0,
        nsteps=cycles * len(controls),
        extra={
            "S_cycles": history,
            "period": options.period,
            "W_plus_steps": float(cyc.w_plus_steps.sum()),
        },
        **sample_cycle(model, engine, cyc, controls, phases, t0),
        **cycle_metrics(
            model.robot,
            cyc.S,
            cyc.w_plus,
            {"input_work": cyc.input_work, "gross_work": cyc.gross_work},
        ),
    )


def sample_cycle(model: Model, engine, cyc: _Cycle, controls, phases, t0: float) -> dict:
    """The sample fields (:func:`~ocp_crawl.sim.assemble.sample_fields`) and ``events`` of the
    steady cycle [t0, t0 + 1] at ``phases`` [cycles in [0, 1]] (nearest step), with the contact
    modes.

    A foot slides between two samples when its mean speed there exceeds :data:`SLIP_SPEED` L / T
    (and :data:`SLIP_SHARE` times the other foot's); the mode of a sample is that of the interval
    after it (the last sample's that of the interval before), and an event is placed at a sample
    where the mode changes (located to the sample spacing)."""
    mujoco, mjm, data = engine
    r, n = model.robot, len(controls)
    idx = np.clip(np.rint(np.clip(phases, 0.0, 1.0) * n).astype(int), 0, n)
    qpos, qvel = cyc.qpos[idx], cyc.qvel[idx]
    f1, f2 = foot_positions(r, qpos)
    forces = np.zeros((len(idx), 2, 2))
    feet = {mjm.geom("foot1").id: 0, mjm.geom("foot2").id: 1}
    for j, i in enumerate(idx):
        data.qpos[:], data.qvel[:] = qpos[j], qvel[j]
        data.ctrl[:] = controls[min(i, n - 1)]
        mujoco.mj_forward(mjm, data)
        forces[j] = foot_forces(mujoco, mjm, data, feet)
    modes = _modes(f1[:, 0], f2[:, 0], phases, r.L * SLIP_SPEED)
    tau = cyc.tau[np.minimum(idx, n - 1)].T
    phi = qpos[:, 3:5].T + math.pi
    samples = sample_fields(
        t0 + phases,
        phi,
        -qpos[:, 2],
        f2[:, 0] - f1[:, 0],
        f1[:, 0],
        f2[:, 0],
        forces[:, 0, 0],
        forces[:, 0, 1],
        forces[:, 1, 1],
        tau,
        modes,
    )
    events = [
        Event(
            float(t0 + phases[j]),
            mode_change_kind(Mode(modes[j - 1]), Mode(modes[j])),
            Mode(modes[j - 1]).label,
            Mode(modes[j]).label,
        )
        for j in range(1, len(modes))
        if modes[j] != modes[j - 1]
    ]
    return {**samples, "events": events}


def _modes(x1, x2, phases, speed) -> np.ndarray:
    """Contact mode codes from the feet's positions x1, x2 [m] at ``phases`` [cycles]: a foot
    slides in an interval where its mean speed exceeds ``speed`` [m per cycle] and
    :data:`SLIP_SHARE` times the other's.
    """
    codes = np.zeros(len(phases), dtype=int)
    if len(phases) < 2:
        return codes
    dt = np.maximum(np.diff(phases), 1e-12)
    v1, v2 = np.diff(x1) / dt, np.diff(x2) / dt
    for j, (a, b) in enumerate(zip(v1, v2)):
        s1 = abs(a) > max(speed, SLIP_SHARE * abs(b))
        s2 = abs(b) > max(speed, SLIP_SHARE * abs(a))
        if s1 and s2:
            mode = Mode.slip(3, 1 if b - a > 0 else -1)
        elif s1:
            mode = Mode.SLIP1_POS if a > 0 else Mode.SLIP1_NEG
        elif s2:
            mode = Mode.SLIP2_POS if b > 0 else Mode.SLIP2_NEG
        else:
            mode = Mode.STICK
        codes[j] = int(mode)
    codes[-1] = codes[-2]
    return codes
