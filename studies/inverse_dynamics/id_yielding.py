#!/usr/bin/env python3
"""Designs of a chapter 5 transfer that yields to the robot's own experience, measured on the
seeds used to choose (0 and 1; seeds 10-19 confirm the chosen one, in_process runs).

Usage, from the repository root::

    python -m studies.inverse_dynamics.id_yielding run --seed N [--designs D ...] [--trials 20]
        [--out DIR]
    python -m studies.inverse_dynamics.id_yielding report [--out DIR]

Every design initialises the target's LWPR with the source's 15 trials from scratch mapped by
PA (transfer-PA's data; set-up ``zero_spline_mj``, in_process.set_up) and learns online for
``--trials`` trials of both stars, beside learning from scratch; ``report`` prints, over the
seeds in ``--out``, the time saved by the mean curves within 5 / 10 / 20 % of scratch's final
error (analysis.convergence_table, 14.4 s of babbling charged) and the final errors (mean of
the last 3 trials). The designs (:data:`DESIGNS`):

* ``transfer-PA``: the thesis' initialisation;
* ``discount K``: transfer-PA, then every receptive field's weighted sums scaled by K, so the
  transferred samples count K times an own sample (:func:`discount`);
* ``gate N``: the transferred data in a frozen prior LWPR, a fresh own LWPR learning online,
  their predictions mixed by the own model's local evidence against N pseudo-samples
  (:class:`YieldingRegressor`, mode ``gate``);
* ``residual``: the own LWPR learns what the frozen prior gets wrong (mode ``residual``);
* ``own fields W``: transfer-PA, then the robot's own samples make receptive fields of their
  own unless one answers them above W (FeedForwardLearner's ``yielding``, kept in the library
  as the ``-yielding`` conditions).
"""
import argparse
import json
import sys
from pathlib import Path

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.exceptions import NotFittedError

from lpa_transfer.inverse_dynamics import BABBLING_SECONDS, convergence_table, interpolated, set_up
from lpa_transfer import _validation as check
from lpa_transfer.learners import LWPR
from lpa_transfer.learners.lwpr import _PROJ_AXES, _PROJ_STATS, _SCALARS

SETUP = "zero_spline_mj"
MODES = ("residual", "gate")


def discount(lwpr, factor):
    """Scale every receptive field's weighted sums (Σw, the PLS statistics, the error and
    metric traces) of ``lwpr`` by ``factor``, keeping its ratios (β, p, u's direction, x0, β0)
    and sample counts: the predictions stay, and later samples move each local model as if
    the earlier ones had activations ``factor`` times smaller."""
    rfs, n = lwpr._rfs, lwpr._rfs.n
    scale = np.where(np.arange(rfs.n_slots) < rfs.n_reg[:n, None], factor, 1.0)
    for name in ("SSs2", "SSY", "H", "r", "sum_w", "sum_ecv2"):
        rfs.proj_stats[:n, _PROJ_STATS.index(name)] *= scale
    for name in ("SXY", "SSX"):
        rfs.proj_axes[:n, _PROJ_AXES.index(name)] *= scale[:, :, None]
    for name in ("sum_e2", "SSp"):
        rfs.scalars[:n, _SCALARS.index(name)] *= factor
    return lwpr


class YieldingRegressor(RegressorMixin, BaseEstimator):
    """A prior learned from transferred data that yields to the own model (module docstring).

    ``regressor``: the unfitted online regressor both models are cloned from (e.g. an
    :class:`~lpa_transfer.learners.lwpr.LWPR` with the robot's hyperparameters); ``mode``:
    one of :data:`MODES`; ``prior_samples``: n₀ of ``"gate"``.
    Learned: ``prior_`` (after ``fit_prior``), ``own_`` (after ``partial_fit``).
    """

    def __init__(self, regressor, mode="residual", prior_samples=200.0):
        self.regressor = regressor
        self.mode = mode
        self.prior_samples = prior_samples

    def _check(self):
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, got {self.mode!r}")
        check.check_float(self.prior_samples, "prior_samples", 0.0)
        if self.mode == "gate" and not isinstance(self.regressor, LWPR):
            raise ValueError("mode 'gate' needs an LWPR regressor (its receptive fields give "
                             "the own model's local evidence)")

    def fit_prior(self, X, Y):
        """Learn (more) transferred samples into the prior; the own model is not touched."""
        self._check()
        if not hasattr(self, "prior_"):
            self.prior_ = clone(self.regressor)
        self.prior_.partial_fit(X, Y)
        return self

    def partial_fit(self, X, Y):
        """Learn the robot's own samples (rows in order) into the own model."""
        self._check()
        if not hasattr(self, "own_"):
            self.own_ = clone(self.regressor)
        Y = np.asarray(Y, dtype=np.float64)
        if self.mode == "residual":
            Y = Y - self._prior(X, Y.shape)
        self.own_.partial_fit(X, Y)
        return self

    def predict(self, X):
        """prior + own correction (``"residual"``) or their evidence-weighted mean (``"gate"``);
        NotFittedError before either model has learned anything."""
        if not hasattr(self, "prior_") and not hasattr(self, "own_"):
            raise NotFittedError("YieldingRegressor has learned nothing yet")
        model = self.own_ if hasattr(self, "own_") else self.prior_
        shape = (len(np.atleast_2d(X)), model.n_outputs_)
        prior = self._prior(X, shape)
        if not hasattr(self, "own_"):
            return prior
        own = np.asarray(self.own_.predict(X), dtype=np.float64).reshape(shape)
        if self.mode == "residual":
            return prior + own
        if not hasattr(self, "prior_"):
            return own
        evidence = self._evidence(X, shape)
        return (evidence * own + self.prior_samples * prior) / np.maximum(
            evidence + self.prior_samples, np.finfo(float).tiny)

    def _prior(self, X, shape):
        if not hasattr(self, "prior_"):
            return np.zeros(shape)
        return np.asarray(self.prior_.predict(X), dtype=np.float64).reshape(shape)

    def _evidence(self, X, shape):
        """Per query and output: Σ_k w_k n_k over the own LWPR's trustworthy fields that answer."""
        lwpr = self.own_
        rfs = lwpr._rfs
        evidence = np.zeros(shape)
        for i, x in enumerate(lwpr._check_queries(X)):
            rows, w = rfs.answering(x, lwpr.cutoff)
            if len(rows):
                n = rfs.field("proj_stats", "n_data", rows)[:, 0]
                evidence[i] = np.bincount(rfs.out[rows], weights=w * n, minlength=shape[1])
        return evidence


