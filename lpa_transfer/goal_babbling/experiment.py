"""Experiment 1 of thesis §6.5.1 (Table 6.1): goal babbling of a 2-link target arm from scratch
or after guided exploration and transfer from a 2-link source arm, with and without the guard
against negative transfer. :func:`run_condition` runs one condition and seed.
"""
from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from lpa_transfer import _validation as check
from lpa_transfer._estimator import clone
from lpa_transfer.robots.kinematics import Kinematics
from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer.exploration.guided import guided_exploration
from lpa_transfer.robots.kinematics import planar_forward_kinematics, sample_joint_uniform
from lpa_transfer.transfer.local_procrustes import LocalProcrustesAnalysis
from lpa_transfer.goal_babbling.negative_transfer import GuardedModel, chain_lipschitz
from lpa_transfer.transfer.procrustes import ProcrustesAnalysis
from lpa_transfer.goal_babbling.reaching import evaluate_reaching, evaluation_points
from lpa_transfer.learners.sensorimotor import make_sensorimotor_model
from lpa_transfer.goal_babbling.transfer import initialise_with_transfer, transfer_experience
from lpa_transfer.goal_babbling.seeds import derived_seeds
from lpa_transfer.goal_babbling.yielding import YieldingModel

CONDITIONS = ("scratch", "PA", "LPA", "PA-guarded", "LPA-guarded", "PA-yielding",
              "LPA-yielding")


@dataclass(frozen=True)
class Experiment1:
    """Configuration of experiment 1 (§6.5.1); frozen, hence hashable (results are cached).

    Arms (Table 6.1): ``source_links``, ``target_links`` (m), one ``joint_limits`` (rad) for
    both, ``home`` (default: the middle of the ranges, our choice). Times (simulated s):
    the source babbles ``source_seconds`` and its whole experience is transferred; the target
    learns for ``total_seconds``, of which the first ``guided_seconds`` are guided exploration
    (T_guided: 60, 120, 180 or 240); it is evaluated every ``interval`` s (and at the end) on
    grid points ``eval_spacing`` apart, reaching rate at ``threshold`` (0.01 m, §6.5.1).
    ``babbling``, ``lpa``, ``guard`` and ``yielding`` are (name, value) pairs of
    GoalBabbling, LocalProcrustesAnalysis, GuardedModel and YieldingModel hyperparameters
    (the yielding gate defaults to ``threshold``). LPA: N_min 7 (Humanoids 2015's
    2-link value); the thesis' c_min 0.001 yields one cluster here (c_k of eq. 3.15 shrinks
    like 1/sqrt(N_k): 600 pairs with 2 cm RMS error give c_k ≈ 8e-4), so c_min is 1e-7 and
    N_min sets the number of clusters (§3.5). The guard's L defaults to
    :func:`chain_lipschitz` of the target. The task boxes are the arms' workspaces' bounding
    boxes, rounded out to 0.1 m.
    """

    source_links: tuple = (0.5, 0.5)
    target_links: tuple = (0.7, 0.4)
    joint_limits: tuple = ((-np.pi / 2, 0.0), (0.4, 2.9))
    home: tuple = None
    source_seconds: float = 1000.0
    total_seconds: float = 1000.0
    guided_seconds: float = 60.0
    interval: float = 60.0
    threshold: float = 0.01
    eval_spacing: float = 0.05
    babbling: tuple = ()
    lpa: tuple = (("n_min", 7), ("c_min", 1e-7))
    guard: tuple = ()
    yielding: tuple = ()

    def arm(self, links):
        limits = np.array(self.joint_limits, dtype=np.float64)
        home = limits.mean(axis=1) if self.home is None else np.asarray(self.home, float)
        links = np.asarray(links, dtype=np.float64)
        return Kinematics(limits, home, lambda q: planar_forward_kinematics(q, links),
                          workspace_box(limits, links))


def workspace_box(joint_limits, links, n_samples=20000):
    """The bounding box of a planar arm's workspace (sampled), rounded out to 0.1 m."""
    joints = sample_joint_uniform(n_samples, joint_limits, np.random.default_rng(0))
    reached = planar_forward_kinematics(joints, links)
    return (tuple(float(v) for v in np.floor(reached.min(axis=0) * 10) / 10),
            tuple(float(v) for v in np.ceil(reached.max(axis=0) * 10) / 10))


class Curves(NamedTuple):
    """Learning curves of one run: at ``times`` (s of the target's clock), the mean reaching
    error (m), the reaching rate and the active transferred samples in the model."""

    times: np.ndarray
    mean_error: np.ndarray
    rate: np.ndarray
    n_transferred: np.ndarray


def _babbler(config, environment, seed):
    return GoalBabbling(environment.task_box, seed=seed, **dict(config.babbling))


@lru_cache(maxsize=8)
def source_experience(config, seed):
    """The source's experience ξ_s (N, d + m), rows (q, x_s) of its goal babbling for
    ``config.source_seconds`` (read-only; cached)."""
    source = config.arm(config.source_links)
    babbler = _babbler(config, source, derived_seeds(seed)[0])
    rows = np.hstack(babbler.start(source, make_sensorimotor_model(forward=False))
                     .run_for(config.source_seconds))
    rows.flags.writeable = False
    return rows


