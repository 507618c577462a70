"""The chapter 5 experiment's analysis: trials to convergence, time saved, joining runs."""
import json
import re
import runpy

import numpy as np
import pytest

from conftest import ROOT
from lpa_transfer.inverse_dynamics.analysis import (BANDS, CONDITIONS, TRIAL_SECONDS,
                                                    band_savings, bootstrap_savings,
                                                    convergence_table, finals_against_scratch,
                                                    paired_against, per_seed_savings,
                                                    scratch_finals, trials_to_convergence)
from lpa_transfer.inverse_dynamics.report import merge


def merge_main(argv):
    """The scenario's thin merge_results.py, run as a script would be."""
    script = ROOT / "scenarios" / "inverse_dynamics" / "merge_results.py"
    return runpy.run_path(str(script))["main"](argv)

SETTINGS = {"robots": ["a", "b"], "stars": ["star1"], "n_trials": 3, "tolerance": 0.1,
            "babbling_seconds": 2.0}


def test_trials_to_convergence_is_the_first_trial_that_stays_within_the_tolerance():
    assert trials_to_convergence([5.0, 1.05, 1.0], 1.0, 0.1) == 2
    assert trials_to_convergence([5.0, 1.05, 2.0, 1.0], 1.0, 0.1) == 4   # a relapse counts
    assert trials_to_convergence([1.0, 1.0], 1.0, 0.1) == 1
    assert trials_to_convergence([3.0, 2.0], 1.0, 0.1) == 3              # never: n + 1
    assert trials_to_convergence([5.0, 1.05, 2.0, 1.0], 1.0, 0.1, stay=False) == 2
    assert trials_to_convergence([3.0, 2.0], 1.0, 0.1, stay=False) == 3


def test_time_saved_counts_trials_and_babbling_like_the_thesis():
    curves = {"a/star1/uninitialised": [[4.0, 2.0, 1.0]], "a/star1/random": [[1.0, 1.0, 1.0]],
              "a/star1/transfer-PA": [[2.0, 1.0, 1.0]], "a/star1/transfer-LPA": [[3.0, 3.0, 3.0]]}
    rows, savings = convergence_table(curves, ["a"], ["star1"], 0.1, 2.0)
    assert [row[3] for row in rows] == [3, 1, 2, 4]
    scratch = 3 * TRIAL_SECONDS
    assert savings["a"]["random"] == pytest.approx(1 - (TRIAL_SECONDS + 2.0) / scratch)
    assert savings["a"]["transfer-LPA"] < 0      # slower than learning from scratch
    # results written before the own+transfer conditions existed have no such rows
    assert {row[2] for row in rows} == set(CONDITIONS[:4]) and set(savings["a"]) == {
        "random", "transfer-PA", "transfer-LPA"}


def test_bootstrap_over_seeds_brackets_the_saving_and_counts_who_saves_more():
    """Seeds that all agree give a zero-width interval at the saving; a condition that
    converges a trial earlier than random on every seed saves more in every resample."""
    same = {"a/star1/uninitialised": [[4.0, 2.0, 1.0]] * 4,
            "a/star1/random": [[2.0, 1.0, 1.0]] * 4, "a/star1/transfer-PA": [[1.0, 1.0, 1.0]] * 4}
    _, savings = convergence_table(same, ["a"], ["star1"], 0.1, 2.0)
    summary = bootstrap_savings(same, ["a"], ["star1"], 0.1, 2.0, n_resamples=50)
    low, high, more, as_much, less = summary["a"]["transfer-PA"]
    assert low == high == pytest.approx(savings["a"]["transfer-PA"])
    assert (more, as_much, less) == (1.0, 0.0, 0.0)
    assert np.isnan(summary["a"]["random"][2:]).all()
    # seeds that disagree: transfer-PA converges at trial 1 on two seeds, at trial 3 on two
    mixed = dict(same, **{"a/star1/transfer-PA": [[1.0, 1.0, 1.0]] * 2 + [[3.0, 3.0, 1.0]] * 2})
    low, high, more, as_much, less = bootstrap_savings(mixed, ["a"], ["star1"], 0.1, 2.0,
                                                       n_resamples=400)["a"]["transfer-PA"]
    assert low < savings["a"]["random"] < high and 0 < more < 1 and 0 < less < 1
    assert more + as_much + less == pytest.approx(1.0)
    again = bootstrap_savings(mixed, ["a"], ["star1"], 0.1, 2.0, n_resamples=400)
    assert again["a"]["transfer-PA"] == (low, high, more, as_much, less)     # seeded



