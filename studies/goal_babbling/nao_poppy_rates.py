"""Experiment 2 of thesis ch. 6 (§6.5.2, Nao -> Poppy) in process, on the analytic arms, at
several movement rates: how the number of movements a simulated second changes learning
from scratch and the benefit of transfer. nao_poppy.yaml's rate (4 a second) is the one at
which our scratch learner ends near the thesis' scratch (reaching rate about 0.81 at 5000 s).

    nice -n 10 python -m studies.goal_babbling.nao_poppy_rates --rates 2 3 4 10 --seeds 0 1

Robots, homes, boxes, test points (200 000 joint samples), threshold, guided exploration, LPA
and guard are nao_poppy.yaml's; Nao babbles with its 4 shared joints. Kinematic, not physical
(the graph runs the same library pieces on pybullet), and its seeds are not the graph's; one
rate and seed takes ~20-60 s. Prints, per rate and seed, the reaching rate every 600 s for
scratch, guided exploration alone, LPA transfer and LPA transfer behind the guard.

``--override FILE`` merges a scenario override (e.g. nao_poppy_zup.yaml) into nao_poppy.yaml.
Instead of the rates: ``--accuracy`` what caps the transfer (the transferred samples' error
against Poppy's kinematics, and which reachable test points lie near a transferred, an
accurate or an own sample), ``--mixing`` how the k-NN model mixes transferred and own samples
(:func:`mixing`), ``--guard`` what the guard retires (:func:`guard`), ``--unshared-noise K``
the final rates when every condition explores the joints Nao lacks with K times the
exploration noise (:func:`unshared_noise`).
"""
import argparse
import os
from functools import partial
from pathlib import Path
from types import SimpleNamespace

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")
ROOT = Path(__file__).resolve().parents[2]

import numpy as np  # noqa: E402

from studies.scenario_params import node_params  # noqa: E402

from lpa_transfer.robots import hold_at_home, load_robot_params, robot_kinematics  # noqa: E402
from lpa_transfer.goal_babbling import (ACTIVE, COVERED, DISAGREED, GoalBabbling,  # noqa: E402
                                        GuardedModel, YieldingModel, chain_lipschitz,
                                        evaluate_reaching, evaluation_points,
                                        initialise_with_transfer, padded_rows, reaching_errors,
                                        transfer_experience)
from lpa_transfer.exploration import guided_exploration  # noqa: E402
from lpa_transfer.transfer import LocalProcrustesAnalysis  # noqa: E402
from lpa_transfer.learners import make_sensorimotor_model  # noqa: E402

#: nao_poppy.yaml, then the --override files (later ones win)
CONFIG_FILES = [ROOT / "scenarios" / "goal_babbling" / "nao_poppy.yaml"]
CONDITIONS = ("scratch", "guided only", "LPA", "LPA-guarded", "LPA-yielding",
              "LPA-yielding-gated", "LPA-yielding-fresh")
#: What :func:`run` prints by default (the last three are YieldingModel's designs)
SHOWN = CONDITIONS[:4]


def params(node):
    return node_params(node, *CONFIG_FILES)


def setting():
    """Both arms' kinematics, boxes and the shared joints, from nao_poppy.yaml."""
    source, target = params("/source/learner"), params("/target/learner")
    robots = {side: load_robot_params(ROOT / p["robot"]) for side, p in
              (("source", source), ("target", target))}
    arms = {side: robot_kinematics(robots[side], p["home"])
            for side, p in (("source", source), ("target", target))}
    boxes = {side: (tuple(p["x_low"]), tuple(p["x_high"]))
             for side, p in (("source", source), ("target", target))}
    return robots, arms, boxes, params("experiment")


def prepare(rate, seed, total=5000.0, guided=600.0):
    """Everything before the target's curves, for one rate and seed: a namespace of the arms,
    boxes, robots, shared joints, test points, threshold, the target home, the derived seeds,
    a ``babbler(side, stream, **kw)`` factory, the guided pairs, and Nao's experience after
    T_guided transferred by LPA (``commands``, ``task_points``)."""
    robots, arms, boxes, experiment = setting()
    shared = {side: experiment[f"{side}_joints"] for side in ("source", "target")}
    home = np.asarray(params("/target/learner")["home"])
    points = evaluation_points(arms["target"], boxes["target"], spacing=0.05,
                               n_joint_samples=200000)
    seeds = [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(seed).spawn(4)]

    def babbler(side, stream, **kw):
        return GoalBabbling(boxes[side], seed=seeds[stream], steps_per_second=rate, **kw)

    nao = babbler("source", 0).start(hold_at_home(arms["source"], shared["source"]))
    q_s, x_s = nao.run_for(total)
    guide = babbler("target", 1, home=home[shared["target"]])
    guided_pairs = guided_exploration(
        guide, arms["source"], arms["target"], shared["source"], shared["target"], guided,
        make_sensorimotor_model(forward=False), params("guided_exploration")["target_range"])
    lpa = LocalProcrustesAnalysis(n_min=experiment["n_min"], c_min=experiment["c_min"],
                                  random_state=seeds[2]).fit(*guided_pairs.correspondences())
    after = int(round(guided * rate))       # Nao's experience after T_guided (§6.5.2)
    commands, task_points = transfer_experience(
        lpa, np.hstack((q_s[after:, shared["source"]], x_s[after:])), home, shared["target"])
    return SimpleNamespace(robots=robots, arms=arms, boxes=boxes, shared=shared, home=home,
                points=points, threshold=experiment["reaching_threshold"], seeds=seeds,
                babbler=babbler, guided_pairs=guided_pairs, commands=commands,
                task_points=task_points)


