"""ABB confdata: definition on hand-made poses, round trips, selection rules."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics import IKStatus, available_robots, load_robot
from rapidfix.kinematics.confdata import confdata, nearest_chain, slot_confdata

pytestmark = pytest.mark.filterwarnings("error")

ROBOTS = available_robots()


def deg(*a):
    return np.radians(np.array(a, dtype=float))


def test_quadrants_of_axes_1_4_6():
    robot = load_robot("IRB1600-10/1.45")
    q = np.stack([deg(100, 0, 0, -10, 30, 190), deg(-100, 0, 0, 95, 30, -370)])
    conf = confdata(robot, q)
    assert conf[:, :3].tolist() == [[1, -1, 2], [-2, 1, -5]]


def test_cfx_bits_on_hand_made_poses():
    robot = load_robot("IRB1600-10/1.45")
    cases = {
        # wrist in front of axis 1 and of the lower arm, θ5 > 0
        (0, 0, 0, 0, 30, 0): 0,
        (0, 0, 0, 0, -30, 0): 1,
        # upper arm folded back over the lower arm: wrist behind the line axis 2 → 3
        (0, 60, -200, 0, 30, 0): 2,
        # lower arm tilted back horizontal, upper arm raised: wrist behind axis 1
        (0, -90, 30, 0, 30, 0): 4,
        (0, -90, 30, 0, -30, 0): 5,
    }
    for joints, cfx in cases.items():
        assert confdata(robot, deg(*joints))[3] == cfx, joints
    # The geometry behind two of them, by hand: wrist centre x for θ2 = −90°, θ3 = 30°.
    t2, t23 = np.radians(-90), np.radians(-60)
    assert 150 + 700 * np.sin(t2) + 600 * np.cos(t23) < 0


@pytest.mark.parametrize("name", ROBOTS)
def test_confdata_round_trip_selects_the_source_joints(name):
    robot = load_robot(name)
    rng = np.random.default_rng(30)
    q = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (2000, 6))
    conf = confdata(robot, q)
    assert len({tuple(c) for c in conf[:, 3:]}) == 8  # every cfx value occurs
    q_sel, status = robot.ik_conf(robot.fk(q), conf)
    assert (status == IKStatus.OK).all()
    assert np.abs(q_sel - q).max() < 1e-8


@pytest.mark.parametrize("name", ROBOTS)
def test_every_slot_has_the_confdata_of_its_own_joints(name):
    """slot_confdata (the cfx geometry once per branch, turns added) against confdata of
    each valid slot's joints on their own."""
    robot = load_robot(name)
    rng = np.random.default_rng(31)
    q = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (500, 6))
    sols = robot.ik(robot.fk(q))
    found = slot_confdata(robot, sols)
    assert sols.valid.sum() > 500 and found.shape == (*sols.valid.shape, 4)
    assert np.array_equal(found[sols.valid], confdata(robot, sols.q[sols.valid]))
    assert not found[~sols.valid].any()


@settings(max_examples=30, deadline=None)
@given(
    name=st.sampled_from(ROBOTS),
    u=st.lists(st.floats(0.02, 0.98), min_size=6, max_size=6),
)
def test_property_selected_solution_has_the_asked_confdata(name, u):
    robot = load_robot(name)
    lo, hi = robot.limits[:, 0], robot.limits[:, 1]
    q = lo + np.array(u) * (hi - lo)
    T = robot.fk(q)
    sols = robot.ik(T, q_prev=q)
    for conf in {tuple(c) for c in confdata(robot, sols.q[0, sols.valid[0]])}:
        q_sel, status = robot.ik_conf(T, np.array(conf), q_prev=q)
        assert IKStatus(int(status[0])).solved
        assert tuple(confdata(robot, q_sel[0])) == conf


def test_missing_confdata_is_reported():
    robot = load_robot("IRB1600-10/1.45")
    T = robot.fk(deg(10, 20, 30, 40, 50, 60))
    q, status = robot.ik_conf(T, np.array([3, 0, 0, 0]))  # axis 1 in the 4th quadrant: no
    assert status[0] == IKStatus.NO_MATCHING_CONF and np.isnan(q).all()
    with pytest.raises(KinematicsError):
        robot.ik_conf(T, np.array([0, 0, 0]))


def test_boundary_angles_match_both_quadrants():
    robot = load_robot("IRB1600-10/1.45")
    q = deg(90, 10, 10, 0, 30, -90)
    T = robot.fk(q)
    for cf1 in (0, 1):
        for cf6 in (-2, -1):
            q_sel, status = robot.ik_conf(T, np.array([cf1, 0, cf6, 0]))
            assert status[0] == IKStatus.OK and np.abs(q_sel[0] - q).max() < 1e-9


def test_nearest_rule_picks_the_closest_valid_solution():
    robot = load_robot("IRB2600-12/1.65")
    rng = np.random.default_rng(31)
    q = rng.uniform(robot.limits[:, 0] * 0.8, robot.limits[:, 1] * 0.8, (500, 6))
    T = robot.fk(q)
    q_near, status = robot.ik_nearest(T, q + 1e-4)
    assert (status == IKStatus.OK).all()
    assert np.abs(q_near - q).max() < 1e-8
    # brute force on a far previous vector
    prev = np.zeros(6)
    q_near, _ = robot.ik_nearest(T, prev)
    sols = robot.ik(T)
    for i in range(20):
        cand = sols.q[i, sols.valid[i]]
        best = cand[np.argmin(np.linalg.norm(cand - prev, axis=1))]
        assert np.allclose(q_near[i], best)


def test_nearest_chain_follows_a_path_without_jumps():
    robot = load_robot("IRB1600-10/1.45")
    s = np.linspace(0, 1, 60)[:, None]
    path = deg(-30, 10, 20, 170, 40, 340) + s * deg(60, 20, -30, 25, 30, 50)  # crosses 180°, 360°
    sols = robot.ik(robot.fk(path))
    q, status = nearest_chain(sols, path[0])
    assert (status == IKStatus.OK).all()
    assert np.abs(q - path).max() < 1e-8
