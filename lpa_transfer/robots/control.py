"""Torque control for tracking: PID feedback plus a learned feed-forward term.

Thesis ch. 5 (§5.3, Fig. 5-1): the commanded torque is

    τ = τ_ff(q_d, q̇_d, q̈_d) + τ_fb,   τ_fb = K_p e + K_i ∫e dt + K_d ė,   e = q_d − q,

clipped to the robot's torque limits, where τ_ff is an inverse dynamics model learned online
from the observed (q, q̇, q̈, τ). Gains of §5.5.2: Pincher K_p 5, K_d 0.1, K_i 0.01; youBot
K_p 100, K_d 2.0, K_i 0.01 (times the identity).

The robots are anything with ``step(torques, n_steps) -> state`` (state with ``time``,
``positions``, ``velocities``, ``efforts``, ``end_effector``: a torque-mode
:class:`lpa_transfer.robots.simulator.RobotSimulator` or a robot_sim node's service).
"""
from dataclasses import dataclass

import numpy as np

from lpa_transfer.robots.simulator import elapsed


@dataclass
class PID:
    """Joint-space PID feedback (thesis §5.5.2); ``kp``, ``ki``, ``kd`` scalars or per joint.

    The derivative acts on the velocity error ė = q̇_d − q̇ (no derivative kick); the integral
    accumulates e·dt from the last :meth:`reset`.
    """

    kp: object
    ki: object
    kd: object

    def __post_init__(self):
        for name in ("kp", "ki", "kd"):
            gain = np.asarray(getattr(self, name), dtype=np.float64)
            if not np.isfinite(gain).all() or (gain < 0).any():
                raise ValueError(f"PID gain {name} must be finite and >= 0, got {gain}")
        self.reset()

    @classmethod
    def from_gains(cls, gains, name="pid"):
        """A PID from a ``[kp, ki, kd]`` list (a node parameter called ``name``)."""
        if len(gains) != 3:
            raise ValueError(f"{name} must be [kp, ki, kd], got {list(gains)}")
        return cls(*gains)

    def reset(self):
        self.integral_ = None

    def torque(self, q_d, qd_d, q, qd, dt):
        """τ_fb for the desired and measured positions/velocities, one control period dt."""
        error = np.asarray(q_d, dtype=np.float64) - q
        if self.integral_ is None:
            self.integral_ = np.zeros_like(error)
        self.integral_ = self.integral_ + error * dt
        return (np.asarray(self.kp) * error + np.asarray(self.ki) * self.integral_
                + np.asarray(self.kd) * (np.asarray(qd_d, dtype=np.float64) - qd))


class PIDServo:
    """A torque-controlled robot that takes joint *position* commands, through a PID.

    ``servo.step(q_d, n_steps)`` applies τ = PID(q_d, q̇_d, q, q̇) for ``n_steps`` physics steps
    and returns the new state; q̇_d is the change of the command over the last control period
    (0 for the first command). Babbling programs written for position control thus drive a
    torque-mode robot the way §5.4.1 collects correspondences: PID tracking, no dynamics model.
    The applied torque is what the simulator reports as effort (clipped to its limits).
    """

    def __init__(self, step, pid, state):
        self._step, self.pid, self.state = step, pid, state
        self._last_command, self._last_dt = None, None

    def step(self, command, n_steps):
        command = np.asarray(command, dtype=np.float64)
        if self._last_command is None or not self._last_dt:
            velocity = np.zeros_like(command)
        else:
            velocity = (command - self._last_command) / self._last_dt
        dt = self._last_dt or 0.0
        torque = self.pid.torque(command, velocity, self.state.positions,
                                 self.state.velocities, dt)
        state = self._step(torque, n_steps)
        self._last_dt = elapsed(state, self.state)
        self._last_command, self.state = command, state
        return state


def start_servo(step, n_joints, pid):
    """A :class:`PIDServo` on ``step``, its first state read by one zero-torque physics step."""
    return PIDServo(step, pid, step(np.zeros(n_joints), 1))
