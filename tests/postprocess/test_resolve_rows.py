"""Target rows of `resolve`: one row per usable target, in program order, each site's rows
pointing at its own targets; a zero orientation quaternion is refused wherever it is
written (checked on the arrays for one-target moves, inline for the others)."""

import numpy as np

from rapidfix.postprocess.resolve import Declarations, resolve
from rapidfix.rapid import parse_program

Q = "[0.5,0.5,0.5,0.5]"
ZERO = "[0,0,0,0]"
CONF = "[0,0,0,0]"
EXTAX = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"


def _target(x: float, quat: str = Q) -> str:
    return f"[[{x:g},20,800],{quat},{CONF},{EXTAX}]"


PROGRAM = f"""MODULE M
  CONST robtarget pA:={_target(501)};
  CONST robtarget pZero:={_target(502, ZERO)};
  VAR robtarget pVar;
  PROC main()
    MoveL {_target(503)}, v100, z1, tool0;
    MoveL {_target(504, ZERO)}, v100, z1, tool0;
    MoveL pA, v100, z1, tool0;
    MoveJ pZero, v100, fine, tool0;
    MoveC {_target(505)}, {_target(506)}, v100, z1, tool0;
    MoveC {_target(507, ZERO)}, pVar, v100, z1, tool0;
    MoveC {_target(508, ZERO)}, {_target(509)}, v100, z1, tool0;
    MoveL pVar, v100, z1, tool0;
    MoveL {_target(510)}, v100, z1, tool0;
  ENDPROC
ENDMODULE
"""


def test_rows_follow_the_sites_and_zero_quaternions_are_refused():
    program = parse_program(PROGRAM.encode(), "m.mod")
    sites, targets = resolve(program, Declarations([]), "jointtargets")
    assert len(sites) == 9
    reasons = [site.reason for site in sites]
    assert reasons[0] is None and reasons[2] is None and reasons[4] is None
    assert reasons[1] == "orientation quaternion is zero"
    assert reasons[3] == "orientation quaternion is zero"
    # the CirPoint is checked before the unknown ToPoint, as the targets are written
    assert reasons[5].startswith("CirPoint ") and reasons[5].endswith(
        "orientation quaternion is zero")
    assert reasons[6].startswith("CirPoint ")
    assert reasons[7] is not None and "quaternion" not in reasons[7]
    assert reasons[8] is None
    # rows: 0..N-1 in program order, each the x its own target was written with
    rows = [row for site in sites for row in site.rows]
    assert rows == list(range(len(targets.site)))
    x_of_row = targets.pose[:, 0, 3]
    expected = {0: [503], 2: [501], 4: [505, 506], 8: [510]}
    for i, xs in expected.items():
        assert np.array_equal(x_of_row[sites[i].rows], xs)
        assert np.all(targets.site[sites[i].rows] == i)
    assert all(not site.rows for i, site in enumerate(sites) if i not in expected)
    assert [op.text for op in targets.operand][:1] == [program.motions[0].targets[0].text]
