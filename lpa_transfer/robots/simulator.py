"""A robot dynamics simulator on pybullet, for the robot_sim node.

:class:`RobotSimulator` wraps one pybullet DIRECT client (its own client id, passed to every
call, so several simulators in one process never interfere) and one fixed-base robot loaded
from URDF with ``URDF_USE_INERTIA_FROM_FILE`` (otherwise pybullet recomputes the inertias
from the collision shapes). Gravity is −9.81 m/s² along −y, as in :mod:`planar_chain`: the
planar chains move in the vertical x-y plane. pybullet's artificial link damping is set to 0,
so the dynamics are the URDF's; nothing is random: the same inputs give the same outputs.

Control modes: ``"position"`` (pybullet's position motors, targets clipped to the limits) and
``"torque"`` (torques clipped to ± the effort limits, which pybullet does not enforce). In
torque mode the joint drives of :mod:`lpa_transfer.robots.params` act as the usual rotor
model, (M(q) + diag(A)) q̈ + h(q, q̇) + D q̇⁺ = τ, solved implicitly at every physics step,
because pybullet has no armature and its explicit damping diverges on light geared links.
Actuator ``"velocity_motor"`` is V-REP's torque mode, which the thesis' chapter 5 used
(§5.5.1): velocity motors towards ± the velocity limit with force capped at |τ|, no armature
or damping. The equations and their limits: docs/library.md, "The simulator".
"""
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.linalg import _umath_linalg

from lpa_transfer.robots.kinematics import home_pose
from lpa_transfer.robots.planar_chain import load_fixed_robot
from lpa_transfer.robots.serial_chain import serial_chain_urdf, urdf_joint_armatures

CONTROL_MODES = ("position", "torque")
ACTUATORS = ("torque", "velocity_motor")


def robot_urdf(robot):
    """URDF text of a :class:`lpa_transfer.robots.params.RobotParams` chain, planar or serial.

    :func:`lpa_transfer.robots.serial_chain.serial_chain_urdf`: the file's masses, centres of mass,
    inertias, limits, joint damping and armature (a planar file's derived ones: the rods of
    ``planar_chain_urdf``).
    """
    return serial_chain_urdf(robot)


def simulated_description(robot="", urdf="", tip_link="", base_link="", repair_inertia=False):
    """(URDF text, end-effector link or None, lines saying what a repair changed) for
    robot_sim: ``robot`` a robot file or a URDF read as a serial chain
    (:func:`~lpa_transfer.robots.params.load_robot_params`, from ``base_link`` to ``tip_link``;
    the text is :func:`robot_urdf`'s), or ``urdf`` a URDF simulated as it is
    (:func:`~lpa_transfer.robots.urdf.simulated_urdf`; ``tip_link`` names the end-effector
    link). Exactly one of them; empty strings are "not given". ValueError otherwise."""
    from lpa_transfer.robots.params import load_robot_params
    from lpa_transfer.robots.urdf import read_urdf, simulated_urdf

    if bool(robot) == bool(urdf):
        raise ValueError("set exactly one of the parameters 'robot' (a robot .toml file) "
                         "and 'urdf' (a URDF file)")
    path = Path(robot or urdf).expanduser()
    if urdf:
        if base_link:
            raise ValueError("base_link applies to robot:=<file>.urdf (a chain read from the "
                             "URDF); urdf:= simulates the whole file from its root link")
        text, lines = simulated_urdf(path, repair_inertia)
        return text, tip_link or None, lines
    options = {k: v for k, v in (("tip_link", tip_link), ("base_link", base_link)) if v}
    if repair_inertia:
        options["repair_inertia"] = True
    lines = read_urdf(path, True)[1] if repair_inertia and path.suffix == ".urdf" else []
    return robot_urdf(load_robot_params(path, **options)), None, lines


@dataclass(frozen=True, eq=False)
class SimState:
    """The robot's state at ``time`` (s of simulated time since start/reset)."""

    time: float
    positions: np.ndarray      # (n,) rad (or m for prismatic joints)
    velocities: np.ndarray     # (n,) rad/s
    efforts: np.ndarray        # (n,) N·m applied during the last step (clipped command in
    #                            torque mode, the motor torque in position mode)
    end_effector: np.ndarray   # (3,) world position of the last link's frame, m


def elapsed(state, previous):
    """Simulated seconds from ``previous`` to ``state``, rounded to 1 ns.

    Clock readings are step counts times the step length; the float difference of two of them
    carries a rounding error that grows with the time run, so without the rounding the same
    seed gives other samples depending on how long the simulator ran before (docs/history.md).
    Every difference of two clock readings goes through here (acceleration samples, the PID
    servo's command velocity).
    """
    return round(state.time - previous.time, 9)


