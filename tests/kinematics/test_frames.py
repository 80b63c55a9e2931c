"""Frames and ABB conventions: quaternions, tooldata, wobjdata, Offs, RelTool."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics import frames


def hand_quat_to_matrix(q):
    """The textbook unit-quaternion rotation matrix, written out (independent truth)."""
    w, x, y, z = np.asarray(q) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_abb_tool0_quaternion_is_a_quarter_turn_about_y():
    R = frames.quat_to_matrix([0.7071068, 0, 0.7071068, 0])
    assert np.allclose(R @ [0, 0, 1], [1, 0, 0], atol=1e-7)  # tool z along base x
    assert np.allclose(R, hand_quat_to_matrix([0.7071068, 0, 0.7071068, 0]), atol=1e-12)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda v: np.linalg.norm(v) > 0.1))
def test_property_quaternion_round_trip_and_sign(v):
    R = frames.quat_to_matrix(v)
    assert np.allclose(R, hand_quat_to_matrix(v), atol=1e-12)
    q = frames.matrix_to_quat(R)
    assert abs(np.linalg.norm(q) - 1) < 1e-12 and q[0] >= 0
    expected = np.asarray(v) / np.linalg.norm(v)
    expected = expected if expected[0] > 0 else -expected
    if abs(expected[0]) > 1e-9:
        assert np.allclose(q, expected, atol=1e-9)


def test_sign_is_fixed_when_w_is_zero():
    q = frames.matrix_to_quat(np.diag([1.0, -1.0, -1.0]))  # half turn about x
    assert np.allclose(q, [0, 1, 0, 0])
    assert np.allclose(frames.canonical_quat([0, -1, 0, 0]), [0, 1, 0, 0])


def test_batch_shapes_and_bad_quaternions():
    T = frames.pose(np.zeros((5, 3)), np.tile([1.0, 0, 0, 0], (5, 1)))
    assert T.shape == (5, 4, 4)
    pos, quat = frames.pose_to_pos_quat(T)
    assert pos.shape == (5, 3) and quat.shape == (5, 4)
    with pytest.raises(KinematicsError):
        frames.quat_to_matrix([0, 0, 0, 0])
    with pytest.raises(KinematicsError):
        frames.quat_to_matrix([1, 0, 0])


def test_offs_moves_in_the_work_object_frame():
    target = frames.pose([100, 200, 300], [0, 0, 1, 0])  # tool turned upside down
    moved = frames.offs(target, 10, 0, -5)
    assert np.allclose(moved[:3, 3], [110, 200, 295])
    assert np.allclose(moved[:3, :3], target[:3, :3])


def test_reltool_moves_and_turns_in_the_tool_frame():
    target = frames.pose([100, 200, 300], [0, 0, 1, 0])  # tool z points down (−z)
    moved = frames.reltool(target, 0, 0, 50)
    assert np.allclose(moved[:3, 3], [100, 200, 250])  # 50 mm along the tool z = down
    turned = frames.reltool(target, rz=90)
    assert np.allclose(turned[:3, 2], target[:3, 2])  # z kept
    assert np.allclose(turned[:3, 0], target[:3, 1], atol=1e-12)  # x turned onto old y
    # x then y then z, each about the already turned axes (intrinsic)
    both = frames.reltool(np.eye(4), rx=90, ry=90)
    Rx = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    Ry = np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]])
    assert np.allclose(both[:3, :3], Rx @ Ry, atol=1e-12)


def test_flange_target_and_its_inverse():
    tool = frames.Tool.from_rapid(True, [0, 0, 200], [1, 0, 0, 0])
    wobj = frames.WorkObject.from_rapid(
        False, True, "", [1000, 0, 0], [0.7071068, 0, 0, 0.7071068], [0, 100, 0], [1, 0, 0, 0]
    )
    target = frames.pose([10, 0, 0], [0, 0, 1, 0])
    flange = frames.flange_target(target, tool, wobj)
    # object frame: uframe at x = 1000 turned 90° about z, then oframe 100 along its y:
    # origin (1000 − 100, 0, 0); target x = 10 in it → base y = 10. TCP 200 mm along the
    # tool z, which points down, so the flange is 200 mm above.
    assert np.allclose(flange[:3, 3], [900, 10, 200], atol=1e-5)
    assert np.allclose(frames.tcp_pose(flange, tool, wobj), target, atol=1e-9)


def test_robot_held_work_object_with_stationary_tool():
    tool = frames.Tool.from_rapid(False, [500, 0, 800], [1, 0, 0, 0])
    wobj = frames.WorkObject.from_rapid(
        True, True, "", [0, 0, 100], [1, 0, 0, 0], [0, 0, 0], [1, 0, 0, 0]
    )
    target = frames.pose([0, 0, 0], [1, 0, 0, 0])
    flange = frames.flange_target(target, tool, wobj)
    # the object origin (100 mm along the flange z) must sit on the stationary TCP
    assert np.allclose(flange @ wobj.frame @ target, tool.tframe)
    assert np.allclose(frames.tcp_pose(flange, tool, wobj), target)


def test_unresolvable_work_objects_are_errors():
    moving = frames.WorkObject(ufprog=False, ufmec="STN1")
    with pytest.raises(KinematicsError, match="STN1"):
        frames.flange_target(np.eye(4), None, moving)
    with pytest.raises(KinematicsError):
        frames.flange_target(np.eye(4), frames.Tool(robhold=True), frames.WorkObject(robhold=True))


def _random_rotations(rng: np.random.Generator, n: int) -> np.ndarray:
    """Rotation vectors (n, 3) of every size, from none through tiny (the Taylor
    branch) to half turns."""
    v = rng.normal(size=(n, 3))
    sizes = np.concatenate([np.zeros(4), 10.0 ** rng.uniform(-9, -2.5, n // 3),
                            rng.uniform(0.0, np.pi, n - 4 - n // 3)])
    return v / np.linalg.norm(v, axis=1)[:, None] * sizes[:, None]


def test_conversions_are_scipys_bit_for_bit():
    """The numpy conversions are scipy's Rotation, the same arithmetic: quaternions and
    matrices (products of rotations, orthogonal to round-off) equal to the last bit at
    any scale; rotation vectors of any size, tiny to half turns, to rounding."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(11)
    wxyz = rng.normal(size=(20000, 4)) * 10.0 ** rng.uniform(-3, 3, (20000, 1))
    wxyz[:50, 1:] = 0.0  # identity and half turns about the axes
    wxyz[50:100, 0] = 0.0
    unit = wxyz / np.linalg.norm(wxyz, axis=1)[:, None]  # as quat_to_matrix takes them
    unit = np.concatenate([unit[:, 1:], unit[:, :1]], axis=1)
    assert np.array_equal(frames.quat_to_matrix(wxyz), Rotation.from_quat(unit).as_matrix())

    rotvec = _random_rotations(rng, 20000)
    m = frames.rotvec_to_matrix(rotvec)
    # rotation vectors also take sin, cos and atan2: numpy's and the C library's are
    # the same where numpy has no SIMD version of its own (no AVX-512), else to an ulp
    np.testing.assert_allclose(m, Rotation.from_rotvec(rotvec).as_matrix(), rtol=0,
                               atol=1e-14)
    m = Rotation.from_rotvec(rotvec).as_matrix()
    product = m @ Rotation.from_rotvec(rotvec[::-1]).as_matrix() @ m
    np.testing.assert_allclose(frames.matrix_to_rotvec(product),
                               Rotation.from_matrix(product).as_rotvec(), rtol=0, atol=1e-14)
    reference = Rotation.from_matrix(product).as_quat()
    expected = frames.canonical_quat(np.concatenate([reference[:, 3:], reference[:, :3]], 1))
    assert np.array_equal(frames.matrix_to_quat(product), expected)
    # back and forth: the rotation vector comes back (to round-off)
    assert np.allclose(frames.matrix_to_rotvec(m), rotvec, atol=1e-12)


def test_a_matrix_off_orthogonal_is_made_a_rotation_first():
    """A matrix far from orthogonal is not read by its diagonal alone: scipy projects it
    onto the nearest rotation, as before; a reflection is refused as before."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(12)
    m = frames.rotvec_to_matrix(_random_rotations(rng, 200))
    skewed = m + rng.normal(size=m.shape) * 1e-6
    np.testing.assert_allclose(frames.matrix_to_rotvec(skewed),
                               Rotation.from_matrix(skewed).as_rotvec(), rtol=0, atol=1e-14)
    assert np.allclose(frames.matrix_to_rotvec(skewed), frames.matrix_to_rotvec(m), atol=1e-5)
    with pytest.raises(ValueError):
        frames.matrix_to_quat(np.diag([1.0, 1.0, -1.0]))
