"""Reading chapter 5's learning curves (thesis §5.5.3): trials to convergence, training time
saved against learning from scratch, how sure that is over the seeds, and each condition
against another seed by seed.

``curves`` map ``"robot/star/condition"`` to one tracking-error curve (m per trial) per seed,
the seeds in one order for every key.
"""
import numpy as np

from lpa_transfer.evaluation.learning_curves import paired_comparison


#: §5.5.3's conditions, ours (own+transfer: the own babbling too), and the transfer whose
#: prior yields to the robot's own experience (lpa_transfer.learners.yielding)
CONDITIONS = ("uninitialised", "random", "transfer-PA", "transfer-LPA", "own+transfer-PA",
              "own+transfer-LPA", "transfer-PA-yielding", "transfer-LPA-yielding")


TRIAL_SECONDS = 8.4


def trials_to_convergence(curve, reference_final, tolerance, stay=True):
    """First trial (1-based) from which the error stays within (1 + tolerance) of the scratch
    learner's final error (``stay=False``: the first trial within it); len(curve) + 1 when
    there is none."""
    threshold = (1 + tolerance) * reference_final
    curve = np.asarray(curve)
    if not stay:
        within = np.flatnonzero(curve <= threshold)
        return int(within[0]) + 1 if len(within) else len(curve) + 1
    above = np.flatnonzero(curve > threshold)
    return 1 if len(above) == 0 else int(above[-1]) + 2


#: Trials at the end of a curve that must lie within the tolerance of one another for the
#: plateau rule to call it levelled off.
PLATEAU_WINDOW = 3


def trials_to_plateau(curve, tolerance, window=PLATEAU_WINDOW):
    """The per-curve plateau rule (our reading of §5.5.3's "> 20 trials"): the first trial
    (1-based) from which the curve stays within (1 + tolerance) of its own final error, if its
    last ``window`` trials lie within that band of their smallest (it has levelled off);
    len(curve) + 1 ("more than the budget") when it is still falling at the end."""
    curve = np.asarray(curve)
    tail = curve[-window:]
    if tail.max() > (1 + tolerance) * tail.min():
        return len(curve) + 1
    return trials_to_convergence(curve, curve[-1], tolerance)


def conditions_in(curves):
    """The CONDITIONS that ``curves`` holds, in their order (results written before a
    condition existed lack it)."""
    present = {key.rsplit("/", 1)[1] for key in curves}
    return [c for c in CONDITIONS if c in present]


def convergence_table(curves, robots, stars, tolerance, babbling_seconds, stay=True,
                      rule="scratch"):
    """Per target robot: trials to convergence per star and condition (mean curves; ``stay``
    as in :func:`trials_to_convergence`), and the training time saved against learning from
    scratch, as §5.5.3 computes it. ``rule``: "scratch" (within ``tolerance`` of learning from
    scratch's final error) or "plateau" (each curve by its own plateau,
    :func:`trials_to_plateau`)."""
    if rule not in ("scratch", "plateau"):
        raise ValueError(f"rule must be 'scratch' or 'plateau', got {rule!r}")
    rows, savings, conditions = [], {}, conditions_in(curves)
    for robot in robots:
        seconds = {c: 0.0 for c in conditions}
        for star in stars:
            mean = {c: np.mean(curves[f"{robot}/{star}/{c}"], axis=0) for c in conditions}
            final = mean["uninitialised"][-1]
            for condition in conditions:
                k = (trials_to_convergence(mean[condition], final, tolerance, stay)
                     if rule == "scratch" else trials_to_plateau(mean[condition], tolerance))
                rows.append((robot, star, condition, k, len(mean[condition])))
                seconds[condition] += k * TRIAL_SECONDS
        for condition in conditions[1:]:
            seconds[condition] += babbling_seconds
        savings[robot] = {c: 1 - seconds[c] / seconds["uninitialised"] for c in conditions[1:]}
    return rows, savings


#: The convergence bands the reports read the time saved under: within 5, 10 (the thesis')
#: and 20 % of learning from scratch's final error.
BANDS = (0.05, 0.1, 0.2)


def band_savings(curves, robots, stars, babbling_seconds, bands=BANDS):
    """:func:`convergence_table`'s time saved (mean curves, scratch rule) under each band:
    {band: {robot: {condition: saved}}}. How far the verdict rests on the thesis' 10 %: a
    band is a share of a final error of a millimetre or two."""
    return {band: convergence_table(curves, robots, stars, band, babbling_seconds)[1]
            for band in bands}


#: Trials at the end of a curve whose mean is its final error.
FINAL_TRIALS = 3


def scratch_finals(curves, robots, stars):
    """Learning from scratch's final error per ``(robot, star)``, the last trial the
    convergence bands are shares of: ``(mean, std, min, max)`` over the seeds (the mean is the
    mean curve's last trial)."""
    table = {}
    for robot in robots:
        for star in stars:
            last = np.asarray(curves[f"{robot}/{star}/uninitialised"])[:, -1]
            table[robot, star] = (last.mean(), last.std(), last.min(), last.max())
    return table


