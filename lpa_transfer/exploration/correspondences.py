"""Correspondences between two robots collected by babbling, and their files.

A correspondence pairs a source-robot point with a target-robot point (thesis ch. 3, §3.1).
The collector drives both robots (anything with ``step(command, n_steps) -> state`` like
:class:`lpa_transfer.robots.simulator.SimState`) through one babbling program and pairs their
samples by one of the rules the thesis' domains use: ``"same_command"`` (§3.6, and §6.4.2's
guided exploration, :func:`collect_guided_correspondences`), ``"same_time_index"`` (§5.4.1)
or ``"same_task_point"`` (§4.4.2). A pair is made true for any robot pair, not only for the
thesis' (:class:`PairCheck`): each commanded robot settles, by its state, before it is
sampled, every pair is checked under its rule, and too many failing pairs end the collection
with a :class:`PairingError`. Each sample is the concatenation of ``features`` of the robot's
state (``position``, ``velocity``, ``acceleration``, ``effort``, ``ee_x``/``ee_y``/``ee_z``);
the default (``position``, ``ee_x``, ``ee_y``) is §3.6's domain z = (q, x) of a planar arm.
The rules and features in detail: docs/library.md, "Correspondences".
"""
import copy
import os
import zipfile
from dataclasses import dataclass, field, replace

import numpy as np

from lpa_transfer._validation import (check_float, check_int, check_x_bounds,
                                      open_regular_file)
from lpa_transfer.robots import inverse_kinematics
from lpa_transfer.robots.kinematics import execute, overlapping_limits, pad_transferred
from lpa_transfer.robots.simulator import elapsed
from lpa_transfer.exploration.guided import (check_source_follows, check_target_range,
                                             explored_target, followed_commands,
                                             guided_exploration)
from lpa_transfer.exploration.guided import shared_limits

PAIRING_RULES = ("same_command", "same_time_index", "same_task_point")
JOINT_FEATURES = ("position", "velocity", "acceleration", "effort")
TASK_FEATURES = ("ee_x", "ee_y", "ee_z")
FEATURES = JOINT_FEATURES + TASK_FEATURES
DEFAULT_FEATURES = ("position", "ee_x", "ee_y")
BAD_PAIR_ACTIONS = ("drop", "retry")


def check_features(features):
    features = tuple(features)
    unknown = [f for f in features if f not in FEATURES]
    if not features or unknown or len(set(features)) != len(features):
        raise ValueError(f"features must be distinct names from {FEATURES}, got {list(features)}")
    return features


def feature_vector(state, previous, features):
    """The sample of ``state`` (see module docstring); ``previous`` gives the acceleration."""
    parts = []
    for name in features:
        if name == "acceleration":
            parts.append((np.asarray(state.velocities) - previous.velocities)
                         / elapsed(state, previous))
        elif name in TASK_FEATURES:
            parts.append([state.end_effector[TASK_FEATURES.index(name)]])
        else:
            parts.append(getattr(state, {"position": "positions", "velocity": "velocities",
                                         "effort": "efforts"}[name]))
    return np.concatenate(parts).astype(np.float64)


def feature_names(features, joint_names):
    """Column names of the samples, e.g. ``position/joint1``, ``ee_x``."""
    return [f"{name}/{joint}" if name in JOINT_FEATURES else name
            for name in features for joint in (joint_names if name in JOINT_FEATURES else [""])]


def feature_columns(features, width):
    """Names of the ``width`` columns of samples made of ``features`` (in the order
    :func:`feature_vector` concatenates them): a joint feature gives one column per joint
    (``position[0]``, ``position[1]``, ...), any other one column (``ee_x``); ``[]`` when
    ``width`` does not fit them. The column names a model's metadata carries."""
    features = [str(feature) for feature in features]
    joint = [feature for feature in features if feature in JOINT_FEATURES]
    n_joints, rest = divmod(width - (len(features) - len(joint)), max(1, len(joint)))
    if not features or rest or n_joints < (1 if joint else 0) or (not joint and n_joints):
        return []
    names = []
    for feature in features:
        names += ([f"{feature}[{j}]" for j in range(n_joints)] if feature in JOINT_FEATURES
                  else [feature])
    return names


