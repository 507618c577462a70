"""Experiment 2's scene (thesis §6.5.2): how much of Poppy's test grid each robot
placement lets Poppy reach, with and without its torso, and how much the joint ranges it shares
with Nao cover; and Nao's task box, scaled from X_bounds about the shoulders.

    nice -n 10 python -m studies.goal_babbling.nao_poppy_zup

Placements: "y-up" (poppy_right_arm.toml / nao_right_arm.toml, X_bounds read in the
simulator's y-up world, the shoulders moved to one point: today's nao_poppy.yaml) and "z-up"
(the *_zup.toml files: the thesis' z-up scene, each robot standing at its own origin; X_bounds
read in the scene, world = (x_S, z_S, -y_S)). Printed per placement, over the 5 cm grid of
X_bounds (378 points), with the evaluation's reaching tolerance 0.015 m and 200 000 joint
samples (lpa_transfer.goal_babbling.reaching.evaluation_points, IK-checked): the reachable
points (all 5 joints), those reachable with the torso at home, and with the torso at home and
the 4 shared joints in the ranges both robots have (what Nao's experience can teach at most).
"""
import dataclasses

import numpy as np

from lpa_transfer.exploration import shared_limits
from lpa_transfer.goal_babbling import evaluation_points, grid
from lpa_transfer.robots import chain_frames, hold_at_home, load_robot_params, robot_kinematics

ROBOTS = "scenarios/robots"
X_BOUNDS = np.array([(0.1, 0.05, 0.4), (0.4, 0.3, 0.8)])        # §6.5.2, in the thesis' scene
SCENE_TO_WORLD = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])   # z-up scene -> y-up world
HOMES = {"poppy": [0.0, 0.2, -0.7, 0.4, 1.3], "nao": [0.2, -0.7, 0.4, 1.3, 0.0]}
SHARED = {"nao": [0, 1, 2, 3], "poppy": [1, 2, 3, 4]}
ARM_RATIO = 0.2195 / 0.3565   # Nao / Poppy arm length (nao_right_arm.toml)
PLACEMENTS = {"y-up": ("", np.eye(3)), "z-up": ("_zup", SCENE_TO_WORLD)}


def world_box(to_world):
    corners = X_BOUNDS @ to_world.T
    return corners.min(axis=0), corners.max(axis=0)


def shoulder(params, home, joint):
    """World position of joint ``joint``'s origin at ``home``."""
    return chain_frames(params, np.array([home]))[0, joint, :3, 3]


def measure(suffix, to_world, n_joint_samples=200_000):
    poppy = load_robot_params(f"{ROBOTS}/poppy_right_arm{suffix}.toml")
    nao = load_robot_params(f"{ROBOTS}/nao_right_arm{suffix}.toml")
    arms = {"poppy": robot_kinematics(poppy, HOMES["poppy"]),
            "nao": robot_kinematics(nao, HOMES["nao"])}
    box = world_box(to_world)
    points = lambda arm: len(evaluation_points(arm, box, spacing=0.05, tolerance=0.015,  # noqa: E731,E501
                                               n_joint_samples=n_joint_samples))
    torso_home = hold_at_home(arms["poppy"], SHARED["poppy"])
    limits = np.array(torso_home.joint_limits)
    limits[SHARED["poppy"]] = shared_limits(arms["nao"], arms["poppy"], SHARED["nao"],
                                            SHARED["poppy"])
    common = dataclasses.replace(torso_home, joint_limits=limits)
    # Nao's box: X_bounds scaled about Poppy's right shoulder by the arm-length ratio and
    # moved onto Nao's right shoulder (in the scene's axes)
    s_poppy = to_world.T @ shoulder(poppy, HOMES["poppy"], 1)
    s_nao = to_world.T @ shoulder(nao, HOMES["nao"], 0)
    nao_box = s_nao + ARM_RATIO * (X_BOUNDS - s_poppy)
    hands = {name: to_world.T @ arm.forward(arm.home[None])[0] for name, arm in arms.items()}
    return dict(grid=len(grid(box, 0.05)), reachable=points(arms["poppy"]),
                torso_home=points(torso_home), common=points(common),
                poppy_shoulder=s_poppy, nao_shoulder=s_nao, nao_box=nao_box, hands=hands)


def main():
    np.set_printoptions(precision=3, suppress=True)
    for name, (suffix, to_world) in PLACEMENTS.items():
        m = measure(suffix, to_world)
        n, r = m["grid"], m["reachable"]
        print(f"{name}: grid {n}; reachable {r} ({r / n:.3f}); torso at home {m['torso_home']} "
              f"(torso needed for {1 - m['torso_home'] / r:.3f} of the reachable); shared "
              f"ranges, torso at home {m['common']} ({m['common'] / n:.3f} of the grid, "
              f"{m['common'] / r:.3f} of the reachable)")
        print(f"  (scene axes) Poppy shoulder {m['poppy_shoulder']}, Nao shoulder "
              f"{m['nao_shoulder']}; Nao's box {m['nao_box'][0]} .. {m['nao_box'][1]}; home "
              f"hands Poppy {m['hands']['poppy']}, Nao {m['hands']['nao']}")


if __name__ == "__main__":
    main()