def finals_against_scratch(curves, robots, stars, last=FINAL_TRIALS):
    """Each initialised condition's final error, the mean of its last ``last`` trials, against
    learning from scratch's, seed by seed (a seed's conditions share its start and babbling;
    without start noise learning from scratch is one run, and the test asks whether the
    seeds' finals differ from its value). Per robot, star and condition: ``(finals, scratch
    finals, (above, below, n, p))``, the arrays over the seeds and
    :func:`lpa_transfer.evaluation.learning_curves.paired_comparison` (Wilcoxon signed-rank)."""
    table = {}
    for robot in robots:
        for star in stars:
            scratch = np.asarray(curves[f"{robot}/{star}/uninitialised"])[:, -last:].mean(1)
            for condition in conditions_in(curves)[1:]:
                finals = np.asarray(curves[f"{robot}/{star}/{condition}"])[:, -last:].mean(1)
                table[robot, star, condition] = (finals, scratch,
                                                 paired_comparison(finals, scratch))
    return table


def bootstrap_savings(curves, robots, stars, tolerance, babbling_seconds, n_resamples=2000,
                      seed=0, reference="random"):
    """How sure the time saved is, given the seeds: :func:`convergence_table`'s savings over
    ``n_resamples`` resamples of the seeds (drawn with replacement, the same seeds for every
    condition, as every seed ran all of them). Per target robot and initialised condition:
    ``(low, high, beats)``, the 2.5 and 97.5 percentiles of its saving and the share of
    resamples in which it saves more than, as much as and less than ``reference`` (nan for
    ``reference`` itself)."""
    n_seeds = len(next(iter(curves.values())))
    rng = np.random.default_rng(seed)
    draws = {}
    for _ in range(n_resamples):
        picks = rng.integers(n_seeds, size=n_seeds)
        _, savings = convergence_table({key: np.asarray(runs)[picks] for key, runs in
                                        curves.items()}, robots, stars, tolerance,
                                       babbling_seconds)
        for robot, saved in savings.items():      # every robot, also with no conditions
            by_condition = draws.setdefault(robot, {})
            for condition, value in saved.items():
                by_condition.setdefault(condition, []).append(value)
    summary = {}
    for robot, by_condition in draws.items():
        base = np.asarray(by_condition.get(reference, np.nan))
        summary[robot] = {c: (*np.percentile(v, [2.5, 97.5]), *(
            (np.mean(np.asarray(v) > base), np.mean(np.asarray(v) == base),
             np.mean(np.asarray(v) < base)) if c != reference and reference in by_condition
            else 3 * (float("nan"),))) for c, v in by_condition.items()}
    return summary


def per_seed_savings(curves, robots, stars, tolerance, babbling_seconds, reference="random"):
    """:func:`convergence_table`'s time saved (scratch rule) seed by seed, each seed's curves
    alone (a secondary reading: the thesis' measure is the mean curves'), and each condition
    against ``reference`` over the seeds (a seed's conditions share its start and babbling,
    so they pair). Per target robot and initialised condition: ``(saved (n_seeds,), (more,
    less, n, p))``, in how many seeds it saves more and less than ``reference`` and
    Wilcoxon's p (:func:`lpa_transfer.evaluation.learning_curves.paired_comparison`; nan for
    ``reference``)."""
    n_seeds = len(next(iter(curves.values())))
    saved = {}
    for seed in range(n_seeds):
        _, savings = convergence_table({key: np.asarray(runs)[[seed]] for key, runs in
                                        curves.items()}, robots, stars, tolerance,
                                       babbling_seconds)
        for robot, by_condition in savings.items():      # every robot, also with no conditions
            for condition, value in by_condition.items():
                saved.setdefault(robot, {}).setdefault(condition, []).append(value)
            saved.setdefault(robot, {})
    table = {}
    for robot, by_condition in saved.items():
        base = by_condition.get(reference)
        table[robot] = {c: (np.asarray(v), paired_comparison(v, base)
                            if base is not None and c != reference else
                            (0, 0, len(v), float("nan")))
                        for c, v in by_condition.items()}
    return table


def paired_against(curves, robots, stars, early_trials=5, reference="random"):
    """Each initialised condition against ``reference`` seed by seed (a seed's conditions
    share its start and its babbling, so they pair): per robot, star and condition, for the
    mean error over the first ``early_trials`` trials and over all trials, ``(lower, n, p)``:
    in how many of the ``n`` seeds the condition's error is below the reference's, and
    :func:`lpa_transfer.evaluation.learning_curves.paired_comparison`'s p (Wilcoxon signed-rank)."""
    def compare(ours, theirs):
        _, lower, n, p = paired_comparison(ours, theirs)
        return lower, n, p

    table = {}
    for robot in robots:
        for star in stars:
            base = np.asarray(curves[f"{robot}/{star}/{reference}"])
            for condition in conditions_in(curves)[1:]:
                if condition == reference:
                    continue
                runs = np.asarray(curves[f"{robot}/{star}/{condition}"])
                table[robot, star, condition] = (
                    compare(runs[:, :early_trials].mean(1), base[:, :early_trials].mean(1)),
                    compare(runs.mean(1), base.mean(1)))
    return table


def simulated_seconds(curves, experiment):
    """Simulated time per robot: its trials (learning from scratch runs once, whatever the
    number of seeds, unless ``start_noise`` > 0) and the babbling of every seed."""
    once = experiment.start_noise == 0
    trials = sum(len(runs[0]) if once and key.endswith("/uninitialised")
                 else sum(map(len, runs)) for key, runs in curves.items() if runs)
    return (trials * TRIAL_SECONDS / len(experiment.robots)
            + len(experiment.done_seeds) * experiment.babbling_seconds)
