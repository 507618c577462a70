#!/usr/bin/env python3
"""Chapter 5's experiment in process (thesis §5.5.3): the graph's experiment computed with the
library's simulator, PID and LWPR, under named set-ups, with the tables the thesis reports.

Usage, from the repository root::

    python -m lpa_transfer.inverse_dynamics.in_process run --setup S --seed N [--trials 15]
        [--out DIR]
    python -m lpa_transfer.inverse_dynamics.in_process report [--out DIR] [--setups S ...]
        [--summary] [--star-out STAR=DIR ...]
    python -m lpa_transfer.inverse_dynamics.in_process export --setup S --to RUN_DIR [--out DIR]

``run`` writes ``DIR/S/seed_N.json``, the tracking-error curves (mm per trial) of both robots
on both stars for every condition (:func:`runs`: one babbling session over both stars, models
fitted on all its pairs, the source's trials from scratch transferred, as run_experiment.py
does; on the smoke size without start noise the curves equal the graph's). ``report`` joins
the seeds of each set-up: first-trial errors, trials to convergence under both rules and the
training time saved as §5.5.3 counts it, beside the thesis' figures. ``export`` writes one
set-up's seeds as a chapter 5 run directory (report.write_outputs), which merge_results.py
and paired_seeds.py read. A set-up (:data:`SETUPS`) switches factors of the scenario (time
laws, actuator, LWPR settings, spline correspondences, babbling volume); each run is
deterministic.
"""
import argparse
import copy
import json
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import yaml

from lpa_transfer.inverse_dynamics.analysis import (BANDS, CONDITIONS, TRIAL_SECONDS,
                                                    band_savings,
                                                    conditions_in, convergence_table,
                                                    finals_against_scratch, paired_against)
from lpa_transfer.inverse_dynamics.interpolation import interpolated
from lpa_transfer.inverse_dynamics.report import write_outputs
from lpa_transfer.inverse_dynamics.star_robot import CONFIG, StarRobot, babble
from lpa_transfer.transfer.local_procrustes import LocalProcrustesAnalysis
from lpa_transfer.transfer.procrustes import ProcrustesAnalysis

THESIS_LWPR = {"init_D": 30.0, "norm_in": 1.0}
#: The set-ups' base is the first references' set-up: LWPR answers the nearest field's offset
#: where none is active. config.yaml has since chosen the zero answer (factor 6), so every
#: set-up states the answer it runs with.
BASE_LWPR = {"empty_prediction": "nearest"}
#: name -> the switches of the set-up's factors (absent: today's choice).
SETUPS = {
    "today": {},
    "linear_legs": {"time_law": "linear"},                        # factor 1
    "velocity_motor": {"actuator": "velocity_motor"},             # factor 2
    "raw_inputs": {"lwpr": THESIS_LWPR},                          # factor 3
    "spline": {"interpolation": "spline"},                        # factor 4
    "volume": {"volume": True},                                   # factor 5
    "zero_answer": {"lwpr": {"empty_prediction": "zero"}},        # factor 6
    "all": {"time_law": "linear", "actuator": "velocity_motor", "interpolation": "spline",
            "volume": True, "lwpr": {**THESIS_LWPR, "empty_prediction": "zero"}},
    "all_but_actuator": {"time_law": "linear", "interpolation": "spline", "volume": True,
                         "lwpr": {**THESIS_LWPR, "empty_prediction": "zero"}},
    "legs_spline_volume": {"time_law": "linear", "interpolation": "spline", "volume": True},
    # init_D 30 read as the LWPR package's guideline has it, on inputs normalised to unit
    # spread (ours: the star's spread), alone and with the reference library's zero answer
    "narrow_fields": {"lwpr": {"init_D": 30.0}},
    "narrow_fields_zero": {"lwpr": {"init_D": 30.0, "empty_prediction": "zero"}},
    # the reference library's zero answer (factor 6) with spline correspondences (factor 4)
    "zero_spline": {"lwpr": {"empty_prediction": "zero"}, "interpolation": "spline"},
    # the zero answer, predictions only from fields activated above w_gen (0.1; the thesis
    # does not give the LWPR package's prediction cutoff, 0.001 elsewhere)
    "zero_cutoff": {"lwpr": {"empty_prediction": "zero", "cutoff": 0.1}},
    # a diagnostic, not an LWPR variant: the zero answer, and 0 also where only fields the
    # initial data made answer, none of them above w_gen (gate_initial_fields)
    "zero_gated": {"lwpr": {"empty_prediction": "zero"}, "gate": True},
    # the final set-up (zero answer) with babbling lines spaced like the star legs (minimum
    # jerk, at rest at every waypoint) instead of at constant speed: §5.4.1 leaves the lines'
    # time law open, and it decides which accelerations the correspondences hold (factor 4)
    "zero_mj_babbling": {"lwpr": {"empty_prediction": "zero"},
                         "babbling_time_law": "minimum_jerk"},
    # and with the spline correspondences of factor 4 (§5.4.1 after its ref. [8])
    "zero_spline_mj": {"lwpr": {"empty_prediction": "zero"}, "interpolation": "spline",
                       "babbling_time_law": "minimum_jerk"},
}
#: Thesis §5.5.3 (youBot) and the ICRA 2018 paper (Pincher): trials to convergence of learning
#: from scratch on (Star 1, Star 2) and the time saved by transfer / by random initialisation.
THESIS = {"youbot": {"scratch": "9 / > 20", "transfer": "63 %", "random": "up to 4.6 %"},
          "pincher": {"scratch": "-", "transfer": "58.7 % (ICRA 2018)", "random": "15.8 % (ICRA 2018)"}}
