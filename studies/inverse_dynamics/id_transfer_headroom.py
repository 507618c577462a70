#!/usr/bin/env python3
"""How much of the chapter 5 transfer is lost in the mapping? (thesis §5.4, §5.5.3)

Usage: ``python -m studies.inverse_dynamics.id_transfer_headroom [--seed S] [--trials N]
[--targets pincher youbot] [--stars star1 star2]``, from the repository root.

In process, with the library only (no ROS), from ``scenarios/inverse_dynamics/config.yaml``:
for each target robot and star, the babbling of experiment seed S (both robots track the same
random task lines near the star with PID only, paired by time index; the robots start at the
star's centre pose, so the pairs of Star 2 differ slightly from the graph's, whose robots go on
from where Star 1's babbling left them), then

1. the held-out nMSE of PA on those pairs per feature (q, q̇, q̈, τ; median over the joints the
   babbling moves), with ``id_mapping_quality.py``'s 6 blocks of whole lines each held out
   once: 1 means no better than predicting the mean;
2. the tracking error per trial (mm) of a fresh learner initialised with nothing
   (uninitialised), with the target's own babbling side of the pairs (random), with the
   source's experience of the star from scratch mapped by PA and LPA (transfer-PA/-LPA), and
   with the target's own experience of the star from scratch (oracle: the data a perfect
   mapping would deliver, as many samples as the source's).

The simulation and the learners are deterministic: the same seed prints the same numbers.
"""
import argparse
import json
from pathlib import Path

import numpy as np
import yaml
from sklearn.neighbors import NearestNeighbors

from lpa_transfer.transfer import LocalProcrustesAnalysis, ProcrustesAnalysis
from lpa_transfer.inverse_dynamics import CONFIG, StarRobot, babble, interpolated

# the same held-out blocks
from studies.inverse_dynamics.id_mapping_quality import held_out_predictions

MOVING = 1e-3          # a column whose spread is below this is a joint the babbling leaves still


def feature_nmse(make_model, source, target):
    """Held-out nMSE per feature group (q, q̇, q̈, τ): the median over the moving joints."""
    squared = ((held_out_predictions(make_model, source, target) - target) ** 2).mean(axis=0)
    spread = target.var(axis=0)
    nmse = squared / np.where(spread > 0, spread, 1.0)
    n = target.shape[1] // 4
    moving = target[:, :n].std(axis=0) > MOVING
    return [float(np.median(nmse[g * n:(g + 1) * n][moving])) for g in range(4)]