def test_seed_by_seed_savings_judge_each_seed_by_its_own_curves():
    """Each seed's curves alone give its saving (not the mean curve's): transfer-PA converges
    at trial 1 on three seeds and never on one, where the mean curve converges at trial 3;
    random at trial 2 on every seed, so transfer-PA saves more on 3 seeds and less on 1."""
    scratch = [[4.0, 2.0, 1.0]] * 4
    curves = {"a/star1/uninitialised": scratch, "a/star1/random": [[2.0, 1.0, 1.0]] * 4,
              "a/star1/transfer-PA": [[1.0, 1.0, 1.0]] * 3 + [[9.0, 9.0, 9.0]]}
    table = per_seed_savings(curves, ["a"], ["star1"], 0.1, 2.0)
    saved, (more, less, n, p) = table["a"]["transfer-PA"]
    one = 1 - (TRIAL_SECONDS + 2.0) / (3 * TRIAL_SECONDS)
    never = 1 - (4 * TRIAL_SECONDS + 2.0) / (3 * TRIAL_SECONDS)
    np.testing.assert_allclose(saved, [one, one, one, never])
    assert (more, less, n) == (3, 1, 4) and 0 < p <= 1
    _, mean_savings = convergence_table(curves, ["a"], ["star1"], 0.1, 2.0)
    assert mean_savings["a"]["transfer-PA"] == pytest.approx(never)   # the mean curve's view
    assert np.isnan(table["a"]["random"][1][3])


def test_a_run_of_learning_from_scratch_only_has_nothing_to_bootstrap():
    """conditions [uninitialised] (e.g. seed shares of scratch runs): every robot is in the
    summary, with no condition (a run of the chapter 5 graph stopped on a KeyError here)."""
    scratch = {f"{robot}/star1/uninitialised": [[4.0, 2.0, 1.0]] * 2 for robot in ("a", "b")}
    assert bootstrap_savings(scratch, ["a", "b"], ["star1"], 0.1, 2.0, n_resamples=5) == \
        {"a": {}, "b": {}}
    assert per_seed_savings(scratch, ["a", "b"], ["star1"], 0.1, 2.0) == {"a": {}, "b": {}}


def test_paired_comparison_counts_the_seeds_each_condition_beats_random_in():
    """Seed by seed against random: lower early on every seed of 6 gives Wilcoxon's exact
    two-sided p = 2 / 2^6; a condition equal to random on every seed has no p."""
    random = [[3.0 + seed, 2.0, 1.0] for seed in range(6)]
    curves = {"a/star1/uninitialised": [[9.0, 5.0, 1.0]] * 6, "a/star1/random": random,
              "a/star1/transfer-PA": [[2.0 + seed, 2.0, 1.0] for seed in range(6)],
              "a/star1/transfer-LPA": random,
              "a/star1/own+transfer-PA": [[3.0 + seed, 2.0, 1.0 + (seed % 2) - 0.5]
                                          for seed in range(6)]}
    table = paired_against(curves, ["a"], ["star1"], early_trials=2)
    assert set(table) == {("a", "star1", c) for c in
                          ("transfer-PA", "transfer-LPA", "own+transfer-PA")}
    (lower, n, p), (lower_all, _, p_all) = table["a", "star1", "transfer-PA"]
    assert (lower, n, lower_all) == (6, 6, 6) and p == pytest.approx(2 / 2 ** 6)
    assert p_all == pytest.approx(p)
    (lower, n, p), _ = table["a", "star1", "transfer-LPA"]
    assert (lower, n) == (0, 6) and np.isnan(p)
    # equal over the first two trials, lower in the last on half of the seeds
    early, whole = table["a", "star1", "own+transfer-PA"]
    assert early[0] == 0 and np.isnan(early[2]) and whole[0] == 3 and 0.5 < whole[2] <= 1


def write_run(path, seeds, offset, settings=SETTINGS, conditions=CONDITIONS):
    """Made-up curves; learning from scratch is the same for every seed unless the settings
    have start noise, as in the experiment."""
    def varies(condition):
        return condition != "uninitialised" or settings.get("start_noise", 0) > 0
    curves = {f"{robot}/star1/{condition}": [[offset + varies(condition) * seed + trial
                                              for trial in (3, 2, 1)] for seed in seeds]
              for robot in settings["robots"] for condition in conditions}
    trace = {"trial": 1, "desired": [[0.0, 0.0], [1.0, 1.0]], "actual": [[0.0, 0.1], [1.0, 0.9]]}
    path.mkdir()
    (path / "results.json").write_text(json.dumps({
        "settings": settings, "curves_m": curves, "seeds": seeds,
        "traces": {f"{robot}/star1": [trace, dict(trace, trial=3)]
                   for robot in settings["robots"]}}))
    return curves


