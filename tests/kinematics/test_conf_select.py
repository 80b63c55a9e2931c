"""Choosing the solution a confdata names on the compact IK result, against a slot-by-slot
reference over the expanded solutions (every branch and ±360° variant)."""

import numpy as np
import pytest

from rapidfix.kinematics import IKStatus, available_robots, load_robot
from rapidfix.kinematics.confdata import conf_matches, select_by_conf, select_nearest
from rapidfix.kinematics.ik import accelerated, backend_for
from rapidfix.kinematics.robot_model import RobotModel

pytestmark = pytest.mark.filterwarnings("error")


def reference(robot, sols, conf):
    """The first valid slot (in slot order) whose joints have the confdata `conf`."""
    n = len(sols)
    match = sols.valid & conf_matches(robot, sols.q, conf[:, None, :])
    status = np.asarray(sols.status, dtype=np.int8).copy()
    q = np.full((n, 6), np.nan)
    for i in range(n):
        if not sols.valid[i].any():
            continue  # the pose's own status: unreachable, beyond limits, invalid
        hits = np.flatnonzero(match[i])
        if hits.size == 0:
            status[i] = IKStatus.NO_MATCHING_CONF
            continue
        q[i] = sols.q[i, hits[0]]
        status[i] = IKStatus.WRIST_SINGULAR if sols.singular[i, hits[0]] else IKStatus.OK
    return q, status


def awkward_targets(robot, rng, n):
    """Poses and confdata: true, other branches', random; singular, on quadrant
    boundaries, beyond limits, out of reach and not rigid."""
    lo, hi = robot.limits[:, 0], robot.limits[:, 1]
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    q = rng.uniform(mid - 1.3 * half, mid + 1.3 * half, (n, 6))  # some beyond the limits
    q[::7, 4] = 0.0  # wrist singular
    q[1::9, 0] = np.radians(90.0)  # quadrant boundaries of axes 1, 4, 6
    q[2::9, 3] = np.radians(-90.0)
    q[3::9, 5] = np.radians(180.0)
    q[4::11, 4] = 1e-12  # θ5 sign at its tolerance
    T = robot.fk(q)
    T[5::50, :3, 3] *= 10.0  # out of reach
    T[6::50, 0, 0] = np.nan  # not a pose
    T[8::50, :3, :3] *= 1.5  # not rigid
    conf = robot.confdata(q)
    conf[::3] = np.column_stack([rng.integers(-3, 3, (len(conf[::3]), 3)),
                                 rng.integers(0, 8, len(conf[::3]))])
    # the confdata of another valid solution of the same pose: another branch chosen
    sols = robot.ik(T)
    for i in range(1, n, 4):
        valid = np.flatnonzero(sols.valid[i])
        if valid.size:
            conf[i] = robot.confdata(sols.q[i, valid[rng.integers(valid.size)]][None])[0]
    return T, conf


def wide(robot):
    """The robot with axes 2, 3 and 5 turning more than a whole turn: several variants
    of one branch can pass the quadrant tests, so the compact choice must fall back."""
    limits = np.array(robot.limits, dtype=float)
    limits[[1, 2, 4]] = np.radians([[-190.0, 190.0]])
    return RobotModel(robot.name + "-wide", robot.axis_dirs, robot.axis_points, robot.home,
                      limits)


def actual(robot, rng):
    """A calibrated-style model: axis points moved by up to a millimetre (numeric IK)."""
    return robot.with_screws(robot.axis_dirs, robot.axis_points + rng.uniform(-1, 1, (6, 3)))


CASES = [(name, "nominal", seed) for seed, name in enumerate(available_robots())]
CASES += [("IRB1600-10/1.45", "wide", 99), ("IRB2600-12/1.65", "actual", 98)]


@pytest.mark.parametrize(("name", "variant", "seed"), CASES)
def test_compact_choice_is_the_slot_by_slot_choice(name, variant, seed):
    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    robot = {"nominal": robot, "wide": wide(robot), "actual": actual(robot, rng)}[variant]
    T, conf = awkward_targets(robot, rng, 600 if variant == "nominal" else 300)
    sols = robot.ik(T)
    want_q, want_status = reference(robot, sols, conf)
    got_q, got_status = select_by_conf(robot, sols, conf)
    assert np.array_equal(got_status, want_status)
    assert np.array_equal(np.isnan(got_q), np.isnan(want_q))
    assert np.array_equal(np.nan_to_num(got_q), np.nan_to_num(want_q))  # the very same slot
    seen = set(got_status.tolist())
    assert {IKStatus.OK, IKStatus.NO_MATCHING_CONF, IKStatus.UNREACHABLE,
            IKStatus.INVALID_POSE}.issubset(seen)
    if variant != "actual":  # an actual model's wrist is not exactly singular at θ5 = 0
        assert IKStatus.WRIST_SINGULAR in seen
    if variant != "wide":
        assert IKStatus.BEYOND_LIMITS in seen


