"""Moves with configuration monitoring off (ConfL/ConfJ \\Off) on the virtual cell.

With monitoring off the controller reaches a robtarget on the configuration nearest
the one it is in, not necessarily the one the target's confdata names (a CAM
post-processor often writes [0,0,0,0] everywhere). The targets here are made from
known joints on one branch (scipy frames, not the post-processor's); their confdata
name another. The rewrite must compensate them on the branch the controller takes,
and the rewritten program must land on the targets on the virtual robot.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_file
from rapidfix.rapid import load_program

#: source joints (deg) of the targets: one smooth path on the elbow-up branch
SOURCE = np.array([[10, 10, 20, 30, 40, 50], [15, 12, 18, 35, 42, 55],
                   [20, 14, 16, 40, 44, 60], [25, 16, 14, 45, 46, 65],
                   [30, 18, 12, 50, 48, 70]], dtype=float)


def _robtarget(T: np.ndarray, conf: list[int]) -> str:
    x, y, z, w = Rotation.from_matrix(T[:3, :3]).as_quat()
    p = T[:3, 3]
    return (f"[[{p[0]:.6f},{p[1]:.6f},{p[2]:.6f}],[{w:.9f},{x:.9f},{y:.9f},{z:.9f}],"
            f"[{conf[0]},{conf[1]},{conf[2]},{conf[3]}],[9E9,9E9,9E9,9E9,9E9,9E9]]")


def _program(robot, switch: str) -> tuple[str, np.ndarray]:
    q = np.radians(SOURCE)
    T = robot.fk(q)
    conf = robot.confdata(q)
    decls = [f"  CONST robtarget p0:={_robtarget(T[0], conf[0].tolist())};"]
    for k in range(1, len(q)):  # cf4 two quadrants off: a branch the arm is not on
        wrong = conf[k].copy()
        wrong[1] += 2
        decls.append(f"  CONST robtarget p{k}:={_robtarget(T[k], wrong.tolist())};")
    moves = ["    MoveJ p0, v100, fine, tool0;", f"    {switch}"]
    moves += [f"    Move{'L' if k % 2 else 'J'} p{k}, v100, fine, tool0;"
              for k in range(1, len(q))]
    text = "MODULE Off\n" + "\n".join(decls) + "\n  PROC main()\n" + "\n".join(moves)
    return text + "\n  ENDPROC\nENDMODULE\n", T


def _landing(cell, path, targets):
    program = load_program(path)
    written = {d.name.lower(): np.radians(np.asarray(d.data.robax, dtype=float))
               for d in program.declarations if d.type_key == "jointtarget"}
    q_cmd = np.array([written[f"jt_p{k}"] for k in range(len(targets))])
    virtual = cell["virtual"]
    flange = virtual.actual_model.fk(virtual.actual_joints(q_cmd))
    return q_cmd, flange[:, :3, 3], targets[:, :3, 3]


def test_monitoring_off_compensates_on_the_branch_the_controller_takes(cell, comp, tmp_path):
    text, targets = _program(cell["robot"], "ConfL \\Off;\n    ConfJ \\Off;")
    src = tmp_path / "off.mod"
    src.write_text(text, encoding="utf-8")
    result = rewrite_file(src, tmp_path / "out.mod", comp, RewriteOptions())
    assert result.moves_compensated == len(SOURCE), result.notes
    q_cmd, landed, wanted = _landing(cell, tmp_path / "out.mod", targets)
    # the branch of the source joints (not the one the confdata name), within the model's
    # correction, and on the true robot within a few hundredths of a millimetre after the
    # joint-1 turn no measurement in the cell sees
    assert np.abs(np.degrees(q_cmd) - SOURCE).max() < 0.2
    err = landed - wanted
    assert np.linalg.norm(err - err.mean(axis=0), axis=1).max() < 0.05
    header = (tmp_path / "out.mod").read_text(encoding="utf-8")
    assert "config_free_moves=4" in header
    assert any("configuration monitoring off" in note and "for 4 of them" in note
               for note in result.notes)


def test_monitoring_on_refuses_a_branch_the_arm_is_not_on(cell, comp, tmp_path):
    text, _ = _program(cell["robot"], "ConfL \\On;")
    src = tmp_path / "on.mod"
    src.write_text(text, encoding="utf-8")
    result = rewrite_file(src, tmp_path / "out.mod", comp, RewriteOptions())
    # the controller would stop at each: no solution on the branch its confdata names
    assert result.moves_compensated == 1
    assert "config_free_moves" not in (tmp_path / "out.mod").read_text(encoding="utf-8")


# axis 6 past 180°: beyond the range the model was fitted on, which the rewrite says
@pytest.mark.filterwarnings("ignore:joint 6 at:rapidfix.error_model.joint_rbf.OutsideRangeWarning")
@pytest.mark.parametrize("path", ["winding", "flipped", "misnamed"])
def test_monitoring_off_follows_the_chain_however_long(cell, comp, tmp_path, path):
    """160 moves whose confdata name no solution (a CAM program's [0,0,0,0]), the first
    on the source's branch. The controller follows the chain, each move nearest the one
    before; so must the rewrite, also past the moves the passes follow one by one, where
    a solution nearest the calibration position would differ. `winding`: axis 6 turns
    from 0° to 300° (it would jump back a turn, -60° for 300°, and the MoveAbsJ unwind
    the wrist). `flipped`: the wrist on its flipped branch (axis 5 negative), whose other
    solution lies nearer the calibration position (the wrist would flip). `misnamed`: the
    same path, each confdata naming the other wrist branch, which the controller ignores
    (taken mid-chain, those solutions would lead the moves after them onto it)."""
    robot = cell["robot"]
    n = 160
    if path == "winding":
        source = np.column_stack([np.full((n, 5), [10.0, 10.0, 20.0, 30.0, 40.0]),
                                  np.linspace(0.0, 300.0, n)])
    else:  # flipped, misnamed
        source = np.column_stack([np.full((n, 3), [10.0, 10.0, 20.0]),
                                  np.linspace(150.0, 166.0, n), np.full(n, -40.0),
                                  np.linspace(150.0, 230.0, n)])
    T = robot.fk(np.radians(source))
    first = robot.confdata(np.radians(source[:1]))[0].tolist()
    written = np.zeros((n, 4), dtype=int)
    if path == "misnamed":  # the other wrist: axis 4 and 6 a half turn round, 5 mirrored
        other = source + np.array([0.0, 0.0, 0.0, -180.0, 0.0, -180.0])
        other[:, 4] *= -1.0
        assert np.allclose(robot.fk(np.radians(other)), T, atol=1e-6)
        written = robot.confdata(np.radians(other))
    written[0] = first
    decls = [f"  CONST robtarget p{k}:={_robtarget(T[k], written[k].tolist())};"
             for k in range(n)]
    moves = ["    MoveJ p0, v100, fine, tool0;", "    ConfL \\Off;", "    ConfJ \\Off;"]
    moves += [f"    MoveJ p{k}, v100, z1, tool0;" for k in range(1, n)]
    src = tmp_path / "wind.mod"
    src.write_text("MODULE Wind\n" + "\n".join(decls) + "\n  PROC main()\n" + "\n".join(moves)
                   + "\n  ENDPROC\nENDMODULE\n", encoding="utf-8")
    result = rewrite_file(src, tmp_path / "out.mod", comp, RewriteOptions())
    assert result.moves_compensated == n
    q_cmd, landed, wanted = _landing(cell, tmp_path / "out.mod", T)
    assert np.abs(np.degrees(q_cmd) - source).max() < 0.2  # every turn as the source's
    assert np.abs(np.diff(np.degrees(q_cmd), axis=0)).max() < 3.0  # no jump, no flip
    err = landed - wanted
    assert np.linalg.norm(err - err.mean(axis=0), axis=1).max() < 0.05
