"""Pieces of the post-processor on their own: names, header, curves, MoveC, move chains."""

from __future__ import annotations

import itertools
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from rapidfix.postprocess.header import Header, is_compensated, read_header
from rapidfix.postprocess.naming import MAX_IDENTIFIER, NameAllocator, identifiers_in
from rapidfix.postprocess.path import Curves
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.rapid import load_program, parse_program

IDENT = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,31}$")


@settings(max_examples=60, deadline=None)
@given(
    taken=st.lists(st.from_regex(r"[A-Za-z][A-Za-z0-9_]{0,40}", fullmatch=True), max_size=30),
    stems=st.lists(st.text(min_size=0, max_size=45), min_size=1, max_size=30),
)
def test_allocated_names_are_valid_and_unique(taken, stems):
    names = NameAllocator(taken)
    used = {t.lower() for t in taken}
    for stem in stems:
        name = names.allocate(stem)
        assert IDENT.match(name) and len(name) <= MAX_IDENTIFIER
        assert name.lower() not in used
        used.add(name.lower())


@settings(max_examples=100, deadline=None)
@given(
    words=st.lists(st.from_regex(r"[A-Za-z0-9_]{0,12}", fullmatch=True), max_size=20),
    separators=st.lists(st.sampled_from([" ", "\n", ",", ":=", "(", "9", "_", "!", "é"]),
                        min_size=20, max_size=20),
    stems=st.lists(st.sampled_from(["p1", "P1", "x", "p1_2", "a9", "Ⅷ", ""]), min_size=1,
                   max_size=12),
    prefix=st.sampled_from(["jt_", "ft_", "JT_", "_", ""]),
)
def test_names_avoid_every_identifier_of_the_texts_it_is_given(words, separators, stems, prefix):
    text = "".join(w + s for w, s in zip(words, separators))
    names = NameAllocator(texts=[text])
    used = identifiers_in(text)  # every identifier, the independent way
    for stem in stems:
        name = names.allocate(stem, prefix)
        assert IDENT.match(name) and name.lower() not in used
        used.add(name.lower())
    assert not names.is_free(next(iter(used)))


def test_names_follow_the_robtarget_and_avoid_collisions():
    names = NameAllocator(["JT_P10", "jt_p20"])
    assert names.allocate("p30") == "jt_p30"
    assert names.allocate("p10") == "jt_p10_2"  # case-insensitive collision
    assert names.allocate("p20") == "jt_p20_2"
    assert names.allocate("p20") == "jt_p20_3"
    long = names.allocate("x" * 40)
    assert len(long) == MAX_IDENTIFIER and long.startswith("jt_x")


def test_header_round_trip():
    header = Header(
        "1.2.3",
        "models/cell model.json",
        "a" * 64,
        "b" * 64,
        {"emit": "jointtargets", "path_tolerance_mm": "0.1"},
        "3 moves",
    )
    text = "MODULE M" + header.render("  ", "\r\n") + "\r\nENDMODULE\r\n"
    back = read_header(text)
    assert back.model_sha256 == "a" * 64 and back.input_sha256 == "b" * 64
    assert back.options == {"emit": "jointtargets", "path_tolerance_mm": "0.1"}
    assert back.version == "1.2.3" and back.model_path == "models/cell model.json"
    assert is_compensated(text) and not is_compensated("MODULE M\n! rapidfix rocks\nENDMODULE\n")


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