BABBLING_SECONDS = 14.4
#: FeedForwardLearner's settings of the ``-yielding`` conditions (config.yaml's learners')
YIELDING = {"own_w_gen": 0.3}
TOLERANCE = 0.1
#: The convergence rules of the tables (factor 7): analysis.convergence_table's ``rule``.
RULES = ("scratch", "plateau")


def with_volume(config):
    """The config with babbling boxes as deep across the arms' plane as along it (factor 5)."""
    config = copy.deepcopy(config)
    for key, node in config.items():
        if key.startswith("/babbling/") and key != "/babbling/*":
            for side in ("source", "target"):
                half = node["ros__parameters"][f"{side}_task_halfwidth"]
                node["ros__parameters"][f"{side}_task_halfwidth"] = [half[0], half[1], half[0]]
    return config


def babble_session(config, robots, seed):
    """The seed's correspondences of every star as the graph collects them: one babbling
    session per robot on one simulator, Star 2's collector going on from where Star 1's left
    the arm (each collector first commands its star's centre pose for one sample period,
    ``collect_correspondences``); {robot: rows of all stars, Star 1's first}."""
    stars = config["experiment"]["ros__parameters"]["stars"]
    names = list(robots[stars[0]])
    rows = {name: [] for name in names}
    for k, star in enumerate(stars):
        arms = [SimpleNamespace(kinematics=robots[star][name].kinematics,
                                params=robots[star][name].params,
                                sim=robots[stars[0]][name].sim) for name in names]  # one arm each
        for name, part in zip(names, babble(config, arms, star, seed, reset=k == 0)):
            rows[name].append(part)
    return {name: np.vstack(parts) for name, parts in rows.items()}


def run(setup, seed, n_trials, config_path=CONFIG, conditions=None, yielding=YIELDING):
    """{"robot/star/condition": curve (mm per trial)} of one set-up and experiment seed, as
    the graph's experiment (run_experiment.py) computes them: the pairs of both stars fit one
    PA and one LPA model per direction, 'random' is the target's babbling of both stars, and
    each star's transferred data are the source's 15 trials of that star from scratch.
    ``conditions`` (default all) and ``yielding`` as :func:`runs`."""
    return {f"{target}/{star}/{condition}": [1e3 * e for e in errors]
            for target, star, condition, _, _, _, errors in runs(
                setup, seed, n_trials, config_path, conditions=conditions, yielding=yielding)}


