"""Planar serial chains in pybullet and their inverse-dynamics babbling data (thesis ch. 5).

Chapter 5 transfers inverse dynamics models: a domain point is z = (q, q̇, q̈, τ) (§5.4, 4·DoF
numbers), τ given by the rigid-body dynamics τ = M(q) q̈ + C(q, q̇) q̇ + g(q) (eq. 5.1), the
data a learner of τ = D(q̈, q̇, q) + ε (eq. 5.2) is trained on. Correspondences come from a
babbling session in which both robots run the same motion program and samples are paired
by time index (§5.4.1, ICRA 2018: 1464 pairs from ~14 s at 100 Hz).

The model: an n-link chain whose revolute joints all turn about z, each link a thin uniform
rod along its local x axis (mass m, centre of mass at L/2, inertia m L²/12 about y and z;
the axial inertia is set to a negligible 1e-6·m L²). The chain moves in the vertical x-y
plane with gravity −9.81 m/s² along −y, so gravity matters: for one link
τ = m g (L/2) cos q + (m L²/3) q̈. Pure pybullet + numpy.
"""
import os
import tempfile

import numpy as np

GRAVITY = 9.81
#: Default joint range (rad) when none is given: ±90° about the stretched-out pose.
DEFAULT_JOINT_LIMIT = np.pi / 2
#: Babbling motion: this many sinusoids per joint, frequencies drawn in this range (Hz).
N_SINUSOIDS, FREQUENCY_RANGE_HZ = 3, (0.1, 0.8)
_MASSLESS = ('<inertial><mass value="0"/>'
             '<inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial>')


def _link_params(link_lengths, link_masses):
    lengths = np.asarray(link_lengths, dtype=float)
    masses = np.asarray(link_masses, dtype=float)
    if lengths.ndim != 1 or lengths.size == 0 or lengths.shape != masses.shape:
        raise ValueError(f"link_lengths and link_masses must be non-empty 1-D sequences of "
                         f"equal length, got shapes {lengths.shape} and {masses.shape}")
    if not (np.isfinite(lengths).all() and np.isfinite(masses).all()
            and (lengths > 0).all() and (masses > 0).all()):
        raise ValueError("link lengths and masses must be finite and positive")
    return lengths, masses


def _joint_limits(joint_limits, n_joints):
    if joint_limits is None:
        return np.tile([-DEFAULT_JOINT_LIMIT, DEFAULT_JOINT_LIMIT], (n_joints, 1))
    limits = np.asarray(joint_limits, dtype=float)
    if limits.shape != (n_joints, 2) or not np.isfinite(limits).all() \
            or (limits[:, 0] >= limits[:, 1]).any():
        raise ValueError(f"joint_limits must be {n_joints} finite (lower, upper) pairs with "
                         f"lower < upper, got {joint_limits!r}")
    return limits


def planar_chain_urdf(link_lengths, link_masses, joint_limits=None, effort_limits=None,
                      name="planar_chain"):
    """URDF text of an n-link planar chain (module docstring: thin uniform rods, joints about z).

    ``joint_limits`` (n, 2) rad (default ±π/2), ``effort_limits`` (n,) N·m (default 100; note
    that pybullet does not enforce them). Links are ``link1..linkn`` on joints
    ``joint1..jointn``; a massless ``tool`` frame sits at the end of the last link.
    """
    lengths, masses = _link_params(link_lengths, link_masses)
    limits = _joint_limits(joint_limits, len(lengths))
    efforts = np.broadcast_to(np.asarray(100.0 if effort_limits is None else effort_limits,
                                         dtype=float), lengths.shape)
    if not (np.isfinite(efforts).all() and (efforts > 0).all()):
        raise ValueError(f"effort_limits must be finite and positive, got {effort_limits!r}")
    parts = [f'<?xml version="1.0"?>\n<robot name="{name}">\n'
             f'  <link name="base">{_MASSLESS}</link>']
    parent, offset = "base", 0.0
    for i, (length, mass, (lower, upper), effort) in enumerate(
            zip(lengths, masses, limits, efforts), start=1):
        lateral, axial = mass * length ** 2 / 12.0, 1e-6 * mass * length ** 2
        parts.append(
            f'  <link name="link{i}">\n'
            f'    <inertial><origin xyz="{length / 2:.17g} 0 0"/><mass value="{mass:.17g}"/>\n'
            f'      <inertia ixx="{axial:.17g}" iyy="{lateral:.17g}" izz="{lateral:.17g}" '
            f'ixy="0" ixz="0" iyz="0"/></inertial>\n'
            f'    <visual><origin xyz="{length / 2:.17g} 0 0" rpy="0 1.5707963267948966 0"/>'
            f'<geometry><cylinder radius="0.01" length="{length:.17g}"/></geometry></visual>\n'
            f'  </link>\n'
            f'  <joint name="joint{i}" type="revolute">\n'
            f'    <parent link="{parent}"/><child link="link{i}"/>\n'
            f'    <origin xyz="{offset:.17g} 0 0"/><axis xyz="0 0 1"/>\n'
            f'    <limit lower="{lower:.17g}" upper="{upper:.17g}" effort="{effort:.17g}" '
            f'velocity="100"/>\n'
            f'    <dynamics damping="0" friction="0"/>\n'
            f'  </joint>')
        parent, offset = f"link{i}", float(length)
    parts.append(f'  <link name="tool">{_MASSLESS}</link>\n'
                 f'  <joint name="tool_joint" type="fixed">\n'
                 f'    <parent link="{parent}"/><child link="tool"/>\n'
                 f'    <origin xyz="{offset:.17g} 0 0"/>\n  </joint>\n</robot>\n')
    return "\n".join(parts)


