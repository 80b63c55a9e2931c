"""The source paper's ballbar test as a RAPID program (samples/ballbar.mod is its output).

The ball on the tool visits discrete points of a semicircle (radius 100 mm, 10°
steps) in a plane inclined 45°: the xy plane of a work object tilted −45° about
the base y axis, whose origin is the ballbar's fixed pivot. Fine stops at every
point, where the bar length is read. The demo rewrites it even when the samples
folder is not installed.
"""

from __future__ import annotations

import numpy as np

RADIUS_MM = 100.0
STEP_DEG = 10
QUAT = "0,0.258819045,0.965925826,0"
CONF = "0,0,0,1"
EXTAX = "9E+09,9E+09,9E+09,9E+09,9E+09,9E+09"


def _num(x: float) -> str:
    text = f"{x:.4f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def ballbar_program() -> str:
    """RAPID text of the ballbar semicircle program (LF line ends)."""
    angles = np.radians(np.arange(0, 181, STEP_DEG))
    points = [(RADIUS_MM * np.cos(a), RADIUS_MM * np.sin(a)) for a in angles]
    decls = [
        f"    CONST robtarget pBB{k:02d}:=[[{_num(x)},{_num(y)},0],[{QUAT}],[{CONF}],[{EXTAX}]];"
        for k, (x, y) in enumerate(points)
    ]
    moves = [f"        MoveL pBB{k:02d}, v50, fine, tBallbar\\WObj:=wobjBallbar;"
             for k in range(1, len(points))]
    lines = [
        "MODULE Ballbar",
        "    ! Ballbar test of the source paper: the ball on the tool visits discrete points",
        "    ! of a semicircle (radius 100 mm, 10 degree steps) in a plane inclined 45 degrees.",
        "    ! The ballbar's fixed pivot is the origin of wobjBallbar; its length is read at",
        "    ! every point (fine stops). Written for rapidfix; robot IRB 1600-10/1.45.",
        "    PERS tooldata tBallbar:=[TRUE,[[0,0,100],[1,0,0,0]],"
        "[1.2,[0,0,60],[1,0,0,0],0,0,0]];",
        "    ! The circle's plane: work object xy plane, tilted -45 degrees about the base y axis.",
        '    PERS wobjdata wobjBallbar:=[FALSE,TRUE,"",[[850,80,450],'
        "[0.923879533,0,-0.382683432,0]],[[0,0,0],[1,0,0,0]]];",
        *decls,
        "",
        "    PROC main()",
        "        ! approach above the first point, then the semicircle, then leave",
        "        MoveJ Offs(pBB00,0,0,50), v200, z10, tBallbar\\WObj:=wobjBallbar;",
        "        MoveL pBB00, v50, fine, tBallbar\\WObj:=wobjBallbar;",
        "        WaitTime 0.5;",
        *moves,
        "        MoveL Offs(pBB18,0,0,50), v200, z10, tBallbar\\WObj:=wobjBallbar;",
        "    ENDPROC",
        "ENDMODULE",
        "",
    ]
    return "\n".join(lines)