@dataclass
class CorrespondenceSet:
    """Paired samples: row i of ``source`` corresponds to row i of ``target``."""

    source: np.ndarray
    target: np.ndarray
    source_robot: str = ""
    target_robot: str = ""
    pairing_rule: str = ""
    features: tuple = DEFAULT_FEATURES
    sim_time: float = 0.0            # simulated seconds the source robot babbled
    complete: bool = True            # False when collection was stopped early
    metadata: dict = field(default_factory=dict)

    def __len__(self):
        return len(self.source)

    def columns(self):
        """The names of the source and of the target columns (:func:`feature_columns`)."""
        return (feature_columns(self.features, self.source.shape[1]),
                feature_columns(self.features, self.target.shape[1]))

    def save(self, path):
        """Write an ``.npz`` (``source``, ``target`` and the metadata as strings/scalars)
        atomically: a temporary file renamed into place, so a reader never sees half a file."""
        path = os.fspath(path)
        temporary = f"{path}.tmp.npz"
        np.savez(temporary, source=self.source, target=self.target,
                 source_robot=self.source_robot, target_robot=self.target_robot,
                 pairing_rule=self.pairing_rule, features=np.array(self.features, dtype=str),
                 sim_time=self.sim_time, complete=self.complete,
                 **{f"meta_{k}": np.asarray(v) for k, v in self.metadata.items()})
        os.replace(temporary, path)


#: A correspondence file's members besides ``source``, ``target`` and ``meta_*``, as
#: CorrespondenceSet fields: (its type, the member's dimensions).
_HEADER = {"source_robot": (str, 0), "target_robot": (str, 0), "pairing_rule": (str, 0),
           "sim_time": (float, 0), "complete": (bool, 0), "features": (tuple, 1)}


def read_correspondences(path):
    """A correspondence file (:meth:`CorrespondenceSet.save`) as a :class:`CorrespondenceSet`:
    its pairs, robot names, pairing rule, features, clock and completeness, and its
    ``meta_*`` members as ``metadata`` (arrays, by name without ``meta_``).

    What the file does not say (a member it lacks, or of another shape) keeps the set's
    default, except ``features``: ``()`` when the file names none (its columns are
    unknown). A ValueError says why a file cannot be read, or that it lacks source or target.
    """
    try:
        file = open_regular_file(path, "correspondence file")   # never blocks on a FIFO
    except OSError as exc:
        raise ValueError(f"cannot read correspondence file {path}: {exc}") from None
    with file:
        members = _members(path, file)
    header = {key: kind(members[key].tolist() if kind is tuple else members[key])
              for key, (kind, ndim) in _HEADER.items()
              if key in members and members[key].ndim == ndim}
    header.setdefault("features", ())
    return CorrespondenceSet(members["source"], members["target"], **header,
                             metadata={key[len("meta_"):]: value for key, value in members.items()
                                       if key.startswith("meta_")})


def _members(path, file):
    """The arrays of a correspondence file open as ``file``, by name; ValueError says why
    they cannot be read, or that the file lacks source or target."""
    unreadable = (OSError, EOFError, ValueError, zipfile.BadZipFile)   # e.g. a truncated file
    try:
        archive = np.load(file, allow_pickle=False)
    except unreadable as exc:
        raise ValueError(f"cannot read correspondence file {path}: {exc}") from None
    if not isinstance(archive, np.lib.npyio.NpzFile):
        raise ValueError(f"correspondence file {path} is not an .npz archive")
    with archive:
        missing = [key for key in ("source", "target") if key not in archive.files]
        if missing:
            raise ValueError(f"correspondence file {path} lacks the arrays {missing} "
                             f"(has {archive.files})")
        try:
            return {key: archive[key] for key in archive.files}
        except unreadable as exc:   # a damaged member, object arrays
            raise ValueError(f"cannot read correspondence file {path}: {exc}") from None


def load_correspondences(path):
    """``source`` and ``target`` arrays of a correspondence file (:func:`read_correspondences`)."""
    pairs = read_correspondences(path)
    return pairs.source, pairs.target