def learner(robot, samples, design):
    """A StarRobot's learner initialised with ``samples`` as ``design`` (:data:`DESIGNS`) asks."""
    kind, value = DESIGNS[design]
    if kind == "own fields":
        return robot.learner(samples, yielding=True, own_w_gen=value)
    plain = robot.learner(samples if kind in ("thesis", "discount") else None)
    if kind == "discount":
        discount(plain.regressor, value)
    elif kind in MODES:
        regressor = YieldingRegressor(plain.regressor, kind, value or 0.0)
        n = samples.shape[1] // 4
        regressor.fit_prior(samples[:, :3 * n], samples[:, 3 * n:])
        plain.regressor = regressor
    return plain


#: name -> (kind, setting)
DESIGNS = {"transfer-PA": ("thesis", None), "discount 0.01": ("discount", 0.01),
           "discount 0.05": ("discount", 0.05), "discount 0.2": ("discount", 0.2),
           "gate 2": ("gate", 2.0), "gate 10": ("gate", 10.0), "residual": ("residual", None),
           "own fields 0.3": ("own fields", 0.3), "own fields 0.6": ("own fields", 0.6)}


def run(seed, designs, n_trials):
    """{"robot/star/design": curve (mm)} of one seed, scratch as "robot/star/uninitialised"."""
    experiment, names, robots, _, models = set_up(SETUP, seed)
    dt = robots[experiment["stars"][0]][names[0]].dt
    curves = {}
    for star in experiment["stars"]:
        experience = {}
        for name in names:
            errors, experience[name] = robots[star][name].trials(robots[star][name].learner(),
                                                                 n_trials)
            curves[f"{name}/{star}/uninitialised"] = [1e3 * e for e in errors]
        for target in names:
            source = next(name for name in names if name != target)
            samples = models[target]["PA"].transfer(interpolated(
                experience[source], "spline", len(robots[star][source].trajectory[0]), dt))
            for design in designs:
                errors = robots[star][target].trials(
                    learner(robots[star][target], samples, design), n_trials)[0]
                curves[f"{target}/{star}/{design}"] = [1e3 * e for e in errors]
                print(seed, target, star, design, " ".join(f"{1e3 * e:.2f}" for e in errors),
                      flush=True)
    return curves


def report(out):
    """The savings and final errors of every design over the seeds in ``out``, as text."""
    runs = [json.loads(path.read_text()) for path in sorted(Path(out).glob("seed_*.json"))]
    if not runs:
        raise SystemExit(f"error: no seed_*.json under {out}")
    robots, stars = ("youbot", "pincher"), ("star1", "star2")
    designs = [d for d in DESIGNS if all(f"youbot/star1/{d}" in r["curves"] for r in runs)]
    lines = [f"seeds {[r['seed'] for r in runs]}; time saved by the mean curves within "
             "5 / 10 / 20 % of scratch's final error; final errors (mean of the last 3 "
             "trials, mm) Star 1 / Star 2", "",
             "| design | youBot saved | Pincher saved | youBot final | Pincher final |",
             "|---|---|---|---|---|"]
    def mm(robot, key):
        return " / ".join(f"{np.mean([r['curves'][f'{robot}/{star}/{key}'][-3:] for r in runs]):.2f}"
                          for star in stars)

    lines.append("| learning from scratch | - | - | " + " | ".join(mm(r, "uninitialised")
                                                          for r in robots) + " |")
    for design in designs:
        curves = {f"{robot}/{star}/{name}": np.array([r["curves"][f"{robot}/{star}/{key}"]
                                                      for r in runs]) / 1e3
                  for robot in robots for star in stars
                  for name, key in (("uninitialised", "uninitialised"), ("transfer-PA", design))}
        saved = [convergence_table(curves, robots, stars, band, BABBLING_SECONDS)[1]
                 for band in (0.05, 0.1, 0.2)]
        cells = [" / ".join(f"{100 * table[robot]['transfer-PA']:.1f}" for table in saved)
                 + " %" for robot in robots]
        lines.append(f"| {design} | " + " | ".join(cells + [mm(r, design) for r in robots])
                     + " |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    one = sub.add_parser("run")
    one.add_argument("--seed", type=int, required=True)
    one.add_argument("--designs", nargs="+", choices=list(DESIGNS), default=list(DESIGNS))
    one.add_argument("--trials", type=int, default=20)
    one.add_argument("--out", type=Path, default=Path("runs/id_yielding"))
    many = sub.add_parser("report")
    many.add_argument("--out", type=Path, default=Path("runs/id_yielding"))
    args = parser.parse_args(argv)
    if args.command == "report":
        print(report(args.out), end="")
        return 0
    curves = run(args.seed, args.designs, args.trials)
    path = args.out / f"seed_{args.seed}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    previous = json.loads(path.read_text())["curves"] if path.exists() else {}
    path.write_text(json.dumps({"setup": SETUP, "seed": args.seed,
                                "curves": {**previous, **curves}}))
    print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