def model_after_guided(setup, condition):
    """The target's model at T_guided for ``condition`` (one of CONDITIONS[1:]): the guided
    pairs, and unless "guided only" the transferred data (behind the guard for
    "LPA-guarded")."""
    model = make_sensorimotor_model(forward=False)
    if condition == "LPA-guarded":
        model = GuardedModel(model, lipschitz=chain_lipschitz(
            setup.robots["target"].link_lengths))
    elif condition.startswith("LPA-yielding"):
        model = YieldingModel(model, gate_radius=setup.threshold,
                              explore="gated" if condition.endswith("-gated") else "own")
    guided = padded_rows(setup.guided_pairs.target, setup.home, setup.shared["target"])
    if condition == "LPA-yielding-fresh":   # the guided rows join the prior; own from home
        return model.transfer(np.vstack((guided[0], setup.commands)),
                              np.vstack((guided[1], setup.task_points)))
    model.update(*guided)
    if condition != "guided only":
        initialise_with_transfer(model, setup.commands, setup.task_points)
    return model


def run(rate, seed, total=5000.0, guided=600.0, interval=600.0, conditions=SHOWN):
    setup = prepare(rate, seed, total, guided)
    arms, points, threshold, babbler = setup.arms, setup.points, setup.threshold, setup.babbler

    def curve(babbling, model, start):
        rates = []
        babbling.run_for(total - start, lambda b: rates.append(evaluate_reaching(
            model.inverse, arms["target"], points, threshold).rate), interval)
        return rates

    scratch = babbler("target", 1).start(arms["target"])
    curves = {"scratch": curve(scratch, scratch.model_, 0.0)}
    for name in conditions[1:]:
        model = model_after_guided(setup, name)
        first = evaluate_reaching(model.inverse, arms["target"], points, threshold).rate
        curves[name] = [first] + curve(babbler("target", 3).start(arms["target"], model),
                                       model, guided)
    return curves


class ScaledNoise:
    """A babbler's exploration noise E_t (goal_babbling.ExplorationNoise) scaled joint by
    joint: diag(scale) E_t(x), the same random walk."""

    def __init__(self, noise, scale):
        self.noise, self.scale = noise, np.asarray(scale, dtype=np.float64)

    def __call__(self, x):
        return self.scale * self.noise(x)

    def step(self):
        self.noise.step()


def scaled(babbling, noise_scale):
    """``babbling`` (started), its noise scaled joint by joint by ``noise_scale`` (None: as
    it is)."""
    if noise_scale is not None:
        babbling.noise_ = ScaledNoise(babbling.noise_, noise_scale)
    return babbling


def from_scratch(setup, total, noise_scale=None):
    """The target goal-babbling from scratch for ``total`` s (its babbling seed, as run's
    "scratch"): (the babbler, its observed task points); ``noise_scale`` as :func:`scaled`."""
    scratch = scaled(setup.babbler("target", 1).start(setup.arms["target"]), noise_scale)
    _, points = scratch.run_for(total)
    return scratch, points


def after_guided(setup, model, total, guided, noise_scale=None):
    """``model`` (:func:`model_after_guided`) as the target babbles on from T_guided to
    ``total`` with the after-transfer babbling seed, as run's conditions (``noise_scale`` as
    :func:`scaled`); returns it."""
    scaled(setup.babbler("target", 3).start(setup.arms["target"], model),
           noise_scale).run_for(total - guided)
    return model


def final_rate(setup, model):
    """The reaching rate of ``model``'s inverse on the target's test points."""
    return evaluate_reaching(model.inverse, setup.arms["target"], setup.points,
                             setup.threshold).rate


