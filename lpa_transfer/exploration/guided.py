"""Guided exploration: correspondences for transferring sensorimotor data (thesis §6.4, Alg. 7).

The source robot Ω_s and the target robot Ω_t share d_c ≤ min(d_s, d_t) joints (the motor
subspace Q̄, e.g. Nao's and Poppy's four common arm joints, §6.5.2). The target explores for
T_guided with goal babbling (Alg. 6) moving only those joints, the others held at its home
values; the source then executes the same sequence of shared commands q̄ on its own body,
its other joints at its home (Alg. 7). Pairing the two by command gives the correspondences
{(q̄, x_s)} and {(q̄, x_t)} in R^{d_c + m} from which a domain mapping f is learned (§6.4.1).
Alg. 7 leaves two choices open, and simulated robots lag their commands: ``source_follows``
(``"reached"``, the default: the source takes the joint positions the target reached, so
both rows of a pair are at the same q̄; ``"command"``: the command the target was sent) and
``target_range`` (``"shared"``: both robots' common ranges; ``"own"``: the target's own,
the pairs whose command lay outside the shared ranges then not followed). Both in detail:
docs/library.md, "Guided exploration". :func:`pad_transferred` completes transferred source
data with the target's home values for the joints the source lacks (§6.4.1).
"""
from typing import NamedTuple

import numpy as np

from lpa_transfer.robots.kinematics import check_joints, execute, overlapping_limits, restrict


def shared_limits(source, target, source_joints, target_joints):
    """(d_c, 2) intersection of the ranges of the shared joints (source_joints[i] of the
    source corresponds to target_joints[i] of the target); ValueError if one is empty."""
    source_joints = check_joints(source_joints, source.n_joints, "source_joints")
    target_joints = check_joints(target_joints, target.n_joints, "target_joints")
    if len(source_joints) != len(target_joints):
        raise ValueError(f"source_joints and target_joints must pair the shared joints one to "
                         f"one, got {len(source_joints)} and {len(target_joints)}")
    return overlapping_limits(np.asarray(source.joint_limits)[source_joints],
                              np.asarray(target.joint_limits)[target_joints], "the shared joints")


TARGET_RANGES = ("shared", "own")
SOURCE_FOLLOWS = ("reached", "command")


class GuidedPairs(NamedTuple):
    """What guided exploration observed, one row per movement of the target."""

    source: np.ndarray     # (N, d_c + m) the source's rows (q̄_s, x_s)
    target: np.ndarray     # (N, d_c + m) the target's rows (q̄_t, x_t): all its own experience
    followed: np.ndarray   # (N,) bool: the source could follow movement i (its command lay
    #                        inside the shared ranges), so row i of both is a correspondence

    def correspondences(self):
        """``(source_pairs, target_pairs)``: the followed rows only."""
        return self.source[self.followed], self.target[self.followed]


def check_target_range(target_range):
    """``target_range`` if it is one of :data:`TARGET_RANGES`; ValueError if not."""
    if target_range not in TARGET_RANGES:
        raise ValueError(f"target_range must be one of {TARGET_RANGES}, got {target_range!r}")
    return target_range


def check_source_follows(source_follows):
    """``source_follows`` if it is one of :data:`SOURCE_FOLLOWS`; ValueError if not."""
    if source_follows not in SOURCE_FOLLOWS:
        raise ValueError(f"source_follows must be one of {SOURCE_FOLLOWS}, got "
                         f"{source_follows!r}")
    return source_follows


def explored_target(target, target_joints, limits, target_range):
    """The target (a Kinematics) as guided exploration babbles it: only ``target_joints``
    free, within the shared ranges ``limits`` (``"shared"``) or its own (``"own"``)."""
    explored = limits if check_target_range(target_range) == "shared" else None
    return restrict(target, target_joints, explored)


def followed_commands(commands, limits):
    """(N,) bool: which commands (N, d_c) lie inside the shared ranges ``limits`` (d_c, 2)."""
    commands = np.atleast_2d(np.asarray(commands, dtype=np.float64))
    return np.all((commands >= limits[:, 0]) & (commands <= limits[:, 1]), axis=1)


def guided_exploration(babbling, source, target, source_joints, target_joints, seconds,
                       model=None, target_range="shared", source_follows="reached"):
    """Alg. 7 with the target's goal babbling: a :class:`GuidedPairs` of (N, d_c + m) rows
    (q̄, x), row i of both made for the target's movement i.

    ``babbling`` is a :class:`lpa_transfer.goal_babbling.goal_babbling.GoalBabbling` (its
    ``x_bounds`` in the target's task space, its ``home`` None or over the shared joints); it
    explores the target restricted to ``target_joints`` for ``seconds`` simulated seconds,
    learning ``model`` (default: a fresh one; afterwards ``babbling.model_``), within the ranges
    ``target_range`` names. The source then executes, with its ``source_joints``, what
    ``source_follows`` names (the target's reached joints or its commands; module docstring),
    clipped into the shared ranges. Movement i is followed (a correspondence) when its
    command lay inside them; the reached joints of such a movement may lie a hair beyond (a
    position-controlled joint overshoots its limit), hence the clipping.
    """
    check_source_follows(source_follows)
    limits = shared_limits(source, target, source_joints, target_joints)
    babbling.start(explored_target(target, target_joints, limits, target_range), model)
    target_joint_values, target_points = babbling.run_for(seconds)
    commands = babbling.commands_
    to_follow = target_joint_values if source_follows == "reached" else commands
    source_joint_values, source_points = execute(
        restrict(source, source_joints, limits), np.clip(to_follow, limits[:, 0], limits[:, 1]))
    return GuidedPairs(np.hstack((source_joint_values, source_points)),
                       np.hstack((target_joint_values, target_points)),
                       followed_commands(commands, limits))