def set_up(setup, seed, config_path=CONFIG):
    """What every learner run of ``setup`` and ``seed`` starts from, as the graph's experiment
    makes it: (the experiment's parameters, the robot names, {star: {name: StarRobot}}, the
    babbling session's pairs {name: rows of both stars}, {target: {"PA", "LPA": the mapping
    from the other robot, fitted on all the pairs}})."""
    switches = SETUPS[setup]
    config = yaml.safe_load(Path(config_path).read_text())
    if switches.get("volume"):
        config = with_volume(config)
    # each set-up names its babbling time law (absent: constant speed, the references'), so
    # that it means the same whatever config.yaml has since chosen
    config["/babbling/*"]["ros__parameters"]["time_law"] = switches.get("babbling_time_law",
                                                                       "linear")
    experiment = config["experiment"]["ros__parameters"]
    names = experiment["robots"]                       # names[0] is the babbling's source
    fit = dict(latent_dim=experiment["latent_dim"])
    line = config["/babbling/*"]["ros__parameters"]["samples_per_segment"]
    robots = {star: {name: StarRobot(config, name, star, switches.get("actuator", "torque"))
                     .configure(config, name, star, switches.get("time_law"),
                                {**BASE_LWPR, **switches.get("lwpr", {})})
                     for name in names} for star in experiment["stars"]}
    dt = robots[experiment["stars"][0]][names[0]].dt
    pairs = {name: interpolated(rows, switches.get("interpolation", "none"), line, dt)
             for name, rows in babble_session(config, robots, seed).items()}
    models = {}
    for target in names:
        source = next(name for name in names if name != target)
        n_source = robots[experiment["stars"][0]][source].params.n_joints
        models[target] = {
            "PA": ProcrustesAnalysis(**fit).fit(pairs[source], pairs[target]),
            "LPA": LocalProcrustesAnalysis(
                n_min=experiment["n_min"], c_min=experiment["c_min"],
                cluster_dims=list(range(2 * n_source)), random_state=seed,
                **fit
            ).fit(pairs[source], pairs[target])}
    return experiment, names, robots, pairs, models


def runs(setup, seed, n_trials, config_path=CONFIG, targets=None, stars=None, watch=None,
         conditions=None, yielding=YIELDING):
    """:func:`run`'s learner runs one by one: (target, star, condition, the target's StarRobot
    of that star, the learner after its last trial, the fields its initial data made, errors
    in m); per star (default: all; the
    babbling and the models always use all), learning from scratch of every robot first (each
    source's experience), then ``targets``' (default: all) initialised conditions.
    ``watch(target, star, condition, robot, learner, made, errors)``, if given, is called
    after every trial of the targets' runs (the curves do not change). ``conditions``: the
    initialised conditions to run (default all of analysis.CONDITIONS); in the ``-yielding``
    ones the transferred data yield to the own experience (FeedForwardLearner's
    ``yielding``, its settings from ``yielding``)."""
    switches = SETUPS[setup]
    experiment, names, robots, pairs, models = set_up(setup, seed, config_path)
    interpolation = switches.get("interpolation", "none")
    dt = robots[experiment["stars"][0]][names[0]].dt

    def watcher(name, star, condition, robot, made):
        """``after_trial`` for one run: ``watch`` with the run's context, for targets only."""
        if watch is None or (targets is not None and name not in targets):
            return None
        return lambda model, so_far: watch(name, star, condition, robot, model, made, so_far)

    for star in experiment["stars"] if stars is None else stars:
        experience = {}
        for name in names:          # learning from scratch: the uninitialised curve and the
            robot = robots[star][name]                                        # experience
            learner = robot.learner()
            errors, experience[name] = robot.trials(
                learner, n_trials, after_trial=watcher(name, star, "uninitialised", robot, 0))
            yield name, star, "uninitialised", robot, learner, 0, errors
        for target in names if targets is None else targets:
            source = next(name for name in names if name != target)
            robot = robots[star][target]
            source_experience = interpolated(experience[source], interpolation,
                                             len(robots[star][source].trajectory[0]), dt)
            initial = {"random": pairs[target]}
            for method, model in models[target].items():
                initial[f"transfer-{method}"] = model.transfer(source_experience)
            for method in models[target]:      # the source's experience, then the own babbling
                initial[f"own+transfer-{method}"] = np.vstack((initial[f"transfer-{method}"],
                                                               pairs[target]))
                initial[f"transfer-{method}-yielding"] = initial[f"transfer-{method}"]
            wanted = [c for c in CONDITIONS if c != "uninitialised"
                      and (conditions is None or c in conditions)]
            for condition in wanted:
                samples = initial[condition]
                learner = (robot.learner(samples, yielding=True, **yielding)
                           if condition.endswith("-yielding") else robot.learner(samples))
                made = n_fields(learner)
                if switches.get("gate"):
                    gate_initial_fields(learner)
                errors = robot.trials(learner, n_trials,
                                      after_trial=watcher(target, star, condition, robot, made))[0]
                yield target, star, condition, robot, learner, made, errors


