"""Robots: parameter files, kinematic chains (planar, serial, URDF), forward and inverse
kinematics, the pybullet simulator, PID control and the stepped environment a learner drives.

Everything a learning loop needs to know of one robot lives here, so exploration and the
chapter packages share one notion of a robot (:class:`~lpa_transfer.robots.kinematics.Kinematics`).
"""
from lpa_transfer._lazy import lazy_names

#: The public names and their modules, imported on first use (PEP 562): a node that needs one
#: robot's parameters imports neither the simulator nor the learners' scikit-learn.
_LAZY = {
    **dict.fromkeys(["PID", "start_servo"], "lpa_transfer.robots.control"),
    **dict.fromkeys(["stepped_environment", "task_dims"], "lpa_transfer.robots.environment"),
    **dict.fromkeys(["solve", "solve_many", "solve_path"],
                    "lpa_transfer.robots.inverse_kinematics"),
    **dict.fromkeys(["Kinematics", "arm_kinematics", "domain_data", "end_effector_rmse",
                     "hold_at_home", "home_pose", "pad_transferred", "planar_forward_kinematics",
                     "planar_kinematics", "robot_kinematics", "sample_joint_uniform"],
                    "lpa_transfer.robots.kinematics"),
    **dict.fromkeys(["load_robot_params", "RobotParams"], "lpa_transfer.robots.params"),
    **dict.fromkeys(["babbling_trajectory", "inverse_dynamics", "inverse_dynamics_babbling"],
                    "lpa_transfer.robots.planar_chain"),
    **dict.fromkeys(["chain_frames"], "lpa_transfer.robots.serial_chain"),
    **dict.fromkeys(["minimum_jerk"], "lpa_transfer.robots.trajectories"),
    **dict.fromkeys(["ACTUATORS", "CONTROL_MODES", "robot_urdf", "RobotSimulator", "SimState",
                     "simulated_description"], "lpa_transfer.robots.simulator"),
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
