"""Diagnosis of experiment 1 (thesis §6.5.1): why plain LPA transfer ends below goal
babbling from scratch.

The thesis (§6.5.1): "transfer with LPA is beneficial with respect to the final learning
performance when applied at 180 seconds and beyond ... LPA achieves a better transfer
accuracy when given more data"; its discussion (§6.6): "regression is performed on all data
saved in memory and equal weights are assigned to all data". To see which it is, everything
here runs in process, built like ``scenarios/goal_babbling/run_experiment.py`` builds a
condition over the node graph (scratch; transfer at T_guided: guided exploration, the
mapping, the source's experience mapped into a fresh k-NN, then goal babbling), instrumented:
:class:`NeighbourLog` records which of the k-NN's neighbours are transferred samples, and
:func:`transfer_accuracy` their error against the target's true forward kinematics. Variants
of which rows are transferred and how (``variant`` of :func:`transferred_rows`: plain, only
after T_guided, synthesized, oracles, matched pairs, reached postures, weighted) and the
optional pybullet physics: docs/library.md, "Diagnosis of chapter 6's experiment 1". All
random choices come from the run seed (``seeds.derived_seeds``) or fixed seeds.
"""
from functools import lru_cache

import numpy as np
from scipy.spatial import cKDTree

from lpa_transfer.exploration.guided import guided_exploration
from lpa_transfer.goal_babbling.experiment import (Experiment1, _test_points, evaluation_times,
                                                   source_experience)
from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer.goal_babbling.reaching import evaluation_points, reaching_errors
from lpa_transfer.goal_babbling.seeds import derived_seeds
from lpa_transfer.goal_babbling.transfer import initialise_with_transfer, transfer_experience
from lpa_transfer.goal_babbling.yielding import YieldingModel
from lpa_transfer.learners.sensorimotor import make_sensorimotor_model
from lpa_transfer.exploration.correspondences import PairCheck, SettlingStep
from lpa_transfer.robots.environment import stepped_environment
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf
from lpa_transfer.transfer.local_procrustes import LocalProcrustesAnalysis
from lpa_transfer.transfer.procrustes import ProcrustesAnalysis

ACCURACY_MM = (1.0, 5.0, 10.0)
#: The grid points of NeighbourLog.eval_split, by their neighbours
SPLITS = ("all_own", "transferred_accurate", "transferred_inaccurate")


PHYSICS_STEPS = 100   # physics steps of 1 ms a movement (config.yaml: steps_per_sample)


def environment(config, side, physics=None, settle=False):
    """The ``side`` ("source" or "target") arm as babbling executes it: the analytic
    kinematics, or (``physics`` = (source file, target file)) a fresh pybullet arm at home
    in position mode behind the same Kinematics (module docstring); ``settle``: each command
    stepped on until the arm settles (:class:`SettlingStep` with :class:`PairCheck`'s
    defaults)."""
    arm = config.arm(config.source_links if side == "source" else config.target_links)
    if physics is None:
        return arm
    robot = load_robot_params(physics[0 if side == "source" else 1])
    sim = RobotSimulator(robot_urdf(robot), control_mode="position", physics_step=1e-3,
                         initial_positions=list(arm.home))
    sim.reset(list(arm.home))
    return stepped_environment(arm, SettlingStep(sim.step, PairCheck()) if settle else sim.step,
                               PHYSICS_STEPS)


@lru_cache(maxsize=4)
def physical_source_experience(config, seed, physics):
    """ξ_s (N, 4) of the source's goal babbling on its pybullet arm (``physics``), seed
    ``derived_seeds(seed)[0]``, for ``config.source_seconds``."""
    source = environment(config, "source", physics)
    babbler = GoalBabbling(source.task_box, seed=derived_seeds(seed)[0], **dict(config.babbling))
    rows = np.hstack(babbler.start(source, make_sensorimotor_model(forward=False))
                     .run_for(config.source_seconds))
    rows.flags.writeable = False
    return rows


def source_rows(config, seed, physics=None):
    """The source's experience: analytic (``experiment.source_experience``) or physical."""
    return source_experience(config, seed) if physics is None else \
        physical_source_experience(config, seed, physics)