def gate_initial_fields(learner):
    """Make the learner's LWPR answer 0 for an output wherever the trustworthy fields that
    would answer it are all fields its initial data made, none activated above ``w_gen``,
    as learning from scratch answers where it has no field of its own (the zero answer: the
    PID acts alone). A diagnostic of what caps the saving (how much do weak answers from
    initial data off the task cost?), not the thesis' LWPR. Fields are known by output and
    centre (an LWPR centre never moves; pruning moves rows)."""
    lwpr = learner.regressor
    rfs = lwpr._rfs

    def key(k):
        return int(rfs.out[k]), rfs.field("points", "c", k).tobytes()

    initial = {key(k) for k in range(rfs.n)}
    predict = lwpr.predict

    def gated(X):
        Y = np.array(predict(X), dtype=np.float64, ndmin=2)
        for i, x in enumerate(lwpr._check_queries(X)):
            rows, w = rfs.answering(x, lwpr.cutoff)
            for o in np.unique(rfs.out[rows]):
                mine = rfs.out[rows] == o
                if w[mine].max() <= lwpr.w_gen and all(key(k) in initial for k in rows[mine]):
                    Y[i, o] = 0.0
        return Y

    lwpr.predict = gated


def n_fields(learner):
    """Receptive fields (all outputs) of a learner's LWPR; 0 before it has seen a sample."""
    rfs = getattr(learner.regressor, "_rfs", None)
    return 0 if rfs is None else rfs.n


def load(out, setup, star_out=None):
    """{key: [curve per seed]} and the seeds of one set-up's runs under ``out``; ``star_out``
    ({star: directory}) takes those stars' curves from another run directory instead (e.g. a
    trial budget per star; a star's curves do not depend on the other star's runs), over the
    seeds that every directory holds."""
    def one(directory):
        runs = (json.loads(f.read_text()) for f in (Path(directory) / setup).glob("seed_*.json"))
        return {run["seed"]: run["curves"] for run in runs}

    by_seed = one(out)
    others = {star: one(directory) for star, directory in (star_out or {}).items()}
    seeds = sorted(set(by_seed).intersection(*others.values()))
    curves = {}
    for seed in seeds:
        run = dict(by_seed[seed])
        for star, other in others.items():
            run.update({k: v for k, v in other[seed].items() if k.split("/")[1] == star})
        for key, curve in run.items():
            curves.setdefault(key, []).append(curve)
    return curves, seeds


def analysed(out, setup, robots=None, star_out=None):
    """One set-up's runs (``star_out`` as :func:`load`) and their convergence tables under
    both rules, or None when it has no runs: a namespace of ``curves`` (mm), ``seeds``,
    ``robots`` (youBot first unless given), ``stars``, ``n_trials`` ({star: trials}),
    ``metres`` (the curves in m), ``conditions`` (those the curves hold), ``tables`` (rule ->
    :func:`convergence_table`'s rows and savings) and ``bands`` (:func:`band_savings`: the
    mean curves' savings within 5, 10 and 20 % of scratch's final error)."""
    curves, seeds = load(out, setup, star_out)
    if not curves:
        return None
    robots = robots or sorted({k.split("/")[0] for k in curves}, reverse=True)
    stars = sorted({k.split("/")[1] for k in curves})
    metres = {k: np.asarray(v) / 1e3 for k, v in curves.items()}
    tables = {rule: convergence_table(metres, robots, stars, TOLERANCE, BABBLING_SECONDS,
                                      rule=rule) for rule in RULES}
    return SimpleNamespace(curves=curves, seeds=seeds, robots=robots, stars=stars,
                           conditions=conditions_in(metres),
                           bands=band_savings(metres, robots, stars, BABBLING_SECONDS),
                           n_trials={s: len(next(v for k, v in curves.items()
                                                  if k.split("/")[1] == s)[0]) for s in stars},
                           metres=metres,
                           tables=tables)


def trials_text(k, n_trials):
    """Trials to convergence as the tables print them: "> n" when the curve never got there."""
    return str(k) if k <= n_trials else f"> {n_trials}"