def load_guided_exploration(path):
    """A guided-exploration file (:func:`collect_guided_correspondences`) as ``(source_pairs,
    target_pairs, target_experience, followed)``: the correspondences, the target's rows of
    all N commands and which of them the source followed (N,) bool. A file without the last
    two (every pair a correspondence) gives ``target_pairs`` and all True."""
    pairs = read_correspondences(path)
    source, target, extra = pairs.source, pairs.target, pairs.metadata
    if "followed" not in extra:
        return source, target, target, np.ones(len(target), dtype=bool)
    if "target_experience" not in extra:
        raise ValueError(f"guided-exploration file {path} has meta_followed but no "
                         f"meta_target_experience")
    followed = extra["followed"].astype(bool)
    experience = extra["target_experience"]
    if followed.shape != (len(experience),) or followed.sum() != len(target):
        raise ValueError(f"guided-exploration file {path}: {int(followed.sum())} followed "
                         f"commands of {len(followed)}, {len(experience)} rows of experience "
                         f"and {len(target)} pairs do not agree")
    return source, target, experience, followed


def common_joint_limits(source, target):
    """Intersection of the two robots' limits on their common (first) joints."""
    n_common = min(source.n_joints, target.n_joints)
    return overlapping_limits(source.joint_limits[:n_common], target.joint_limits[:n_common],
                              "same_command needs overlapping joint ranges; the common joints")


def with_home(commands, home):
    """Commands for all joints of a robot: the given columns, then its home values."""
    return pad_transferred(commands, home, np.arange(commands.shape[1]))


def check_pairing_rule(pairing_rule):
    if pairing_rule not in PAIRING_RULES:
        raise ValueError(f"pairing_rule must be one of {PAIRING_RULES}, got {pairing_rule!r}")
    return pairing_rule


def planned_commands(program, pairing_rule, source, target):
    """(source commands, target commands or None when the target follows online)."""
    check_pairing_rule(pairing_rule)
    if pairing_rule == "same_time_index":
        return program.commands(source), program.commands(target)
    if pairing_rule == "same_task_point" or program.program == "task_lines":
        source_commands = program.commands(source)
    else:
        limits = common_joint_limits(source, target)
        start = np.clip(source.home[:len(limits)], limits[:, 0], limits[:, 1])
        source_commands = with_home(program.joint_commands(limits, start), source.home)
    if pairing_rule == "same_task_point":
        return source_commands, None
    return source_commands, with_home(source_commands[:, :min(source.n_joints,
                                                              target.n_joints)], target.home)


def task_point_command(target, end_effector, task_offset, previous_command):
    """The target's joint command for the source's end-effector point (same_task_point):
    the first len(task_offset) end-effector coordinates, shifted by ``task_offset``."""
    point = np.asarray(end_effector[:len(task_offset)], dtype=np.float64) + task_offset
    command, _ = inverse_kinematics.solve(target.forward, point, previous_command,
                                          target.joint_limits)
    return command


def run_commands(commands, step, steps_per_sample, features, home, should_stop=None):
    """One robot's babbling without a partner (its own experience): ``(samples, sim_time)``.

    The robot first settles at ``home`` for one sample period (not recorded)."""
    features = check_features(features)
    check_int(steps_per_sample, "steps_per_sample", 1)
    previous = start = step(home, steps_per_sample)
    samples = []
    for command in commands:
        if should_stop is not None and should_stop():
            break
        state = step(command, steps_per_sample)
        samples.append(feature_vector(state, previous, features))
        previous = state
    return _rows(samples), elapsed(previous, start)


# -- true pairs: settling by state and the pairing checks -------------------------------------
@dataclass(frozen=True)
class PairCheck:
    """How :func:`collect_correspondences` makes pairs true for any robot pair, and checks them.

    Settling (``same_command``, ``same_task_point``; a ``same_time_index`` pair is sampled on
    the move, §5.4.1): after ``steps_per_sample`` steps a commanded robot keeps stepping in
    chunks of ``check_steps`` until no joint moves faster than ``velocity_tol`` (rad/s, or m/s)
    and none moved more than ``position_tol`` over the last chunk, for at most
    ``max_settle_steps`` steps a sample (0: exactly ``steps_per_sample``, no settling).

    The check of each pair, its residual against ``tolerance``:
    ``same_command``, the largest difference of the common joints (rad) — §3.6 pairs equal
    joint angles; ``same_task_point``, the distance of the target's end effector from the
    source's point plus the offset (m); ``same_time_index``, the difference of the two robots'
    clocks since the start (s), so sample i is the same phase of the same line on both.
    A pair that fails is dropped (``on_bad_pair="drop"``) or, with ``"retry"``, settled once
    more for ``max_settle_steps`` and checked again. If more than ``max_bad_share`` of the pairs
    fail, the collection ends with a :class:`PairingError` instead of returning the set.
    """

    max_settle_steps: int = 3000
    check_steps: int = 50
    velocity_tol: float = 1e-3
    position_tol: float = 1e-5
    tolerance: float = 1e-3
    time_tolerance: float = 1e-9
    on_bad_pair: str = "drop"
    max_bad_share: float = 0.05

    def __post_init__(self):
        check_int(self.max_settle_steps, "max_settle_steps", 0)
        check_int(self.check_steps, "check_steps", 1)
        for name in ("velocity_tol", "position_tol", "tolerance", "time_tolerance"):
            value = getattr(self, name)     # inf turns a check off
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or np.isnan(value) or value < 0:
                raise ValueError(f"{name} must be a number >= 0 (inf: no check), got {value!r}")
        if self.on_bad_pair not in BAD_PAIR_ACTIONS:
            raise ValueError(f"on_bad_pair must be one of {BAD_PAIR_ACTIONS}, got "
                             f"{self.on_bad_pair!r}")
        share = self.max_bad_share
        if isinstance(share, bool) or not isinstance(share, (int, float)) \
                or not 0 <= share <= 1:
            raise ValueError(f"max_bad_share must be a number in [0, 1], got {share!r}")


