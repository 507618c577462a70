"""Robots: parameter files, kinematic chains (planar, serial, URDF), forward and inverse
kinematics, the pybullet simulator, PID control and the stepped environment a learner drives.

Everything a learning loop needs to know of one robot lives here, so exploration and the
chapter packages share one notion of a robot (:class:`~lpa_transfer.robots.kinematics.Kinematics`).
"""