def report(out, setups, star_out=None):
    """The ablation's tables as text (``star_out`` as :func:`load`)."""
    lines = []
    for setup in setups:
        result = analysed(out, setup, star_out=star_out)
        if result is None:
            continue
        n_trials, stars = result.n_trials, result.stars
        lines += [f"## {setup}: {json.dumps(SETUPS[setup])}", "",
                  f"{len(result.seeds)} seed(s) {result.seeds}, "
                  + (f"{n_trials[stars[0]]} trials" if len(set(n_trials.values())) == 1 else
                     ", ".join(f"{n} trials on {s}" for s, n in n_trials.items()))
                  + "; mm, mean over the seeds", ""]
        trials = {rule: {(r, s, c): k for r, s, c, k, _ in rows}
                  for rule, (rows, _) in result.tables.items()}
        paired = (paired_against(result.metres, result.robots, stars) if len(result.seeds) > 1
                  else {})
        finals = finals_against_scratch(result.curves, result.robots, stars)
        for robot in result.robots:
            lines.append(f"| {robot} | " + " | ".join(
                f"{star} trial 1 | trial {n_trials[star]} | conv. (scratch rule) | conv. (plateau)"
                for star in stars) + " | saved (scratch rule) | saved (plateau) |")
            lines.append("|---" * (2 + 4 * len(stars) + 1) + "|")
            for condition in result.conditions:
                cells = []
                for star in stars:
                    mean = np.mean(result.curves[f"{robot}/{star}/{condition}"], axis=0)
                    cells += [f"{mean[0]:.2f}", f"{mean[-1]:.2f}",
                              *[trials_text(trials[rule][robot, star, condition],
                                            n_trials[star])
                                for rule in RULES]]
                saved = ["-", "-"] if condition == "uninitialised" else [
                    f"{100 * result.tables[rule][1][robot][condition]:.1f} %" for rule in RULES]
                lines.append(f"| {condition} | " + " | ".join(cells + saved) + " |")
            thesis = THESIS[robot]
            lines += ["", f"saved by the mean curves within {' / '.join(f'{b:.0%}' for b in BANDS)}"
                      f" of scratch's final error: " + ", ".join(
                          f"{c} " + " / ".join(f"{100 * result.bands[b][robot][c]:.1f}"
                                               for b in BANDS) + " %"
                          for c in result.conditions[1:])]
            for star in stars:
                cells = [(c, ours, base, above, below, p) for (r, s, c), (ours, base, (
                    above, below, _, p)) in finals.items() if r == robot and s == star]
                if cells:
                    lines.append(f"{star}, final error (mm, mean of the last 3 trials) against "
                                 f"scratch's {np.mean(cells[0][2]):.2f}, paired by seed: "
                                 + "; ".join(f"{c} {np.mean(ours):.2f} ({above} above / "
                                             f"{below} below, p {p:.3f})"
                                             for c, ours, _, above, below, p in cells))
            lines += [f"thesis ({robot}): scratch converges in {thesis['scratch']} trials "
                      f"(Star 1 / Star 2); transfer saves {thesis['transfer']}, random "
                      f"{thesis['random']}"]
            for star in stars:
                below = [f"{c} {lower}/{n} (p {p:.3f})" for (r, s, c), ((lower, n, p), _) in
                         paired.items() if r == robot and s == star]
                if below:
                    lines.append(f"{star}, mean of trials 1-5 below random in: " + "; ".join(below))
            lines.append("")
    return "\n".join(lines)


