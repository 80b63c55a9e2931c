"""All-branch inverse kinematics: exactness, branches, limits, singularities, statuses."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics import IKStatus, available_robots, frames, load_robot
from rapidfix.kinematics.ik import BACKEND_ENV, accelerated
from rapidfix.kinematics.ik_result import raise_for_status

pytestmark = pytest.mark.filterwarnings("error")  # no numpy warning may leak

ROBOTS = available_robots()
# The numpy closed form always; the compiled one too where numba is installed.
BACKENDS = ["numpy", "numba"] if accelerated() else ["numpy"]


@pytest.fixture(scope="module", autouse=True, params=BACKENDS)
def backend(request):
    """Run every test of this module on each available IK backend."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(BACKEND_ENV, request.param)
        yield request.param


def test_the_chosen_backend_ran(backend):
    robot = load_robot("IRB1600-10/1.45")
    sols = robot.ik(robot.fk(np.radians([10, 20, 30, 40, 50, 60])))
    assert sols.backend == backend
    actual = robot.with_screws(robot.axis_dirs, robot.axis_points + 0.1)
    assert actual.ik(actual.fk(np.radians([10, 20, 30, 40, 50, 60]))).backend == "numpy"


def pose_errors(robot, q, T):
    """Position (mm) and rotation (rad, ≈ Frobenius/√2) errors of fk(q) against T."""
    F = robot.fk(q)
    pos = np.linalg.norm(F[..., :3, 3] - T[..., :3, 3], axis=-1)
    rot = np.linalg.norm(F[..., :3, :3] - T[..., :3, :3], axis=(-2, -1)) / np.sqrt(2)
    return pos, rot


def check_all_branches(robot, T, q_true, joint_tol=1e-8):
    sols = robot.ik(T)
    n = T.shape[0]
    counts = sols.valid.sum(axis=1)
    assert (counts > 0).all()
    qv = sols.q[sols.valid]
    pos, rot = pose_errors(robot, qv, np.repeat(T, counts, axis=0))
    assert pos.max() < 1e-9 and rot.max() < 1e-9
    assert robot.within_limits(qv).all()
    d = np.where(sols.valid, np.abs(sols.q - q_true[:, None, :]).max(axis=2), np.inf)
    assert (d.min(axis=1) < joint_tol).all(), np.argmax(d.min(axis=1))
    assert (sols.status == IKStatus.OK).sum() + (sols.status == IKStatus.WRIST_SINGULAR).sum() == n
    return sols


@pytest.mark.parametrize("name", ROBOTS)
def test_every_branch_reproduces_the_pose_and_one_is_the_source(name):
    robot = load_robot(name)
    rng = np.random.default_rng(20)
    q = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (3000, 6))
    sols = check_all_branches(robot, robot.fk(q), q)
    assert sols.q.shape[1] == sols.branch.shape[0] == sols.turns.shape[0]
    # a generic pose has several distinct valid branches
    assert (sols.valid.sum(axis=1) >= 2).mean() > 0.9


@settings(max_examples=40, deadline=None)
@given(
    name=st.sampled_from(ROBOTS),
    u=st.lists(st.floats(0.0, 1.0), min_size=6, max_size=6),
)
def test_property_ik_inverts_fk(name, u):
    robot = load_robot(name)
    lo, hi = robot.limits[:, 0], robot.limits[:, 1]
    q = (lo + np.array(u) * (hi - lo))[None]
    T = robot.fk(q)
    sols = robot.ik(T, q_prev=q)  # q_prev keeps θ4 if hypothesis finds the wrist singularity
    qv = sols.q[sols.valid]
    pos, rot = pose_errors(robot, qv, np.repeat(T, len(qv), axis=0))
    assert pos.max() < 1e-9 and rot.max() < 1e-9
    d = np.abs(qv - q).max(axis=1)
    assert d.min() < 1e-7


def test_tiny_angles_solve_exactly():
    robot = load_robot("IRB1600-10/1.45")
    q = np.array([[1e-8, -1e-8, 1e-8, -1e-8, 1e-8, -1e-8], [0, 0, 0, 0, 1e-8, 0]])
    sols = robot.ik(robot.fk(q), q_prev=q)
    d = np.where(sols.valid, np.abs(sols.q - q[:, None]).max(axis=2), np.inf)
    assert d.min(axis=1).max() < 1e-15 + 1e-12


