"""Chapter 4's in-process experiment (thesis §4.5): lpa_transfer.lfd.experiment (the
scenario, demonstrations, correspondences, mapping error); scenarios/lfd/accuracy.py is in
test_lfd_accuracy_script.py, the sweeps and skills in test_lfd_skills.py."""
import numpy as np
import pytest
import yaml

from conftest import ROOT
from lpa_transfer.robots.inverse_kinematics import solve_many
from lpa_transfer.robots.kinematics import arm_kinematics
from lpa_transfer.lfd.experiment import (RememberedPairs, collect_pairs, demonstrations,
                                         executed_errors, load_setup)

CONFIG = yaml.safe_load((ROOT / "scenarios" / "lfd" / "config.yaml").read_text())[
    "/**"]["ros__parameters"]
BOX = (CONFIG["task_box_low"], CONFIG["task_box_high"])


@pytest.fixture(scope="module")
def setup():
    return load_setup(ROOT / CONFIG["frames"], ROOT)


@pytest.fixture(scope="module")
def demos(setup):
    return demonstrations(setup.demonstrator, ["LShape", "Zshape"], BOX, seed=0, n_demos=2,
                          n_samples=30)


def test_setup_reads_both_robots(setup):
    assert set(setup.learners) == {"pr2_right_arm", "meka_right_arm"}
    assert setup.learners["meka_right_arm"].joint_map.n_joints == 4
    with pytest.raises(ValueError):
        load_setup(ROOT / "scenarios" / "lfd" / "config.yaml", ROOT)   # not a frames file


def test_demonstrations_are_traced_by_the_human_inside_the_box(setup, demos):
    """Each demonstration: 30 points inside the box, the human's FK of its joints on them
    (IK residual <= 1e-5 m), joints within limits, times from 0; the demonstrations of a
    shape share one placement, so they differ only as the writer's did."""
    assert [d.shape for d in demos] == ["LShape"] * 2 + ["Zshape"] * 2
    arm = arm_kinematics(setup.demonstrator, 4)
    for d in demos:
        assert d.q.shape == (30, 4) and d.x.shape == (30, 3) and d.rows.shape == (30, 7)
        assert d.times[0] == 0 and (np.diff(d.times) > 0).all()
        assert np.linalg.norm(arm.forward(d.q) - d.x, axis=1).max() <= 1e-5
        assert (d.x >= np.array(BOX[0]) - 1e-9).all() and (d.x <= np.array(BOX[1]) + 1e-9).all()
        limits = arm.joint_limits
        assert ((d.q >= limits[:, 0]) & (d.q <= limits[:, 1])).all()
    # both L demonstrations end at LASA's common end point (0, 0), placed identically
    np.testing.assert_allclose(demos[0].x[-1], demos[1].x[-1], atol=1e-12)
    assert not np.allclose(demos[0].x, demos[1].x)
    with pytest.raises(ValueError, match="reach"):
        demonstrations(setup.demonstrator, ["LShape"], ([1.0, 1.0, 1.0], [1.5, 1.5, 1.5]),
                       seed=0, n_demos=1, n_samples=10)


def test_collect_pairs_is_seeded_and_gives_the_number_asked(setup):
    """The same seed gives the same pairs; RememberedPairs hands back what it collected for
    the same learner, demonstrator, size and seed, and collects anew for another."""
    learner = setup.learners["pr2_right_arm"]        # keeps about a quarter of its poses
    remembered = RememberedPairs()
    demo, robot, tried = remembered(learner, setup.demonstrator, 120, seed=2)
    assert demo.shape == robot.shape == (120, 7) and tried >= 240
    again = collect_pairs(learner, setup.demonstrator, 120, seed=2)
    np.testing.assert_array_equal(robot, again[1])
    np.testing.assert_array_equal(demo, again[0])
    assert remembered(learner, setup.demonstrator, 120, seed=2)[1] is robot
    other = collect_pairs(learner, setup.demonstrator, 120, seed=3)
    assert not np.allclose(robot, other[1])
    np.testing.assert_allclose(learner.task_frame.to_demonstrator(robot[:, 4:]), demo[:, 4:],
                               atol=1e-12)
    meka = remembered(setup.learners["meka_right_arm"], setup.demonstrator, 120, seed=2)
    assert meka[1].shape == (120, 7) and not np.allclose(meka[1], robot)


def test_executed_errors_vanish_on_the_robots_own_ik(setup, demos):
    """Robot rows from the robot's own IK of T_R^H x_H execute onto the task points (the
    mapping error of a perfect mapping is 0); moving a joint shows up as an error."""
    learner = setup.learners["meka_right_arm"]
    arm = arm_kinematics(learner.robot, 4)
    x_robot = learner.task_frame.to_robot(demos[0].x)
    q, residuals = solve_many(arm.forward, x_robot, np.tile(arm.joint_limits.mean(axis=1),
                                                            (len(x_robot), 1)), arm.joint_limits)
    assert residuals.max() < 1e-6
    rows = np.hstack((q, x_robot))
    assert executed_errors(learner, rows, demos[0].x).max() < 1e-6
    rows[:, 3] += 0.1
    assert executed_errors(learner, rows, demos[0].x).min() > 0.005
