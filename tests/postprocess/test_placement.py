"""Per-move tool and work-object frames (postprocess/placement.py, resolve.py)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from rapidfix.rapid import load_program, parse_program


def _frame(trans, rot):
    T = np.eye(4)
    w, x, y, z = rot
    T[:3, :3] = Rotation.from_quat([x, y, z, w]).as_matrix()
    T[:3, 3] = trans
    return T


def _random_frames(n: int, seed: int, start: int, reach: float) -> np.ndarray:
    """(3, n, 4, 4) poses: rotations of random_state start, start+1, start+2 and
    positions uniform within ±reach mm."""
    rng = np.random.default_rng(seed)
    frames = np.tile(np.eye(4), (3, n, 1, 1))
    for k in range(3):
        frames[k, :, :3, :3] = Rotation.random(n, random_state=start + k).as_matrix()
        frames[k, :, :3, 3] = rng.uniform(-reach, reach, (n, 3))
    return frames


def test_placement_matches_the_kinematics_frames_for_both_tool_kinds():
    from rapidfix.kinematics.frames import Tool, WorkObject, flange_target
    from rapidfix.postprocess.placement import Placement

    n = 6
    tool, wobj, target = _random_frames(n, 2, 0, 300)
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

    n = 7
    frames = _random_frames(n, 3, 10, 300)
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


def test_tcp_positions_are_the_positions_of_the_tcp_poses():
    """The positions alone (the path check's and the predicted errors' need) are those
    of the whole TCP poses to rounding: frames per move and shared, tools on the robot
    and held still (the robot carrying the work)."""
    from rapidfix.postprocess.placement import Placement, shared

    n = 9
    tool, wobj, flange = _random_frames(n, 5, 20, 900)
    for stationary in (np.zeros(n, bool), np.arange(n) % 3 == 1):
        for placement in (Placement(tool, wobj, stationary),
                          Placement(shared(tool[0], n), shared(wobj[0], n), stationary),
                          Placement(tool, shared(wobj[0], n), stationary)):
            want = placement.tcp(flange)[:, :3, 3]
            got = placement.tcp_positions(flange)
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
