"""Chapter 5's run outputs: results.json, learning_curves.csv, the Fig. 5-6 and Fig. 5-7/5-8
figures and report.txt; and joining the outputs of runs that each ran a share of the seeds or
conditions.

``experiment`` is anything with the attributes of :data:`SETTINGS` plus ``done_seeds`` (the
experiment node, or the settings read back from a results.json).
"""
import csv
import json
from pathlib import Path
from types import SimpleNamespace

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import LogFormatter, MaxNLocator, ScalarFormatter

from lpa_transfer.inverse_dynamics.analysis import (BANDS, FINAL_TRIALS, PLATEAU_WINDOW,
                                                    TRIAL_SECONDS, band_savings,
                                                    bootstrap_savings, conditions_in,
                                                    convergence_table,
                                                    finals_against_scratch, paired_against,
                                                    per_seed_savings, scratch_finals,
                                                    simulated_seconds)


SETTINGS = ("robots", "stars", "n_trials", "tolerance", "babbling_seconds",  # in results.json
            "start_noise")


BOOTSTRAP_RESAMPLES = 2000


THESIS = {"youbot": "Star 1: 9 trials from scratch, 4 with transfer; Star 2: > 20 and 5; "
                    "63% of training time saved (random init: 4.6%)",
          "pincher": "58.7% of training time saved (random init: 15.8%)"}


def name_width(curves):
    """The width of the condition column: 16, or the longest condition name the curves hold."""
    return max([16] + [len(c) for c in conditions_in(curves)])


def paired_lines(curves, robots, stars, early_trials=5, reference="random"):
    """The report's lines of :func:`paired_against`."""
    width = name_width(curves)
    lines = [f"paired over seeds against {reference}: seeds in which the condition's mean error "
             f"is lower / seeds (Wilcoxon signed-rank p), over trials 1-{early_trials} and over "
             f"all trials"]
    for (robot, star, condition), (early, whole) in paired_against(
            curves, robots, stars, early_trials, reference).items():
        lines.append(f"  {robot:<9} {star:<6} {condition:<{width}} " + ",  ".join(
            f"{lower:>2}/{n} (p {p:.3f})" for lower, n, p in (early, whole)))
    return lines


def percent(values):
    """Savings as the report prints them: "12.3" or, for several bands, "12.3 / 4.5"."""
    return " / ".join(f"{100 * v:.1f}" for v in values) + "%"


def headline_lines(curves, experiment):
    """The report's lead, the thesis' measure (§5.5.3): per target robot the training time
    saved read off the mean curves over the seeds, within the run's tolerance and under the
    bands :data:`~lpa_transfer.inverse_dynamics.analysis.BANDS`, and learning from scratch's
    final errors over the seeds that the bands are shares of."""
    robots, stars, tolerance = experiment.robots, experiment.stars, experiment.tolerance
    bands = tuple(sorted(set(BANDS) | {tolerance}))
    by_band = band_savings(curves, robots, stars, experiment.babbling_seconds, bands)
    finals = scratch_finals(curves, robots, stars)
    lines = []
    for robot in robots:
        saved = by_band[tolerance][robot]
        lines.append(f"{robot} as target, training time saved by the mean curves over the "
                     f"{len(experiment.done_seeds)} seed(s), converged within {tolerance:.0%} "
                     f"(trials x {TRIAL_SECONDS} s, + {experiment.babbling_seconds:g} s "
                     f"babbling for initialised runs): "
                     + ", ".join(f"{c} {percent([v])}" for c, v in saved.items()))
        lines.append(f"  converged within {' / '.join(f'{b:.0%}' for b in bands)} of "
                     f"scratch's final error: " + ", ".join(
                         f"{c} {percent([by_band[b][robot][c] for b in bands])}"
                         for c in saved))
        lines.append(f"  scratch's final error (its last trial, mm; mean ± std over the seeds, "
                     f"min-max) and the {' / '.join(f'{b:.0%}' for b in bands)} bands: "
                     + "; ".join(f"{star} {1e3 * mean:.2f} ± {1e3 * std:.2f} "
                                 f"({1e3 * low:.2f}-{1e3 * high:.2f}), "
                                 + " / ".join(f"{1e3 * b * mean:.2f}" for b in bands) + " mm"
                                 for star in stars
                                 for mean, std, low, high in [finals[robot, star]]))
        lines.append(f"  thesis: {THESIS.get(robot, '-')}")
    return lines


