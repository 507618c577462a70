"""The §3.6 experiments as independent seeded tasks: one training size or one pair of target
link lengths, one run each, with PA and LPA (thesis Fig. 3-6, Fig. 3-8), and one training size
of the target learning from scratch (the §3.6 claim that without transfer convergence "would
not have happened until well over 1000 points"). ``cfg`` is the scenario's TOML configuration
(scenarios/two_link_fk/config.toml) as a dict.

The target's forward-kinematics models are LWPR [146], as in §3.6; the learner is named in
``[target_model]`` and defined in ``[learners.<name>]`` (``kind`` plus its hyperparameters), so
the memory-based ``LocallyWeightedRegression`` remains available as another entry. Learners
are deterministic given their data; all randomness is in the seeded data draws.
"""
import concurrent.futures
import contextlib
import dataclasses
import math
import sys

import numpy as np
from tqdm import tqdm

from lpa_transfer.learners.locally_weighted import LocallyWeightedRegression
from lpa_transfer.learners.lwpr import LWPR
from lpa_transfer.robots.kinematics import (domain_data, end_effector_rmse,
                                            planar_forward_kinematics, sample_joint_uniform)
from lpa_transfer.transfer import LocalProcrustesAnalysis, ProcrustesAnalysis


TRANSFER_METHODS = ("PA", "LPA")


SIZE_FIELDS = ("method", "n_train", "run", "mapping_rmse_m", "model_rmse_m", "n_clusters")


SCRATCH_FIELDS = ("learner", "method", "n_train", "run", "model_rmse_m")


#: ``kind`` of a ``[learners.<name>]`` entry -> the regressor class it builds.
LEARNER_KINDS = {"LWPR": LWPR, "LocallyWeightedRegression": LocallyWeightedRegression}


LINK_FIELDS = ("method", "target_link1_m", "target_link2_m", "delta_link1_m", "delta_link2_m",
               "run", "mapping_rmse_m", "model_rmse_m", "n_clusters")


def link_lengths_grid(sweep):
    """Target link lengths of experiment 2 (§3.6: 0.1 m to 1.5 m in 0.1 m steps)."""
    count = int(round((sweep["length_stop"] - sweep["length_start"]) / sweep["length_step"])) + 1
    return np.round(sweep["length_start"] + sweep["length_step"] * np.arange(count), 10)


def draw_correspondences(n, source, target, rng):
    """N correspondences (§3.6): both robots' domain points at the same uniform joint angles."""
    limits = np.column_stack((np.maximum(source.joint_limits[:, 0], target.joint_limits[:, 0]),
                              np.minimum(source.joint_limits[:, 1], target.joint_limits[:, 1])))
    q = sample_joint_uniform(n, limits, rng)
    return domain_data(q, source.link_lengths), domain_data(q, target.link_lengths)


def draw_test_sets(source, target, sizes, rng):
    """Uniform source test points, source experience, and target test joint angles."""
    return {"test_q": sample_joint_uniform(sizes["n_test"], source.joint_limits, rng),
            "experience": domain_data(sample_joint_uniform(sizes["n_experience"],
                                                           source.joint_limits, rng),
                                      source.link_lengths),
            "target_test_q": sample_joint_uniform(sizes["n_target_test"], target.joint_limits,
                                                  rng)}


def make_learner(cfg, name=None):
    """An unfitted regressor from ``[learners.<name>]`` (default: ``[target_model] learner``)."""
    name = cfg["target_model"]["learner"] if name is None else name
    params = dict(cfg["learners"][name])
    return LEARNER_KINDS[params.pop("kind")](**params)


def model_error(train_q, train_x, test_q, target, cfg, learner=None):
    """RMSE (m) on the target test set of a forward-kinematics model trained on (q, x), the
    rows learned in their (random) order."""
    model = make_learner(cfg, learner).fit(train_q, train_x)
    return end_effector_rmse(model.predict(test_q),
                             planar_forward_kinematics(test_q, target.link_lengths))