def test_merging_runs_of_other_seeds_gives_the_outputs_of_one_run(tmp_path):
    first = write_run(tmp_path / "a", [0, 2], 0.0)
    second = write_run(tmp_path / "b", [1], 0.0)
    curves, traces, experiment = merge([tmp_path / "a", tmp_path / "b"])
    assert experiment.done_seeds == [0, 2, 1] and experiment.n_trials == 3
    for key, runs in curves.items():
        assert runs == first[key] + second[key]
    assert merge_main(["merge", str(tmp_path / "all"), str(tmp_path / "a"),
                       str(tmp_path / "b")]) == 0
    merged = json.loads((tmp_path / "all" / "results.json").read_text())
    assert merged["seeds"] == [0, 2, 1] and merged["settings"] == dict(SETTINGS, start_noise=0.0)
    report = (tmp_path / "all" / "report.txt").read_text()
    lines = report.splitlines()
    assert "3 seed(s) (0, 2, 1)" in lines[0]
    # the made-up mean curves of the initialised conditions never converge, at any tolerance;
    # the report leads with that saving of the mean curves, the thesis' measure, every
    # condition the curves hold included
    never = 100 * (1 - (4 * TRIAL_SECONDS + 2.0) / (3 * TRIAL_SECONDS))
    assert lines[2].startswith(f"a as target, training time saved by the mean curves over the "
                               f"3 seed(s), converged within 10% (trials x 8.4 s, + 2 s "
                               f"babbling for initialised runs): random {never:.1f}%")
    assert all(f"{c} {never:.1f}%" in lines[2] for c in CONDITIONS[1:])
    assert lines[3] == ("  converged within 5% / 10% / 20% of scratch's final error: " + ", ".join(
        f"{c} {never:.1f} / {never:.1f} / {never:.1f}%" for c in CONDITIONS[1:]))
    # scratch ends at 1 m on every seed: the bands are 5, 10 and 20 cm
    assert "star1 1000.00 ± 0.00 (1000.00-1000.00), 50.00 / 100.00 / 200.00 mm" in lines[4]
    # final errors, all 3 trials: scratch 2 m on every seed, the others 2, 4 and 3 m (seeds 0,
    # 2, 1), above scratch on two seeds, one tie: Wilcoxon's exact p of two pairs is 0.5
    assert re.search(r"a\s+star1\s+random\s+3000.00 ± 816.50  \+1000.00 \(\+50.0%\)\s+2/0 of 3 "
                     r"\(p 0.500\)", report)
    assert report.index("by the mean curves") < report.index("each seed's curves alone") \
        < report.index("paired over seeds against random")
    assert "one run per condition" not in report
    # ... but resamples that draw seed 0 alone (its curves equal scratch's) converge at trial 3
    assert (f"bootstrap, 2000 resamples of the seeds), converged: random [{never:.1f}, "
            f"{100 * (1 - (3 * TRIAL_SECONDS + 2.0) / (3 * TRIAL_SECONDS)):.1f}]%") in report
    # made-up curves: every condition equals random on every seed, so no seed is lower
    assert "paired over seeds against random" in report
    assert re.search(r"a\s+star1\s+transfer-PA\s+0/3 \(p nan\),\s+0/3 \(p nan\)", report)
    # per robot: 3 trials from scratch once, each initialised condition 3 seeds x 3 trials,
    # 3 x 2 s babbling
    trials = 3 + 9 * (len(CONDITIONS) - 1)
    assert f"simulated: {trials * 8.4 + 6:.0f} s per robot" in report
    for name in ("learning_curves.csv", "fig5_7_5_8_learning_curves.png", "fig5_6_traces.png"):
        assert (tmp_path / "all" / name).stat().st_size > 0


def test_merging_refuses_a_seed_that_two_runs_give_differently_and_other_settings(tmp_path):
    write_run(tmp_path / "a", [0, 1], 0.0)
    write_run(tmp_path / "b", [1], 0.0)       # seed 1 again, the same curves: reproducible
    write_run(tmp_path / "c", [1], 0.5)       # seed 1 again, other curves
    write_run(tmp_path / "d", [5], 0.0, dict(SETTINGS, n_trials=4))
    curves, _, experiment = merge([tmp_path / "a", tmp_path / "b"])
    assert experiment.done_seeds == [0, 1] and all(len(runs) == 2 for runs in curves.values())
    with pytest.raises(ValueError, match="a/star1/uninitialised seed 1 differs between runs"):
        merge([tmp_path / "a", tmp_path / "c"])
    with pytest.raises(ValueError, match="ran other settings"):
        merge([tmp_path / "a", tmp_path / "d"])