def final_error_lines(curves, experiment, last=FINAL_TRIALS):
    """:func:`finals_against_scratch` as the report prints it: does a condition end where
    learning from scratch ends? (``experiment``: robots, stars and, if known, start_noise.)"""
    one_scratch = getattr(experiment, "start_noise", None) == 0
    width = name_width(curves)
    lines = [f"final error (mean of the last {last} trials, mm; mean ± std over the seeds) "
             f"against learning from scratch's, paired by seed: the difference of the means, "
             f"seeds above / below scratch (Wilcoxon signed-rank p)"
             + ("; without start noise learning from scratch is one run, so the test asks "
                "whether the seeds' finals differ from its value" if one_scratch else "")]
    table = finals_against_scratch(curves, experiment.robots, experiment.stars, last)
    done = set()
    for (robot, star, condition), (finals, scratch, (above, below, n, p)) in table.items():
        if (robot, star) not in done:
            done.add((robot, star))
            lines.append(f"  {robot:<9} {star:<6} {'uninitialised':<{width}} "
                         f"{1e3 * scratch.mean():5.2f} ± {1e3 * scratch.std():4.2f}")
        diff = finals.mean() - scratch.mean()
        lines.append(f"  {robot:<9} {star:<6} {condition:<{width}} {1e3 * finals.mean():5.2f} ± "
                     f"{1e3 * finals.std():4.2f}  {1e3 * diff:+5.2f} "
                     f"({diff / scratch.mean():+6.1%})  {f'{above}/{below}':>5} of {n} "
                     f"(p {p:.3f})")
    return lines