def nearest_reference(sols, q_prev):
    """The first valid slot (in slot order) at the least squared joint distance."""
    dist = np.where(sols.valid, np.sum((sols.q - q_prev[:, None, :]) ** 2, axis=2), np.inf)
    q = np.full((len(sols), 6), np.nan)
    status = np.asarray(sols.status, dtype=np.int8).copy()
    for i in range(len(sols)):
        if sols.valid[i].any():
            slot = np.flatnonzero(dist[i] == dist[i].min())[0]
            q[i] = sols.q[i, slot]
            status[i] = IKStatus.WRIST_SINGULAR if sols.singular[i, slot] else IKStatus.OK
    return q, status


@pytest.mark.parametrize(("name", "variant", "seed"), CASES)
def test_compact_nearest_is_the_slot_by_slot_nearest(name, variant, seed):
    robot = load_robot(name)
    rng = np.random.default_rng(seed + 1000)
    robot = {"nominal": robot, "wide": wide(robot), "actual": actual(robot, rng)}[variant]
    n = 600 if variant == "nominal" else 300
    T, _ = awkward_targets(robot, rng, n)
    lo, hi = robot.limits[:, 0], robot.limits[:, 1]
    q_prev = rng.uniform(lo, hi, (n, 6))
    sols = robot.ik(T)
    # near one of the solutions, and halfway between two whole-turn variants (a tie)
    for i in range(0, n, 5):
        valid = np.flatnonzero(sols.valid[i])
        if valid.size:
            q_prev[i] = sols.q[i, valid[rng.integers(valid.size)]] + rng.normal(0, 0.01, 6)
    q_prev[2::10, 5] = np.where(np.isfinite(sols.base_q[2::10, 0, 5]),
                                sols.base_q[2::10, 0, 5] + np.pi, 0.0)
    with np.errstate(invalid="ignore"):
        want_q, want_status = nearest_reference(sols, q_prev)
    got_q, got_status = select_nearest(sols, q_prev)
    assert np.array_equal(got_status, want_status)
    assert np.array_equal(np.isnan(got_q), np.isnan(want_q))
    assert np.array_equal(np.nan_to_num(got_q), np.nan_to_num(want_q))
    assert (got_status == IKStatus.OK).sum() > n / 3


def test_large_batches_go_through_in_chunks_with_the_same_answers(monkeypatch):
    from rapidfix import chunks

    robot = load_robot("IRB1600-10/1.45")
    rng = np.random.default_rng(3)
    q = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (50, 6))
    poses = robot.fk(q)
    conf = robot.confdata(q)
    conf[::7, 3] = (conf[::7, 3] + 3) % 8  # some branches that do not match
    poses[5, :3, 3] = [5000.0, 0.0, 0.0]  # out of reach
    whole_q, whole_status = robot.ik_conf(poses, conf)
    monkeypatch.setattr(chunks, "IK_CONF", 8)  # six full chunks and a short one
    q_c, status_c = robot.ik_conf(poses, conf)
    assert np.array_equal(np.nan_to_num(q_c, nan=9.0), np.nan_to_num(whole_q, nan=9.0))
    assert np.array_equal(status_c, whole_status)
    assert {IKStatus.OK, IKStatus.UNREACHABLE} <= set(status_c.tolist())
    ok = status_c == IKStatus.OK
    assert np.allclose(robot.fk(q_c[ok]), poses[ok], atol=1e-8)


def test_nearest_in_chunks_gives_the_answers_of_one_pass(monkeypatch):
    """ik_nearest on a large batch goes through in chunks, each pose with its own q_prev
    (or one q_prev for all): the same joints and statuses as one pass over them all."""
    from rapidfix import chunks

    robot = load_robot("IRB1600-10/1.45")
    rng = np.random.default_rng(4)
    q = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (50, 6))
    poses = robot.fk(q)
    poses[9, :3, 3] = [5000.0, 0.0, 0.0]  # out of reach
    prev = q + rng.normal(0.0, 0.3, q.shape)  # near the pose, not always on its branch
    for q_prev in (prev, prev[0]):
        want_q, want_status = select_nearest(robot.ik(poses, q_prev=q_prev), q_prev)
        monkeypatch.setattr(chunks, "IK_CONF", 8)  # six full chunks and a short one
        got_q, got_status = robot.ik_nearest(poses, q_prev)
        monkeypatch.undo()
        assert np.array_equal(got_status, want_status)
        assert np.array_equal(np.nan_to_num(got_q, nan=9.0), np.nan_to_num(want_q, nan=9.0))
        assert {IKStatus.OK, IKStatus.UNREACHABLE} <= set(got_status.tolist())
        ok = got_status == IKStatus.OK
        assert np.allclose(robot.fk(got_q[ok]), poses[ok], atol=1e-8)


_COMPILED_CASES = [c for c in CASES if c[1] != "actual"]


