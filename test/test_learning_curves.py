"""Time to reach a level and time saved (lpa_transfer.evaluation.learning_curves, thesis §6.5)."""
import numpy as np
import pytest

from lpa_transfer.evaluation.learning_curves import (paired_comparison, rank_sum_comparison,
                                                     time_saved, time_to_reach)

TIMES = np.array([300.0, 600.0, 900.0, 1200.0, 1500.0])


def test_time_to_reach_is_the_first_sample_at_the_level():
    assert time_to_reach(TIMES, [0.2, 0.5, 0.81, 0.7, 0.9], 0.81) == 900.0
    assert time_to_reach(TIMES, [0.05, 0.03, 0.02, 0.01, 0.01], 0.02,
                         higher_is_better=False) == 900.0
    assert time_to_reach(TIMES, [0.1, 0.2, 0.3, 0.4, 0.5], 0.6) == np.inf


def test_time_saved_reads_like_the_thesis_poppy_example():
    scratch = np.linspace(0.3, 0.81, 17)
    scratch_times = 300.0 * np.arange(1, 18)     # reaches 0.81 at its end, 5100 s
    level, t_scratch, t, saved = time_saved(scratch_times, scratch, TIMES,
                                            [0.5, 0.7, 0.79, 0.80, 0.81])
    assert (level, t_scratch, t) == (0.81, 5100.0, 1500.0)
    assert saved == pytest.approx(1 - 1500 / 5100)
    *_, never = time_saved(scratch_times, scratch, TIMES, [0.5] * 5)
    assert never == -np.inf


def test_time_saved_at_a_given_level():
    """level: time saved to reach an intermediate rate."""
    scratch = np.linspace(0.3, 0.81, 17)
    scratch_times = 300.0 * np.arange(1, 18)     # 0.36 first reached at 900 s
    level, t_scratch, t, saved = time_saved(scratch_times, scratch, TIMES,
                                            [0.5, 0.7, 0.79, 0.80, 0.81], level=0.36)
    assert (level, t_scratch, t) == (0.36, 900.0, 300.0) and saved == pytest.approx(2 / 3)
    *_, neither = time_saved(scratch_times, scratch, TIMES, [0.5] * 5, level=0.9)
    assert np.isnan(neither)


@pytest.mark.parametrize("times, values", [([1.0, 1.0], [0.1, 0.2]), ([1.0, 2.0], [0.1]),
                                           ([1.0, 2.0], [0.1, np.nan]), ([], [])])
def test_bad_curves_are_refused(times, values):
    with pytest.raises(ValueError):
        time_to_reach(times, values, 0.5)


def test_paired_comparison_counts_seeds_and_gives_wilcoxons_exact_p():
    above, below, n, p = paired_comparison([2, 3, 4, 5, 6, 7], [1, 1, 1, 1, 1, 1])
    assert (above, below, n) == (6, 0, 6) and p == pytest.approx(2 / 2 ** 6)
    # one seed of six ties: it is dropped, the five others give 2 / 2^5
    assert paired_comparison([1, 3, 4, 5, 6, 7], [1] * 6) == (5, 0, 6, pytest.approx(2 / 2 ** 5))
    mixed = paired_comparison([1, 2, 3, 4], [2, 1, 4, 3])
    assert mixed[:3] == (2, 2, 4) and mixed[3] > 0.5
    assert np.isnan(paired_comparison([1.0, 2.0], [1.0, 2.0])[3])       # nothing differs
    assert np.isnan(paired_comparison([1.0], [0.0])[3])                 # one pair


def test_rank_sum_comparison_is_the_share_of_pairs_above_and_mann_whitneys_p():
    share, p = rank_sum_comparison([5, 6, 7], [1, 2, 3, 4])
    assert share == 1.0 and p == pytest.approx(2 / 35)    # exact: 2 of C(7, 3) orderings
    share, p = rank_sum_comparison([1, 2, 3], [1, 2, 3])
    assert share == 0.5 and p == pytest.approx(1.0)
    assert np.isnan(rank_sum_comparison([1.0], [0.0, 2.0])[1])


@pytest.mark.parametrize("compare", [paired_comparison, rank_sum_comparison])
def test_comparisons_refuse_bad_input(compare):
    with pytest.raises(ValueError, match="finite"):
        compare([1.0, np.nan], [1.0, 2.0])
    with pytest.raises(ValueError, match="1-D"):
        compare([[1.0, 2.0]], [1.0, 2.0])
    with pytest.raises(ValueError, match="1-D"):
        compare([], [])


def test_chapter_6_final_rate_is_the_mean_of_the_last_three_evaluations_against_scratch():
    """lpa_transfer.goal_babbling.report's final reaching rate: the mean of a run's last 3
    evaluations, against scratch's over the seeds (unpaired). LPA ends higher on every pair of
    runs by that mean (Mann-Whitney's exact p for 3 against 3: 2 / 20), not by its last
    evaluation alone (0.70, 0.80, 0.85 against 0.70, 0.75, 0.80)."""
    from lpa_transfer.goal_babbling.report import final_rate_lines

    curves = {"scratch": [{"rate": [0.1] + [r] * 3} for r in (0.7, 0.75, 0.8)],
              "LPA/T60": [{"rate": [0.5, 0.95, 0.9, 0.7]}, {"rate": [0.5, 1.0, 0.9, 0.8]},
                          {"rate": [0.5, 1.0, 1.0, 0.85]}]}
    lines = final_rate_lines(curves)
    assert lines[0].startswith("final reaching rate (mean of the last 3 evaluations")
    assert "Mann-Whitney" in lines[0] and "unpaired" in lines[0]
    assert lines[1].split() == ["scratch", "0.750", "±", "0.041"]
    assert lines[2].split() == ["LPA/T60", "0.900", "±", "0.041", "+0.150", "1.00", "(p",
                                "0.100)"]