def report_text_lines(curves, experiment, where="over the node graph"):
    """report.txt: the thesis' measure first (:func:`headline_lines`, the final errors against
    scratch's), then the trials to convergence and errors per condition, the other readings
    of the time saved (first trial within the band, each curve's own plateau, the bootstrap
    over the seeds, each seed alone) and each condition against random seed by seed."""
    args = (curves, experiment.robots, experiment.stars, experiment.tolerance,
            experiment.babbling_seconds)
    rows, savings = convergence_table(*args)
    first_rows, first_savings = convergence_table(*args, stay=False)
    plateau_rows, plateau_savings = convergence_table(*args, rule="plateau")
    intervals = bootstrap_savings(*args, n_resamples=BOOTSTRAP_RESAMPLES)
    by_seed = per_seed_savings(*args)
    width = name_width(curves)
    lines = [f"Thesis §5.5.3 {where}: {len(experiment.done_seeds)} seed(s) "
             f"({', '.join(map(str, experiment.done_seeds))}), "
             f"{experiment.n_trials} trials a condition. The thesis' measure: the training time "
             f"saved, read off the mean learning curves over the seeds (converged: the mean "
             f"error stays within a band of learning from scratch's final error, the thesis' "
             f"{experiment.tolerance:.0%})", ""]
    lines += headline_lines(curves, experiment) + [""]
    lines += final_error_lines(curves, experiment) + [""]
    lines += [f"trials to convergence of the mean curves (converged: the mean error stays "
              f"within {experiment.tolerance:.0%} of learning from scratch's final error; "
              f"'first within': the first trial within it)", "",
              f"{'target':<9} {'star':<6} {'condition':<{width}} {'converged':>9} "
              f"{'first within':>12}"
              f"   tracking error (mm, mean ± std over seeds): trial 1, trials 1-5, all, last"]
    for (r, s, c, k, n), (*_, first, _) in zip(rows, first_rows):
        runs = 1e3 * np.asarray(curves[f"{r}/{s}/{c}"])
        early, whole = runs[:, :5].mean(axis=1), runs.mean(axis=1)
        lines.append(f"{r:<9} {s:<6} {c:<{width}} {k if k <= n else f'> {n}':>9} "
                     f"{first if first <= n else f'> {n}':>12}   "
                     f"{runs[:, 0].mean():5.2f} ± {runs[:, 0].std():4.2f}, "
                     f"{early.mean():5.2f} ± {early.std():4.2f}, "
                     f"{whole.mean():5.2f} ± {whole.std():4.2f}, "
                     f"{runs[:, -1].mean():5.2f} ± {runs[:, -1].std():4.2f}")
    lines.append("")
    for robot in savings:
        lines.append(f"{robot} as target, other readings of the time saved (the headline: the "
                     f"mean curves within {experiment.tolerance:.0%}, above)")
        lines.append("  first within: " + ", ".join(f"{c} {100 * v:.1f}%"
                                                    for c, v in first_savings[robot].items()))
        plateaus = ", ".join(f"{s} {c} {k if k <= n else f'> {n}'}"
                             for r, s, c, k, n in plateau_rows if r == robot)
        lines.append(f"  each curve by its own plateau (within {experiment.tolerance:.0%} of its "
                     f"own final error, its last {PLATEAU_WINDOW} trials levelled off): "
                     + ", ".join(f"{c} {100 * v:.1f}%" for c, v in plateau_savings[robot].items())
                     + f"; trials: {plateaus}")
        lines.append(f"  95% interval over seeds (bootstrap, {BOOTSTRAP_RESAMPLES} resamples of "
                     f"the seeds), converged: " + ", ".join(
                         f"{c} [{100 * low:.1f}, {100 * high:.1f}]%"
                         for c, (low, high, *_) in intervals[robot].items()))
        lines.append("  share of resamples saving more / as much / less than random: "
                     + ", ".join(f"{c} {100 * more:.0f}/{100 * same:.0f}/{100 * less:.0f}%"
                                 for c, (_, _, more, same, less) in intervals[robot].items()
                                 if c != "random"))
        lines.append("  each seed's curves alone (a secondary reading, not the thesis' mean "
                     "curves), converged: median [quartiles], seeds saving more / less than "
                     "random (Wilcoxon p): " + ", ".join(
                         f"{c} {100 * np.median(v):.1f}% [{100 * np.percentile(v, 25):.1f}, "
                         f"{100 * np.percentile(v, 75):.1f}]"
                         + ("" if c == "random" else f" {more}/{less} (p {p:.3f})")
                         for c, (v, (more, less, _, p)) in by_seed[robot].items()))
    lines.append("")
    if "random" in conditions_in(curves):
        lines += paired_lines(curves, experiment.robots, experiment.stars) + [""]
    lines.append(f"simulated: {simulated_seconds(curves, experiment):.0f} s per robot (trials of "
                 f"{TRIAL_SECONDS} s, learning from scratch "
                 f"{'for every seed' if experiment.start_noise else 'once'}, plus the babbling)")
    return lines


