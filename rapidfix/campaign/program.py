"""The measurement program: a RAPID module that drives the robot through a pose table.

Straight-line RAPID, one routine per set, so that an operator can read it and any
controller runs it: per measured pose an optional approach move (fly-by, so every
joint arrives from the chosen side), the move to the pose at a fine point,
`WaitTime` to settle, the optional trigger (`PulseDO` of a digital output, or
`TPWrite` of the point id) and a second `WaitTime` while the tracker measures.
Sweeps, calibration and validation poses are `jointtarget`s (`MoveAbsJ`: these
joints are what is measured, never to be compensated); the ISO 9283 poses are
`robtarget`s of the ball tool `tBall` reached with `MoveJ`, so that
`rapidfix rewrite` can compensate them like any program. A payload change stops
the program (`Stop`) with a message, then sets the load (`GripLoad`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from rapidfix import __version__
from rapidfix.campaign.timing import MotionSettings
from rapidfix.kinematics import matrix_to_quat
from rapidfix.rapid import (
    format_declaration,
    format_jointtarget,
    format_num,
    format_robtarget,
    format_string,
    format_tooldata,
)

TRIGGERS = ("none", "pulse", "tpwrite")
ROUTINES = {"sweep": "rfSweeps", "calibration": "rfCalibration",
            "validation": "rfValidation", "iso9283": "rfIso9283"}


@dataclass(frozen=True)
class ProgramOptions:
    """Module name, trigger (`none`, `pulse`, `tpwrite`), the output signal of `pulse`
    and its pulse length, the zone of approach moves, and the motion settings."""

    module: str = "RfMeasure"
    trigger: str = "none"
    signal: str = "doTrackerTrigger"
    pulse_s: float = 0.1
    approach_zone: str = "z10"
    motion: MotionSettings = field(default_factory=MotionSettings)


def rapid_name(prefix: str, point_id: str) -> str:
    """A RAPID identifier (≤ 32 characters) for a point id."""
    name = prefix + re.sub(r"[^A-Za-z0-9_]", "_", point_id)
    return name[:32]


def measurement_module(*, point_id: list[str], set_name: np.ndarray, q: np.ndarray,
                       approach_q: np.ndarray, iso_pose: np.ndarray, iso_q: np.ndarray | None,
                       iso_trans: np.ndarray | None, iso_rot: np.ndarray | None,
                       iso_conf: np.ndarray | None, pause_before: np.ndarray,
                       payload_kg: np.ndarray, smr_mm: np.ndarray, header: list[str],
                       options: ProgramOptions) -> str:
    """The module's text (CRLF-free, `\\n` line ends).

    Rows (N) in execution order: ids, sets, joints (N, 6) rad, approach joints (N, 6) rad
    (NaN rows: none), ISO pose number (0 outside the cube); for the cube the five flange
    poses' joints, ball translation (5, 3) mm, orientation (3, 3) and confdata (5, 4).
    """
    m = options.motion
    decls: dict[str, str] = {}
    lines_by_routine: dict[str, list[str]] = {}
    ind = "        "
    loads: dict[str, float] = {}
    for i, pid in enumerate(point_id):
        routine = ROUTINES[str(set_name[i])]
        body = lines_by_routine.setdefault(routine, [])
        if pause_before[i]:
            kg = float(payload_kg[i])
            load = f"ldRf{format_num(kg, 3).replace('.', '_').replace('-', 'm')}kg"
            loads[load] = kg
            message = f"rapidfix: mount the {kg:g} kg payload, then press PLAY"
            body.append(f"{ind}TPWrite {format_string(message)};")
            body.append(f"{ind}Stop;")
            body.append(f"{ind}GripLoad {load if kg > 0 else 'load0'};")
        body.append(f"{ind}! {pid}")
        if not np.isnan(approach_q[i, 0]):
            side = "u" if iso_pose[i] == 0 else f"P{iso_pose[i]}"
            a_name = (rapid_name("a", pid) if iso_pose[i] == 0
                      else rapid_name("aIso", side + ("u" if np.all(approach_q[i] <= q[i] + 1e-12)
                                                      else "d")))
            decls.setdefault(a_name, format_declaration(
                "CONST", "jointtarget", a_name, format_jointtarget(np.degrees(approach_q[i]))))
            body.append(f"{ind}MoveAbsJ {a_name}, vRfMeasure, {options.approach_zone}, tool0;")
        if iso_pose[i]:
            body.append(f"{ind}MoveJ pIsoP{iso_pose[i]}, vRfMeasure, fine, tBall;")
        else:
            name = rapid_name("j", pid)
            decls[name] = format_declaration("CONST", "jointtarget", name,
                                             format_jointtarget(np.degrees(q[i])))
            body.append(f"{ind}MoveAbsJ {name}, vRfMeasure, fine, tool0;")
        body.append(f"{ind}WaitTime nRfSettle;")
        if options.trigger == "pulse":
            body.append(f"{ind}PulseDO \\PLength:={format_num(options.pulse_s)}, {options.signal};")
        elif options.trigger == "tpwrite":
            body.append(f"{ind}TPWrite {format_string(pid)};")
        body.append(f"{ind}WaitTime nRfMeasure;")

    out = [f"MODULE {options.module}"]
    out += [f"    ! {line}" if line else "    !" for line in header]
    out.append(f"    ! written by rapidfix {__version__} (rapidfix plan)")
    out.append("    CONST speeddata vRfMeasure := ["
               f"{format_num(m.tcp_speed_mm_s)},{format_num(m.orient_speed_deg_s)},5000,1000];")
    out.append(f"    CONST num nRfSettle := {format_num(m.settle_s)};")
    out.append(f"    CONST num nRfMeasure := {format_num(m.measure_s)};")
    out.append("    PERS tooldata tBall := " + format_tooldata(smr_mm, [1.0, 0.0, 0.0, 0.0]) + ";")
    for name, kg in loads.items():
        if kg > 0:
            out.append(f"    PERS loaddata {name} := [{format_num(kg)},"
                       f"[{','.join(format_num(v, 3) for v in smr_mm)}],[1,0,0,0],0,0,0];")
    if iso_q is not None and iso_trans is not None and iso_rot is not None:
        quat = matrix_to_quat(iso_rot)
        for k in range(len(iso_trans)):
            out.append("    CONST robtarget " + f"pIsoP{k + 1} := "
                       + format_robtarget(iso_trans[k], quat, iso_conf[k]) + ";")
    out += ["    " + d for d in decls.values()]
    out.append("")
    out.append("    PROC main()")
    out += [f"        {r};" for r in dict.fromkeys(ROUTINES[str(s)] for s in set_name)]
    out.append("        GripLoad load0;")
    out.append(f"        TPWrite {format_string('rapidfix: measurement finished')};")
    out.append("    ENDPROC")
    for routine, body in lines_by_routine.items():
        out.append("")
        out.append(f"    PROC {routine}()")
        out += body
        out.append("    ENDPROC")
    out.append("ENDMODULE")
    return "\n".join(out) + "\n"