def transfer_scores(mapping, source, target, tests, cfg):
    """Mapping RMSE and model RMSE (m) of a fitted mapping (Fig. 3-6 a/b, Fig. 3-8)."""
    n_joints = source.n_joints
    transferred = mapping.transfer(domain_data(tests["test_q"], source.link_lengths))
    mapping_rmse = end_effector_rmse(
        transferred[:, n_joints:], planar_forward_kinematics(tests["test_q"], target.link_lengths))
    experience = mapping.transfer(tests["experience"])
    return mapping_rmse, model_error(experience[:, :n_joints], experience[:, n_joints:],
                                     tests["target_test_q"], target, cfg)


def child_seed(seed_seq, i):
    """``seed_seq.spawn(2)[i]`` without advancing its spawn counter, so a run can be repeated."""
    return np.random.SeedSequence(seed_seq.entropy, spawn_key=(*seed_seq.spawn_key, i),
                                  pool_size=seed_seq.pool_size)


def make_mapping(method, seed_seq, cfg):
    if method == "PA":
        return ProcrustesAnalysis()
    return LocalProcrustesAnalysis(**cfg["lpa"],
                                   random_state=int(seed_seq.generate_state(1)[0] >> 1))


def run_transfer(n, source, target, seed_seq, cfg, sizes):
    """Fit PA and LPA on n correspondences and score them.

    Returns ({method: (mapping RMSE, model RMSE, K)}, target training data, test sets, rng).
    """
    data_seq, model_seq = (child_seed(seed_seq, i) for i in range(2))
    rng = np.random.default_rng(data_seq)
    train_source, train_target = draw_correspondences(n, source, target, rng)
    tests = draw_test_sets(source, target, sizes, rng)
    scores = {}
    for method in TRANSFER_METHODS:
        mapping = make_mapping(method, model_seq, cfg).fit(train_source, train_target)
        scores[method] = (*transfer_scores(mapping, source, target, tests, cfg),
                          getattr(mapping, "n_clusters_", 1))
    return scores, train_target, tests, rng


def run_size_point(n, run, seed_seq, cfg):
    """Experiment 1 (Fig. 3-6) for one training size and run: rows for PA, LPA and baselines."""
    source, target, sweep = cfg["source"], cfg["target"], cfg["size_sweep"]
    scores, train_target, tests, rng = run_transfer(n, source, target, seed_seq, cfg, sweep)
    n_joints = source.n_joints
    truth_q = sample_joint_uniform(sweep["n_ground_truth"], target.joint_limits, rng)
    baselines = {
        "no_transfer": model_error(train_target[:, :n_joints], train_target[:, n_joints:],
                                   tests["target_test_q"], target, cfg),
        "ground_truth": model_error(truth_q, planar_forward_kinematics(truth_q,
                                                                      target.link_lengths),
                                    tests["target_test_q"], target, cfg)}
    rows = [dict(method=m, n_train=n, run=run, mapping_rmse_m=mapping, model_rmse_m=model,
                 n_clusters=k) for m, (mapping, model, k) in scores.items()]
    rows += [dict(method=m, n_train=n, run=run, mapping_rmse_m=math.nan, model_rmse_m=model,
                  n_clusters="") for m, model in baselines.items()]
    return rows


def run_link_point(lengths, run, seed_seq, cfg):
    """Experiment 2 (Fig. 3-8) for one pair of target link lengths and run."""
    source, sweep = cfg["source"], cfg["link_sweep"]
    target = dataclasses.replace(cfg["target"], link_lengths=lengths)
    scores, *_ = run_transfer(sweep["n_train"], source, target, seed_seq, cfg, sweep)
    delta = np.asarray(lengths) - source.link_lengths
    return [dict(method=m, target_link1_m=lengths[0], target_link2_m=lengths[1],
                 delta_link1_m=round(delta[0], 10), delta_link2_m=round(delta[1], 10), run=run,
                 mapping_rmse_m=mapping, model_rmse_m=model, n_clusters=k)
            for m, (mapping, model, k) in scores.items()]


