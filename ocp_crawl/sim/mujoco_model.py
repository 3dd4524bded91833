"""The three-link crawler as a MuJoCo model (MJCF generated in code), placed on the ground.

Nothing here imports MuJoCo at module level: :func:`crawler_mjcf` writes the model as text, and
the functions that need the engine take its module as an argument.

The model (the conventions of :mod:`ocp_crawl.model.statics`):

* the body link is the base of the chain, free in the x-z plane (slide x, slide z, hinge about
  y); the legs hang from its ends on the hinges ``joint1`` (axis +y) and ``joint2`` (axis -y), so
  that the hinge angle is q_i = phi_i - pi for both joints (q = 0 is the flat robot, phi = pi);
* every link is a uniform rod: mass m = M/(2+beta) per leg of length l = L/(2+beta), beta m for
  the body of length beta l; the inertia about the y axis through the link's centre is
  mass length^2/12 [kg m^2] (about the rod's own axis 1e-3 of that, never excited in the plane);
* each hinge carries a torsion spring of stiffness k [N m/rad] with rest angle q = 0 (phi = pi),
  a light viscous damping (:data:`DAMPING_RATIO`) and an actuator whose torque tau [N m] acts on
  phi: a torque motor of gear 1 (torque drive) or a position servo (angles drive, see
  :func:`servo_gains`); a sensor per hinge reads the actuator's torque;
* the feet are spheres of radius :data:`FOOT_RADIUS` l centred at the leg ends; only they touch
  the ground, a plane, through explicit contact pairs of friction mu1 and mu2 (condim 3); the
  capsules that draw the links collide with nothing.
"""

from __future__ import annotations

import math

import numpy as np

#: foot sphere radius [fraction of the leg length l]: the contact point rolls by r per radian of
#: the leg while the foot sticks, which the model's point feet do not (measured at T = 20 s on the
#: paper gait: r = 0.01 l moves S by +1.0 %, r = 0.001 l by +0.1 %); the soft contact's
#: penetration (2 to 6 um, 0.1 to 0.2 r for the paper robot) stays well inside it
FOOT_RADIUS = 1e-3
#: joint damping [fraction of the critical damping 2 sqrt(k I_leg) of a leg on its spring]: it
#: takes out the spring-mass ringing (about 30 Hz for the paper robot) within a few periods of it;
#: its torque b phi' is below 1e-3 k A at periods above a few seconds
DAMPING_RATIO = 0.2
#: contact softness: solref = (time constant SOLREF_STEPS x timestep [s], damping ratio
#: SOLREF_DAMPING) and solimp = SOLIMP: a contact stiff enough that the feet sink 2 to 6 um, soft
#: enough for the time step.  With SOLIMP, 2 to 20 steps give the same S within 0.05 % (paper gait,
#: T = 5 s) and 0.2 % (max_speed optimum, T = 20 s)
SOLREF_STEPS = 5.0
#: damping ratio of the contact: with SOLIMP, ratio 1 and 10 give the same S within 0.01 % (paper
#: gait, both drives, T = 5 and 20 s; max_speed optimum at 5, 20 and 40 s); with solimp
#: (0.99, 0.999, 1e-3 l) the ratio decides (optimum at T = 20 s: -21 % at 1, -4.4 % at 4 to 30)
SOLREF_DAMPING = 10.0
#: solimp = (dmin, dmax, width [fraction of l]), MuJoCo's midpoint 0.5 and power 2: the impedance
#: rises from dmin at first touch to dmax at a penetration of width (3 um for the paper robot),
#: so a foot resting 2 to 6 um deep has a hard contact and a foot that rises towards the surface a
#: soft one.  A stiff contact all the way up, (0.99, 0.999, 1e-3 l), lets a sliding foot hop (a
#: few um, every few ms; its normal force is zero in 3 % of the samples at T = 20 s); each hop
#: unloads the other foot, and a sticking foot at nearly all its friction (96 % in the median of
#: the slips of the max_speed optimum) slips a little at each hop: that optimum's S -8.4 % at
#: T = 5 s, -4.4 % at 20 s, -4.8 % at 40 s.  With SOLIMP the feet stay at least 1.2 um deep
#: (T = 5 and 20 s) and that S is -2.5 %, -0.06 %, +0.07 %; dmin 0.1 to 0.7 and width 3e-5 to
#: 3e-4 l all give -0.06 to -0.08 % at 20 s, dmin 0.9 gives -3.9 %.  The paper and pulse gaits
#: move by less than 0.3 % (-0.46 %, +0.07 % and -0.50 %, +0.09 % at 5 and 20 s), the angles drive
#: from -1.57 % to -0.22 % at 5 s.  The time step changes little: -0.50 %, -0.06 %, -0.11 % at
#: 1e-4, 2.5e-4 and 1e-3 s (optimum, 20 s)
SOLIMP = (0.1, 0.999, 1e-4)
#: iterations of MuJoCo's no-slip solver, which removes the creep of a soft friction contact under
#: a steady tangential load (at T = 20 s, S of the max_speed optimum -0.18 % without it, -0.06 %
#: with it; of the paper gait -0.02 % and +0.07 %)
NOSLIP_ITERATIONS = 20
#: position servo of the angles drive: natural frequency of a leg on the servo's stiffness
#: SERVO_OMEGA_STEP / timestep [rad/s], critically damped.  A stiff joint passes any hop of a
#: sliding foot (see SOLIMP) on to the other foot, which then slips too: paper gait at T = 20 s,
#: S -18.3 % at 1.0, -3.3 % at 0.7, +0.09 % at 0.5 to 0.2, +0.10 % at 0.15, +0.11 % at 0.1 (with
#: solimp (0.99, 0.999, 1e-3 l): -23.6 % at 1.0, -1.6 % at 0.3, -0.55 % at 0.15).  A soft servo
#: follows the angles less closely: with the spring and velocity feed-forward of
#: :func:`servo_controls` the load deflects it by up to 4e-3 rad at 0.3, 1.2e-2 rad at 0.15,
#: 1.9e-2 rad at 0.1, and W+ is off by +0.43 % at 0.3, +1.29 % at 0.15, +2.1 % at 0.1 (T = 20 s)
SERVO_OMEGA_STEP = 0.15
#: the drives and their actuators
DRIVES = ("torque", "angles")