def unshared_joints(setup):
    """The target's joints that the source does not have (Poppy's torso)."""
    return [j for j in range(len(setup.home)) if j not in setup.shared["target"]]


def transfer_errors(setup):
    """Each transferred sample's error (m): Poppy's true kinematics of its command against
    its task point."""
    return np.linalg.norm(np.asarray(setup.arms["target"].forward(setup.commands))
                          - setup.task_points, axis=1)


def accuracy(rate, seed, total=5000.0, guided=600.0):
    """What caps the transfer (module docstring): a dict of the figures."""
    from scipy.spatial import cKDTree
    setup = prepare(rate, seed, total, guided)
    threshold = setup.threshold
    errors = transfer_errors(setup)
    _, own_points = from_scratch(setup, total)

    def near(points):
        return float(np.mean(np.isfinite(cKDTree(points).query(
            setup.points, distance_upper_bound=threshold)[0]))) if len(points) else 0.0

    return {"correspondences": int(setup.guided_pairs.followed.sum()),
            "transferred": len(errors),
            "error mean / median (mm)": (1e3 * errors.mean(), 1e3 * np.median(errors)),
            **{f"within {mm:g} mm": float(np.mean(errors <= mm / 1e3))
               for mm in (1, 5, 10, 15)},
            "test points": len(setup.points),
            "points near a transferred sample": near(setup.task_points),
            "points near an accurate transferred sample":
                near(setup.task_points[errors <= threshold]),
            "points near scratch's own samples at the end": near(own_points)}


def mixing(rate, seed, total=5000.0, guided=600.0):
    """How the K = 3 k-NN inverse model mixes transferred and own samples at ``total`` s
    (plain LPA): the reachable test points split by the origin of their query's
    neighbours (all own / mixed / all transferred), with the reaching rate of each group,
    the share of mixed neighbourhoods whose neighbours' non-shared joints (Poppy's torso,
    held at home in every transferred sample) spread by more than 0.1 rad, and scratch's
    rate on the same points."""
    setup = prepare(rate, seed, total, guided)
    target, points, threshold = setup.arms["target"], setup.points, setup.threshold
    model = model_after_guided(setup, "LPA")
    n_before = len(model.inverse.X_)                 # guided pairs + transferred samples
    transferred = np.zeros(n_before, dtype=bool)
    transferred[n_before - len(setup.commands):] = True
    after_guided(setup, model, total, guided)
    origin = np.zeros(len(model.inverse.X_), dtype=bool)
    origin[:n_before] = transferred
    _, neighbours = model.inverse.kneighbors(points)
    n_transferred = origin[neighbours].sum(axis=1)
    reached = reaching_errors(model.inverse, target, points) <= threshold
    unshared = unshared_joints(setup)
    spread = np.ptp(model.inverse.Y_[neighbours][:, :, unshared], axis=1).max(axis=1)
    scratch, _ = from_scratch(setup, total)
    scratch_reached = reaching_errors(scratch.model_.inverse, target, points) <= threshold
    groups = {"all own": n_transferred == 0,
              "mixed": (n_transferred > 0) & (n_transferred < neighbours.shape[1]),
              "all transferred": n_transferred == neighbours.shape[1]}
    figures = {"LPA rate": float(reached.mean()), "scratch rate": float(scratch_reached.mean()),
               "transferred share of the samples": float(origin.mean()),
               "transferred share of the neighbours": float(n_transferred.mean()
                                                             / neighbours.shape[1])}
    for name, members in groups.items():
        figures[f"{name}: points / LPA rate / scratch rate"] = (
            float(members.mean()), float(reached[members].mean()) if members.any() else np.nan,
            float(scratch_reached[members].mean()) if members.any() else np.nan)
    mixed = groups["mixed"]
    wide = mixed & (spread > 0.1)
    figures["mixed, torso spread > 0.1 rad: share of mixed / LPA rate / scratch rate"] = (
        float(wide.sum() / max(mixed.sum(), 1)),
        float(reached[wide].mean()) if wide.any() else np.nan,
        float(scratch_reached[wide].mean()) if wide.any() else np.nan)
    return figures