def check_pair_check(pair_check):
    """``pair_check``, or :class:`PairCheck`'s defaults when None; ValueError if it is not a
    PairCheck."""
    check = PairCheck() if pair_check is None else pair_check
    if not isinstance(check, PairCheck):
        raise ValueError(f"pair_check must be a PairCheck, got {type(check).__name__}")
    return check


class PairingError(RuntimeError):
    """The robots' samples cannot be made true correspondences under the pairing rule."""


def settle(step, command, steps, check):
    """Step ``command`` for ``steps``, then until settled (:class:`PairCheck`); returns
    (state, settled, steps run). Without settling (max_settle_steps 0) settled is True."""
    state = step(command, steps)
    if not check.max_settle_steps:
        return state, True, steps
    run, before = steps, None
    while True:
        if before is not None and np.all(np.abs(state.velocities) <= check.velocity_tol) \
                and np.all(np.abs(state.positions - before) <= check.position_tol):
            return state, True, run
        if run >= check.max_settle_steps:
            return state, False, run
        chunk = min(check.check_steps, check.max_settle_steps - run)
        before = state.positions
        state = step(command, chunk)
        run += chunk


class SettlingStep:
    """A robot's ``step(command, n_steps) -> state`` that, after ``n_steps``, steps on until the
    robot has settled (:func:`settle` under ``check``), e.g. the source of guided exploration
    taking the target's posture. ``settled`` says whether the last command settled within
    ``check.max_settle_steps``; ``unsettled`` counts the commands that did not."""

    def __init__(self, step, check):
        self.step, self.check = step, check
        self.settled, self.unsettled = True, 0

    def __call__(self, command, n_steps):
        state, self.settled, _ = settle(self.step, command, n_steps, self.check)
        self.unsettled += not self.settled
        return state


class PairTally:
    """Counts a collection's checked and dropped pairs, the robots that did not settle and
    the residuals; ``summary()`` goes into the set's metadata (:func:`pair_check_line`)."""

    UNITS = {"same_command": "rad", "same_task_point": "m", "same_time_index": "s"}

    def __init__(self, pairing_rule, check, names):
        self.rule, self.check, self.names = pairing_rule, check, names
        self.tolerance = check.time_tolerance if pairing_rule == "same_time_index" \
            else check.tolerance
        self.checked = self.dropped = 0
        self.unsettled = {"source": 0, "target": 0}
        self.residuals, self.worst_dropped = [], 0.0

    def add(self, residual, settled):
        """Count one checked pair; True if it is kept."""
        self.checked += 1
        for side, ok in settled.items():
            self.unsettled[side] += not ok
        if residual <= self.tolerance:
            self.residuals.append(residual)
            return True
        self.dropped += 1
        self.worst_dropped = max(self.worst_dropped, residual)
        return False

    def too_many_dropped(self, n_planned):
        return self.dropped > self.check.max_bad_share * n_planned

    def summary(self):
        return dict(pairs_checked=self.checked, pairs_dropped=self.dropped,
                    pair_tolerance=self.tolerance, residual_unit=self.UNITS[self.rule],
                    worst_residual=max(self.residuals, default=0.0),
                    worst_dropped_residual=self.worst_dropped,
                    unsettled_source=self.unsettled["source"],
                    unsettled_target=self.unsettled["target"])

    def error(self):
        """The PairingError naming the robots, the rule and the residual."""
        lagging = [f"{name} did not settle on {count} commands within "
                   f"{self.check.max_settle_steps} steps"
                   for name, count in zip(self.names, self.unsettled.values()) if count]
        unit = self.UNITS[self.rule]
        return PairingError(
            f"{self.names[0]} -> {self.names[1]}: {self.dropped} of {self.checked} "
            f"{self.rule} pairs are not true correspondences (worst residual "
            f"{self.worst_dropped:.3g} {unit} > tolerance {self.tolerance:g} {unit}; more than "
            f"max_bad_share {self.check.max_bad_share:g})"
            + (": " + "; ".join(lagging) if lagging else "")
            + ". Raise max_settle_steps or steps_per_sample, or check the robots.")