def _inertial(mass: float, length: float, centre_x: float) -> str:
    """The ``<inertial>`` of a uniform rod of ``mass`` [kg] and ``length`` [m] along x, centred at
    x = ``centre_x`` [m]: I_yy = I_zz = mass length^2/12, I_xx = 1e-3 of that [kg m^2]."""
    i = mass * length**2 / 12.0
    return (
        f'<inertial pos="{centre_x!r} 0 0" mass="{mass!r}" '
        f'diaginertia="{1e-3 * i!r} {i!r} {i!r}"/>'
    )


def servo_gains(robot, timestep: float) -> tuple[float, float]:
    """Stiffness kp [N m/rad] and damping kv [N m s/rad] of the angles drive's position servo: the
    stiffest the explicit step integrates stably (:data:`SERVO_OMEGA_STEP`), critically damped
    for a leg about its hinge (inertia m l^2/3)."""
    i_leg = robot.m * robot.l**2 / 3.0
    kp = i_leg * (SERVO_OMEGA_STEP / timestep) ** 2
    return kp, 2.0 * math.sqrt(kp * i_leg)


def servo_controls(robot, timestep: float, q_ref, dq_ref) -> np.ndarray:
    """Set points [rad] of the position servos that hold the hinge angles q_ref [rad] moving at
    dq_ref [rad/s]: the servo's torque kp (u - q) - kv q' is then the spring's k q plus
    kv (q_ref' - q') plus kp (q_ref - q), so the angles do not lag the reference and the servo
    deflects only under the load of gravity and friction."""
    kp, kv = servo_gains(robot, timestep)
    return np.asarray(q_ref, float) * (1.0 + robot.k / kp) + (kv / kp) * np.asarray(dq_ref, float)