@pytest.mark.parametrize(("name", "variant", "seed"),
                         _COMPILED_CASES if accelerated() else _COMPILED_CASES[:1])
def test_compiled_choice_is_the_numpy_choice(name, variant, seed):
    """Where the IK's closed form is compiled, the choice is compiled too
    (`conf_compiled`): the same slot and status as the numpy route, boundaries included.
    Without numba neither is compiled, and the choice is numpy's."""
    import dataclasses

    from rapidfix.compiled import load_kernel

    assert (load_kernel("rapidfix.kinematics.conf_compiled") is not None) == accelerated()
    robot = load_robot(name)
    rng = np.random.default_rng(seed + 2000)
    robot = {"nominal": robot, "wide": wide(robot)}[variant]
    T, conf = awkward_targets(robot, rng, 600)
    sols = robot.ik(T)
    assert sols.backend == backend_for(robot)  # numba where installed (and not turned off)
    got_q, got_status = select_by_conf(robot, sols, conf)
    want_q, want_status = select_by_conf(robot, dataclasses.replace(sols, backend="numpy"), conf)
    assert np.array_equal(got_status, want_status)
    assert np.array_equal(np.isnan(got_q), np.isnan(want_q))
    assert np.array_equal(np.nan_to_num(got_q), np.nan_to_num(want_q))


@pytest.mark.parametrize("backend", ["auto", "numpy"])
@pytest.mark.parametrize("name", available_robots())
def test_compiled_conf_quantities_are_numpys_to_rounding(name, backend, monkeypatch):
    """Inside `compiled_forward` the wrist centre's distances behind cfx come from the
    compiled kernel where numba is installed, and from its arithmetic in numpy columns
    (`conf_columns`) where it is not (RAPIDFIX_IK_BACKEND=numpy): the 4×4 products' to
    rounding (1e-9 mm), the angles the same numbers, a joint vector with a NaN all NaN;
    the confdata of awkward targets' solutions and of random joints the same."""
    from rapidfix.compiled import BACKEND_ENV, load_kernel, numpy_only
    from rapidfix.kinematics import conf_columns
    from rapidfix.kinematics.confdata import conf_quantities, confdata
    from rapidfix.kinematics.screws import compiled_forward

    monkeypatch.setenv(BACKEND_ENV, backend)
    calls = []
    kernel = None if numpy_only() else load_kernel("rapidfix.kinematics.conf_compiled")
    owner, name_of = (conf_columns, "wrist_sides") if kernel is None \
        else (kernel, "wrist_sides_rows")
    real = getattr(owner, name_of)
    monkeypatch.setattr(owner, name_of, lambda *args: calls.append(len(args[0])) or real(*args))
    robot = load_robot(name)
    rng = np.random.default_rng(7)
    lo, hi = np.asarray(robot.limits, dtype=float).T
    q = rng.uniform(lo, hi, (500, 6))
    T, _ = awkward_targets(robot, rng, 300)
    solved = robot.ik(T).q.reshape(-1, 6)
    q = np.concatenate([q, solved[np.isfinite(solved).all(axis=1)]])
    with_nan = q.copy()
    with_nan[3, 2] = np.nan
    want = conf_quantities(robot, with_nan)
    assert not calls  # outside the block: numpy's
    with compiled_forward():
        got = conf_quantities(robot, with_nan)
        got_conf = confdata(robot, q)
    assert calls == [len(q)] * 2
    assert np.isnan(got[3]).all() and np.isnan(want[3]).all()
    keep = np.ones(len(q), dtype=bool)
    keep[3] = False
    assert np.array_equal(got[keep][:, [0, 1, 2, 5]], want[keep][:, [0, 1, 2, 5]])
    assert np.allclose(got[keep][:, 3:5], want[keep][:, 3:5], rtol=0, atol=1e-9)
    assert np.array_equal(got_conf, confdata(robot, q))


def test_columns_wrist_sides_are_the_same_across_chunks():
    """`conf_columns.wrist_sides` works through `chunks.FK_COLUMNS` rows at a time; each
    joint vector's sides are its own numbers, wherever a chunk boundary falls."""
    from rapidfix import chunks
    from rapidfix.kinematics import conf_columns
    from rapidfix.kinematics.confdata import _arm_frame

    robot = load_robot("IRB1600-10/1.45")
    w, r, c0, fwd0, side_sign = _arm_frame(robot)
    lo, hi = np.asarray(robot.limits, dtype=float).T
    q = np.random.default_rng(2).uniform(lo, hi, (chunks.FK_COLUMNS + 30, 6))
    whole = conf_columns.wrist_sides(q, w, r, c0, fwd0, side_sign)
    parts = np.concatenate([conf_columns.wrist_sides(q[:45], w, r, c0, fwd0, side_sign),
                            conf_columns.wrist_sides(q[45:], w, r, c0, fwd0, side_sign)])
    assert np.array_equal(whole, parts)
    assert np.all(np.isfinite(whole)) and np.ptp(whole[:, 0]) > 100.0