def run_scratch_point(n, run, seed_seq, cfg):
    """The target learning its forward kinematics from n of its own uniform samples, no
    transfer (§3.6), with every learner of ``[scratch_sweep] learners`` on the same data."""
    target, sweep = cfg["target"], cfg["scratch_sweep"]
    rng = np.random.default_rng(seed_seq)
    test_q = sample_joint_uniform(sweep["n_target_test"], target.joint_limits, rng)
    train_q = sample_joint_uniform(n, target.joint_limits, rng)
    train_x = planar_forward_kinematics(train_q, target.link_lengths)
    return [dict(learner=name, method="no_transfer", n_train=n, run=run,
                 model_rmse_m=model_error(train_q, train_x, test_q, target, cfg, name))
            for name in sweep["learners"]]


def run_scratch_reference(run, seed_seq, cfg):
    """What the from-scratch curves are compared with: per learner of ``[scratch_sweep]
    learners``, the model trained on the source experience transferred by LPA from
    ``compare_n`` correspondences (§3.6: "convergence ... with about 200 data points")."""
    source, target, sweep = cfg["source"], cfg["target"], cfg["scratch_sweep"]
    data_seq, model_seq = (child_seed(seed_seq, i) for i in range(2))
    rng = np.random.default_rng(data_seq)
    n = sweep["compare_n"]
    train_source, train_target = draw_correspondences(n, source, target, rng)
    tests = draw_test_sets(source, target, dict(cfg["size_sweep"],
                                                n_target_test=sweep["n_target_test"]), rng)
    mapping = make_mapping("LPA", model_seq, cfg).fit(train_source, train_target)
    experience = mapping.transfer(tests["experience"])
    n_joints = source.n_joints
    return [dict(learner=name, method="LPA", n_train=n, run=run,
                 model_rmse_m=model_error(experience[:, :n_joints], experience[:, n_joints:],
                                          tests["target_test_q"], target, cfg, name))
            for name in sweep["learners"]]


def build_tasks(cfg, seed):
    """All runs as (function, args) with seeds spawned from one SeedSequence(seed): the size
    sweep, the link sweep and the from-scratch sweep (children 0, 1, 2 of the root; in the
    last, child i seeds size i and the child after the sizes the transferred references)."""
    size_seq, link_seq, scratch_seq = np.random.SeedSequence(seed).spawn(3)
    size_sweep, link_sweep = cfg["size_sweep"], cfg["link_sweep"]
    sizes = size_sweep["sizes"]
    lengths = link_lengths_grid(link_sweep)
    grid = [(l1, l2) for l1 in lengths for l2 in lengths]
    size_tasks = [(run_size_point, (n, run, run_seq, cfg))
                  for n, n_seq in zip(sizes, size_seq.spawn(len(sizes)))
                  for run, run_seq in enumerate(n_seq.spawn(size_sweep["runs"]))]
    link_tasks = [(run_link_point, ((float(l1), float(l2)), run, run_seq, cfg))
                  for (l1, l2), cell_seq in zip(grid, link_seq.spawn(len(grid)))
                  for run, run_seq in enumerate(cell_seq.spawn(link_sweep["runs"]))]
    scratch_sizes = cfg["scratch_sweep"]["sizes"]
    runs = cfg["scratch_sweep"]["runs"]
    *size_seqs, reference_seq = scratch_seq.spawn(len(scratch_sizes) + 1)
    scratch_tasks = [(run_scratch_point, (n, run, run_seq, cfg))
                     for n, n_seq in zip(scratch_sizes, size_seqs)
                     for run, run_seq in enumerate(n_seq.spawn(runs))]
    scratch_tasks += [(run_scratch_reference, (run, run_seq, cfg))
                      for run, run_seq in enumerate(reference_seq.spawn(runs))]
    return size_tasks, link_tasks, scratch_tasks


def _call(task):
    function, args = task
    return function(*args)


def run_all(tasks, jobs):
    """Run the tasks in order (optionally in ``jobs`` processes) with a progress bar."""
    results = []
    with (concurrent.futures.ProcessPoolExecutor(jobs) if jobs > 1 else contextlib.nullcontext()) \
            as pool, tqdm(total=len(tasks), desc="runs", unit="run", file=sys.stderr) as bar:
        for rows in (pool.map(_call, tasks, chunksize=4) if pool else map(_call, tasks)):
            results.append(rows)
            bar.update()
    return results
