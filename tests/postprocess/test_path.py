"""Moves kept on their line or arc when they become joint moves (postprocess/path.py, chain.py)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rapidfix.postprocess.path import Curves
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.rapid import load_program, parse_program


def test_curves_follow_lines_and_circles():
    rng = np.random.default_rng(4)
    m = 20
    centre = rng.uniform(-500, 500, (m, 3))
    radius = rng.uniform(10, 300, m)
    basis = Rotation.random(m, random_state=5).as_matrix()
    angles = np.sort(rng.uniform(0.1, 5.5, (m, 3)), axis=1)
    angles[:, 0] = 0.0

    def point(k):
        a = angles[:, k]
        return centre + radius[:, None] * (
            np.cos(a)[:, None] * basis[:, :, 0] + np.sin(a)[:, None] * basis[:, :, 1]
        )

    start, end = np.tile(np.eye(4), (m, 1, 1)), np.tile(np.eye(4), (m, 1, 1))
    start[:, :3, 3], end[:, :3, 3] = point(0), point(2)
    arc = Curves(start, end, point(1), np.ones(m, dtype=bool))
    seg = np.repeat(np.arange(m), 9)
    s = np.tile(np.linspace(0, 1, 9), m)
    pos = arc.positions(seg, s)
    # on the circle, from the start to the end, through the circle point's side
    assert np.allclose(np.linalg.norm(pos - centre[seg], axis=1), radius[seg])
    assert np.allclose(pos[::9], point(0)) and np.allclose(pos[8::9], point(2))
    assert np.allclose(arc.distance(seg, pos), 0.0, atol=1e-9)
    swept = np.angle(np.exp(1j * (angles[:, 2] - angles[:, 0])))
    mid = arc.positions(np.arange(m), np.full(m, 0.5))
    expected_mid = angles[:, 2] / 2.0
    want = centre + radius[:, None] * (
        np.cos(expected_mid)[:, None] * basis[:, :, 0]
        + np.sin(expected_mid)[:, None] * basis[:, :, 1]
    )
    assert np.allclose(mid, want) and swept.shape == (m,)
    line = Curves(start, end, point(1), np.zeros(m, dtype=bool))
    off = (
        point(0)
        + 5.0
        * np.cross(point(2) - point(0), basis[:, :, 2])
        / np.linalg.norm(np.cross(point(2) - point(0), basis[:, :, 2]), axis=1)[:, None]
    )
    assert np.allclose(line.distance(np.arange(m), off), 5.0)


def _circle_program(robot):
    """MoveJ to a start, then one MoveC over half the ballbar circle (confdata from IK)."""

    def target(x, y):
        extax = ",".join(["9E+09"] * 6)
        return f"[[{x},{y},0],[0,0.258819045,0.965925826,0],[CONF],[{extax}]]"

    text = f"""MODULE Circle
  PERS tooldata tBar:=[TRUE,[[0,0,100],[1,0,0,0]],[1.2,[0,0,60],[1,0,0,0],0,0,0]];
  PERS wobjdata wPlate:=[FALSE,TRUE,"",[[850,80,450],[0.923879533,0,-0.382683432,0]],
                         [[0,0,0],[1,0,0,0]]];
  CONST robtarget pS:={target(100, 0)};
  CONST robtarget pM:={target(0, 100)};
  CONST robtarget pE:={target(-100, 0)};
  PROC main()
    MoveJ pS, v100, fine, tBar\\WObj:=wPlate;
    MoveC pM, pE, v100, z1, tBar\\WObj:=wPlate;
  ENDPROC