@lru_cache(maxsize=4)
def guided_rows(config, seed, seconds, physics=None, source_follows="command"):
    """Guided exploration (Alg. 7, §6.4) of ``seconds`` s with the target's babbling seed
    (``derived_seeds(seed)[1]``, as run.sh's collector): a GuidedPairs. Shorter T_guided are
    prefixes of the longest (deterministic), as the graph uses them. ``source_follows``
    "command" is the collector's earlier behaviour (the tables of the diagnosis); "reached"
    its default: the source settles on the target's reached posture, and the pairs
    apart by more than :class:`PairCheck`'s tolerance are not followed (dropped)."""
    reached = source_follows == "reached"
    target = environment(config, "target", physics)
    source = environment(config, "source", physics, settle=reached and physics is not None)
    babbler = GoalBabbling(target.task_box, seed=derived_seeds(seed)[1],
                           **dict(config.babbling))
    pairs = guided_exploration(babbler, source, target, [0, 1], [0, 1], seconds,
                               source_follows=source_follows)
    if reached:
        apart = np.abs(pairs.source[:, :2] - pairs.target[:, :2]).max(axis=1)
        pairs = pairs._replace(followed=pairs.followed & (apart <= PairCheck().tolerance))
    return pairs


def _guided_pairs(config, seed, seconds, variant, physics):
    """guided_rows for ``variant`` (``reached``: the source follows the reached postures)."""
    return guided_rows(config, seed, seconds, physics,
                       "reached" if variant == "reached" else "command")


def _n_commands(config, seconds):
    """Goal-babbling steps in ``seconds`` (10 a second unless ``config.babbling`` says)."""
    return int(round(seconds * dict(config.babbling).get("steps_per_second", 10.0)))


def prefix(pairs, n_commands):
    """(own target rows, source correspondences, target correspondences) of the first
    ``n_commands`` commands of a GuidedPairs."""
    n_pairs = int(pairs.followed[:n_commands].sum())
    src, tgt = pairs.correspondences()
    return pairs.target[:n_commands], src[:n_pairs], tgt[:n_pairs]


def transfer_accuracy(config, commands, points, levels_mm=ACCURACY_MM):
    """Errors (N,) (m) of transferred samples (q, x̂_t) against the target's true forward
    kinematics, ||FK_t(q) − x̂_t||, and {level: share within level mm}."""
    target = config.arm(config.target_links)
    errors = np.linalg.norm(np.asarray(target.forward(commands)) - points, axis=1)
    return errors, {level: float(np.mean(errors <= level / 1000)) for level in levels_mm}


def synthesized_source(config, seed, spacing=0.05, physics=None):
    """ξ_s synthesized from the source's learned inverse model (§6.4): its model after
    ``source_seconds`` of babbling queried on a grid of ``spacing`` over its reachable task
    box, each command executed on the source: rows (q, x_s)."""
    source = config.arm(config.source_links)
    rows = source_rows(config, seed, physics)
    model = make_sensorimotor_model(forward=False)
    model.update(rows[:, :2], rows[:, 2:])
    goals = evaluation_points(source, source.task_box, spacing=spacing)
    limits = np.asarray(source.joint_limits)
    commands = np.clip(model.infer_command(goals), limits[:, 0], limits[:, 1])
    return np.hstack((commands, np.asarray(source.forward(commands))))


def fit_mapping(config, seed, source_pairs, target_pairs, method="lpa"):
    """PA or LPA (N_min, c_min of ``config.lpa``; seed ``derived_seeds(seed)[2]``) fitted on
    the correspondences."""
    mapping = ProcrustesAnalysis() if method == "pa" else \
        LocalProcrustesAnalysis(random_state=derived_seeds(seed)[2], **dict(config.lpa))
    return mapping.fit(source_pairs, target_pairs)


def transferred_rows(config, seed, guided_seconds, variant="plain", method="lpa",
                     synth_spacing=0.05, guided_longest=240.0, physics=None):
    """(commands (N, 2), points (N, 2), weights (N,), info dict) transferred at T_guided for
    ``variant`` (module docstring; guided exploration is run for ``guided_longest`` s and
    cut to T_guided, as the graph does); ``info`` has the correspondence count, the mapping errors'
    mean/median and the shares within 1/5/10 mm of all mapped rows (before any filter)."""
    n_commands = _n_commands(config, guided_seconds)
    pairs = _guided_pairs(config, seed, max(guided_seconds, guided_longest), variant, physics)
    _, src, tgt = prefix(pairs, n_commands)
    if variant.startswith("matched_pairs_"):   # correspondences whose arms' joints agree
        agree = np.abs(src[:, :2] - tgt[:, :2]).max(axis=1) <= float(variant.rsplit("_", 1)[1])
        src, tgt = src[agree], tgt[agree]
    mapping = fit_mapping(config, seed, src, tgt, method)
    experience = source_rows(config, seed, physics)
    if variant == "from_guided":
        experience = experience[n_commands:]
    elif variant == "synthesized":
        experience = synthesized_source(config, seed, synth_spacing, physics)
    commands, points = transfer_experience(mapping, experience,
                                           config.arm(config.target_links).home, [0, 1])
    errors, shares = transfer_accuracy(config, commands, points)
    info = dict(n_correspondences=len(src), n_mapped=len(commands),
                mapping_error_mean_mm=1000 * float(errors.mean()),
                mapping_error_median_mm=1000 * float(np.median(errors)),
                mapping_error_p90_mm=1000 * float(np.quantile(errors, 0.9)),
                **{f"within_{level:g}mm": share for level, share in shares.items()})
    weights = np.ones(len(commands))
    if variant == "oracle_exact":
        points = np.asarray(config.arm(config.target_links).forward(commands))
        errors = np.zeros(len(commands))
    elif variant.startswith("oracle_filter_"):
        keep = errors <= float(variant.rsplit("_", 1)[1]) / 1000
        commands, points, errors, weights = (commands[keep], points[keep], errors[keep],
                                             weights[keep])
    elif variant.startswith("weighted_"):
        weights = np.full(len(commands), float(variant.rsplit("_", 1)[1]))
    info["n_transferred"] = len(commands)
    return commands, points, weights, errors, info