def _actuators(robot, timestep: float, drive: str) -> str:
    """The ``<actuator>`` and ``<sensor>`` elements of ``drive``: one actuator per hinge and a
    sensor of its torque [N m]."""
    if drive == "torque":
        kind = ('motor', 'gear="1"')
    else:
        kp, kv = servo_gains(robot, timestep)
        kind = ('position', f'kp="{kp!r}" kv="{kv!r}"')
    acts = "".join(f'<{kind[0]} name="act{i}" joint="joint{i}" {kind[1]}/>' for i in (1, 2))
    sensors = "".join(f'<actuatorfrc actuator="act{i}"/>' for i in (1, 2))
    return f"<actuator>{acts}</actuator><sensor>{sensors}</sensor>"


def crawler_mjcf(robot, timestep: float, cone: str = "elliptic", drive: str = "torque") -> str:
    """The MJCF text of the crawler ``robot`` (a :class:`~ocp_crawl.model.robot.Robot`).

    Parameters
    ----------
    robot : Robot
        M [kg], L [m], beta [-], k [N m/rad], mu1, mu2 [-], g [m/s^2].
    timestep : float
        Integration step [s]; the contact time constant is :data:`SOLREF_STEPS` times it.
    cone : str
        Friction cone, ``"elliptic"`` or ``"pyramidal"``.
    drive : str
        ``"torque"``: torque motors (the control is tau [N m]); ``"angles"``: position servos
        (the control is the set point of :func:`servo_controls` [rad]).

    Returns
    -------
    str
        The model, for ``mujoco.MjModel.from_xml_string``.
    """
    l, m, body_m = robot.l, robot.m, robot.beta * robot.m
    bl = robot.beta * l
    i_leg = m * l**2 / 3.0  # a leg about its hinge [kg m^2]
    damping = DAMPING_RATIO * 2.0 * math.sqrt(robot.k * i_leg)
    r_foot, r_draw = FOOT_RADIUS * l, 0.02 * l
    solref = f'{SOLREF_STEPS * timestep!r} {SOLREF_DAMPING!r}'
    solimp = f'{SOLIMP[0]!r} {SOLIMP[1]!r} {SOLIMP[2] * l!r}'
    joint = f'type="hinge" stiffness="{robot.k!r}" springref="0" damping="{damping!r}"'
    legs = []
    for i, (sign, axis) in enumerate(((-1.0, "0 1 0"), (1.0, "0 -1 0")), start=1):
        end = sign * l
        legs.append(
            f'<body name="leg{i}" pos="{sign * bl / 2!r} 0 0">'
            f'<joint name="joint{i}" axis="{axis}" {joint}/>{_inertial(m, l, end / 2)}'
            f'<geom type="capsule" fromto="0 0 0 {end!r} 0 0" size="{r_draw!r}"/>'
            f'<geom name="foot{i}" type="sphere" pos="{end!r} 0 0" size="{r_foot!r}"/></body>'
        )
    pairs = "".join(
        f'<pair geom1="floor" geom2="foot{i}" condim="3" friction="{mu!r} {mu!r} 0 0 0" '
        f'solref="{solref}" solimp="{solimp}"/>'
        for i, mu in ((1, robot.mu1), (2, robot.mu2))
    )
    return (
        '<mujoco model="three-link crawler"><compiler angle="radian" inertiafromgeom="false"/>'
        f'<option timestep="{timestep!r}" gravity="0 0 {-robot.g!r}" cone="{cone}" '
        f'noslip_iterations="{NOSLIP_ITERATIONS}" integrator="implicitfast"/>'
        '<default><geom contype="0" conaffinity="0" density="0"/></default>'
        f'<worldbody><geom name="floor" type="plane" size="{10 * robot.L!r} {10 * robot.L!r} 1"/>'
        '<body name="body"><joint name="base_x" type="slide" axis="1 0 0"/>'
        '<joint name="base_z" type="slide" axis="0 0 1"/>'
        '<joint name="base_pitch" type="hinge" axis="0 1 0"/>'
        f'{_inertial(body_m, bl, 0.0)}'
        f'<geom type="capsule" fromto="{-bl / 2!r} 0 0 {bl / 2!r} 0 0" size="{r_draw!r}"/>'
        f'{"".join(legs)}</body></worldbody><contact>{pairs}</contact>'
        f'{_actuators(robot, timestep, drive)}</mujoco>'
    )