def test_placement_matches_the_kinematics_frames_for_both_tool_kinds():
    from rapidfix.kinematics.frames import Tool, WorkObject, flange_target
    from rapidfix.postprocess.placement import Placement

    rng = np.random.default_rng(2)
    n = 6
    poses = np.tile(np.eye(4), (3, n, 1, 1))
    for k in range(3):
        poses[k, :, :3, :3] = Rotation.random(n, random_state=k).as_matrix()
        poses[k, :, :3, 3] = rng.uniform(-300, 300, (n, 3))
    tool, wobj, target = poses
    stationary = np.array([False, True] * (n // 2))
    placement = Placement(tool, wobj, stationary)
    flange = placement.flange(target)
    for i in range(n):
        want = flange_target(
            target[i],
            Tool(tool[i], robhold=not stationary[i]),
            WorkObject(uframe=wobj[i], robhold=bool(stationary[i])),
        )
        assert np.allclose(flange[i], want)
    assert np.allclose(placement.tcp(flange), target)


def test_shared_frames_give_what_copied_frames_give():
    """One tool and work object broadcast to every move (no copies) converts, subsets
    and inverts exactly as the same frames copied per move, and stays broadcast."""
    from rapidfix.postprocess.placement import Placement, shared

    rng = np.random.default_rng(3)
    n = 7
    frames = np.tile(np.eye(4), (3, n, 1, 1))
    for k in range(3):
        frames[k, :, :3, :3] = Rotation.random(n, random_state=10 + k).as_matrix()
        frames[k, :, :3, 3] = rng.uniform(-300, 300, (n, 3))
    tool, wobj, target = frames[0][0], frames[1][0], frames[2]
    for stationary in (np.zeros(n, bool), np.array([False, True] * 3 + [False])):
        one = Placement(shared(tool, n), shared(wobj, n), stationary)
        copied = Placement(np.tile(tool, (n, 1, 1)), np.tile(wobj, (n, 1, 1)), stationary)
        assert one.tool.strides[0] == 0  # one matrix, viewed n times
        assert np.allclose(one.flange(target), copied.flange(target))
        assert np.allclose(one.tcp(copied.flange(target)), target)
        for index in (np.array([4, 1, 1]), stationary, np.arange(n)):
            part, want = one.take(index), copied.take(index)
            assert part.tool.strides[0] == 0 and len(part) == len(want)
            assert np.array_equal(part.tool, want.tool) and np.array_equal(part.wobj, want.wobj)
            assert np.allclose(part.flange(target[index]), want.flange(target[index]))


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


def test_targets_are_the_target_operands_among_the_arguments(samples):
    count = 0
    for path in sorted(samples.iterdir()):
        if path.suffix.lower() not in (".mod", ".prg"):
            continue
        for motion in load_program(path).motions:
            arguments = motion.arguments
            want = [arguments[key] for key in motion.spec.target_keys if key in arguments]
            assert len(motion.targets) == len(want)
            assert all(a is b for a, b in zip(motion.targets, want))
            count += 1
    assert count > 50


joint_values = st.one_of(
    st.floats(-400, 400, allow_nan=False),
    st.sampled_from([0.0, -0.0, -4e-7, 4e-7, -5e-7, 5e-7, 1e-6, -1e-6, 10.0, -100.0, 12.5,
                     0.0000105, 359.9999996, -179.9999995, 100.0, -1000.0, 1e7, 20.5, -0.1,
                     1e8, -3e9]),
)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(*[joint_values] * 6), min_size=1, max_size=8),
       st.sampled_from([9e9, 0.0, -12.25]))
def test_jointtarget_literals_are_what_format_jointtarget_writes(rows, ext):
    from rapidfix.postprocess.literals import jointtarget_literals
    from rapidfix.rapid.format import format_jointtarget

    q = np.array(rows)
    extax = np.full((len(rows), 6), ext)
    got = jointtarget_literals(q, extax)
    assert got == [format_jointtarget(r, e) for r, e in zip(q.tolist(), extax.tolist())]