class NeighbourLog:
    """Logs the K = 3 neighbours a KNNRegressor uses (Alg. 6's inverse model, §6.5): wraps
    the instance's ``kneighbors``. Rows ``[start, stop)`` of the model are the transferred
    samples, ``errors`` their mapping errors. ``mode`` says whether a query is a goal-babbling
    step ("babble") or an evaluation ("eval")."""

    def __init__(self, knn, start, stop, errors):
        self.knn, self.start, self.stop, self.errors = knn, start, stop, np.asarray(errors)
        self.mode, self.babble, self.last_eval = "babble", [], None
        self._original = knn.kneighbors
        knn.kneighbors = self._kneighbors

    def _kneighbors(self, X):
        distances, indices = self._original(X)
        transferred = (indices >= self.start) & (indices < self.stop)
        if self.mode == "babble":
            self.babble.append(float(transferred.mean()))
        else:
            self.last_eval = (indices, transferred)
        return distances, indices

    def eval_split(self, reach_errors, threshold, bad_mm=5.0):
        """Of the last evaluation: share of neighbours transferred, and reaching rates (with
        point counts) of grid points whose neighbours are all own, include transferred ones
        all within ``bad_mm`` of the truth, or include one beyond it."""
        indices, transferred = self.last_eval
        err = np.where(transferred, self.errors[np.clip(indices - self.start, 0,
                                                        len(self.errors) - 1)], 0.0)
        bad = (err > bad_mm / 1000).any(axis=1)
        none = ~transferred.any(axis=1)
        good = ~none & ~bad
        reached = reach_errors <= threshold

        def rate(mask):
            return (float(reached[mask].mean()) if mask.any() else float("nan"),
                    int(mask.sum()))
        return dict(eval_neighbours_transferred=float(transferred.mean()),
                    **dict(zip((f"rate_{kind}" for kind in SPLITS),
                               (rate(none), rate(good), rate(bad)))))


def density(config, own_points, transferred_points, radius=0.025):
    """Transferred against own samples over the target's test grid: at each grid point the
    counts within ``radius`` (m); returns the mean share transferred, the share of grid
    points where transferred samples outnumber own ones, and the totals."""
    points = _test_points(config)
    n_own = cKDTree(own_points).query_ball_point(points, radius, return_length=True)
    n_tr = (cKDTree(transferred_points).query_ball_point(points, radius, return_length=True)
            if len(transferred_points) else np.zeros(len(points)))
    total = np.maximum(n_own + n_tr, 1)
    return dict(density_share_transferred=float(np.mean(n_tr / total)),
                density_points_transferred_majority=float(np.mean(n_tr > n_own)),
                n_own_total=int(len(own_points)), n_transferred_total=int(len(transferred_points)))


GRIDS = (0.05, 0.025)
THRESHOLDS_MM = (5.0, 10.0, 15.0, 20.0)


def _final_sweep(config, model, target):
    """Final reaching rate on grids of GRIDS spacing at THRESHOLDS_MM (§6.5 measure)."""
    out = {}
    for spacing in GRIDS:
        points = evaluation_points(target, target.task_box, spacing=spacing)
        errors = reaching_errors(model.inverse, target, points)
        for mm in THRESHOLDS_MM:
            out[f"grid{spacing:g}_thr{mm:g}mm"] = float(np.mean(errors <= mm / 1000))
    return out