class RobotSimulator:
    """One fixed-base robot in its own pybullet DIRECT client (see module docstring).

    ``urdf`` is a URDF file path or the URDF text itself. ``initial_positions`` default to
    zero clipped into the joint limits; given ones must lie within the limits. The end
    effector is the frame of the robot's last link (the ``tool`` frame of a planar chain).
    ``seed`` is kept for reproducible noise models; the simulation itself is deterministic.

    ``position_gain`` is the position motors' gain (pybullet's ``positionGains``: the share of
    the position error the motor constraint removes per step; velocity gain 1). pybullet's
    default 0.1 lets an arm whose effort limit saturates fall into a limit cycle (the §3.6
    target arm did after some random targets); at 0.05 it settles (docs/history.md).

    ``armature`` and ``joint_damping`` (read-only, per joint) are the URDF's joint drives
    (module docstring); the armature acts in torque mode with the ``"torque"`` actuator.
    ``actuator`` (torque mode only): ``"torque"`` or ``"velocity_motor"`` (module docstring).
    ``tip_link``: the link whose frame is the end effector (default: the last link).
    """

    def __init__(self, urdf, control_mode="position", physics_step=1e-3,
                 initial_positions=None, seed=0, position_gain=0.05, actuator="torque",
                 tip_link=None):
        import pybullet as p

        if control_mode not in CONTROL_MODES:
            raise ValueError(f"control_mode must be one of {CONTROL_MODES}, got {control_mode!r}")
        if actuator not in ACTUATORS:
            raise ValueError(f"actuator must be one of {ACTUATORS}, got {actuator!r}")
        self.actuator = actuator
        if not (isinstance(physics_step, (int, float)) and np.isfinite(physics_step)
                and physics_step > 0):
            raise ValueError(f"physics_step must be a positive number of seconds, "
                             f"got {physics_step!r}")
        if not (isinstance(position_gain, (int, float)) and 0 < position_gain <= 1):
            raise ValueError(f"position_gain must be in (0, 1], got {position_gain!r}")
        self._p, self.control_mode, self.physics_step = p, control_mode, float(physics_step)
        self.seed, self.position_gain = seed, float(position_gain)
        self.tip_link = tip_link
        self._client = p.connect(p.DIRECT)
        try:
            self._load(urdf)
            self.reset(initial_positions)
        except BaseException:
            self.close()
            raise

    # -- set-up -----------------------------------------------------------------------------
    def _load(self, urdf):
        p, cid = self._p, self._client
        self._body = load_fixed_robot(p, urdf, cid)
        p.setTimeStep(self.physics_step, physicsClientId=cid)
        n_all = p.getNumJoints(self._body, physicsClientId=cid)
        infos = [p.getJointInfo(self._body, j, physicsClientId=cid) for j in range(n_all)]
        movable = [info for info in infos if info[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC)]
        if not movable:
            raise ValueError("the robot has no revolute or prismatic joint")
        self._joints = [info[0] for info in movable]
        self.joint_names = [info[1].decode() for info in movable]
        limits = []
        for info in movable:
            lower, upper = info[8], info[9]
            # pybullet reports lower > upper for joints without limits (e.g. continuous).
            limits.append((lower, upper) if lower <= upper else (-np.inf, np.inf))
        self.joint_limits = np.array(limits, dtype=float)
        self.effort_limits = np.array([info[10] for info in movable], dtype=float)
        self.velocity_limits = np.array([info[11] for info in movable], dtype=float)
        if not (self.effort_limits > 0).all():
            bad = [n for n, e in zip(self.joint_names, self.effort_limits) if not e > 0]
            raise ValueError(f"joints {bad} have no positive effort limit in the URDF "
                             f"(<limit effort=...>); the simulator needs one to clip commands")
        # every link's name and its parent's (-1: the base), for link_frames()
        self.base_link = p.getBodyInfo(self._body, physicsClientId=cid)[0].decode()
        self.link_names = [info[12].decode() for info in infos]
        self._ee_link = n_all - 1
        if self.tip_link is not None:
            if self.tip_link not in self.link_names:
                raise ValueError(f"no link {self.tip_link!r} (tip_link) below the base link "
                                 f"{self.base_link!r}; its links: {self.link_names}")
            self._ee_link = self.link_names.index(self.tip_link)
        self._link_parents = [info[16] for info in infos]
        self._base_inertial = p.invertTransform(*p.getDynamicsInfo(
            self._body, -1, physicsClientId=cid)[3:5])
        self.joint_damping = np.array([info[6] for info in movable], dtype=float)
        self.armature = self._armatures(urdf)
        for link in range(-1, n_all):
            p.changeDynamics(self._body, link, linearDamping=0.0, angularDamping=0.0,
                             physicsClientId=cid)
        for array in (self.joint_limits, self.effort_limits, self.velocity_limits,
                      self.joint_damping, self.armature):
            array.setflags(write=False)
        self._motor = self.control_mode == "torque" and self.actuator == "velocity_motor"
        if self._motor and not (np.isfinite(self.velocity_limits).all()
                                and (self.velocity_limits > 0).all()):
            raise ValueError(f"the velocity_motor actuator needs a positive velocity limit on "
                             f"every joint (<limit velocity=...>), got "
                             f"{self.velocity_limits.tolist()}")
        self._drives = self.control_mode == "torque" and not self._motor and (
            (self.armature > 0).any() or (self.joint_damping > 0).any())
        # _drive_torques' constants, computed once: diag(A + D·Δt) and a zero acceleration
        self._drive = np.diag(self.armature + self.joint_damping * self.physics_step)
        self._zero_accel = [0.0] * len(self._joints)
        if self._drives or self._motor:   # damping implicitly in _drive_torques, or none
            for joint in self._joints:
                p.changeDynamics(self._body, joint, jointDamping=0.0, physicsClientId=cid)
        if self.control_mode == "torque":
            p.setJointMotorControlArray(self._body, self._joints, p.VELOCITY_CONTROL,
                                        targetVelocities=[0.0] * self.n_joints,
                                        forces=[0.0] * self.n_joints, physicsClientId=cid)

    def _armatures(self, urdf):
        """Armature per movable joint from the URDF's ``<lpa:armature>`` elements (default 0)."""
        text = str(urdf)
        if not text.lstrip().startswith("<"):
            text = Path(text).read_text()
        armatures = urdf_joint_armatures(text)
        unknown = set(armatures) - set(self.joint_names)
        if unknown:
            raise ValueError(f"lpa:armature on joints {sorted(unknown)}, which are not movable "
                             f"joints of the robot ({', '.join(self.joint_names)})")
        return np.array([armatures.get(name, 0.0) for name in self.joint_names])

    def _drive_torques(self, torques):
        """τ' that makes pybullet's step follow (M + diag A) q̈ + h + D q̇⁺ = τ (module doc)."""
        p, cid, body = self._p, self._client, self._body
        states = p.getJointStates(body, self._joints, physicsClientId=cid)
        q, qd = [s[0] for s in states], [s[1] for s in states]
        mass, bias = self._mass_and_bias(q, qd)
        # numpy.linalg.solve's own kernel (LAPACK gesv) for one right-hand side, without its
        # argument checks, which cost more than the solve on so small a system: the same
        # bits, and this runs at every physics step (docs/history.md)
        accel = _umath_linalg.solve1(mass + self._drive,
                                     torques - self.joint_damping * np.asarray(qd) - bias,
                                     signature="dd->d")
        return mass @ accel + bias

    def _mass_and_bias(self, q, qd):
        """M(q) and h(q, q̇) = Coriolis + gravity of the URDF's rigid bodies (lists in, arrays
        out): the drive model's pybullet part, shared by the drive and inverse_dynamics."""
        p, cid, body = self._p, self._client, self._body
        mass = np.array(p.calculateMassMatrix(body, q, physicsClientId=cid))
        bias = np.array(p.calculateInverseDynamics(body, q, qd, self._zero_accel,
                                                   physicsClientId=cid))
        return mass, bias

    @property
    def n_joints(self):
        return len(self._joints)

    @property
    def time(self):
        return self._steps * self.physics_step

    def _vector(self, values, name):
        array = np.asarray(values, dtype=float)
        if array.shape != (self.n_joints,):
            raise ValueError(f"{name} must have {self.n_joints} values (joints "
                             f"{', '.join(self.joint_names)}), got {array.size}")
        if not np.isfinite(array).all():
            raise ValueError(f"{name} contains NaN or infinite values: {array.tolist()}")
        return array

    # -- public API -------------------------------------------------------------------------
    def reset(self, positions=None, keep_time=False):
        """Put the joints at ``positions`` (default: zero clipped into the limits), at rest,
        and the clock at 0 (unless ``keep_time``: then it runs on, so that the stamps of
        what is published stay ordered); in position mode the motors then hold that pose."""
        q = home_pose(self.joint_limits, positions, name="initial positions")
        p, cid = self._p, self._client
        for joint, value in zip(self._joints, q):
            p.resetJointState(self._body, joint, float(value), 0.0, physicsClientId=cid)
        self._steps = self._steps if keep_time else 0
        self._efforts = np.zeros(self.n_joints)
        if self.control_mode == "position":
            self._position_motors(q)
        return self.state()

    def _position_motors(self, target):
        self._p.setJointMotorControlArray(
            self._body, self._joints, self._p.POSITION_CONTROL, targetPositions=target.tolist(),
            forces=self.effort_limits.tolist(), positionGains=[self.position_gain] * self.n_joints,
            velocityGains=[1.0] * self.n_joints, physicsClientId=self._client)

    def step(self, command, n_substeps=1):
        """Apply ``command`` (positions or torques, see module docstring), advance
        ``n_substeps`` physics steps (0 counts as 1), return the new :class:`SimState`.

        Raises ValueError for a command of the wrong length or with NaN/inf, before
        touching the simulation.
        """
        command = self._vector(command, "command")
        n_substeps = max(1, int(n_substeps))
        p, cid, body, joints = self._p, self._client, self._body, self._joints
        if self.control_mode == "position":
            self._position_motors(np.clip(command, self.joint_limits[:, 0],
                                          self.joint_limits[:, 1]))
            for _ in range(n_substeps):
                p.stepSimulation(physicsClientId=cid)
            self._efforts = np.array([s[3] for s in p.getJointStates(body, joints,
                                                                    physicsClientId=cid)])
        else:
            torques = np.clip(command, -self.effort_limits, self.effort_limits)
            if self._motor:   # V-REP's torque mode; the motor settings persist over the steps
                p.setJointMotorControlArray(
                    body, joints, p.VELOCITY_CONTROL,
                    targetVelocities=(np.sign(torques) * self.velocity_limits).tolist(),
                    forces=np.abs(torques).tolist(), physicsClientId=cid)
                for _ in range(n_substeps):
                    p.stepSimulation(physicsClientId=cid)
            else:
                for _ in range(n_substeps):
                    applied = self._drive_torques(torques) if self._drives else torques
                    p.setJointMotorControlArray(body, joints, p.TORQUE_CONTROL,
                                                forces=applied.tolist(), physicsClientId=cid)
                    p.stepSimulation(physicsClientId=cid)
            self._efforts = torques
        self._steps += n_substeps
        return self.state()

    def inverse_dynamics(self, positions, velocities, accelerations):
        """Torques (n,) that give the joints ``accelerations`` from ``positions`` and
        ``velocities`` in one physics step of torque mode with the ``"torque"`` actuator:
        (M(q) + diag(A + D·dt)) q̈ + h(q, q̇) + D q̇, the drive model of the module docstring
        (no effort clipping; the simulation's state is not touched). What the robot's own
        inverse dynamics say a sample's torque should be (the chapter 5 ablation's mapping
        ceiling, scenarios/inverse_dynamics/reference_results/ablation/README.md)."""
        if self.control_mode != "torque" or self._motor:
            raise ValueError("inverse_dynamics is the torque mode's drive model; this "
                             f"simulator runs {self.control_mode!r} with the {self.actuator!r} "
                             "actuator")
        qd = self._vector(velocities, "velocities")
        qdd = self._vector(accelerations, "accelerations")
        mass, bias = self._mass_and_bias(self._vector(positions, "positions").tolist(),
                                         qd.tolist())
        return (mass + self._drive) @ qdd + bias + self.joint_damping * qd

    def state(self):
        """The current :class:`SimState` (read-only arrays)."""
        p, cid = self._p, self._client
        joint_states = p.getJointStates(self._body, self._joints, physicsClientId=cid)
        ee = p.getLinkState(self._body, self._ee_link, computeForwardKinematics=True,
                            physicsClientId=cid)[4]
        arrays = [np.array([s[0] for s in joint_states]), np.array([s[1] for s in joint_states]),
                  np.array(self._efforts, dtype=float), np.array(ee, dtype=float)]
        for array in arrays:
            array.setflags(write=False)
        return SimState(self.time, *arrays)

    def link_frames(self):
        """Every link's frame relative to its parent's, as a URDF's joints chain them:
        ``[(parent, child, translation (3,), quaternion (x, y, z, w)), ...]``, the base link
        first, relative to the world frame ``None``. The frames are the URDF link frames (not
        pybullet's centre-of-mass frames), so a URDF viewer fed these transforms (TF) draws
        the robot as simulated."""
        p, cid = self._p, self._client
        base = p.multiplyTransforms(*p.getBasePositionAndOrientation(self._body,
                                                                     physicsClientId=cid),
                                    *self._base_inertial)
        states = p.getLinkStates(self._body, list(range(len(self.link_names))),
                                 computeForwardKinematics=True, physicsClientId=cid)
        world = [(state[4], state[5]) for state in states]
        frames = [(None, self.base_link, np.array(base[0]), np.array(base[1]))]
        for child, parent in enumerate(self._link_parents):
            parent_pose = base if parent < 0 else world[parent]
            name = self.base_link if parent < 0 else self.link_names[parent]
            relative = p.multiplyTransforms(*p.invertTransform(*parent_pose), *world[child])
            frames.append((name, self.link_names[child], np.array(relative[0]),
                           np.array(relative[1])))
        return frames

    def close(self):
        """Disconnect the pybullet client (idempotent)."""
        if getattr(self, "_client", None) is not None:
            try:
                self._p.disconnect(physicsClientId=self._client)
            finally:
                self._client = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass
