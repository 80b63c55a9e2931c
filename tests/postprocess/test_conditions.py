"""How the program runs: gripped loads in execution order, arrival directions along chains."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.postprocess.conditions import (
    NO_LOAD,
    arrival_directions,
    config_monitoring,
    grip_loads,
    program_displacement,
)
from rapidfix.rapid import parse_program

PROGRAM = """MODULE Cell
  PERS loaddata lPart:=[4,[0,0,50],[1,0,0,0],0,0,0];
  VAR bool ok:=TRUE;
  PROC main()
    MoveJ p1, v100, fine, tool0;
    GripLoad lPart;
    MoveL p2, v100, fine, tool0;
    Place;
    MoveL p3, v100, fine, tool0;
    IF ok THEN
      GripLoad lPart;
    ENDIF
    MoveL p4, v100, fine, tool0;
    FOR i FROM 1 TO 3 DO
      MoveL p5, v100, fine, tool0;
      GripLoad lPart;
    ENDFOR
  ENDPROC
  PROC Place()
    MoveL p6, v100, fine, tool0;
    GripLoad load0;
  ENDPROC
  PROC Service()
    MoveL p7, v100, fine, tool0;
  ENDPROC
ENDMODULE
"""


def test_gripped_loads_follow_the_execution_order():
    program = parse_program(PROGRAM.encode(), "cell.mod")
    loads = grip_loads(program)
    by_target = {m.target.text: loads.load[k] for k, m in enumerate(program.motions)}
    assert loads.statements == 4
    assert by_target["p1"] == NO_LOAD  # main starts with no gripped load
    assert by_target["p2"].name == "lPart" and by_target["p2"].mass == 4.0
    assert by_target["p6"].name == "lPart"  # carried into the routine called
    assert by_target["p3"] == NO_LOAD  # ... and the routine's GripLoad load0 out of it
    assert by_target["p4"] is None  # the IF may or may not have run: not known
    assert by_target["p5"] is None  # first pass: unknown; later passes: lPart
    assert by_target["p7"] is None  # not called from this program
    assert loads.uncalled == ["Service"]


def test_without_gripload_every_move_has_none():
    text = PROGRAM.replace("GripLoad lPart;", "").replace("GripLoad load0;", "")
    loads = grip_loads(parse_program(text.encode(), "cell.mod"))
    assert loads.statements == 0 and all(ld == NO_LOAD for ld in loads.load)


def _naive(q, prev, initial):
    """A second formulation: walk each chain point by point."""
    out = np.zeros_like(q)
    for i in range(len(q)):
        for j in range(6):
            k, d = i, 0.0
            while True:
                p = prev[k]
                if p < 0:
                    d = initial[k, j]
                    break
                step = q[k, j] - q[p, j]
                if abs(step) > 1e-9:
                    d = np.sign(step)
                    break
                k = p
            out[i, j] = d
    return out


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 30), st.integers(0, 10_000))
def test_arrival_directions_match_a_point_by_point_walk(n, seed):
    rng = np.random.default_rng(seed)
    q = np.round(rng.normal(size=(n, 6)), 1)  # repeated values: joints that stand still
    q[rng.random((n, 6)) < 0.3] = 0.0
    prev = np.array([rng.integers(-1, i) if i else -1 for i in range(n)])
    initial = rng.choice([-1.0, 0.0, 1.0], size=(n, 6))
    got = arrival_directions(q, prev, initial)
    assert np.array_equal(got, _naive(q, prev, initial))


MONITORING = """MODULE Cell
  VAR bool ok:=TRUE;
  PROC main()
    MoveL p1, v100, fine, tool0;
    ConfL \\Off;
    MoveL p2, v100, fine, tool0;
    MoveJ p3, v100, fine, tool0;
    Weld;
    MoveL p4, v100, fine, tool0;
    IF ok ConfL \\Off;
    MoveC p5, p6, v100, fine, tool0;
    ConfJ \\Off;
    MoveJ p7, v100, fine, tool0;
  ENDPROC
  PROC Weld()
    MoveL p8, v100, fine, tool0;
    ConfL \\On;
  ENDPROC
  PROC Service()
    TriggJ p9, v100, t1, fine, tool0;
    ConfJ \\Off;
    MoveJ p10, v100, fine, tool0;
  ENDPROC