def setups_summary(out, setups, star_out=None):
    """One table per target robot, one row per set-up: learning from scratch's trials to
    convergence and first-trial error per star, the thesis conditions' first-trial errors, and
    the time saved by the mean curves per condition the runs hold under both rules ("scratch
    rule / plateau")."""
    robots = ("youbot", "pincher")
    runs = {setup: analysed(out, setup, list(robots), star_out) for setup in setups}
    initialised = list(dict.fromkeys(c for result in runs.values() if result is not None
                                     for c in result.conditions[1:]))
    lines = []
    for robot in robots:
        lines += [f"### {robot} as target ({THESIS[robot]['scratch']} trials from scratch, "
                  f"transfer saves {THESIS[robot]['transfer']}, random {THESIS[robot]['random']}"
                  f" in the thesis)", "",
                  "| set-up | seeds | scratch converges (S1 / S2) | trial 1, S1: scratch / random "
                  "/ PA / LPA (mm) | trial 1, S2 | saved: " + " | ".join(initialised) + " |",
                  "|---" * (5 + len(initialised)) + "|"]
        for setup, result in runs.items():
            if result is None:
                continue
            converged = {(r, s, c): k for r, s, c, k, _ in result.tables["scratch"][0]}
            scratch = " / ".join(trials_text(converged[robot, s, "uninitialised"],
                                             result.n_trials[s]) for s in result.stars)
            firsts = [" / ".join(f"{np.mean(result.curves[f'{robot}/{s}/{c}'], axis=0)[0]:.1f}"
                                 if f"{robot}/{s}/{c}" in result.curves else "-"
                                 for c in ("uninitialised", "random", "transfer-PA",
                                           "transfer-LPA")) for s in result.stars]
            saved = [" / ".join(f"{100 * result.tables[rule][1][robot][c]:.0f}" for rule in RULES)
                     + " %" if c in result.conditions else "-" for c in initialised]
            lines.append(f"| {setup} | {len(result.seeds)} | {scratch} | "
                         + " | ".join(firsts + saved) + " |")
        lines.append("")
    return "\n".join(lines)


def export(out, setup, to):
    """Write ``setup``'s runs under ``out`` as a chapter 5 run directory ``to`` (report.write_
    outputs: no traces, no start noise); returns the report's text."""
    result = analysed(out, setup, ["youbot", "pincher"])
    if result is None:
        raise SystemExit(f"error: no runs of {setup} under {out}")
    n_trials, = set(result.n_trials.values())           # one run directory: one budget
    experiment = SimpleNamespace(robots=result.robots, stars=result.stars,
                                 n_trials=n_trials, tolerance=TOLERANCE,
                                 babbling_seconds=BABBLING_SECONDS, start_noise=0.0,
                                 done_seeds=result.seeds)
    curves = {key: runs.tolist() for key, runs in result.metres.items()}
    return write_outputs(curves, {}, experiment, Path(to),
                         where=f"in process (lpa_transfer/inverse_dynamics/in_process.py, "
                               f"set-up {setup}: {json.dumps(SETUPS[setup])}; equal to the "
                               f"graph at start_noise 0)")


def _main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    one = sub.add_parser("run")
    one.add_argument("--setup", choices=sorted(SETUPS), required=True)
    one.add_argument("--seed", type=int, required=True)
    one.add_argument("--trials", type=int, default=15)
    one.add_argument("--out", type=Path, default=Path("runs/id_ablation"))
    one.add_argument("--conditions", nargs="+", choices=CONDITIONS[1:], default=None,
                     help="the initialised conditions to run (default all)")
    one.add_argument("--own-w-gen", type=float, default=YIELDING["own_w_gen"],
                     help="the -yielding conditions' field-making threshold for own samples")
    one.add_argument("--tag", default="", help="appended to the set-up's folder under --out")
    many = sub.add_parser("report")
    many.add_argument("--out", type=Path, default=Path("runs/id_ablation"))
    many.add_argument("--setups", nargs="+", default=list(SETUPS))
    many.add_argument("--summary", action="store_true",
                      help="one table per robot across the set-ups instead of one per set-up")
    many.add_argument("--star-out", nargs="+", default=[], metavar="STAR=DIR",
                      help="take these stars' curves from another run directory (the same "
                           "seeds), e.g. star1=DIR of 15-trial runs beside 20-trial runs")
    to = sub.add_parser("export")
    to.add_argument("--setup", choices=sorted(SETUPS), required=True)
    to.add_argument("--to", type=Path, required=True)
    to.add_argument("--out", type=Path, default=Path("runs/id_ablation"))
    args = parser.parse_args(argv)
    if args.command == "export":
        print(export(args.out, args.setup, args.to), end="")
        return 0
    if args.command == "report":
        star_out = dict(item.split("=", 1) for item in args.star_out)
        print((setups_summary if args.summary else report)(args.out, args.setups, star_out))
        return 0
    yielding = {"own_w_gen": args.own_w_gen}
    curves = run(args.setup, args.seed, args.trials, conditions=args.conditions,
                 yielding=yielding)
    path = args.out / (args.setup + args.tag) / f"seed_{args.seed}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"setup": args.setup, "switches": SETUPS[args.setup],
                                "seed": args.seed, "trials_seconds": TRIAL_SECONDS,
                                "yielding": yielding, "curves": curves}))
    print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(_main())
