"""confdata on a quadrant boundary, as real (rounded) programs write it (issue #15, item 13)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rapidfix.kinematics import IKStatus, load_robot
from rapidfix.kinematics.confdata import CONF_TOL, conf_matches

ROBOT = load_robot("IRB1600-10/1.45")


def rounded_target(q_deg):
    """The pose of joints q as a program writes it: mm to 3 decimals, quaternion to 9."""
    q = np.radians([q_deg])
    T = ROBOT.fk(q)[0]
    x, y, z, w = Rotation.from_matrix(T[:3, :3]).as_quat()
    quat = np.round([w, x, y, z], 9)
    out = np.eye(4)
    out[:3, :3] = Rotation.from_quat([quat[1], quat[2], quat[3], quat[0]]).as_matrix()
    out[:3, 3] = np.round(T[:3, 3], 3)
    return out, ROBOT.confdata(q)[0]


@pytest.mark.parametrize("q_deg", [
    (10, 20, 10, 0, 30, 0),
    (-35, 10, 25, 0, 60, 0),
    (20, 15, -5, 90, 40, -90),
])
def test_rounded_target_on_a_boundary_is_solved_on_its_confdata(q_deg):
    T, conf = rounded_target(q_deg)
    q, status = ROBOT.ik_conf(T[None], conf)
    assert IKStatus(int(status[0])).solved
    # and it is the pose the program meant, not another branch
    assert np.abs(np.degrees(q[0]) - np.asarray(q_deg, float)).max() < 1e-3


def test_boundary_tolerance_is_documented_and_small():
    assert np.degrees(CONF_TOL) == pytest.approx(0.01)
    q = np.radians([[10, 20, 10, -0.005, 30, 0.0]])  # j4 just below 0: quadrant -1
    assert conf_matches(ROBOT, q, np.array([0, 0, 0, 0]))[0]
    assert conf_matches(ROBOT, q, np.array([0, -1, 0, 0]))[0]
    q_far = np.radians([[10, 20, 10, -0.05, 30, 0.0]])  # 0.05° is no rounding: one side
    assert not conf_matches(ROBOT, q_far, np.array([0, 0, 0, 0]))[0]
