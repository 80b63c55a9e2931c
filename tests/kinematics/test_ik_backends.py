"""The compact IK result, its expansion, and the numpy and compiled closed forms.

The numpy path is checked everywhere; the compiled (numba) path wherever numba
is importable, and then also against the numpy path on the same poses.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics import IKStatus, available_robots, frames, load_robot
from rapidfix.kinematics.ik import BACKEND_ENV, accelerated, solve_all

pytestmark = pytest.mark.filterwarnings("error")

ROBOTS = available_robots()
BACKENDS = ["numpy", "numba"] if accelerated() else ["numpy"]


def test_accelerated_matches_whether_numba_imports():
    try:
        import numba  # noqa: F401

        importable = True
    except ImportError:
        importable = False
    assert accelerated() == importable
    robot = load_robot("IRB120-3/0.58")
    T = robot.fk(np.radians([[10, 20, 30, 40, 50, 60]]))
    assert robot.ik(T).backend == ("numba" if importable else "numpy")  # auto
    assert solve_all(robot, T, backend="numpy").backend == "numpy"
    if importable:
        assert solve_all(robot, T, backend="numba").backend == "numba"
    else:
        with pytest.raises(KinematicsError, match="numba"):
            solve_all(robot, T, backend="numba")
    with pytest.raises(KinematicsError, match="unknown IK backend"):
        solve_all(robot, T, backend="fortran")


def test_environment_variable_picks_the_backend(monkeypatch):
    robot = load_robot("IRB120-3/0.58")
    T = robot.fk(np.radians([[10, 20, 30, 40, 50, 60]]))
    monkeypatch.setenv(BACKEND_ENV, "numpy")
    assert robot.ik(T).backend == "numpy"


def awkward_poses(robot, rng, n):
    """Random poses from joints inside the limits, plus poses that test every status."""
    lo, hi = robot.limits[:, 0], robot.limits[:, 1]
    q = rng.uniform(lo, hi, (n, 6))
    q[: n // 20, 4] = 0.0  # wrist singular
    q[n // 20 : n // 10, 4] = rng.uniform(-1e-8, 1e-8, n // 20)  # nearly singular
    T = robot.fk(q)
    far = frames.pose([[1e4, 0, 0]], [[1, 0, 0, 0]])
    skew = np.eye(4)[None].copy()
    skew[0, 0, 1] = 0.3
    nan = np.full((1, 4, 4), np.nan)
    beyond = robot.fk(np.array([[0, 0, 0, 0, hi[4] + 0.3, 0]]))  # axis 5 past its limit
    return np.concatenate([T, far, skew, nan, beyond]), q


@pytest.mark.parametrize("name", ROBOTS)
def test_every_backend_inverts_fk_and_expands_consistently(name):
    robot = load_robot(name)
    rng = np.random.default_rng(40)
    T, q_true = awkward_poses(robot, rng, 600)
    prev = np.zeros((len(T), 6))
    prev[: len(q_true)] = q_true  # θ4 at the singular poses
    for backend in BACKENDS:
        sols = solve_all(robot, T, q_prev=prev, backend=backend)
        assert sols.backend == backend
        # Expanded view against an independent check of the limits.
        assert sols.q.shape == (len(T), 8 * int(np.prod(sols.counts)), 6)
        finite = np.isfinite(sols.q).all(axis=2)
        assert np.array_equal(sols.valid, finite & robot.within_limits(sols.q))
        assert np.array_equal(sols.count(), sols.valid.sum(axis=1))
        shifts = 2 * np.pi * sols.turns
        assert np.array_equal(sols.q, sols.base_q[:, sols.branch] + shifts, equal_nan=True)
        # Every valid slot reproduces its pose, and one of them is the source joints.
        counts = sols.valid.sum(axis=1)
        qv = sols.q[sols.valid]
        F = robot.fk(qv)
        goal = np.repeat(T, counts, axis=0)
        assert np.abs(F[:, :3, 3] - goal[:, :3, 3]).max() < 1e-9
        assert np.abs(F[:, :3, :3] - goal[:, :3, :3]).max() < 1e-9
        d = np.where(
            sols.valid[: len(q_true)],
            np.abs(sols.q[: len(q_true)] - q_true[:, None]).max(axis=2),
            np.inf,
        )
        assert d.min(axis=1).max() < 1e-6
        n = len(q_true)
        assert (sols.status[: n // 20] == IKStatus.WRIST_SINGULAR).all()
        assert np.isin(sols.status[:n], [IKStatus.OK, IKStatus.WRIST_SINGULAR]).all()
        assert sols.status[n:].tolist() == [
            IKStatus.UNREACHABLE,
            IKStatus.INVALID_POSE,
            IKStatus.INVALID_POSE,
            IKStatus.BEYOND_LIMITS,
        ]
        assert np.isnan(sols.base_q[n : n + 3]).all() and not sols.reachable[n : n + 3].any()


@pytest.mark.parametrize("name", ROBOTS)
def test_compiled_and_numpy_closed_forms_agree(name):
    robot = load_robot(name)
    rng = np.random.default_rng(41)
    T, q_true = awkward_poses(robot, rng, 2000)
    # and arbitrary rigid poses around the robot, many of them out of reach or limits
    reach = np.abs(robot.home[:3, 3]).sum()
    rotations = Rotation.random(1000, random_state=42).as_matrix()
    arbitrary = np.repeat(np.eye(4)[None], 1000, axis=0)
    arbitrary[:, :3, :3] = rotations
    arbitrary[:, :3, 3] = rng.uniform(-reach, reach, (1000, 3))
    T = np.concatenate([T, arbitrary])
    prev = np.zeros((len(T), 6))
    prev[: len(q_true)] = q_true
    results = [solve_all(robot, T, q_prev=prev, backend=b) for b in BACKENDS]
    ref = results[0]
    assert ref.backend == "numpy"
    assert {IKStatus.UNREACHABLE, IKStatus.BEYOND_LIMITS} <= set(ref.status[len(q_true) :])
    for other in results[1:]:
        assert other.backend == "numba"
        assert np.array_equal(other.status, ref.status)
        assert np.array_equal(other.reachable, ref.reachable)
        assert np.array_equal(other.base_singular, ref.base_singular)
        assert np.array_equal(np.isnan(other.base_q), np.isnan(ref.base_q))
        gap = np.abs(np.angle(np.exp(1j * (other.base_q - ref.base_q))))
        assert np.median(gap[np.isfinite(gap)]) < 1e-14  # rounding, not another method
        assert np.nanmax(gap) < 1e-8  # ill-conditioned near the stretched arm (~√ε)
        # The limit masks agree wherever no angle sits within 1e-8 rad of a limit.
        lo, hi = robot.limits[:, 0], robot.limits[:, 1]
        k = np.arange(max(ref.counts))[:, None, None, None]
        angles = ref.base_q[None] + 2 * np.pi * k
        edge = (np.abs(angles - lo) < 1e-8) | (np.abs(angles - hi) < 1e-8)
        clear = ~edge.any(axis=(0, 3))
        assert clear.mean() > 0.99
        assert np.array_equal(other.turn_ok[clear], ref.turn_ok[clear])


def test_compact_count_for_wide_turn_masks():
    """Masks wider than a byte (an axis of more than eight turns) count correctly."""
    robot = load_robot("IRB1600-10/1.45")
    limits = robot.limits.copy()
    limits[5] = [-np.radians(1800.0), np.radians(1800.0)]  # axis 6: ±5 turns
    wide = type(robot)(robot.name, robot.axis_dirs, robot.axis_points, robot.home, limits)
    q = np.radians([[10, 20, 30, 40, 50, 60]])
    sols = solve_all(wide, wide.fk(q), backend="numpy")  # the masks are the same on both
    assert sols.turn_ok.dtype == np.uint16 and sols.counts[5] == 11
    assert np.array_equal(sols.count(), sols.valid.sum(axis=1))
    # θ6 = 60° + k·360° for k = −5 … 4 is inside ±1800°: 10 variants in the source branch
    in_branch = sols.valid[0] & (np.abs(sols.q[0, :, :5] - q[0, :5]).max(axis=1) < 1e-9)
    assert in_branch.sum() == 10


def test_prepare_solves_once_ahead_only_where_the_compiled_kernel_will_run(monkeypatch):
    from rapidfix.kinematics import ik

    robot = load_robot("IRB120-3/0.58")
    ik.prepare(robot)  # the real thing, in whichever environment this runs
    calls = []
    monkeypatch.setattr(ik, "solve_all", lambda model, T, **kw: calls.append((model, T)))
    for backend in ("numpy", "auto"):
        monkeypatch.setenv(BACKEND_ENV, backend)
        calls.clear()
        ik.prepare(robot)
        if backend == "auto" and accelerated():
            (model, T), = calls
            assert model is robot and T.shape == (1, 4, 4) and T.flags.writeable
            assert np.array_equal(T[0], robot.home)
        else:
            assert calls == []

