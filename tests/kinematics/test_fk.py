"""Forward kinematics against known poses and an independent link-frame formulation."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rapidfix.kinematics import available_robots, frames, load_robot

# Datasheet lengths (mm) of each shipped robot, written here independently of the
# robot files: c1 base→axis 2 height, a1 axis 1→axis 2 offset, c2 lower arm,
# a2 axis 3→axis 4 offset, c3 axis 3→wrist centre, c4 wrist centre→flange.
DATASHEET = {
    "IRB120-3/0.58": (290.0, 0.0, 270.0, 70.0, 302.0, 72.0),
    "IRB1600-10/1.45": (486.5, 150.0, 700.0, 0.0, 600.0, 65.0),
    "IRB2600-12/1.65": (445.0, 150.0, 700.0, 115.0, 795.0, 85.0),
    "IRB4600-60/2.05": (495.0, 175.0, 900.0, 175.0, 960.0, 135.0),
    "IRB6700-200/2.60": (780.0, 320.0, 1125.0, 200.0, 1142.5, 200.0),
}


def rot(axis, t):
    """Elementary rotations (N, 4, 4) about a local x, y or z axis."""
    c, s = np.cos(t), np.sin(t)
    T = np.zeros((t.shape[0], 4, 4))
    T[:, 3, 3] = 1.0
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    k = 3 - i - j
    T[:, k, k] = 1.0
    T[:, i, i] = c
    T[:, j, j] = c
    T[:, i, j] = -s
    T[:, j, i] = s
    return T


def trans(x, y, z):
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def link_chain_fk(name, q):
    """Independent FK: successive link frames (DH style), one elementary move at a time."""
    c1, a1, c2, a2, c3, c4 = DATASHEET[name]
    zero = np.zeros(q.shape[0])
    T = rot("z", q[:, 0]) @ trans(a1, 0, c1)
    T = T @ rot("y", q[:, 1]) @ trans(0, 0, c2)
    T = T @ rot("y", q[:, 2]) @ trans(c3, 0, a2)
    T = T @ rot("x", q[:, 3]) @ rot("y", q[:, 4]) @ trans(c4, 0, 0) @ rot("x", q[:, 5])
    return T @ rot("y", zero + np.pi / 2)  # tool0: z along the flange axis


def opw_wrist_centre(name, q):
    """OPW-style closed form of the wrist centre position."""
    c1, a1, c2, a2, c3, _ = DATASHEET[name]
    t23 = q[:, 1] + q[:, 2]
    x = a1 + c2 * np.sin(q[:, 1]) + c3 * np.cos(t23) + a2 * np.sin(t23)
    z = c1 + c2 * np.cos(q[:, 1]) - c3 * np.sin(t23) + a2 * np.cos(t23)
    return np.stack([x * np.cos(q[:, 0]), x * np.sin(q[:, 0]), z], axis=1)


ROBOTS = available_robots()


def test_every_documented_robot_is_shipped():
    assert sorted(ROBOTS) == sorted(DATASHEET)


def test_irb1600_home_pose():
    robot = load_robot("IRB1600-10/1.45")
    pos, quat = frames.pose_to_pos_quat(robot.fk(np.zeros(6)))
    assert np.allclose(pos, [815.0, 0.0, 1186.5], atol=1e-12)
    assert np.allclose(quat, [0.7071068, 0.0, 0.7071068, 0.0], atol=1e-7)


def test_irb1600_known_poses():
    robot = load_robot("IRB1600-10/1.45")
    # Axis 1 at 90°: the arm points along base y.
    pos = robot.fk(np.radians([90, 0, 0, 0, 0, 0]))[:3, 3]
    assert np.allclose(pos, [0.0, 815.0, 1186.5], atol=1e-9)
    # Axis 2 forward 90°: lower arm horizontal along x, upper arm pointing down.
    pos = robot.fk(np.radians([0, 90, 0, 0, 0, 0]))[:3, 3]
    assert np.allclose(pos, [150 + 700, 0.0, 486.5 - 665.0], atol=1e-9)
    # Axis 3 at −90°: upper arm straight up.
    pos = robot.fk(np.radians([0, 0, -90, 0, 0, 0]))[:3, 3]
    assert np.allclose(pos, [150.0, 0.0, 1186.5 + 665.0], atol=1e-9)
    # Axis 5 at 90°: flange points down, 65 mm below the wrist centre.
    T = robot.fk(np.radians([0, 0, 0, 0, 90, 0]))
    assert np.allclose(T[:3, 3], [750.0, 0.0, 1186.5 - 65.0], atol=1e-9)
    assert np.allclose(T[:3, 2], [0.0, 0.0, -1.0], atol=1e-12)


@pytest.mark.parametrize("name", ROBOTS)
def test_poe_matches_independent_link_chain(name):
    robot = load_robot(name)
    rng = np.random.default_rng(10)
    q = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (3000, 6))
    T = robot.fk(q)
    ref = link_chain_fk(name, q)
    assert np.abs(T[:, :3, 3] - ref[:, :3, 3]).max() < 1e-9
    assert np.abs(T[:, :3, :3] - ref[:, :3, :3]).max() < 1e-12
    c = robot.joint_frames(q)[1][:, 4]  # axis 5 passes the wrist centre
    assert np.abs(c - opw_wrist_centre(name, q)).max() < 1e-9


def test_batches_go_through_in_chunks_with_every_row_in_place(monkeypatch):
    from rapidfix import chunks

    name = "IRB2600-12/1.65"
    robot = load_robot(name)
    q = np.random.default_rng(12).uniform(robot.limits[:, 0], robot.limits[:, 1], (23, 6))
    whole = robot.fk(q), robot.joint_frames(q)[1]
    monkeypatch.setattr(chunks, "FK", 5)  # four full chunks and a short one
    T, points = robot.fk(q), robot.joint_frames(q)[1]
    assert np.abs(T[:, :3, 3] - link_chain_fk(name, q)[:, :3, 3]).max() < 1e-9
    assert np.abs(points[:, 4] - opw_wrist_centre(name, q)).max() < 1e-9
    assert np.allclose(T, whole[0], rtol=0, atol=1e-12)
    assert np.allclose(points, whole[1], rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ROBOTS)
def test_tiny_angles_are_exact(name):
    robot = load_robot(name)
    q = np.zeros((6, 6))
    np.fill_diagonal(q, 1e-8)
    T = robot.fk(q)
    ref = link_chain_fk(name, q)
    assert np.abs(T - ref).max() < 1e-12
    # First-order motion: displacement = J(0)·q to relative precision 1e-6, and not zero.
    J = robot.jacobian(np.zeros(6))
    home = robot.fk(np.zeros(6))
    for i in range(6):
        w, v = J[:3, i], J[3:, i]
        expected = 1e-8 * (np.cross(w, home[:3, 3]) + v)
        moved = T[i, :3, 3] - home[:3, 3]
        assert np.linalg.norm(moved - expected) <= 1e-6 * np.linalg.norm(expected) + 1e-13
        rot_change = T[i, :3, :3] @ home[:3, :3].T - np.eye(3)
        assert np.abs(rot_change[[2, 0, 1], [1, 2, 0]] - 1e-8 * w).max() < 1e-15


@pytest.mark.parametrize("name", ROBOTS)
def test_jacobian_matches_finite_differences(name):
    robot = load_robot(name)
    rng = np.random.default_rng(11)
    q = rng.uniform(-1.5, 1.5, (50, 6))
    J = robot.jacobian(q)
    h = 1e-6
    for i in range(6):
        dq = np.zeros(6)
        dq[i] = h
        Tp, Tm = robot.fk(q + dq), robot.fk(q - dq)
        dR = (Tp[:, :3, :3] - Tm[:, :3, :3]) / (2 * h) @ np.swapaxes(robot.fk(q)[:, :3, :3], 1, 2)
        w = np.stack([dR[:, 2, 1], dR[:, 0, 2], dR[:, 1, 0]], axis=1)
        dp = (Tp[:, :3, 3] - Tm[:, :3, 3]) / (2 * h)
        v = dp - np.cross(w, robot.fk(q)[:, :3, 3])
        assert np.abs(J[:, :3, i] - w).max() < 1e-8
        assert np.abs(J[:, 3:, i] - v).max() < 1e-5


def test_joint_frames_follow_the_arm():
    robot = load_robot("IRB1600-10/1.45")
    dirs, points = robot.joint_frames(np.radians([90, 0, 0, 0, 0, 0]))
    assert np.allclose(dirs[1], [-1, 0, 0], atol=1e-12)  # axis 2 turned with axis 1
    assert np.allclose(points[1], [0, 150, 486.5], atol=1e-9)
    assert np.allclose(dirs[0], [0, 0, 1]) and np.allclose(points[0], [0, 0, 0])


def test_single_and_batch_shapes():
    robot = load_robot("IRB120-3/0.58")
    assert robot.fk(np.zeros(6)).shape == (4, 4)
    assert robot.fk(np.zeros((7, 6))).shape == (7, 4, 4)
    assert robot.jacobian(np.zeros((3, 6))).shape == (3, 6, 6)


def test_fk_with_tool_and_work_object():
    robot = load_robot("IRB1600-10/1.45")
    tool = frames.Tool.from_rapid(True, [0, 0, 100], [1, 0, 0, 0])
    wobj = frames.WorkObject.from_rapid(
        False, True, "", [500, 0, 0], [1, 0, 0, 0], [0, 0, 100], [1, 0, 0, 0]
    )
    T = robot.fk(np.zeros(6), tool=tool, wobj=wobj)
    # TCP 100 mm along tool0 z (= base x) from (815, 0, 1186.5); wobj origin at (500, 0, 100).
    assert np.allclose(T[:3, 3], [815 + 100 - 500, 0, 1186.5 - 100], atol=1e-9)


@pytest.mark.parametrize("backend", ["auto", "numpy"])
@pytest.mark.parametrize("name", available_robots())
def test_compiled_product_of_exponentials_is_numpys_to_rounding(name, backend, monkeypatch):
    """Inside `compiled_forward` (the post-processor) the poses come from the compiled
    kernel when numba is installed, and from its arithmetic in numpy columns
    (`fk_columns`) when it is not (RAPIDFIX_IK_BACKEND=numpy): the 4×4 products to
    rounding, on every shipped robot, over the whole joint range and at the tiny angles
    where the versine matters."""
    from rapidfix.compiled import BACKEND_ENV
    from rapidfix.kinematics import fk_columns
    from rapidfix.kinematics.screws import compiled_forward

    monkeypatch.setenv(BACKEND_ENV, backend)
    calls = []
    real = fk_columns.forward_poses
    monkeypatch.setattr(fk_columns, "forward_poses", lambda *a: calls.append(1) or real(*a))
    robot = load_robot(name)
    rng = np.random.default_rng(3)
    q = np.concatenate([rng.uniform(-np.pi, np.pi, (3000, 6)),
                        rng.normal(scale=1e-9, size=(100, 6))])
    expected = robot.fk(q)
    with compiled_forward():
        got = robot.fk(q)
    np.testing.assert_allclose(got[:, :3, :3], expected[:, :3, :3], rtol=0, atol=1e-14)
    np.testing.assert_allclose(got[:, :3, 3], expected[:, :3, 3], rtol=0, atol=1e-11)
    assert np.array_equal(got[:, 3], expected[:, 3])
    assert np.array_equal(robot.fk(q), expected)  # outside the block: numpy's as before
    if backend == "numpy":
        assert calls  # the columns, not the 4×4 products again
        assert not np.array_equal(got, expected)  # rounding: another order of the sums


def test_columns_product_against_rotations_and_across_chunks():
    """`fk_columns` against a product of scipy's rotations about each joint's line, on
    an arm whose axes are not the base axes, and a chunk boundary
    (`chunks.FK_COLUMNS`) changes nothing: each pose is its own sums."""
    from rapidfix import chunks
    from rapidfix.kinematics import fk_columns

    rng = np.random.default_rng(5)
    dirs = rng.normal(size=(6, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    points = rng.uniform(-800.0, 800.0, (6, 3))
    home = np.eye(4)
    home[:3, :3] = Rotation.from_rotvec([0.3, -0.2, 0.9]).as_matrix()
    home[:3, 3] = [815.0, 12.0, 961.5]
    q = rng.uniform(-3.0, 3.0, (chunks.FK_COLUMNS + 50, 6))
    whole = np.empty((q.shape[0], 4, 4))
    fk_columns.forward_poses(dirs, points, home, q, whole)
    for row in range(0, q.shape[0], 97):
        expected = np.eye(4)
        for k in range(6):
            turn = np.eye(4)
            turn[:3, :3] = Rotation.from_rotvec(dirs[k] * q[row, k]).as_matrix()
            turn[:3, 3] = points[k] - turn[:3, :3] @ points[k]
            expected = expected @ turn
        expected = expected @ home
        np.testing.assert_allclose(whole[row, :3, :3], expected[:3, :3], rtol=0, atol=1e-14)
        np.testing.assert_allclose(whole[row, :3, 3], expected[:3, 3], rtol=0, atol=1e-10)
        assert np.array_equal(whole[row, 3], [0.0, 0.0, 0.0, 1.0])
    parts = np.empty_like(whole)
    fk_columns.forward_poses(dirs, points, home, q[:70], parts[:70])
    fk_columns.forward_poses(dirs, points, home, q[70:], parts[70:])
    assert np.array_equal(whole, parts)
