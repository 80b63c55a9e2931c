"""IK on the confdata branch and loading the compensator (postprocess/plan.py, compensator.py)."""

from __future__ import annotations

import numpy as np
import pytest


def test_ik_on_conf_gives_the_first_matching_slot_of_the_expanded_solutions(cell):
    from rapidfix.kinematics import IKStatus
    from rapidfix.kinematics.confdata import conf_matches
    from rapidfix.postprocess.plan import ik_on_conf

    robot = cell["robot"]
    rng = np.random.default_rng(8)
    q = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (400, 6))
    q[::10, 4] = 0.0  # wrist singular
    q[5::10, 0] = np.radians(90.0)  # on a quadrant boundary
    poses = robot.fk(q)
    conf = robot.confdata(q)
    conf[::3] = np.column_stack(
        [rng.integers(-2, 2, (len(conf[::3]), 3)), rng.integers(0, 8, len(conf[::3]))]
    )
    poses[7, :3, 3] = [5000.0, 0.0, 0.0]  # out of reach
    # reference: the first slot, over every branch and ±360° variant, whose joints are
    # valid and have the confdata
    sols = robot.ik(poses)
    match = sols.valid & conf_matches(robot, sols.q, conf[:, None, :])
    found = match.any(axis=1)
    slot = np.argmax(match, axis=1)
    want_q = np.where(found[:, None], sols.q[np.arange(len(conf)), slot], np.nan)
    want_status = np.where(found, IKStatus.OK, IKStatus.NO_MATCHING_CONF)
    want_status[found & sols.singular[np.arange(len(conf)), slot]] = IKStatus.WRIST_SINGULAR
    none = ~sols.valid.any(axis=1)
    want_status[none] = sols.status[none]
    got_q, got_status = ik_on_conf(robot, poses, conf)
    assert np.array_equal(want_status, np.asarray(got_status))
    assert np.array_equal(np.nan_to_num(want_q, nan=7.0), np.nan_to_num(got_q, nan=7.0))
    assert {0, 1, 4}.issubset(set(np.asarray(got_status).tolist()))


def test_small_programs_solve_in_numpy_large_ones_with_the_compiled_kernels(cell):
    """The compiled kernels' one-time load (0.4-0.7 s) costs more than they save on a
    small program: below COMPILED_FROM_WORK (moves, an arc counting four) the rewrite
    stays in numpy. The choice is the program's alone, not what the process ran before."""
    from rapidfix.error_model import joint_rbf
    from rapidfix.kinematics import ik, screws
    from rapidfix.postprocess import rewrite

    robot = cell["robot"]
    assert robot.is_nominal
    with rewrite._kernels_for(rewrite.COMPILED_FROM_WORK - 1):
        assert ik.backend_for(robot) == "numpy"
        assert not screws._COMPILED.get() and not joint_rbf._COMPILED.get()
    with rewrite._kernels_for(rewrite.COMPILED_FROM_WORK):
        assert ik.backend_for(robot) == ("numba" if ik.accelerated() else "numpy")
        assert screws._COMPILED.get() and joint_rbf._COMPILED.get()
    assert ik.backend_for(robot) == ("numba" if ik.accelerated() else "numpy")


def test_the_kernels_are_chosen_by_the_moves_an_arc_counting_four():
    """An arc's circle point, and the points its path check samples and inserts, make
    it about four moves' work of the kernels; other instructions count once."""
    from rapidfix.postprocess.rewrite import kernel_work
    from rapidfix.rapid import parse_program

    text = "\n".join([
        "MODULE M", "PROC main()",
        "  MoveL p1, v100, z1, tool0;", "  MoveJ p2, v100, z1, tool0;",
        "  MoveC p1, p2, v100, z1, tool0;", "  MoveC Offs(p1,0,1,0), p2, v100, fine, tool0;",
        "  MoveAbsJ j1, v100, z1, tool0;", "  SetDO do1, 1;",
        "  TriggC p1, p2, v100, t1, z1, tool0;",
        "ENDPROC", "ENDMODULE", ""])
    assert kernel_work(parse_program(text, "arcs.mod")) == 3 + 4 * 3