def write_outputs(curves, traces, experiment, out, where="over the node graph"):
    """Write results.json, learning_curves.csv, the figures (Fig. 5-6 only with ``traces``)
    and report.txt into ``out``; ``where`` names what computed the curves in the report."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps({
        "settings": {key: getattr(experiment, key) for key in SETTINGS},
        "curves_m": curves, "seeds": experiment.done_seeds,
        "traces": {f"{r}/{s}": t for (r, s), t in traces.items()}}) + "\n")
    with open(out / "learning_curves.csv", "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["target", "star", "condition", "seed", "trial", "tracking_error_m"])
        for key, runs in curves.items():
            robot, star, condition = key.split("/")
            for seed, errors in zip(experiment.done_seeds, runs):
                writer.writerows([robot, star, condition, seed, trial + 1, repr(error)]
                                 for trial, error in enumerate(errors))
    plot_curves(curves, experiment, out / "fig5_7_5_8_learning_curves.png")
    if traces:
        plot_traces(traces, experiment, out / "fig5_6_traces.png")
    lines = report_text_lines(curves, experiment, where)
    text = "\n".join(lines) + "\n"
    (out / "report.txt").write_text(text)
    return text


def plot_curves(curves, experiment, path):
    fig, axes = plt.subplots(len(experiment.robots), len(experiment.stars), squeeze=False,
                             figsize=(6 * len(experiment.stars), 4.2 * len(experiment.robots)),
                             constrained_layout=True)
    for row, robot in enumerate(experiment.robots):
        for col, star in enumerate(experiment.stars):
            ax = axes[row, col]
            for condition in conditions_in(curves):
                runs = np.asarray(curves[f"{robot}/{star}/{condition}"]) * 1e3
                trials = np.arange(1, runs.shape[1] + 1)
                mean, std = runs.mean(axis=0), runs.std(axis=0)
                line, = ax.plot(trials, mean, marker="o", ms=3, label=condition,
                                linestyle="--" if condition.startswith("own+") else "-")
                # on the log scale the band stops at the lowest seed where mean - std < 0
                ax.fill_between(trials, np.maximum(mean - std, runs.min(axis=0)), mean + std,
                                color=line.get_color(), alpha=0.15)
            final = np.mean(curves[f"{robot}/{star}/uninitialised"], axis=0)[-1] * 1e3
            ax.axhline((1 + experiment.tolerance) * final, color="black", linewidth=0.8,
                       linestyle=":", label=f"converged: within {experiment.tolerance:.0%} "
                                            f"of scratch's final")
            ax.set(title=f"{robot} learning {star}", xlabel="trial",
                   ylabel="tracking error (mm, log scale)", yscale="log")
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))   # trial 1, 2, ..., not 2.5
            ax.yaxis.set_major_formatter(ScalarFormatter())   # 2, 3, 5 mm, not 2×10⁰
            # minor ticks labelled as plain numbers, a subset of them above half a decade
            ax.yaxis.set_minor_formatter(LogFormatter(labelOnlyBase=False,
                                                      minor_thresholds=(2, 0.5)))
            ax.grid(True, which="both", alpha=0.3)
            ax.legend()
    # one star's panel is too narrow for the title on one line
    n_seeds = len(experiment.done_seeds)
    fig.suptitle("Thesis Fig. 5-7/5-8: " + (
        "one seed (a trial is 8.4 s)" if n_seeds == 1 else
        f"mean ± std over {n_seeds} seeds," + ("\n" if len(experiment.stars) < 2 else " ")
        + "the band at most down to the lowest seed (a trial is 8.4 s)"))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_traces(traces, experiment, path):
    star = experiment.stars[-1]
    fig, axes = plt.subplots(1, len(experiment.robots), squeeze=False,
                             figsize=(6 * len(experiment.robots), 5), constrained_layout=True)
    for ax, robot in zip(axes[0], experiment.robots):
        first, last = traces[robot, star]
        desired = np.asarray(first["desired"])
        ax.plot(desired[:, 0], desired[:, 1], "k--", lw=1, label="desired")
        for trace, style in ((first, "tab:red"), (last, "tab:blue")):
            actual = np.asarray(trace["actual"])
            ax.plot(actual[:, 0], actual[:, 1], color=style, lw=1,
                    label=f"trial {trace['trial']}")
        ax.set(title=f"{robot}, {star}, learning from scratch", xlabel="x (m)",
               ylabel="y (m)", aspect="equal")
        ax.legend()
    fig.suptitle("Thesis Fig. 5-6: end effector in the first and last trial")
    fig.savefig(path, dpi=110)
    plt.close(fig)


RTOL = 1e-6


def read_run(run_dir):
    """(settings, {key: {seed: curve}}, traces or None) of one run directory."""
    run_dir = Path(run_dir)
    if (run_dir / "results.json").exists():
        result = json.loads((run_dir / "results.json").read_text())
        cells = {key: dict(zip(result["seeds"], runs))
                 for key, runs in result["curves_m"].items()}
        settings = {"start_noise": 0.0, **result["settings"]}   # older runs: no start noise
        return settings, cells, result["traces"]
    path = run_dir / "learning_curves.csv"
    if not path.exists():
        raise ValueError(f"{run_dir} holds neither results.json nor learning_curves.csv")
    cells, robots, stars = {}, {}, {}
    with open(path, newline="") as handle:
        for row in csv.DictReader(handle):
            robots[row["target"]] = stars[row["star"]] = None   # ordered sets
            key = f"{row['target']}/{row['star']}/{row['condition']}"
            curve = cells.setdefault(key, {}).setdefault(int(row["seed"]), [])
            if int(row["trial"]) != len(curve) + 1:
                raise ValueError(f"{path}: {key} seed {row['seed']} trial {row['trial']} "
                                 f"out of order")
            curve.append(float(row["tracking_error_m"]))
    lengths = {len(curve) for seeds in cells.values() for curve in seeds.values()}
    if len(lengths) != 1:
        raise ValueError(f"{path}: curves of different lengths {sorted(lengths)}")
    return ({"robots": list(robots), "stars": list(stars), "n_trials": lengths.pop()},
            cells, None)


def merge(run_dirs):
    """(curves, traces, experiment-like settings) of the runs in ``run_dirs`` together."""
    runs = [(run_dir, *read_run(run_dir)) for run_dir in run_dirs]
    full = [run for run in runs if set(SETTINGS) <= set(run[1])]
    if not full:
        raise ValueError("at least one run must have a results.json (settings, traces)")
    settings, traces = full[0][1], full[0][3]
    cells, seeds = {}, {}
    for run_dir, run_settings, run_cells, _ in runs:
        if any(run_settings.get(key) != settings[key] for key in run_settings):
            raise ValueError(f"{run_dir} ran other settings: {run_settings} against {settings}")
        for key, by_seed in run_cells.items():
            for seed, curve in by_seed.items():
                seeds[seed] = None
                known = np.asarray(cells.setdefault(key, {}).setdefault(seed, curve))
                if known.shape != np.shape(curve) or not np.allclose(curve, known, rtol=RTOL,
                                                                      atol=0):
                    raise ValueError(f"{key} seed {seed} differs between runs ({run_dir}) by "
                                     f"more than a relative {RTOL:g}: {known.tolist()} against "
                                     f"{list(curve)}; the runs are not reproducible")
    seeds = list(seeds)
    for key, by_seed in cells.items():
        if set(by_seed) != set(seeds):
            raise ValueError(f"{key} lacks seed(s) {sorted(set(seeds) - set(by_seed))}")
        if key.endswith("/uninitialised"):
            check_start_noise(key, by_seed, settings["start_noise"])
    curves = {key: [by_seed[seed] for seed in seeds] for key, by_seed in cells.items()}
    return (curves, {tuple(key.split("/")): value for key, value in traces.items()},
            SimpleNamespace(done_seeds=seeds, **settings))


def check_start_noise(key, by_seed, start_noise):
    """Learning from scratch is the same for every seed without start noise and differs
    between any two seeds with it. A share run with other start noise (a CSV does not say)
    breaks that, and so does, without start noise, a share whose last digits differ (the
    shares of the 10-seed reference gave the youBot's final Star 1 error from scratch as
    2.31123, 2.31217 and 2.31280 mm, because the acceleration then depended on how long the
    simulator's clock had run; another host's floating point can do the same); either is
    refused."""
    seeds = sorted(by_seed)
    for i, a in enumerate(seeds):
        for b in seeds[i + 1:]:
            same = np.allclose(by_seed[a], by_seed[b], rtol=RTOL, atol=0)
            if same != (start_noise == 0):
                cause = ("a share ran with other start noise" if same else "a share ran "
                         "with other start noise, other code or on a host whose floating "
                         "point differs; join such shares only with start_noise > 0")
                raise ValueError(f"{key}: seeds {a} and {b} learn from scratch "
                                 f"{'alike' if same else 'differently'}, which runs with "
                                 f"start_noise {start_noise:g} cannot ({cause})")


def summary_lines(curves, experiment):
    """A short table for the terminal: per target, star and condition the tracking error of
    the first and the last trial (mean over seeds) and the trial from which the mean error
    stays within the convergence tolerance of learning from scratch's final error."""
    rows, _ = convergence_table(curves, experiment.robots, experiment.stars,
                                experiment.tolerance, experiment.babbling_seconds)
    width = name_width(curves)
    lines = [f"{'target':<9} {'star':<6} {'condition':<{width}} {'trial 1 (mm)':>12} "
             f"{'last trial (mm)':>15} {'converged at trial':>18}"]
    for robot, star, condition, k, n in rows:
        mean = 1e3 * np.mean(curves[f"{robot}/{star}/{condition}"], axis=0)
        lines.append(f"{robot:<9} {star:<6} {condition:<{width}} {mean[0]:>12.2f} "
                     f"{mean[-1]:>15.2f} "
                     f"{k if k <= n else f'> {n}':>18}")
    lines.append(f"(converged: the mean error stays within {experiment.tolerance:.0%} of "
                 f"learning from scratch's final error; {len(experiment.done_seeds)} seed(s))")
    return lines