def guard(rate, seed, total=5000.0, guided=600.0):
    """Why LPA behind the guard still ends below scratch: the final reaching rates
    of scratch, guided exploration alone, LPA behind the guard, the guarded model's own
    samples alone, and LPA behind the guard given only the transferred samples within the
    threshold of Poppy's true kinematics (an oracle filter, as RobMech 2019 filtered by the
    known error), and plain transfer whose every task point is Poppy's true kinematics of its
    command (an exact mapping: the ceiling of any transfer of these commands, held at home in
    the torso); which transferred samples the guard retired by the end (covered /
    contradicted / still active), split by their true error; and how far the own samples
    move the joints Nao does not have (Poppy's torso; every transferred sample holds it at
    home)."""
    setup = prepare(rate, seed, total, guided)
    target = setup.arms["target"]
    errors = transfer_errors(setup)
    bad = errors > setup.threshold

    def babbled(model):
        return after_guided(setup, model, total, guided)

    scratch, _ = from_scratch(setup, total)
    guided_only = babbled(model_after_guided(setup, "guided only"))
    guarded = babbled(model_after_guided(setup, "LPA-guarded"))
    accurate = SimpleNamespace(**vars(setup))
    accurate.commands, accurate.task_points = setup.commands[~bad], setup.task_points[~bad]
    figures = {"transferred / past the threshold": (len(errors), int(bad.sum())),
               "final rate: scratch": final_rate(setup, scratch.model_),
               "guided only": final_rate(setup, guided_only),
               "LPA-guarded": final_rate(setup, guarded),
               "its own samples alone": final_rate(setup, guarded.model),
               "LPA-guarded, accurate samples only": final_rate(
                   setup, babbled(model_after_guided(accurate, "LPA-guarded")))}
    exact = SimpleNamespace(**vars(setup))
    exact.task_points = np.asarray(target.forward(setup.commands))
    figures["exact transfer"] = final_rate(setup, babbled(model_after_guided(exact, "LPA")))
    unshared = unshared_joints(setup)
    figures["std of the unshared joints over the own samples: scratch / guided only / "
            "LPA-guarded (rad)"] = tuple(
        float(np.std(np.asarray(own.inverse.Y_)[:, unshared]))
        for own in (scratch.model_, guided_only, guarded.model))
    for name, rows in (("accurate", ~bad), ("past the threshold", bad)):
        status = guarded.status_[rows]
        figures[f"{name}: active / covered / contradicted at the end"] = tuple(
            float(np.mean(status == code)) if rows.any() else np.nan
            for code in (ACTIVE, COVERED, DISAGREED))
    return figures


def unshared_noise(rate, seed, factor, total=5000.0, guided=600.0):
    """Whether more exploration of the joints Nao lacks (Poppy's torso, held at home by the
    guided phase and by every transferred sample) after T_guided closes the gap to scratch
    (§6.5.2: Poppy "continues exploring utilizing all the motors available", with
    no noise given): the final rates of scratch, guided only, LPA behind the guard and LPA,
    each exploring those joints with ``factor`` times the noise."""
    setup = prepare(rate, seed, total, guided)
    scale = np.ones(len(setup.home))
    scale[unshared_joints(setup)] = factor
    scratch, _ = from_scratch(setup, total, scale)
    figures = {"scratch": final_rate(setup, scratch.model_)}
    for condition in ("guided only", "LPA-guarded", "LPA"):
        figures[condition] = final_rate(setup, after_guided(
            setup, model_after_guided(setup, condition), total, guided, scale))
    return figures


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rates", type=float, nargs="+", default=[2.0, 3.0, 4.0, 10.0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--override", nargs="*", default=[])
    parser.add_argument("--accuracy", action="store_true")
    parser.add_argument("--mixing", action="store_true")
    parser.add_argument("--guard", action="store_true")
    parser.add_argument("--unshared-noise", type=float, metavar="K")
    parser.add_argument("--conditions", nargs="+", choices=CONDITIONS[1:],
                        default=list(SHOWN[1:]), help="run's conditions beside scratch")
    args = parser.parse_args()
    CONFIG_FILES.extend(args.override)
    diagnosis = accuracy if args.accuracy else mixing if args.mixing else \
        guard if args.guard else None
    if args.unshared_noise is not None:
        diagnosis = partial(unshared_noise, factor=args.unshared_noise)
    if diagnosis:
        for rate in args.rates:
            for seed in args.seeds:
                figures = diagnosis(rate, seed)
                print(f"{rate:g} movements a simulated second, seed {seed}: " + "; ".join(
                    f"{k} " + (" / ".join(f"{x:.3g}" for x in v) if isinstance(v, tuple)
                               else f"{v:.3g}" if isinstance(v, float) else str(v))
                    for k, v in figures.items()), flush=True)
        return
    print("reaching rate; scratch at 600, 1200, ... 4800 s; the others at 600 s (right "
          "after the transfer), 1200, ... 4800 s")
    for rate in args.rates:
        for seed in args.seeds:
            print(f"\n{rate:g} movements a simulated second, seed {seed}")
            for name, values in run(rate, seed,
                                    conditions=("scratch", *args.conditions)).items():
                print(f"  {name:<20}" + "".join(f"{v:6.2f}" for v in values))


if __name__ == "__main__":
    main()