def pair_check_line(metadata):
    """One line on a collection's pairing check, from its set's metadata (PairTally)."""
    unit = metadata["residual_unit"]
    return (f"{metadata['pairs_checked']} pairs checked, {metadata['pairs_dropped']} dropped "
            f"(residual > {metadata['pair_tolerance']:g} {unit}); worst kept residual "
            f"{metadata['worst_residual']:.3g} {unit}; commands not settled: source "
            f"{metadata['unsettled_source']}, target {metadata['unsettled_target']}")


def pair_residual(pairing_rule, source, target, source_state, target_state, offset, times):
    """The pair's residual under its rule (PairCheck)."""
    if pairing_rule == "same_command":
        n = min(source.n_joints, target.n_joints)
        return float(np.abs(source_state.positions[:n] - target_state.positions[:n]).max())
    if pairing_rule == "same_task_point":
        point = np.asarray(source_state.end_effector[:len(offset)]) + offset
        return float(np.linalg.norm(target_state.end_effector[:len(offset)] - point))
    return abs(times[0] - times[1])


def collect_correspondences(program, pairing_rule, source, target, step_source, step_target,
                            steps_per_sample, features=DEFAULT_FEATURES, task_offset=None,
                            on_pair=None, should_stop=None, pair_check=None,
                            names=("source", "target")):
    """Drive both robots through ``program`` and pair their samples (module docstring).

    ``source``/``target`` are :class:`~lpa_transfer.robots.kinematics.Kinematics`; ``step_*`` advance
    the robots; ``on_pair(index, source_sample, target_sample)`` sees each kept pair as it is
    made; ``should_stop()`` ends collection early (the result then has ``complete=False``).
    ``pair_check`` (:class:`PairCheck`, its defaults when None) settles the robots and checks
    every pair; ``names`` name the robots in its :class:`PairingError`. Returns a
    :class:`CorrespondenceSet` (robot names left empty for the caller) whose metadata hold the
    check's tally (:meth:`PairTally.summary`).
    """
    features = check_features(features)
    check_int(steps_per_sample, "steps_per_sample", 1)
    check = check_pair_check(pair_check)
    source_commands, target_commands = planned_commands(program, pairing_rule, source, target)
    # a same_time_index pair is sampled on the move (§5.4.1): no settling
    settling = replace(check, max_settle_steps=0) if pairing_rule == "same_time_index" \
        else check
    offset = np.zeros(0) if task_offset is None else np.asarray(task_offset, dtype=np.float64)
    if pairing_rule == "same_task_point":
        n_task = target.forward(target.home[None]).shape[1]
        offset = np.zeros(n_task) if offset.size == 0 else offset
        if offset.shape != (n_task,) or not np.isfinite(offset).all():
            raise ValueError(f"task_offset needs {n_task} finite values, got {task_offset}")
    source_previous = source_start = settle(step_source, source.home, steps_per_sample,
                                            settling)[0]
    target_previous = target_start = settle(step_target, target.home, steps_per_sample,
                                            settling)[0]
    target_command = target.home
    tally = PairTally(pairing_rule, check, names)
    pairs_source, pairs_target, complete = [], [], True
    for index, source_command in enumerate(source_commands):
        if should_stop is not None and should_stop():
            complete = False
            break
        for attempt in range(1 + (check.on_bad_pair == "retry" and settling.max_settle_steps > 0)):
            first = attempt == 0
            source_state, source_settled, _ = settle(
                step_source, source_command, steps_per_sample if first else settling.check_steps,
                settling)
            if target_commands is None:
                target_command = task_point_command(target, source_state.end_effector, offset,
                                                    target_command)
            else:
                target_command = target_commands[index]
            target_state, target_settled, _ = settle(
                step_target, target_command, steps_per_sample if first else settling.check_steps,
                settling)
            residual = pair_residual(pairing_rule, source, target, source_state, target_state,
                                     offset, (elapsed(source_state, source_start),
                                              elapsed(target_state, target_start)))
            if residual <= tally.tolerance:
                break
        kept = tally.add(residual, {"source": source_settled, "target": target_settled})
        if kept:
            pairs_source.append(feature_vector(source_state, source_previous, features))
            pairs_target.append(feature_vector(target_state, target_previous, features))
            if on_pair is not None:
                on_pair(len(pairs_source) - 1, pairs_source[-1], pairs_target[-1])
        source_previous, target_previous = source_state, target_state
        if tally.too_many_dropped(len(source_commands)):
            raise tally.error()
    if not complete and tally.dropped > check.max_bad_share * tally.checked:
        raise tally.error()
    return CorrespondenceSet(_rows(pairs_source), _rows(pairs_target), pairing_rule=pairing_rule,
                             features=features, sim_time=elapsed(source_previous, source_start),
                             complete=complete, metadata=tally.summary())