ENDMODULE
"""


def test_configuration_monitoring_follows_the_execution_order():
    program = parse_program(MONITORING.encode(), "cell.mod")
    off, known = config_monitoring(program)
    state = {m.target.text: ("off" if o else "on") if k else "unknown"
             for m, o, k in zip(program.motions, off, known)}
    assert state["p1"] == "on"  # main starts with both on
    assert state["p2"] == "off"
    assert state["p3"] == "on"  # ConfJ governs MoveJ, and it is still on
    assert state["p8"] == "off"  # carried into the routine ...
    assert state["p4"] == "on"  # ... and its ConfL \On out of it
    assert state["p6"] == "unknown"  # the IF may switch it off (MoveC to p6)
    assert state["p7"] == "off"
    assert state["p9"] == "unknown"  # not called from main: not known ...
    assert state["p10"] == "off"  # ... until the routine itself switches it


@pytest.mark.parametrize("word", ["ConfL", "CONFL", "confl", "cOnFl", "coNfL", "CoNFl"])
def test_the_switch_is_found_in_any_case(word):
    text = MONITORING.replace("ConfL \\Off;\n    MoveL p2", f"{word} \\Off;\n    MoveL p2")
    assert word in text
    off, _ = config_monitoring(parse_program(text.encode(), "cell.mod"))
    assert off[1] and not off[0]  # p2 after the switch, p1 before it


def test_without_conf_statements_monitoring_is_on_everywhere():
    text = "\n".join(line for line in MONITORING.splitlines() if "Conf" not in line)
    off, known = config_monitoring(parse_program(text.encode(), "cell.mod"))
    assert not off.any() and known.all()


DISPLACEMENT = """MODULE Cell
  VAR pose pGroove:=[[0,0,2],[1,0,0,0]];
  VAR bool ok:=TRUE;
  PROC main()
    MoveJ p1, v100, fine, tool0;
    PDispSet pGroove;
    MoveL p2, v100, fine, tool0;
    Weld;
    MoveL p3, v100, fine, tool0;
    IF ok PDispOn \\ExeP:=p1, p1, tool0;
    MoveL p4, v100, fine, tool0;
    PDispOff;
    MoveL p5, v100, fine, tool0;
  ENDPROC
  PROC Weld()
    MoveL p6, v100, fine, tool0;
    PDispOff;
  ENDPROC
  PROC Service()
    MoveL p7, v100, fine, tool0;  ! PDispOff in a comment sets nothing
    PDispOff;
    MoveL p8, v100, fine, tool0;
  ENDPROC
ENDMODULE
"""


def test_program_displacement_follows_the_execution_order():
    program = parse_program(DISPLACEMENT.encode(), "cell.mod")
    displaced = dict(zip((m.target.text for m in program.motions),
                         program_displacement(program).tolist()))
    assert displaced == {
        "p1": False,  # main starts without one
        "p2": True, "p6": True,  # set, and carried into the routine ...
        "p3": False,  # ... which takes it off
        "p4": True,  # the compact IF may set it: not known, taken as on
        "p5": False,
        "p7": True,  # not called from main: not known ...
        "p8": False,  # ... until the routine takes it off
    }


def test_without_displacement_statements_nothing_is_displaced():
    lines = [line for line in DISPLACEMENT.splitlines() if "PDisp" not in line
             or line.lstrip().startswith("MoveL")]
    program = parse_program("\n".join(lines).encode(), "cell.mod")
    assert "PDispOff" in program.text  # in a comment only
    assert not program_displacement(program).any()