def test_unreachable_and_invalid_poses_are_named_not_nan():
    robot = load_robot("IRB120-3/0.58")
    far = frames.pose([[5000.0, 0, 0]], [[1, 0, 0, 0]])[0]
    close = frames.pose([[0.0, 0, 362.0]], [[1, 0, 0, 0]])[0]  # wrist centre on axis 2
    nan = np.full((4, 4), np.nan)
    skew = np.eye(4)
    skew[0, 1] = 0.5
    good = robot.fk(np.radians([10, 20, 30, 40, 50, 60]))
    sols = robot.ik(np.stack([far, close, nan, skew, good]))
    assert sols.status.tolist() == [
        IKStatus.UNREACHABLE,
        IKStatus.UNREACHABLE,
        IKStatus.INVALID_POSE,
        IKStatus.INVALID_POSE,
        IKStatus.OK,
    ]
    assert not sols.valid[:4].any()
    assert np.isnan(sols.q[:4]).all()  # no silent numbers for failed poses
    with pytest.raises(KinematicsError, match="pose 0: UNREACHABLE"):
        raise_for_status(sols.status)
    q, status = robot.ik_nearest(np.stack([far, good]), np.zeros(6))
    assert status.tolist() == [IKStatus.UNREACHABLE, IKStatus.OK]
    assert np.isnan(q[0]).all() and np.isfinite(q[1]).all()


def test_beyond_limits_in_every_branch():
    robot = load_robot("IRB6700-200/2.60")  # axis 5 only ±130°
    q = np.radians([[0, 0, 0, 0, 150, 0]])
    T = robot.fk(q)
    sols = robot.ik(T)
    assert sols.status[0] == IKStatus.BEYOND_LIMITS
    reached = np.isfinite(sols.q[0]).all(axis=1)
    assert reached.any() and not sols.valid.any()
    pos, _ = pose_errors(robot, sols.q[0, reached], np.repeat(T, reached.sum(), axis=0))
    assert pos.max() < 1e-9  # they are solutions …
    assert not robot.within_limits(sols.q[0, reached]).any()  # … outside the limits


def test_wrist_singularity_keeps_theta4_and_moves_the_sum_to_theta6():
    robot = load_robot("IRB2600-12/1.65")
    q = np.array([[0.2, 0.3, -0.4, 0.7, 0.0, 0.5]])
    T = robot.fk(q)
    sols = robot.ik(T, q_prev=q)
    assert sols.status[0] == IKStatus.WRIST_SINGULAR
    d = np.where(sols.valid[0], np.abs(sols.q[0] - q).max(axis=1), np.inf)
    assert d.min() < 1e-12
    # Default previous θ4 = 0: θ6 takes θ4 + θ6.
    q_sel, status = robot.ik_nearest(T, np.array([0.2, 0.3, -0.4, 0.0, 0.0, 1.2]))
    assert status[0] == IKStatus.WRIST_SINGULAR
    assert np.allclose(q_sel[0], [0.2, 0.3, -0.4, 0.0, 0.0, 1.2], atol=1e-12)
    pos, rot = pose_errors(robot, q_sel, T)
    assert pos.max() < 1e-9 and rot.max() < 1e-12


def test_targets_behind_the_robot():
    robot = load_robot("IRB1600-10/1.45")
    # Tool pointing down, 700 mm behind the base.
    target = frames.pose([[-700.0, 100.0, 600.0]], [[0, 0, 1, 0]])
    sols = robot.ik(target)
    assert sols.status[0] == IKStatus.OK
    qv = sols.q[0, sols.valid[0]]
    assert (np.abs(np.abs(qv[:, 0]) - np.pi) < np.radians(20)).any()  # turned round
    pos, rot = pose_errors(robot, qv, np.repeat(target, len(qv), axis=0))
    assert pos.max() < 1e-9 and rot.max() < 1e-9
    conf = robot.confdata(qv)
    behind = conf[:, 3] >= 4  # reached over the shoulder: wrist centre behind axis 1
    assert behind.any() and (~behind).any()
    assert (np.abs(qv[behind, 0]) < np.radians(20)).all()


def test_whole_turn_variants_of_multi_turn_axes():
    robot = load_robot("IRB1600-10/1.45")  # axis 6 ±400°, axis 4 ±200°
    q = np.radians([[10, 20, 30, 190, 40, 350]])
    sols = robot.ik(robot.fk(q))
    qv = np.degrees(sols.q[0, sols.valid[0]])
    same_branch = np.abs(qv[:, :3] - [10, 20, 30]).max(axis=1) < 1e-6
    same_branch &= np.abs(qv[:, 4] - 40) < 1e-6
    a46 = {(round(a), round(b)) for a, b in qv[same_branch][:, [3, 5]]}
    assert a46 == {(a, b) for a in (190, -170) for b in (350, -10, -370)}


def test_perturbed_model_solves_to_1e9_mm():
    nominal = load_robot("IRB4600-60/2.05")
    rng = np.random.default_rng(21)
    dirs = nominal.axis_dirs + rng.normal(scale=1e-3, size=(6, 3))
    points = nominal.axis_points + rng.normal(scale=0.5, size=(6, 3))
    actual = nominal.with_screws(dirs, points)
    assert not actual.is_nominal and actual.nominal is nominal
    q = rng.uniform(nominal.limits[:, 0] * 0.9, nominal.limits[:, 1] * 0.9, (400, 6))
    q[:, 4] = np.where(np.abs(q[:, 4]) < 0.05, 0.3, q[:, 4])  # away from the wrist singularity
    T = actual.fk(q)
    assert np.abs(nominal.fk(q)[:, :3, 3] - T[:, :3, 3]).max() > 0.1  # really different
    sols = actual.ik(T)
    qv = sols.q[sols.valid]
    pos, rot = pose_errors(actual, qv, np.repeat(T, sols.valid.sum(axis=1), axis=0))
    assert pos.max() < 1e-9 and rot.max() < 1e-9
    d = np.where(sols.valid, np.abs(sols.q - q[:, None]).max(axis=2), np.inf)
    assert d.min(axis=1).max() < 1e-8