def babbling_trajectory(n_joints, times, seed, joint_limits=None):
    """Smooth seeded joint motion q(t), q̇(t), q̈(t) (each (T, n)), analytic derivatives.

    Joint j follows its range's middle plus a sum of ``N_SINUSOIDS`` sinusoids whose
    amplitudes add up to at most 90 % of the half range, so q stays inside the limits. The
    parameters of joint j depend only on (seed, j): two chains babbling with the same seed
    move their common joints alike, in proportion to their ranges — the "same babbling
    program" whose samples are paired by time index (§5.4.1).
    """
    limits = _joint_limits(joint_limits, n_joints)
    t = np.asarray(times, dtype=float)[:, None]
    q, qd, qdd = (np.zeros((len(t), n_joints)) for _ in range(3))
    for j, (lower, upper) in enumerate(limits):
        rng = np.random.default_rng([seed, j])
        shares = rng.dirichlet(np.ones(N_SINUSOIDS))
        amplitude = 0.9 * (upper - lower) / 2 * shares
        omega = 2 * np.pi * rng.uniform(*FREQUENCY_RANGE_HZ, N_SINUSOIDS)
        phase = rng.uniform(0, 2 * np.pi, N_SINUSOIDS)
        angle = omega * t + phase
        q[:, j] = (lower + upper) / 2 + np.sin(angle) @ amplitude
        qd[:, j] = np.cos(angle) @ (amplitude * omega)
        qdd[:, j] = -np.sin(angle) @ (amplitude * omega ** 2)
    return q, qd, qdd


def load_fixed_robot(p, urdf, client):
    """Load a URDF (file path or URDF text) fixed to the world into pybullet ``client``.

    With ``URDF_USE_INERTIA_FROM_FILE`` (else pybullet recomputes inertias from collision
    shapes) and gravity −9.81 m/s² along −y (the chains move in the vertical x-y plane). URDF
    text goes through a temporary file, removed again. Returns the body id.
    """
    text = str(urdf)
    if not text.lstrip().startswith("<"):
        if not os.path.isfile(text):
            raise ValueError(f"URDF file not found: {text}")
        path, temporary = text, False
    else:
        handle, path = tempfile.mkstemp(suffix=".urdf")
        temporary = True
        with os.fdopen(handle, "w") as f:
            f.write(text)
    try:
        p.setGravity(0, -GRAVITY, 0, physicsClientId=client)
        return p.loadURDF(path, useFixedBase=True, flags=p.URDF_USE_INERTIA_FROM_FILE,
                          physicsClientId=client)
    finally:
        if temporary:
            os.remove(path)


def inverse_dynamics(link_lengths, link_masses, q, qd, qdd, joint_limits=None):
    """τ (T, n) of eq. 5.1 for each row of (q, q̇, q̈), by ``p.calculateInverseDynamics``.

    A private pybullet DIRECT session is opened and closed per call (:func:`load_fixed_robot`).
    """
    import pybullet as p

    urdf = planar_chain_urdf(link_lengths, link_masses, joint_limits)
    client = p.connect(p.DIRECT)
    try:
        body = load_fixed_robot(p, urdf, client)
        return np.array([p.calculateInverseDynamics(body, list(a), list(b), list(c),
                                                    physicsClientId=client)
                         for a, b, c in zip(q, qd, qdd)]).reshape(len(q), -1)
    finally:
        p.disconnect(physicsClientId=client)


def inverse_dynamics_babbling(link_lengths, link_masses, duration_s, rate_hz, seed,
                              joint_limits=None):
    """Babbling data of one chain: dict q, qd, qdd, tau, each (T, n), T = round(duration·rate).

    Samples at t = i / rate_hz of :func:`babbling_trajectory` with τ from
    :func:`inverse_dynamics` (eq. 5.1). ``np.hstack((q, qd, qdd, tau))`` is the ch. 5 domain
    point z = (q, q̇, q̈, τ). Deterministic for a seed.
    """
    lengths, masses = _link_params(link_lengths, link_masses)
    n_samples = int(round(duration_s * rate_hz))
    if n_samples < 1 or rate_hz <= 0:
        raise ValueError(f"duration_s·rate_hz must give at least one sample, got "
                         f"{duration_s!r} s at {rate_hz!r} Hz")
    q, qd, qdd = babbling_trajectory(len(lengths), np.arange(n_samples) / rate_hz, seed,
                                     joint_limits)
    tau = inverse_dynamics(lengths, masses, q, qd, qdd, joint_limits)
    return dict(q=q, qd=qd, qdd=qdd, tau=tau)
