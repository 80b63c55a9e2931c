"""A generated CAM-style milling program for the post-processor benchmarks.

Zig-zag passes over a 300 x 200 mm plate in the ballbar's inclined work object:
one CONST robtarget and one MoveL per point, confdata from the kinematics so
that every target is on its named branch. About two lines per move.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from rapidfix.kinematics import load_robot
from rapidfix.rapid.format import format_num

ROBOT = "IRB1600-10/1.45"
WOBJ = ((850.0, 80.0, 450.0), (0.923879533, 0.0, -0.382683432, 0.0))
TOOL = ((0.0, 0.0, 100.0), (1.0, 0.0, 0.0, 0.0))
ROT = (0.0, 0.258819045, 0.965925826, 0.0)


def _frame(trans, rot) -> np.ndarray:
    T = np.eye(4)
    w, x, y, z = rot
    T[:3, :3] = Rotation.from_quat([x, y, z, w]).as_matrix()
    T[:3, 3] = trans
    return T


def cam_positions(n_moves: int) -> np.ndarray:
    """Zig-zag points (n, 3) mm in the work object, 0.5 mm apart along each pass."""
    per_pass = 600
    k = np.arange(n_moves)
    row, col = divmod(k, per_pass)
    col = np.where(row % 2 == 0, col, per_pass - 1 - col)
    x = -150.0 + 0.5 * col
    y = -100.0 + (row % 200) * 1.0
    z = -0.2 * (row // 200)
    return np.stack([x, y, z], axis=1)


def cam_program(n_moves: int, name: str = "Cam") -> str:
    """RAPID text of a CAM program with n_moves MoveL to n_moves CONST robtargets."""
    robot = load_robot(ROBOT)
    pos = cam_positions(n_moves)
    target = np.tile(_frame((0, 0, 0), ROT), (n_moves, 1, 1))
    target[:, :3, 3] = pos
    flange = _frame(*WOBJ) @ target @ np.linalg.inv(_frame(*TOOL))
    q, status = robot.ik_nearest(flange, np.radians([[8, 28, 35, 20, -20, 12]]))
    if not np.all(status == 0):
        raise RuntimeError("a generated CAM target is out of reach")
    conf = robot.confdata(q)
    extax = ",".join(["9E+09"] * 6)
    rot = ",".join(format_num(v, 9) for v in ROT)
    decls = [
        f"  CONST robtarget p{i}:=[[{x:.3f},{y:.3f},{z:.3f}],[{rot}],"
        f"[{c[0]},{c[1]},{c[2]},{c[3]}],[{extax}]];"
        for i, ((x, y, z), c) in enumerate(zip(pos.tolist(), conf.tolist()))
    ]
    moves = ["    MoveJ p0, v500, fine, tMill\\WObj:=wPlate;"]
    moves += [f"    MoveL p{i}, v100, z1, tMill\\WObj:=wPlate;" for i in range(1, n_moves)]
    (tx, ty, tz), trot = TOOL
    (wx, wy, wz), wrot = WOBJ
    head = [
        f"MODULE {name}",
        f"  PERS tooldata tMill:=[TRUE,[[{tx:g},{ty:g},{tz:g}],[{','.join(map(str, trot))}]],"
        "[2.5,[0,0,60],[1,0,0,0],0,0,0]];",
        f'  PERS wobjdata wPlate:=[FALSE,TRUE,"",[[{wx:g},{wy:g},{wz:g}],'
        f"[{','.join(map(str, wrot))}]],[[0,0,0],[1,0,0,0]]];",
    ]
    return "\n".join([*head, *decls, "  PROC main()", *moves, "  ENDPROC", "ENDMODULE", ""])