ENDMODULE
"""
    program = parse_program(text.replace("CONF", "0,0,0,0"))
    conf = []
    for name in ("ps", "pm", "pe"):
        motion = next(
            m for m in program.motions if any(t.name and t.name.lower() == name for t in m.targets)
        )
        t = next(t for t in motion.targets if t.name and t.name.lower() == name).data
        T = (
            _frame(*motion.wobj.data.uframe.__dict__.values())
            @ _frame(t.trans, t.rot)
            @ np.linalg.inv(_frame(motion.tool.data.tframe.trans, motion.tool.data.tframe.rot))
        )
        q, _ = robot.ik_nearest(T[None], np.radians([[5, 25, 30, 0, -20, 10]]))
        conf.append(",".join(str(c) for c in robot.confdata(q)[0]))
    out = text
    for c in conf:
        out = out.replace("CONF", c, 1)
    return out


def _frame(trans, rot):
    T = np.eye(4)
    w, x, y, z = rot
    T[:3, :3] = Rotation.from_quat([x, y, z, w]).as_matrix()
    T[:3, 3] = trans
    return T


def test_movec_becomes_joint_moves_along_the_arc(cell, comp, tmp_path):
    model, robot = cell["model"], cell["robot"]
    text = _circle_program(robot)
    tol = 0.05
    options = RewriteOptions(path_tolerance_mm=tol)
    result = rewrite_source(text.encode(), "circle.mod", comp, options)
    assert not result.skipped and result.points_added > 3
    out_path = tmp_path / "circle.mod"
    out_path.write_bytes(result.data)
    out = load_program(out_path)
    assert [m.name for m in out.motions] == ["MoveAbsJ"] * len(out.motions)
    assert "MoveAbsJ jt_pE, v100, z1, tBar\\WObj:=wPlate;" in out.text  # CirPoint removed
    jts = {
        d.name.lower(): np.radians(np.asarray(d.data.robax, dtype=float))
        for d in out.declarations
        if d.type_key == "jointtarget"
    }
    chain = [jts[m.target.text.lower()] for m in out.motions]
    wobj = _frame([850, 80, 450], [0.923879533, 0, -0.382683432, 0])
    tool = _frame([0, 0, 100], [1, 0, 0, 0])
    s = np.linspace(0, 1, 31)[:, None]
    worst = 0.0
    for q0, q1 in itertools.pairwise(chain):
        tcp = model.actual_flange(robot, q0 + s * (q1 - q0)) @ tool
        local = (np.linalg.inv(wobj) @ tcp)[:, :3, 3]  # the arc: radius 100 about the origin
        dist = np.hypot(np.hypot(local[:, 0], local[:, 1]) - 100.0, local[:, 2])
        worst = max(worst, dist.max())
    assert worst <= tol


def test_first_move_of_a_loop_keeps_its_line(comp, samples):
    """A MoveL whose start is known only at run time keeps MoveL, with a filtered target."""
    text = (
        (samples / "ballbar.mod")
        .read_text()
        .replace("        WaitTime 0.5;\n", "        WHILE TRUE DO\n", 1)
        .replace("        MoveL Offs(pBB18", "        ENDWHILE\n        MoveL Offs(pBB18", 1)
    )
    result = rewrite_source(text.encode(), "loop.mod", comp, RewriteOptions())
    out = result.data.decode()
    # used by this move only: the declaration itself holds the filtered pose
    assert "MoveL pBB01, v50, fine" in out and "pBB01:=[[98.4808,17.3648,0]," not in out
    assert "MoveAbsJ jt_pBB02, v50, fine" in out
    # after ENDWHILE the start is unknown again (last move of the loop or before it)
    assert "MoveL ft_pBB18_offs, v200, z10" in out
    assert result.moves_filtered == 2 and not result.skipped


@pytest.mark.filterwarnings("ignore::rapidfix.error_model.joint_rbf.OutsideRangeWarning")
@pytest.mark.parametrize("step_deg", [0.02, 0.2, 2.0, 10.0])
def test_the_line_bound_holds_for_joint_moves_the_model_predicts(comp, step_deg):
    from rapidfix.error_model.context import Context
    from rapidfix.postprocess.path import chain_span, line_deviation_bound, wrist_levers

    robot, model = comp.robot, comp.model
    rng = np.random.default_rng(int(step_deg * 100))
    n = 300
    lo, hi = robot.limits[:, 0] * 0.8, robot.limits[:, 1] * 0.8
    q0 = rng.uniform(lo, hi, (n, 6))
    q1 = q0 + np.radians(step_deg) * rng.uniform(-1, 1, (n, 6))
    tool = np.array([30.0, -20.0, 150.0])

    def flange(q):
        return model.actual_flange(robot, q, Context(payload_kg=np.full(len(q), 2.0)))

    def carried(q):
        f = flange(q)
        return np.einsum("nij,j->ni", f[:, :3, :3], tool) + f[:, :3, 3]

    # the truth: the predicted path sampled finely, its distance from its own chord
    s = np.linspace(0.0, 1.0, 41)
    path = carried((q0[:, None] + s[None, :, None] * (q1 - q0)[:, None]).reshape(-1, 6))
    path = path.reshape(n, len(s), 3)
    a, b = path[:, :1], path[:, -1:]
    chord = (b - a) / np.linalg.norm(b - a, axis=2, keepdims=True)
    rel = path - a
    off = rel - np.sum(rel * chord, axis=2, keepdims=True) * chord
    truth = np.linalg.norm(off, axis=2).max(axis=1)

    # the bound sees the nominal flange poses the plan has, not the model's
    bound = line_deviation_bound(
        chain_span(robot.axis_points), wrist_levers(robot.axis_dirs, robot.axis_points,
                                                    robot.home),
        robot.fk(q0), robot.fk(q1), np.tile(tool, (n, 1)), q1 - q0)
    assert np.all(truth <= bound)
    # conservative, yet it settles CAM-sized steps
    # (0.5 mm is about 0.02° per joint) without sampling: below 10 % of 0.1 mm
    assert np.median(bound / np.maximum(truth, 1e-12)) < 1000
    if step_deg <= 0.02:
        assert bound.max() < 0.01


def test_wrist_levers_bound_the_distance_from_every_wrist_axis_on_every_robot():
    from rapidfix.kinematics import available_robots, load_robot
    from rapidfix.postprocess.path import wrist_levers

    rng = np.random.default_rng(11)
    for name in available_robots():
        robot = load_robot(name)
        foot, gap = wrist_levers(robot.axis_dirs, robot.axis_points, robot.home)
        q = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (200, 6))
        flange = robot.fk(q)
        point = rng.uniform(-300, 300, (200, 3))  # carried points in the flange frame
        p = np.einsum("nij,nj->ni", flange[:, :3, :3], point) + flange[:, :3, 3]
        lever = np.linalg.norm(p - (flange[:, :3, :3] @ foot + flange[:, :3, 3]), axis=1)
        dirs, points = robot.joint_frames(q)  # the independent way: the axes themselves
        for axis in (3, 4, 5):
            rel = p - points[:, axis]
            along = np.sum(rel * dirs[:, axis], axis=1)[:, None] * dirs[:, axis]
            distance = np.linalg.norm(rel - along, axis=1)
            assert np.all(distance <= lever + gap + 1e-9), (name, axis)


def _bowed_lines(jump: np.ndarray):
    """Straight lines x 0 → 100 mm and a joint model whose joint-linear moves bow off
    them (a parabola, which points close), plus, on the segments `jump`, a branch flip
    half way: joint 3 goes 0 → 1 there, and a joint-linear move across the flip swings
    10 mm off the line however short it is."""
    m = jump.shape[0]
    start, end = np.tile(np.eye(4), (m, 1, 1)), np.tile(np.eye(4), (m, 1, 1))
    end[:, 0, 3] = 100.0
    curves = Curves(start, end, np.zeros((m, 3)), np.zeros(m, dtype=bool))

    def predict(seg, q):
        y = 50.0 * (q[:, 0] - q[:, 0] ** 2) + 20.0 * q[:, 1] + 10.0 * np.sin(np.pi * q[:, 2])
        return np.stack([100.0 * q[:, 0], y, np.zeros(len(q))], axis=1)

    def joints(seg, s):  # on the line: the bow cancelled by joint 2, the flip on joint 3
        q = np.zeros((len(s), 6))
        q[:, 0], q[:, 1] = s, -2.5 * (s - s**2)
        q[:, 2] = np.where(jump[seg] & (s >= 0.5), 1.0, 0.0)
        return q

    calls = []

    def solve(seg, poses, seed):
        calls.append(np.unique(seg))
        q = joints(seg, poses[:, 0, 3] / 100.0)
        return q, q, np.ones(len(seg), dtype=bool)

    ends = (joints(np.arange(m), np.zeros(m)), joints(np.arange(m), np.ones(m)))
    return curves, ends, predict, solve, calls


def test_a_segment_whose_worst_piece_stops_improving_is_given_up_early():
    from rapidfix.postprocess import path

    jump = np.array([False, True, False, True])
    curves, ends, predict, solve, calls = _bowed_lines(jump)
    r = path.refine(curves, ends, ends, 0.1, predict, solve)
    # the smooth lines close within the tolerance; the flips cannot and are given up
    assert r.failed.tolist() == jump.tolist()
    assert np.all(r.deviation[~jump] <= 0.1) and set(r.seg.tolist()) == {0, 2}
    # after STALL_ROUNDS rounds without a better worst piece, not after MAX_ROUNDS
    rounds = sum(1 for c in calls if np.isin(c, np.flatnonzero(jump)).any())
    assert rounds <= path.STALL_ROUNDS + 2 < path.MAX_ROUNDS
    # the smooth lines' points are those a run without the flips gives
    curves2, ends2, predict2, solve2, _ = _bowed_lines(np.zeros(2, dtype=bool))
    r2 = path.refine(curves2, ends2, ends2, 0.1, predict2, solve2)
    assert np.array_equal(r.s[r.seg == 0], r2.s[r2.seg == 0])


def _pick_and_place(robot, n: int = 12) -> tuple[str, np.ndarray]:
    """`MoveAbsJ` to a jointtarget 50 mm above each point, then `MoveL` down to it; every
    third jointtarget holds the same pose with the other wrist (axis 5 negated, 4 and 6
    turned half a turn). Returns the program and which lines start on the other wrist."""
    rng = np.random.default_rng(5)
    wobj = _frame([850, 80, 450], [0.923879533, 0, -0.382683432, 0])
    tool = _frame([0, 0, 100], [1, 0, 0, 0])
    rot = [0, 0.258819045, 0.965925826, 0]
    rot_text = ",".join(map(str, rot))
    extax = ",".join(["9E+09"] * 6)
    flipped = np.arange(n) % 3 == 2
    decls, moves = [], []
    for k in range(n):
        xy = rng.uniform(-120, 120, 2)
        point, above = _frame([*xy, 0.0], rot), _frame([*xy, 50.0], rot)
        seed = np.radians([[5, 25, 30, 0, -20, 10]])
        q, status = robot.ik_nearest((wobj @ point @ np.linalg.inv(tool))[None], seed)
        qa, status_a = robot.ik_nearest((wobj @ above @ np.linalg.inv(tool))[None], q)
        assert status[0] == 0 and status_a[0] == 0
        qa = qa[0]
        if flipped[k]:
            qa = qa + np.array([0, 0, 0, np.pi, 0, np.pi])
            qa[4] = -qa[4]
            qa[[3, 5]] = np.angle(np.exp(1j * qa[[3, 5]]))
        conf = ",".join(str(c) for c in robot.confdata(q)[0])
        joints = ",".join(f"{v:.6f}" for v in np.degrees(qa))
        decls += [f"  CONST jointtarget jA{k}:=[[{joints}],[{extax}]];",
                  f"  CONST robtarget p{k}:=[[{xy[0]:.4f},{xy[1]:.4f},0],[{rot_text}],[{conf}],"
                  f"[{extax}]];"]
        moves += [f"    MoveAbsJ jA{k}\\NoEOffs, v1000, z50, tBar\\WObj:=wPlate;",
                  f"    MoveL p{k}, v200, fine, tBar\\WObj:=wPlate;"]
    return "\n".join([
        "MODULE Pick",
        "  PERS tooldata tBar:=[TRUE,[[0,0,100],[1,0,0,0]],[1.2,[0,0,60],[1,0,0,0],0,0,0]];",
        '  PERS wobjdata wPlate:=[FALSE,TRUE,"",[[850,80,450],[0.923879533,0,-0.382683432,0]],'
        "[[0,0,0],[1,0,0,0]]];",
        *decls, "  PROC main()", *moves, "  ENDPROC", "ENDMODULE", ""]), flipped


def _general_route(monkeypatch):
    """Make refine_paths split every open segment (no segment given up before)."""
    from rapidfix.postprocess import path, refinement

    monkeypatch.setattr(refinement, "refine",
                        lambda *args, given_up=None, **kwargs: path.refine(*args, **kwargs))


@pytest.mark.filterwarnings("ignore::rapidfix.error_model.joint_rbf.OutsideRangeWarning")
def test_lines_that_start_off_their_path_are_given_up_as_the_general_route_gives_them_up(
        cell, comp, monkeypatch):
    from rapidfix.postprocess.refinement import OFF_START

    robot, model = cell["robot"], cell["model"]
    text, _ = _pick_and_place(robot)
    tol = 0.2  # some lines start within it, some off it
    result = rewrite_source(text.encode(), "pick.mod", comp, RewriteOptions(path_tolerance_mm=tol))
    # the truth: where the robot stands after each MoveAbsJ (its joints as written), how
    # far from the line down to the point
    program = parse_program(text)
    wobj = _frame([850, 80, 450], [0.923879533, 0, -0.382683432, 0])
    tool = _frame([0, 0, 100], [1, 0, 0, 0])
    off = 0
    for absj, line in itertools.pairwise(program.motions):
        if absj.name != "MoveAbsJ":
            continue
        q = np.radians(np.asarray(absj.target.data.robax, dtype=float))
        start = (np.linalg.inv(wobj) @ model.actual_flange(robot, q[None])[0] @ tool)[:3, 3]
        a = (np.linalg.inv(wobj) @ robot.fk(q[None])[0] @ tool)[:3, 3]
        b = np.asarray(line.target.data.trans, dtype=float)
        t = np.clip(np.dot(start - a, b - a) / np.dot(b - a, b - a), 0, 1)
        off += np.linalg.norm(start - a - t * (b - a)) > tol
    assert 0 < off < 12
    assert result.filtered_reasons.get(f"{OFF_START} {tol:g} mm") == off
    assert result.points_added > 0  # lines that start within the tolerance are refined
    # the general route splits them for rounds, and gives them up too: the same bytes
    _general_route(monkeypatch)
    general = rewrite_source(text.encode(), "pick.mod", comp,
                             RewriteOptions(path_tolerance_mm=tol))
    assert general.data == result.data and general.moves_filtered == result.moves_filtered