def test_merging_runs_of_other_conditions_joins_them_and_checks_the_shared_curves(tmp_path):
    """A run of the own+transfer conditions joins the reference result of the others (a
    learning_curves.csv only); learning from scratch, which both ran, must agree."""
    first = write_run(tmp_path / "a", [0, 1], 0.0, conditions=CONDITIONS[:4])
    second = write_run(tmp_path / "b", [0, 1], 0.0, conditions=CONDITIONS[:1] + CONDITIONS[4:])
    assert merge_main(["merge", str(tmp_path / "ref"), str(tmp_path / "a")]) == 0
    (tmp_path / "ref" / "results.json").unlink()            # keep only the CSV, as committed
    curves, traces, experiment = merge([tmp_path / "ref", tmp_path / "b"])
    assert sorted(curves) == sorted({**first, **second}) and experiment.done_seeds == [0, 1]
    for key, runs in {**first, **second}.items():
        assert curves[key] == runs
    assert set(traces) == {("a", "star1"), ("b", "star1")} and experiment.tolerance == 0.1
    write_run(tmp_path / "c", [0, 1], 1e-3, conditions=CONDITIONS[:1] + CONDITIONS[4:])
    with pytest.raises(ValueError, match="uninitialised seed 0 differs"):
        merge([tmp_path / "ref", tmp_path / "c"])
    write_run(tmp_path / "e", [0, 1], 1e-14, conditions=CONDITIONS[:1] + CONDITIONS[4:])
    curves, _, _ = merge([tmp_path / "ref", tmp_path / "e"])   # last-digit noise: accepted,
    assert curves["a/star1/uninitialised"] == first["a/star1/uninitialised"]   # first kept
    write_run(tmp_path / "d", [1], 0.0, conditions=CONDITIONS[:1] + CONDITIONS[4:])
    with pytest.raises(ValueError, match=r"own\+transfer-PA lacks seed\(s\) \[0\]"):
        merge([tmp_path / "ref", tmp_path / "d"])
    with pytest.raises(ValueError, match="at least one run must have a results.json"):
        merge([tmp_path / "ref"])


def test_merging_runs_with_start_noise_checks_that_scratch_varies_by_seed(tmp_path):
    """With start noise every seed learns from scratch from its own start: such shares join,
    and counted time includes every seed's scratch run; a share without start noise (whose
    scratch curves are alike) is refused, also as a CSV that does not say."""
    noisy = dict(SETTINGS, start_noise=1e-3)
    write_run(tmp_path / "a", [0, 1], 0.0, noisy)
    write_run(tmp_path / "b", [2], 0.0, noisy)
    curves, _, experiment = merge([tmp_path / "a", tmp_path / "b"])
    assert curves["a/star1/uninitialised"] == [[3, 2, 1], [4, 3, 2], [5, 4, 3]]
    assert merge_main(["merge", str(tmp_path / "all"), str(tmp_path / "a"),
                       str(tmp_path / "b")]) == 0
    report = (tmp_path / "all" / "report.txt").read_text()
    # per robot: every condition x 3 seeds x 3 trials, scratch included, and 3 x 2 s babbling
    assert f"simulated: {9 * len(CONDITIONS) * 8.4 + 6:.0f} s per robot" in report
    assert "learning from scratch for every seed" in report
    write_run(tmp_path / "quiet", [3, 4], 0.0)
    assert merge_main(["merge", str(tmp_path / "ref"), str(tmp_path / "quiet")]) == 0
    (tmp_path / "ref" / "results.json").unlink()
    with pytest.raises(ValueError, match="learn from scratch alike, which runs with "
                                         "start_noise 0.001 cannot"):
        merge([tmp_path / "a", tmp_path / "ref"])
    with pytest.raises(ValueError, match="ran other settings"):
        merge([tmp_path / "a", tmp_path / "quiet"])
    write_run(tmp_path / "c", [5, 6], 0.0, noisy)
    assert merge_main(["merge", str(tmp_path / "noisy_ref"), str(tmp_path / "c")]) == 0
    (tmp_path / "noisy_ref" / "results.json").unlink()
    with pytest.raises(ValueError, match="learn from scratch differently, which runs with "
                                         "start_noise 0 cannot"):
        merge([tmp_path / "quiet", tmp_path / "noisy_ref"])