def against_own(robot, own_experience, samples, near=0.5):
    """Where ``samples`` lie and what torques they carry, against the target's own star
    experience: the median distance of their (q, q̇, q̈) to the nearest own sample (in units
    of the learner's input scale, the spread of the star's desired states), and, for the
    samples nearer than ``near``, the RMS difference of their torques from that own sample's
    over the spread of the own torques (moving joints). The robot's own exact babbling
    ('random') calibrates the second figure: neighbours ``near`` apart differ that much."""
    n = robot.params.n_joints
    scale = np.broadcast_to(np.asarray(robot.regressor[1]["norm_in"], dtype=float), (3 * n,))
    index = NearestNeighbors(n_neighbors=1).fit(own_experience[:, :3 * n] / scale)
    distance, nearest = index.kneighbors(samples[:, :3 * n] / scale)
    distance, nearest = distance[:, 0], nearest[:, 0]
    moving = own_experience[:, :n].std(axis=0) > MOVING
    close = distance < near
    own_tau = own_experience[:, 3 * n:][:, moving]
    difference = samples[close][:, 3 * n:][:, moving] - own_tau[nearest[close]]
    relative = np.sqrt((difference ** 2).mean()) / own_tau.std() if close.any() else np.nan
    by_feature = []            # the same median distance in the q, q̇ and q̈ columns alone
    for group in range(3):
        columns = slice(group * n, (group + 1) * n)
        alone = NearestNeighbors(n_neighbors=1).fit(own_experience[:, columns] / scale[columns])
        by_feature.append(float(np.median(alone.kneighbors(samples[:, columns]
                                                           / scale[columns])[0])))
    return float(np.median(distance)), by_feature, float(close.mean()), float(relative)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--config", type=Path, default=CONFIG)
    parser.add_argument("--trials", type=int, default=5)
    parser.add_argument("--targets", nargs="+", default=["pincher", "youbot"])
    parser.add_argument("--stars", nargs="+", default=["star1", "star2"])
    parser.add_argument("--time-law", default=None, help="minimum_jerk (default) or linear")
    parser.add_argument("--lwpr", type=json.loads, default=None,
                        help="JSON of LWPR hyperparameters replacing the config's, both robots")
    parser.add_argument("--interpolation", default="none",
                        help="none (default) or spline: the pairs (per babbling line) and the "
                             "source's experience (per trial) read off smoothing splines")
    args = parser.parse_args(argv)
    config = yaml.safe_load(args.config.read_text())
    experiment = config["experiment"]["ros__parameters"]
    names = experiment["robots"]            # names[0] is the babbling's source
    fit = dict(latent_dim=experiment["latent_dim"])
    for star in args.stars:
        robots = {name: StarRobot(config, name, star).configure(config, name, star,
                                                                 args.time_law, args.lwpr)
                  for name in names}
        pairs = dict(zip(names, babble(config, [robots[name] for name in names], star,
                                       args.seed)))
        line = config["/babbling/*"]["ros__parameters"]["samples_per_segment"]
        dt = robots[names[0]].dt
        pairs = {name: interpolated(rows, args.interpolation, line, dt)
                 for name, rows in pairs.items()}
        scratch_errors, experience = {}, {}
        for name in names:     # each robot's star from scratch: the source's experience
            scratch_errors[name], experience[name] = robots[name].trials(
                robots[name].learner(), experiment["n_source_trials"])
        for target in args.targets:
            source = next(name for name in names if name != target)
            n_source = robots[source].params.n_joints
            models = {"PA": lambda: ProcrustesAnalysis(**fit),
                      "LPA": lambda: LocalProcrustesAnalysis(
                          n_min=experiment["n_min"], c_min=experiment["c_min"],
                          cluster_dims=list(range(2 * n_source)), random_state=0, **fit)}
            nmse = feature_nmse(models["PA"], pairs[source], pairs[target])
            print(f"\n{source} -> {target}, {star}, seed {args.seed}: {len(pairs[target])} "
                  f"pairs; PA held-out nMSE q {nmse[0]:.2f}, q̇ {nmse[1]:.2f}, "
                  f"q̈ {nmse[2]:.2f}, τ {nmse[3]:.2f}")
            initial = {"uninitialised": None, "random": pairs[target],
                       **{f"transfer-{name}": make().fit(pairs[source], pairs[target])
                          .transfer(interpolated(experience[source], args.interpolation,
                                                 len(robots[source].trajectory[0]), dt))
                          for name, make in models.items()},
                       "oracle": experience[target]}
            for name in models:   # the source's experience, then the own babbling (learned last)
                initial[f"own+transfer-{name}"] = np.vstack((initial[f"transfer-{name}"],
                                                             pairs[target]))
            for condition in ("random", "transfer-PA", "transfer-LPA"):
                distance, by_feature, share, relative = against_own(
                    robots[target], experience[target], initial[condition])
                print(f"  {condition:14s} data: median distance to the own star data "
                      f"{distance:.2f} (q {by_feature[0]:.2f}, q̇ {by_feature[1]:.2f}, "
                      f"q̈ {by_feature[2]:.2f} alone), {100 * share:.0f} % nearer than 0.5"
                      + (f"; their torques differ by {relative:.2f} own-torque spreads"
                         if np.isfinite(relative) else ""))
            for condition, samples in initial.items():
                errors = robots[target].trials(robots[target].learner(samples), args.trials)[0]
                print(f"  {condition:14s} " + " ".join(f"{1e3 * e:6.2f}" for e in errors)
                      + f"   (scratch after {experiment['n_source_trials']} trials: "
                      f"{1e3 * scratch_errors[target][-1]:.2f} mm)", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