@lru_cache(maxsize=8)
def _test_points(config):
    target = config.arm(config.target_links)
    points = evaluation_points(target, target.task_box, spacing=config.eval_spacing)
    points.flags.writeable = False
    return points


def evaluation_times(config):
    """Multiples of ``interval`` up to ``total_seconds``, and ``total_seconds``."""
    check.check_float(config.interval, "interval", 0)
    check.check_float(config.total_seconds, "total_seconds", 0)
    if config.interval == 0 or config.total_seconds < config.interval:
        raise ValueError(f"need 0 < interval <= total_seconds, got {config.interval!r} and "
                         f"{config.total_seconds!r}")
    count = int(config.total_seconds / config.interval + 1e-9)
    times = float(config.interval) * np.arange(1, count + 1)
    return times if np.isclose(times[-1], config.total_seconds) \
        else np.append(times, config.total_seconds)


def run_condition(condition, seed, config=Experiment1()):
    """One run of experiment 1 (§6.5.1): :class:`Curves` of the target for ``condition``.

    "scratch": the target goal-babbles (Alg. 6) for ``total_seconds``. Otherwise the target
    starts with guided exploration (Alg. 7) for ``guided_seconds``, both joints shared, the
    source executing the same commands; PA or LPA is fitted on the (q̄, x) pairs; the source's
    experience is transferred (§6.4.1) into the target's model — with weight 1 ("PA",
    "LPA", as the thesis), into a :class:`GuardedModel` ("…-guarded") or a
    :class:`YieldingModel` ("…-yielding") — and the target goes
    on babbling. Time accounting: the target's clock starts with guided exploration, so its
    T_guided s count toward ``total_seconds`` (the source's replay of the commands runs on the
    other robot and costs the target nothing; fitting and transfer take no simulated time);
    the evaluation at t = T_guided is after the transfer. The target's babbling uses the same
    seed in all conditions, so up to T_guided all conditions see the same samples (for these
    arms guided exploration is the target's goal babbling). Same seed, same curves.
    """
    if condition not in CONDITIONS:
        raise ValueError(f"condition must be one of {CONDITIONS}, got {condition!r}")
    times = evaluation_times(config)
    target = config.arm(config.target_links)
    points, seeds = _test_points(config), derived_seeds(seed)
    babbler = _babbler(config, target, seeds[1])
    model = make_sensorimotor_model(forward=False)
    if condition.endswith("-guarded"):
        guard = {"lipschitz": chain_lipschitz(config.target_links), **dict(config.guard)}
        model = GuardedModel(model, **guard)
    elif condition.endswith("-yielding"):
        model = YieldingModel(model, **{"gate_radius": config.threshold,
                                        **dict(config.yielding)})
    results, transferred = {}, [0]

    def evaluate(inverse, time, n_transferred):
        reaching = evaluate_reaching(inverse, target, points, config.threshold)
        results[round(float(time), 6)] = (reaching.mean_error, reaching.rate, n_transferred)

    def on_tick(babbling):
        active = model.n_active_ if hasattr(model, "n_active_") else transferred[0]
        evaluate(model.inverse, babbling.time_, active)

    if condition == "scratch":
        babbler.start(target, model)
        elapsed = 0.0
    else:
        elapsed, transferred[0] = _guided_phase(condition, config, babbler, model, seed,
                                                evaluate, times)
        on_tick(babbler)   # just after the transfer
    babbler.run_for(config.total_seconds - elapsed, on_tick, config.interval)
    on_tick(babbler)   # the end (a repeat if it is a multiple of the interval)
    rows = np.array([results[round(float(t), 6)] for t in times])
    return Curves(times, rows[:, 0], rows[:, 1], rows[:, 2].astype(int))


def _guided_phase(condition, config, babbler, model, seed, evaluate, times):
    """Guided exploration, the evaluations during it (on prefixes of the own samples, which
    is what the k-NN model held then), fitting and transfer; returns (T_guided, N
    transferred)."""
    seconds = config.guided_seconds
    check.check_float(seconds, "guided_seconds", 0)
    if not 0 < seconds <= config.total_seconds:
        raise ValueError(f"need 0 < guided_seconds <= total_seconds, got {seconds!r}")
    source, target = config.arm(config.source_links), config.arm(config.target_links)
    pairs = guided_exploration(babbler, source, target, [0, 1], [0, 1], seconds, model)
    own = model.model.inverse if hasattr(model, "transfer") else model.inverse
    for time in times[times < seconds]:
        n = 1 + int(round(time * babbler.steps_per_second))   # the home sample, then steps
        evaluate(clone(own).fit(own.X_[:n], own.Y_[:n], own.sample_weight_[:n]), time, 0)
    mapping = ProcrustesAnalysis() if condition.startswith("PA") else \
        LocalProcrustesAnalysis(random_state=derived_seeds(seed)[2], **dict(config.lpa))
    commands, task_points = transfer_experience(mapping.fit(*pairs.correspondences()),
                                                source_experience(config, seed),
                                                target.home, [0, 1])
    initialise_with_transfer(model, commands, task_points)
    return seconds, len(commands)