def run_scratch(config, seed, physics=None):
    """Goal babbling from scratch (Alg. 6), as the graph's scratch run: curves (times, rates,
    mean errors) and the final sweep over grids and thresholds."""
    target = config.arm(config.target_links)
    points = _test_points(config)
    model = make_sensorimotor_model(forward=False)
    babbler = GoalBabbling(target.task_box, seed=derived_seeds(seed)[1], **dict(config.babbling))
    curve = []

    def tick(b):
        errors = reaching_errors(model.inverse, target, points)
        curve.append((b.time_, float(np.mean(errors <= config.threshold)), float(errors.mean())))
    babbler.start(environment(config, "target", physics), model).run_for(
        config.total_seconds, tick, config.interval)
    return dict(curve=curve, sweep=_final_sweep(config, model, target))


def run_transfer_condition(config, seed, guided_seconds, variant="plain", method="lpa",
                           guided_longest=240.0, physics=None, yielding=None):
    """One transfer run as the graph builds it (module docstring), instrumented: the learning
    curve with, at every evaluation, the neighbour split (:class:`NeighbourLog`), the mean share
    of transferred neighbours in the goal-babbling steps since the previous evaluation, the
    density of transferred samples (at the transfer and at the end), the final sweep over grids
    and thresholds, and the transfer's ``info``. ``yielding`` (a dict of
    :class:`~lpa_transfer.goal_babbling.yielding.YieldingModel` hyperparameters) keeps the
    transferred rows in a YieldingModel instead (no neighbour split then: NaN)."""
    target = config.arm(config.target_links)
    points = _test_points(config)
    n_commands = _n_commands(config, guided_seconds)
    pairs = _guided_pairs(config, seed, max(guided_seconds, guided_longest), variant, physics)
    own, src, tgt = prefix(pairs, n_commands)
    commands, task_points, weights, errors, info = transferred_rows(
        config, seed, guided_seconds, variant, method, guided_longest=guided_longest,
        physics=physics)
    residual = np.abs(src[:, :2] - tgt[:, :2]).max(axis=1)
    info.update(pair_residual_median_rad=float(np.median(residual)),
                pair_residual_p95_rad=float(np.quantile(residual, 0.95)),
                pair_residual_max_rad=float(residual.max()))
    model = make_sensorimotor_model(forward=False)
    if yielding is not None:
        model = YieldingModel(model, **yielding)
    model.update(own[:, :2], own[:, 2:])
    if len(commands):
        initialise_with_transfer(model, commands, task_points) if yielding is not None \
            else model.update(commands, task_points, weights)
    own_knn = model.model.inverse if yielding is not None else model.inverse
    n_in_own = len(own) + (0 if yielding is not None else len(commands))
    log = NeighbourLog(own_knn, len(own), n_in_own, errors)
    density_start = density(config, own[:, 2:], task_points)
    curve = []

    def evaluate(time):
        log.mode = "eval"
        reach = reaching_errors(model.inverse, target, points)
        log.mode = "babble"
        babble_share = float(np.mean(log.babble)) if log.babble else float("nan")
        log.babble = []
        split = log.eval_split(reach, config.threshold) if yielding is None else dict(
            eval_neighbours_transferred=float("nan"), **{f"rate_{kind}": (float("nan"), 0)
                                                         for kind in SPLITS})
        curve.append(dict(time=time, rate=float(np.mean(reach <= config.threshold)),
                          mean_error=float(reach.mean()),
                          babble_neighbours_transferred=babble_share, **split))
    evaluate(guided_seconds)
    babbler = GoalBabbling(target.task_box, seed=derived_seeds(seed)[3], **dict(config.babbling))
    babbler.start(environment(config, "target", physics), model)
    babbler.run_for(config.total_seconds - guided_seconds,
                    lambda b: evaluate(guided_seconds + b.time_), config.interval)
    if not np.isclose(curve[-1]["time"], config.total_seconds):
        evaluate(config.total_seconds)   # the end, as the graph's last evaluation
    X = own_knn.X_
    own_all = np.vstack((X[:len(own)], X[n_in_own:]))
    density_end = density(config, own_all, task_points if yielding is not None
                          else X[len(own):n_in_own])
    log.mode = "eval"
    sweep = _final_sweep(config, model, target)
    return dict(info=info, curve=curve, density_start=density_start, density_end=density_end,
                sweep=sweep)


def default_config():
    """The project's experiment-1 configuration (config.yaml's values)."""
    return Experiment1()


__all__ = ["ACCURACY_MM", "GRIDS", "NeighbourLog", "THRESHOLDS_MM", "default_config", "density",
           "environment", "evaluation_times", "fit_mapping", "guided_rows", "prefix", "run_scratch",
           "run_transfer_condition", "synthesized_source", "transfer_accuracy",
           "transferred_rows"]