def place_on_ground(mujoco, model, data, phi) -> None:
    """Set ``data`` to the robot at rest with joint angles ``phi`` [rad] and both feet touching the
    ground (sphere bottoms at z = 0), foot 1 at x = 0."""
    data.qpos[:] = 0.0
    data.qvel[:] = 0.0
    data.qpos[3:5] = np.asarray(phi, float) - math.pi
    mujoco.mj_kinematics(model, data)
    f1, f2 = _foot_centres(model, data)
    pitch = math.atan2(f1[2] - f2[2], f1[0] - f2[0])  # rotation about y that levels the feet
    if abs(pitch) > math.pi / 2:
        pitch -= math.copysign(math.pi, pitch)
    data.qpos[2] = pitch
    mujoco.mj_kinematics(model, data)
    f1, _ = _foot_centres(model, data)
    r_foot = model.geom_size[model.geom("foot1").id][0]
    data.qpos[0] -= f1[0]
    data.qpos[1] += r_foot - f1[2]
    mujoco.mj_forward(model, data)


def _foot_centres(model, data) -> tuple[np.ndarray, np.ndarray]:
    """World positions [m] of the two foot sphere centres."""
    return (
        data.geom_xpos[model.geom("foot1").id].copy(),
        data.geom_xpos[model.geom("foot2").id].copy(),
    )


def foot_forces(mujoco, model, data, foot_geoms) -> np.ndarray:
    """Contact forces of the ground on the robot at the feet [N]: shape (2, 2), rows foot 1 and 2,
    columns (x, z) in the world frame."""
    out = np.zeros((2, 2))
    buf = np.zeros(6)
    for j in range(data.ncon):
        con = data.contact[j]
        g1, g2 = int(con.geom1), int(con.geom2)
        foot = foot_geoms.get(g2, foot_geoms.get(g1))
        if foot is None:
            continue
        mujoco.mj_contactForce(model, data, j, buf)
        world = con.frame.reshape(3, 3).T @ buf[:3]  # force of geom1 on geom2
        sign = 1.0 if g2 in foot_geoms else -1.0
        out[foot] += sign * world[[0, 2]]
    return out


def _to_world(robot, qpos: np.ndarray, x: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Points (x, z) [m] of the body link's frame in the world, for each row of ``qpos`` (N, 5):
    shape (N, 2)."""
    p = qpos[:, 2]
    return np.stack(
        [qpos[:, 0] + x * np.cos(p) + z * np.sin(p), qpos[:, 1] - x * np.sin(p) + z * np.cos(p)],
        axis=1,
    )


def foot_positions(robot, qpos) -> tuple[np.ndarray, np.ndarray]:
    """World (x, z) [m] of the foot sphere centres for each row of ``qpos`` (N, 5) = (base x [m],
    base z [m], pitch [rad], q1, q2 [rad]): two arrays of shape (N, 2)."""
    qpos = np.atleast_2d(np.asarray(qpos, float))
    l, half = robot.l, 0.5 * robot.beta * robot.l
    q1, q2 = qpos[:, 3], qpos[:, 4]
    return (
        _to_world(robot, qpos, -half - l * np.cos(q1), l * np.sin(q1)),
        _to_world(robot, qpos, half + l * np.cos(q2), l * np.sin(q2)),
    )


def joint_heights(robot, qpos) -> np.ndarray:
    """Heights [m] of the two hinges above the ground for each row of ``qpos`` (N, 5): shape
    (N, 2)."""
    qpos = np.atleast_2d(np.asarray(qpos, float))
    half, zero = 0.5 * robot.beta * robot.l, np.zeros(len(qpos))
    return np.stack(
        [
            _to_world(robot, qpos, zero - half, zero)[:, 1],
            _to_world(robot, qpos, zero + half, zero)[:, 1],
        ],
        axis=1,
    )