def _rows(samples):
    """Samples as an (N, D) array; (0, 0) when there are none."""
    return np.array(samples) if samples else np.empty((0, 0))


# -- guided exploration (§6.4.2, Alg. 7) ------------------------------------------------------
class _Stopped(Exception):
    """Raised inside a robot's ``execute`` when ``should_stop()`` ends a guided collection."""


def _observing(environment, joints, n_task, should_stop, on_row):
    """``environment`` (a Kinematics) executing its commands one at a time: before each,
    ``should_stop()`` may end the collection (:class:`_Stopped`); after each, ``on_row(row)``
    sees the observed row (q̄, x): the positions of ``joints`` and the task point."""
    def run(commands):
        commands = np.atleast_2d(np.asarray(commands, dtype=np.float64))
        positions, points = [], []
        for command in commands:
            if should_stop is not None and should_stop():
                raise _Stopped
            q, x = execute(environment, command[None])
            positions.append(q[0])
            points.append(x[0])
            on_row(np.concatenate((q[0, joints], x[0])))
        return (np.reshape(positions, commands.shape),
                np.reshape(points, (len(commands), n_task)))

    return replace(environment, forward=lambda commands: run(commands)[1],
                               execute=run)


def check_guided_exploration(babbling, source, target, source_joints, target_joints, seconds,
                             target_range="shared"):
    """Check a guided collection's set-up before any robot moves; ValueError if it is bad.

    ``source``/``target`` must be kinematic models (their ``forward`` must not run a robot,
    e.g. :func:`lpa_transfer.robots.kinematics.robot_kinematics`): a copy of ``babbling`` is started on
    the restricted target, which checks its hyperparameters, home and ``x_bounds`` against the
    target's task space. Returns the (d_c, 2) shared joint limits.
    """
    check_float(seconds, "seconds", 0)
    limits = shared_limits(source, target, source_joints, target_joints)
    kinematic = replace(target, execute=None)
    copy.copy(babbling).start(explored_target(kinematic, target_joints, limits, target_range))
    return limits