def test_the_plateau_rule_judges_each_curve_by_its_own_end():
    """Convergence of a curve: one still falling at the end has not converged within the
    budget ("> n"); a levelled curve converges where it enters its own final band."""
    from lpa_transfer.inverse_dynamics.analysis import convergence_table, trials_to_plateau

    levelled = [10.0, 6.0, 3.0, 2.05, 2.02, 2.0, 2.01, 2.0]
    falling = [10.0, 8.0, 6.5, 5.0, 4.0, 3.2, 2.6, 2.1]
    assert trials_to_plateau(levelled, 0.1) == 4
    assert trials_to_plateau(falling, 0.1) == len(falling) + 1
    assert trials_to_plateau(falling, 0.6) == 6          # its last 3 within 60 %
    curves = {"youbot/star1/uninitialised": [falling], "youbot/star1/random": [levelled]}
    rows, savings = convergence_table(curves, ["youbot"], ["star1"], 0.1, 0.0, rule="plateau")
    assert [row[3] for row in rows] == [9, 4]
    assert savings["youbot"]["random"] == pytest.approx(1 - 4 / 9)
    with pytest.raises(ValueError, match="rule must be"):
        convergence_table(curves, ["youbot"], ["star1"], 0.1, 0.0, rule="slope")


def test_savings_under_the_three_bands_read_the_mean_curves():
    """Within 5, 10 and 20 % of scratch's final error (1): scratch converges at trials 4, 4
    and 3, transfer-PA at 3, 2 and 1, so it saves 1/4, 1/2 and 2/3 of the time."""
    curves = {"a/star1/uninitialised": [[4.0, 2.0, 1.15, 1.0]] * 2,
              "a/star1/transfer-PA": [[1.3, 1.0, 1.04, 1.0], [1.06, 1.16, 1.04, 1.0]]}
    saved = band_savings(curves, ["a"], ["star1"], 0.0)
    assert sorted(saved) == list(BANDS) == [0.05, 0.1, 0.2]
    assert [saved[b]["a"]["transfer-PA"] for b in BANDS] == pytest.approx([1 / 4, 1 / 2, 2 / 3])
    assert saved[0.1] == convergence_table(curves, ["a"], ["star1"], 0.1, 0.0)[1]


def test_scratch_finals_give_the_spread_of_the_last_trial_over_the_seeds():
    curves = {"a/star1/uninitialised": [[4.0, 2.0, 1.0], [4.0, 2.0, 1.2]]}
    mean, std, low, high = scratch_finals(curves, ["a"], ["star1"])["a", "star1"]
    assert (mean, std, low, high) == pytest.approx((1.1, 0.1, 1.0, 1.2))


def test_final_errors_pair_each_seed_with_scratch_over_the_last_three_trials():
    """The final error is the mean of the last 3 trials: transfer-PA ends below scratch on
    every seed of 6 (Wilcoxon's exact p 2 / 2^6) although its last trial equals scratch's;
    random equals scratch's over the last 3 trials on every seed (no p) although its first
    trial differs; a new condition is compared like the others."""
    scratch = [[9.0, 3.0 + seed, 2.0, 1.0] for seed in range(6)]
    curves = {"a/star1/uninitialised": scratch,
              "a/star1/random": [[5.0, 3.0 + seed, 2.0, 1.0] for seed in range(6)],
              "a/star1/transfer-PA": [[5.0, 2.0 + seed, 1.5, 1.0] for seed in range(6)],
              "a/star1/transfer-PA-yielding": [[5.0, 4.0 + seed, 2.5, 1.0] for seed in range(6)]}
    table = finals_against_scratch(curves, ["a"], ["star1"])
    assert list(table) == [("a", "star1", c) for c in ("random", "transfer-PA",
                                                       "transfer-PA-yielding")]
    finals, base, (above, below, n, p) = table["a", "star1", "transfer-PA"]
    np.testing.assert_allclose(base, [(3.0 + seed + 3.0) / 3 for seed in range(6)])
    np.testing.assert_allclose(finals, base - 0.5)
    assert (above, below, n) == (0, 6, 6) and p == pytest.approx(2 / 2 ** 6)
    _, _, (above, below, n, p) = table["a", "star1", "random"]
    assert (above, below, n) == (0, 0, 6) and np.isnan(p)
    _, _, (above, below, n, p) = table["a", "star1", "transfer-PA-yielding"]
    assert (above, below) == (6, 0) and p == pytest.approx(2 / 2 ** 6)