def test_each_move_gets_its_own_work_object_and_load_with_the_same_tool():
    from rapidfix.postprocess.resolve import Declarations, resolve

    extax = ",".join(["9E+09"] * 6)
    target = f"[[10,20,30],[0,0.258819045,0.965925826,0],[0,0,0,0],[{extax}]]"
    text = f"""MODULE Frames
  PERS tooldata tBar:=[TRUE,[[0,0,100],[1,0,0,0]],[1.2,[0,0,60],[1,0,0,0],0,0,0]];
  PERS wobjdata wA:=[FALSE,TRUE,"",[[850,80,450],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  PERS wobjdata wB:=[FALSE,TRUE,"",[[700,-80,400],[0.923879533,0,-0.382683432,0]],
                     [[5,0,0],[1,0,0,0]]];
  PERS loaddata heavy:=[7.5,[0,0,50],[1,0,0,0],0,0,0];
  CONST robtarget p1:={target};
  PROC main()
    MoveJ p1, v100, fine, tBar\\WObj:=wA;
    MoveJ p1, v100, fine, tBar\\WObj:=wB;
    MoveJ p1, v100, fine, tBar;
    MoveJ p1, v100, fine, tBar\\WObj:=wB\\TLoad:=heavy;
  ENDPROC
ENDMODULE
"""
    sites, t = resolve(parse_program(text), Declarations([]), "jointtargets")
    assert [s.reason for s in sites] == [None] * 4
    wa = _frame([850, 80, 450], [1, 0, 0, 0])
    wb = _frame([700, -80, 400], [0.923879533, 0, -0.382683432, 0]) @ _frame([5, 0, 0],
                                                                           [1, 0, 0, 0])
    for row, wobj in enumerate([wa, wb, np.eye(4), wb]):
        assert np.allclose(t.placement.wobj[row], wobj, atol=1e-9)
    assert t.payload_kg.tolist() == [1.2, 1.2, 1.2, 7.5]


@pytest.mark.filterwarnings("ignore::rapidfix.errors.joint_rbf.OutsideRangeWarning")
@pytest.mark.parametrize("step_deg", [0.02, 0.2, 2.0, 10.0])
def test_the_line_bound_holds_for_joint_moves_the_model_predicts(comp, step_deg):
    from rapidfix.errors.context import Context
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


@settings(max_examples=200, deadline=None)
@given(
    taken=st.lists(st.sampled_from(["jt_p1", "JT_P2", "jt_p1_2", "x", "jt_"]), max_size=4),
    stems=st.lists(st.sampled_from(["p1", "P1", "p2", "p3", "_p4", "a" * 31, "b c", "9"]),
                   max_size=8),
    prefix=st.sampled_from(["jt_", "ft_", "_"]),
)
def test_allocating_many_names_gives_what_allocating_one_by_one_gives(taken, stems, prefix):
    text = " ".join(taken)
    one = NameAllocator(texts=[text])
    many = NameAllocator(texts=[text])
    assert many.allocate_many(stems, prefix) == [one.allocate(s, prefix) for s in stems]
    assert many.allocate("p1", prefix) == one.allocate("p1", prefix)


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


def test_the_written_out_moveabsj_is_the_statement_the_general_edits_make():
    from rapidfix.postprocess.resolve import Declarations, resolve
    from rapidfix.postprocess.rewrite import _joint_edits, _joint_statement, _statement_variant

    samples = Path(__file__).resolve().parents[2] / "samples"
    checked = 0
    for path in sorted(samples.glob("*.mod")):
        program = load_program(path)
        sites, _ = resolve(program, Declarations([]), "jointtargets")
        for site in sites:
            if site.kind in "LJC" and site.targets:
                general = _statement_variant(program, site.motion, _joint_edits(site, "jt_x"))
                assert _joint_statement(program.text, site, "jt_x") == general
                checked += 1
    assert checked > 20


def test_loading_a_compensator_prepares_its_robot(cell, monkeypatch):
    """The compiled IK kernel's one-time load happens with the model, not in a rewrite."""
    from rapidfix.postprocess import compensator

    prepared = []
    monkeypatch.setattr(compensator, "prepare", prepared.append)
    comp = compensator.Compensator.load(cell["model_path"])
    assert prepared == [comp.robot]