def collect_guided_correspondences(babbling, source, target, source_joints, target_joints,
                                   seconds, on_pair=None, should_stop=None, model=None,
                                   target_range="shared", source_follows="reached",
                                   pair_check=None, source_settling=None,
                                   names=("source", "target")):
    """Guided exploration (thesis §6.4.2, Alg. 7) as a correspondence collection.

    ``babbling`` is a :class:`lpa_transfer.goal_babbling.goal_babbling.GoalBabbling` (its
    ``x_bounds`` in the target's task space); ``source``/``target`` are environments
    (Kinematics whose commands run on the robots, e.g.
    :func:`lpa_transfer.robots.environment.stepped_environment`). ``source_joints[i]`` of the
    source is ``target_joints[i]`` of the target (the shared joints Q̄). The target
    goal-babbles for ``seconds`` simulated seconds moving the shared joints only, its other
    joints at home, within ``target_range`` (``shared`` or ``own`` ranges), learning ``model``
    (default: a fresh one; then ``babbling.model_``); the source then takes, movement by
    movement, the posture the target reached (``source_follows="reached"``) or the command it
    was sent (``"command"``), clipped into the shared ranges, its other joints at its home
    (:func:`lpa_transfer.exploration.guided.guided_exploration`). Row i holds each robot's
    observed (q̄, x) for movement i.

    Every pair whose command lay in the shared ranges is checked as a ``same_command`` pair
    (:class:`PairCheck`, ``pair_check``; its defaults when None): the largest difference of
    the two robots' reached shared joints must be at most ``tolerance``, or the pair is
    dropped (the target's row stays its own experience; ``on_bad_pair`` "retry" drops too:
    the source has already had ``max_settle_steps`` to take the posture, if its environment
    settles, e.g. a :class:`SettlingStep` passed again as ``source_settling`` so that its
    unsettled commands are counted). More than ``max_bad_share`` dropped ends the collection
    with a :class:`PairingError` naming ``names``, the rule and the residual.
    ``on_pair(index, source_row, target_row)`` sees each kept pair as it is made (``index``
    the movement's). ``should_stop()`` (checked before every command of either robot) ends the
    collection early: only the movements both robots executed count (none while the target
    is still babbling) and ``complete`` is False.

    Returns a :class:`CorrespondenceSet` of the kept pairs: pairing rule ``same_command``,
    features (``position``, ``ee_x``, …) with ``position`` the shared joints only,
    ``sim_time`` the source's execution time on goal babbling's clock (movements /
    ``steps_per_second``), and in ``metadata`` the hyperparameters, the check's tally
    (:meth:`PairTally.summary`, with ``median_residual``), ``followed`` (N,) bool (kept pairs)
    and ``target_experience`` (N, d_c + m), the target's rows of all N movements, for
    :func:`load_guided_exploration`; robot names are left empty for the caller.
    """
    check_float(seconds, "seconds", 0)
    check_target_range(target_range)
    check_source_follows(source_follows)
    check = check_pair_check(pair_check)
    limits = shared_limits(source, target, source_joints, target_joints)  # before a step
    low, high = check_x_bounds(babbling.x_bounds)
    n_task, n_shared = len(low), len(source_joints)
    tally = PairTally("same_command", check, names)
    target_rows, source_rows, followed = [], [], []
    in_range = None    # which commands lie in the shared ranges: known once the source starts

    def on_source_row(row):
        nonlocal in_range
        index = len(source_rows)
        source_rows.append(row)
        target_row = target_rows[index + 1]                # target_rows[0]: its home
        if in_range is None:  # the source starts once the target has babbled every movement
            in_range = followed_commands(babbling.commands_, limits)
        kept = bool(in_range[index])
        if kept:
            residual = float(np.abs(row[:n_shared] - target_row[:n_shared]).max())
            settled = True if source_settling is None else source_settling.settled
            kept = tally.add(residual, {"source": settled, "target": True})
            if tally.too_many_dropped(int(in_range.sum())):
                raise tally.error()
        followed.append(kept)
        if on_pair is not None and kept:
            on_pair(index, row, target_row)

    try:
        guided_exploration(
            babbling, _observing(source, source_joints, n_task, should_stop, on_source_row),
            _observing(target, target_joints, n_task, should_stop, target_rows.append),
            source_joints, target_joints, seconds, model, target_range, source_follows)
        complete = True
    except _Stopped:
        complete = False
        if tally.dropped > check.max_bad_share * tally.checked:
            raise tally.error() from None
    source_rows, experience = _rows(source_rows), _rows(target_rows[1:len(source_rows) + 1])
    followed = np.array(followed, dtype=bool)
    metadata = dict(guided_seconds=float(seconds), x_low=low, x_high=high,
                    source_joints=np.asarray(source_joints),
                    target_joints=np.asarray(target_joints), target_range=target_range,
                    source_follows=source_follows,
                    n_subtargets=babbling.n_subtargets, sigma=babbling.sigma,
                    drift=babbling.drift, p_home=babbling.p_home,
                    steps_per_second=babbling.steps_per_second, seed=babbling.seed,
                    followed=followed, target_experience=experience, **tally.summary(),
                    median_residual=float(np.median(tally.residuals)) if tally.residuals
                    else 0.0)
    return CorrespondenceSet(
        source_rows[followed], experience[followed],
        pairing_rule="same_command", features=("position",) + TASK_FEATURES[:n_task],
        sim_time=len(followed) / babbling.steps_per_second, complete=complete,
        metadata=metadata)