@pytest.mark.parametrize("chunk", [64, 2048])
def test_a_target_on_a_wrong_branch_names_the_nearest_confdata_that_reach_it(
        cell, chunk, monkeypatch):
    """The reason names, per target, the three nearest distinct confdata among the valid
    solutions (distance: sum of absolute differences; ties in confdata order). Reference:
    each target on its own, np.unique then a stable sort, as the rule reads; in one
    pass and in chunks."""
    from rapidfix import chunks
    from rapidfix.kinematics import IKStatus
    from rapidfix.postprocess.plan import _explain_conf

    monkeypatch.setattr(chunks, "EXPLAIN_CONF", chunk)

    robot = cell["robot"]
    rng = np.random.default_rng(21)
    q = rng.uniform(robot.limits[:, 0] * 0.9, robot.limits[:, 1] * 0.9, (300, 6))
    poses = robot.fk(q)
    conf = robot.confdata(q) + np.array([3, -4, 5, 0])  # a branch no solution is on
    status = np.full(300, IKStatus.NO_MATCHING_CONF)
    status[::7] = IKStatus.OK  # not explained
    reason = np.full(300, "", dtype=object)
    _explain_conf(robot, poses, conf, status, reason)
    sols = robot.ik(poses)
    for row in range(300):
        if status[row] == IKStatus.OK:
            assert reason[row] == ""
            continue
        found = np.unique(robot.confdata(sols.q[row][sols.valid[row]]), axis=0)
        order = np.argsort(np.abs(found - conf[row]).sum(axis=1), kind="stable")
        want = ", ".join(str(found[i].tolist()) for i in order[:3])
        assert reason[row] == (f"no solution on the branch its confdata {conf[row].tolist()} "
                               f"names (it is reachable with {want})")


def _followed(q: np.ndarray, extra: np.ndarray, prev: np.ndarray, turns: np.ndarray,
              limits: np.ndarray) -> np.ndarray:
    """The chains walked one move at a time (each move after the ones before it): a move's
    turning joints by whole turns nearest the move before it, as moved already."""
    n = q.shape[0]
    points = np.concatenate([q, extra])
    want = points.copy()
    for k in range(n):
        up = prev[k]
        if up < 0 or not (np.isfinite(q[k]).all() and np.isfinite(want[up]).all()):
            continue
        # the whole turns the move before took, and those between the two as they stand
        shift = (want[up] - points[up]) + 2 * np.pi * np.round((points[up] - q[k]) / (2 * np.pi))
        moved = np.where(turns, q[k] + shift, q[k])
        if np.all((moved >= limits[:, 0]) & (moved <= limits[:, 1])):
            want[k] = moved
    return want[:n]


def test_joints_unwound_along_chains_are_those_followed_move_by_move(cell):
    """`_unwound` (turns summed by pointer jumping) against the chains walked one move at
    a time; a move that would leave the limits keeps its joints, and the moves after it
    follow those."""
    from rapidfix.postprocess.plan import _unwound

    robot = cell["robot"]
    limits = np.asarray(robot.limits, dtype=float)
    turns = limits[:, 1] - limits[:, 0] > 2 * np.pi + 1e-9
    rng = np.random.default_rng(5)
    for trial in range(40):
        n, m = int(rng.integers(1, 60)), int(rng.integers(0, 4))
        # a path whose turning joints drift over several turns, taken within one turn
        path = np.cumsum(rng.normal(0.0, 0.4, (n, 6)), axis=0)
        q = np.where(turns, (path + np.pi) % (2 * np.pi) - np.pi, np.clip(path, -1, 1))
        extra = rng.uniform(-np.pi, np.pi, (m, 6))
        prev = np.full(n + m, -1, dtype=np.int64)
        for k in range(n):  # each move after one before it (a forest of chains), or none
            choice = int(rng.integers(-1, k + m)) if k + m else -1
            prev[k] = -1 if choice < 0 else (n + choice if choice < m else choice - m)
        q[rng.random(n) < 0.05] = np.nan  # a move without a solution breaks its chain
        got = _unwound(robot, q, extra, prev, np.flatnonzero(prev[:n] >= 0))
        want = _followed(q, extra, prev, turns, limits)
        assert np.array_equal(np.isnan(got), np.isnan(want)), trial
        assert np.allclose(got[~np.isnan(got)], want[~np.isnan(want)], atol=1e-12), trial


def test_spans_are_the_ranges_one_after_the_other():
    from rapidfix.postprocess.plan import _spans

    rng = np.random.default_rng(2)
    for _ in range(50):
        lo = rng.integers(0, 30, rng.integers(0, 8))
        hi = lo + rng.integers(0, 5, lo.size)
        want = [k for a, b in zip(lo.tolist(), hi.tolist()) for k in range(a, b)]
        assert _spans(lo, hi).tolist() == want