def test_ik_with_tool_and_work_object():
    robot = load_robot("IRB1600-10/1.45")
    tool = frames.Tool.from_rapid(True, [10, 0, 150], [0.9238795, 0, 0.3826834, 0])
    wobj = frames.WorkObject.from_rapid(
        False, True, "", [800, -200, 300], [0.9659258, 0, 0, 0.258819], [0, 0, 50], [1, 0, 0, 0]
    )
    q = np.radians([[5, 15, 10, 30, 45, -20]])
    target = robot.fk(q, tool=tool, wobj=wobj)
    sols = robot.ik(target, tool=tool, wobj=wobj)
    d = np.where(sols.valid, np.abs(sols.q - q[:, None]).max(axis=2), np.inf)
    assert d.min() < 1e-10


def test_bad_shapes_raise_kinematics_error():
    robot = load_robot("IRB120-3/0.58")
    with pytest.raises(KinematicsError):
        robot.ik(np.eye(3))
    with pytest.raises(KinematicsError):
        robot.fk(np.zeros(5))
    with pytest.raises(KinematicsError):
        robot.ik(np.stack([np.eye(4)] * 3), q_prev=np.zeros((2, 6)))


def test_shoulder_singularity_keeps_theta1():
    robot = load_robot("IRB120-3/0.58")  # no axis-1 offset: the wrist can sit on axis 1
    theta3 = np.arctan2(-302.0, 70.0)  # c3·cos θ3 + a2·sin θ3 = 0: wrist centre above axis 1
    q = np.array([[0.4, 0.0, theta3, 0.2, 0.5, 0.1]])
    T = robot.fk(q)
    assert np.hypot(*robot.joint_frames(q)[1][0, 4, :2]) < 1e-9  # wrist centre on axis 1
    sols = robot.ik(T, q_prev=q)
    d = np.where(sols.valid, np.abs(sols.q - q[:, None]).max(axis=2), np.inf)
    assert d.min() < 1e-9
    qv = sols.q[sols.valid]
    pos, rot = pose_errors(robot, qv, np.repeat(T, len(qv), axis=0))
    assert pos.max() < 1e-9 and rot.max() < 1e-9


def test_single_pose_input():
    robot = load_robot("IRB4600-60/2.05")
    sols = robot.ik(robot.fk(np.radians([1, 2, 3, 4, 5, 6])))
    assert len(sols) == 1 and sols.status[0] == IKStatus.OK


@pytest.mark.parametrize(
    ("name", "stretched_deg"),
    [("IRB1600-10/1.45", -90.0), ("IRB4600-60/2.05", -np.degrees(np.arctan2(960.0, 175.0)))],
)
def test_arm_fully_stretched_at_the_edge_of_reach(name, stretched_deg):
    robot = load_robot(name)
    q = np.radians([[5, 30, stretched_deg, 10, 20, 30]])
    T = robot.fk(q)
    sols = robot.ik(T)
    assert sols.status[0] == IKStatus.OK
    qv = sols.q[sols.valid]
    pos, rot = pose_errors(robot, qv, np.repeat(T, len(qv), axis=0))
    assert pos.max() < 1e-9 and rot.max() < 1e-9
    # a double root: the angle is only determined to ~√ε there
    assert np.abs(qv - q).max(axis=1).min() < 1e-6
    # 1 mm further is out of reach
    outward = T[0, :3, 3] - robot.joint_frames(q)[1][0, 1]  # from axis 2 to the flange
    T_far = T.copy()
    T_far[0, :3, 3] += outward / np.linalg.norm(outward)
    assert robot.ik(T_far).status[0] == IKStatus.UNREACHABLE


def test_pose_at_a_limit_with_a_stretched_elbow_keeps_its_own_solution():
    # found by hypothesis: the stretched elbow costs the closed form ~1e-8 rad, and
    # joint 6 at +400° (its limit) was then refused as 7.6e-9 rad beyond it
    robot = load_robot("IRB1600-10/1.45")
    lo, hi = robot.limits[:, 0], robot.limits[:, 1]
    # (-180, 30, -90, -200, -115, 400)°, computed as hypothesis computes it
    q = (lo + np.array([0, 0.5, 0.5, 0, 0, 1]) * (hi - lo))[None]
    sols = robot.ik(robot.fk(q), q_prev=q)
    d = np.abs(sols.q[sols.valid] - q).max(axis=1)
    assert d.min() < 1e-7
