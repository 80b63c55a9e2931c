"""Targets with external axis values: a track may carry the robot, a positioner the work.

Nothing in a program says which external axis moves what, and the joints of the arm
depend on it: a target 1,500 mm along a track solved as if the robot stood at the
track's zero puts the arm 1.5 m off. Such moves are left as they were unless the user
says the axes carry neither (`static_external_axes`); 0 and RAPID's 9E9 (unused) are
where the robot stands as configured, and are compensated as before.
"""

from __future__ import annotations

import re

import numpy as np

from rapidfix.cli import main
from rapidfix.postprocess.resolve import Declarations, resolve
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.rapid import parse_program

Q = "[0,0.258819045,0.965925826,0]"
CONF = "[0,0,-1,1]"
UNUSED = "9E+09"


def _target(x: float, eax_a: str = UNUSED, eax_b: str = UNUSED, quat: str = Q) -> str:
    return f"[[{x:g},50,0],{quat},{CONF},[{eax_a},{eax_b},9E9,9E9,9E9,9E9]]"


RESOLVED = f"""MODULE M
  PERS tooldata tBar:=[TRUE,[[0,0,100],[1,0,0,0]],[1.2,[0,0,60],[1,0,0,0],0,0,0]];
  CONST robtarget pUnused:={_target(501)};
  CONST robtarget pZeroAxis:={_target(502, "0", "0")};
  CONST robtarget pTrack:={_target(503, "1500")};
  PROC main()
    MoveL pUnused, v100, z1, tBar;
    MoveL pTrack, v100, z1, tBar;
    MoveL {_target(504, quat="[0,0,0,0]")}, v100, z1, tBar;
    MoveL pZeroAxis, v100, z1, tBar;
    MoveC {_target(505, eax_b="-90")}, {_target(506)}, v100, z1, tBar;
    MoveC {_target(507)}, {_target(508, "12.5", "45")}, v100, z1, tBar;
    MoveC {_target(509)}, {_target(510)}, v100, z1, tBar;
    MoveL {_target(511, "-0.5")}, v100, z1, tBar;
    MoveL {_target(512)}, v100, z1, tBar;
  ENDPROC
ENDMODULE
"""


def test_a_target_with_an_external_axis_standing_is_left_with_the_axis_named():
    program = parse_program(RESOLVED.encode(), "m.mod")
    sites, targets = resolve(program, Declarations([]), "jointtargets",
                             static_external_axes=False)
    reasons = [site.reason for site in sites]
    assert reasons[0] is None and reasons[3] is None and reasons[6] is None
    assert reasons[8] is None
    assert reasons[1].startswith("external axis eax_a at 1500: a track")
    assert reasons[2] == "orientation quaternion is zero"
    assert reasons[4].startswith("CirPoint ") and "eax_b at -90:" in reasons[4]
    assert reasons[5].startswith("external axes eax_a at 12.5, eax_b at 45:")
    assert "eax_a at -0.5:" in reasons[7]
    # the rows left are the compensated targets', numbered 0..N-1 in program order
    rows = [row for site in sites for row in site.rows]
    assert rows == list(range(len(targets.site)))
    expected = {0: [501], 3: [502], 6: [509, 510], 8: [512]}
    for i, xs in expected.items():
        assert np.array_equal(targets.pose[sites[i].rows, 0, 3], xs)
        assert np.all(targets.site[sites[i].rows] == i)
    assert np.array_equal(targets.extax[sites[3].rows], [[0, 0, 9e9, 9e9, 9e9, 9e9]])
    # told the axes carry nothing, every target but the zero quaternion is compensated
    sites, targets = resolve(program, Declarations([]), "jointtargets",
                             static_external_axes=True)
    assert [i for i, site in enumerate(sites) if site.reason is not None] == [2]
    assert len(targets.site) == 11


TRACK = """MODULE Track
  PERS tooldata tBar:=[TRUE,[[0,0,100],[1,0,0,0]],[1.2,[0,0,60],[1,0,0,0],0,0,0]];
  PERS wobjdata wPlate:=[FALSE,TRUE,"",[[850,80,450],[0.923879533,0,-0.382683432,0]],
                         [[0,0,0],[1,0,0,0]]];
""" + "".join(
    f"  CONST robtarget p{k}:={_target(100 + 20 * k, f'{1000 + 250 * k:g}')};\n"
    for k in range(4)) + """  PROC main()
    MoveJ p0, v500, fine, tBar\\WObj:=wPlate;
    MoveL p1, v100, z1, tBar\\WObj:=wPlate;
    MoveL p2, v100, z1, tBar\\WObj:=wPlate;
    MoveJ p3, v500, fine, tBar\\WObj:=wPlate;
  ENDPROC
ENDMODULE
"""


def test_a_track_program_is_left_as_it_was_unless_its_axes_are_said_to_carry_nothing(comp):
    left = rewrite_source(TRACK.encode(), "track.mod", comp, RewriteOptions())
    assert left.moves_compensated == 0 and len(left.skipped) == 4
    assert all("a track carrying the robot" in s.reason for s in left.skipped)
    body = left.data.decode()
    assert "MoveAbsJ" not in body and "jointtarget" not in body
    assert body.split("PROC main()")[1] == TRACK.split("PROC main()")[1]
    told = rewrite_source(TRACK.encode(), "track.mod", comp,
                          RewriteOptions(static_external_axes=True))
    assert told.moves_compensated == 4 and not told.skipped
    text = told.data.decode()
    assert "external_axes=static" in text.splitlines()[5]
    # each jointtarget carries the track position of the target it stands for
    for k in range(4):
        decl = re.search(rf"CONST jointtarget jt_p{k}:=\[\[[^]]*\],\[([^]]*)\]\];", text)
        assert decl is not None
        assert float(decl.group(1).split(",")[0]) == 1000 + 250 * k


def test_the_command_line_names_the_flag_and_exits_three(cell, tmp_path, capsys):
    src = tmp_path / "track.mod"
    src.write_text(TRACK)
    model = str(cell["model_path"])
    assert main(["rewrite", str(src), "--model", model, "-o", str(tmp_path / "a.mod")]) == 3
    err = capsys.readouterr().err
    assert "track.mod:" in err and "eax_a at 1000:" in err
    assert "--static-external-axes where they carry neither" in err
    assert main(["rewrite", str(src), "--model", model, "-o", str(tmp_path / "b.mod"),
                 "--static-external-axes"]) == 0
    assert "MoveAbsJ jt_p3" in (tmp_path / "b.mod").read_text()
