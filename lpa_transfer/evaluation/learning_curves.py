"""Reading learning curves: when does a learner reach a level, how much time does transfer
save (thesis §6.5: "the time it takes for the target robot to learn from scratch and the time
it takes to learn when provided with additional knowledge").

A curve is sampled at increasing ``times`` (s of the learner's clock). The thesis reads its
Fig. 6-10 this way: Poppy alone reaches a reaching rate of 0.81 after 5000 s, with transfer
after 1500 s, so 1 − 1500/5000 = 70% of the learning time is saved.
"""
import numpy as np


def _curve(times, values):
    times, values = np.asarray(times, dtype=np.float64), np.asarray(values, dtype=np.float64)
    if times.ndim != 1 or times.shape != values.shape or times.size == 0:
        raise ValueError(f"times and values must be 1-D arrays of one non-zero length, got "
                         f"shapes {times.shape} and {values.shape}")
    if not (np.isfinite(times).all() and np.isfinite(values).all()) \
            or (np.diff(times) <= 0).any():
        raise ValueError("times must increase and times and values be finite")
    return times, values


def time_to_reach(times, values, level, higher_is_better=True):
    """The first time at which the curve reaches ``level`` (>= it, or <= it with
    ``higher_is_better=False``, e.g. for an error); ``inf`` if it never does."""
    times, values = _curve(times, values)
    reached = values >= level if higher_is_better else values <= level
    return float(times[np.argmax(reached)]) if reached.any() else float("inf")


def time_saved(scratch_times, scratch_values, times, values, higher_is_better=True,
               level=None):
    """(level, t_scratch, t, saved): ``level`` (default: the scratch learner's final value),
    when the scratch curve first reaches it, when the other curve does, and the share of time
    saved, 1 − t / t_scratch (negative when it is slower; −inf when it never gets there; nan
    when neither does)."""
    scratch_times, scratch_values = _curve(scratch_times, scratch_values)
    level = float(scratch_values[-1]) if level is None else float(level)
    t_scratch = time_to_reach(scratch_times, scratch_values, level, higher_is_better)
    t = time_to_reach(times, values, level, higher_is_better)
    saved = 1.0 - t / t_scratch if np.isfinite(t_scratch) else float("nan")
    return level, t_scratch, t, saved


def _runs(values, reference, same_length):
    """Two conditions' results over runs as finite, non-empty 1-D float arrays (of one length
    when ``same_length``); ValueError otherwise."""
    values, reference = np.asarray(values, np.float64), np.asarray(reference, np.float64)
    if values.ndim != 1 or reference.ndim != 1 or not (len(values) and len(reference)) \
            or (same_length and values.shape != reference.shape):
        raise ValueError(f"values and reference must be non-empty 1-D arrays"
                         f"{' of one length' if same_length else ''}, got shapes "
                         f"{values.shape} and {reference.shape}")
    if not (np.isfinite(values).all() and np.isfinite(reference).all()):
        raise ValueError("values and reference must be finite")
    return values, reference


def paired_comparison(values, reference):
    """Two conditions seed by seed: ``values[i]`` and ``reference[i]`` come from the same seed
    (which fixes the randomness both conditions share, e.g. a start or a babbling run), so the
    differences pair. Returns ``(above, below, n, p)``: in how many of the ``n`` seeds the
    value is above and below the reference, and the two-sided p of Wilcoxon's signed-rank
    test on the differences (zero differences dropped; nan with fewer than two pairs or none
    that differ). Whether above is better depends on the measure (a rate, an error)."""
    from scipy.stats import wilcoxon

    values, reference = _runs(values, reference, same_length=True)
    diff = values - reference
    p = float("nan")
    if len(diff) >= 2 and np.count_nonzero(diff):
        p = float(wilcoxon(diff, zero_method="wilcox").pvalue)
    return int(np.sum(diff > 0)), int(np.sum(diff < 0)), len(diff), p


def rank_sum_comparison(values, reference):
    """Two conditions whose runs share no randomness (unpaired): ``(share_above, p)``, the
    share of (run, reference run) pairs in which the run's value is above the reference's
    (ties count half: the probability of superiority, 0.5 when the two spread alike) and the
    two-sided p of the Mann-Whitney U test (nan with fewer than two runs on either side)."""
    from scipy.stats import mannwhitneyu

    values, reference = _runs(values, reference, same_length=False)
    diff = values[:, None] - reference[None, :]
    share = float(np.mean((diff > 0) + 0.5 * (diff == 0)))
    p = float("nan")
    if len(values) >= 2 and len(reference) >= 2:
        p = float(mannwhitneyu(values, reference, alternative="two-sided").pvalue)
    return share, p
