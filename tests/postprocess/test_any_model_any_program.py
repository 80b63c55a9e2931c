"""Every effect the model can hold, alone and combined, on random programs: rewrite or a
one-line project error, never another exception; and what is written lands.

Programs mix tools (with loads), work objects, GripLoad changes, MoveL / MoveJ /
MoveC / MoveAbsJ and Offs / RelTool targets. Models are random combinations of
every registered effect type with random parameters. Where a target was
compensated, the model itself, pushed through the joints read back from the
written file, must put the TCP where the original program meant it (independent
of how the rewrite solved it: forward model against the intended pose).
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rapidfix.error_model.candidates.backlash import Backlash
from rapidfix.error_model.candidates.compliance import JointCompliance
from rapidfix.error_model.candidates.coupling import JointCoupling
from rapidfix.error_model.candidates.geometry import N_ERRORS, LinkGeometry
from rapidfix.error_model.candidates.joint_reference import JointReference
from rapidfix.error_model.candidates.registration import TrackerFrame, TrackerScale
from rapidfix.error_model.candidates.thermal import ThermalDrift
from rapidfix.error_model.candidates.tool_offset import ToolOffset
from rapidfix.error_model.joint_rbf import OutsideRangeWarning
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.registry import registered_effects
from rapidfix.exceptions import InvalidOption, RapidfixError
from rapidfix.kinematics import load_robot
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.emission_forms import robtarget_literals
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.rapid import parse_program
from rapidfix.sim.plans import point_plan

ROBOT = load_robot("IRB1600-10/1.45")
TOOLS = [
    "PERS tooldata tA:=[TRUE,[[0,0,150],[1,0,0,0]],[2.5,[0,0,60],[1,0,0,0],0,0,0]];",
    "PERS tooldata tB:=[TRUE,[[35,0,110],[0.9659258,0,0.258819,0]],[1,[5,0,40],[1,0,0,0],0,0,0]];",
    "PERS tooldata tC:=[TRUE,[[0,-20,90],[1,0,0,0]],[0.4,[0,0,30],[1,0,0,0],0,0,0]];",
]
TOOL_FRAMES = [((0, 0, 150), (1, 0, 0, 0)), ((35, 0, 110), (0.9659258, 0, 0.258819, 0)),
               ((0, -20, 90), (1, 0, 0, 0))]
WOBJ = ('PERS wobjdata wT:=[FALSE,TRUE,"",[[650,-100,200],[0.9238795,0,0,0.3826834]],'
        '[[0,0,0],[1,0,0,0]]];')
LOAD = "PERS loaddata lBox:=[5,[0,0,40],[1,0,0,0],0,0,0];"


def _frame(trans, quat):
    from rapidfix.kinematics.frames import pose

    return pose(np.array([trans], float), np.array([quat], float))[0]


def _effect(kind: str, rng: np.random.Generator):
    """A random instance of an effect type (every registered type is covered)."""
    if kind == "backlash":
        e = Backlash()
        e.set_fitted(rng.uniform(0, np.radians(0.04), 6))
    elif kind == "joint_compliance":
        e = JointCompliance(ROBOT.name, (60.0, 80.0, 90.0), 1.0)
        e.set_fitted(np.concatenate([rng.uniform(0, 3e-6, 2), rng.normal(0, 1e-4, 4)]))
    elif kind == "joint_coupling":
        src, dst = rng.choice(6, 2, replace=False)
        e = JointCoupling(int(src), int(dst))
        e.set_fitted(rng.normal(0, 2e-4, 2))
    elif kind == "link_geometry":
        e = LinkGeometry(ROBOT.name, np.eye(N_ERRORS)[:8])
        e.set_fitted(rng.normal(0, 1e-4, 8))
    elif kind == "thermal_drift":
        e = ThermalDrift("temp_c", 21.0)
        e.set_fitted(rng.normal(0, 20.0, 2))
    elif kind == "tool_offset":
        e = ToolOffset()
        e.set_fitted(rng.normal(0, 0.3, 3))
    elif kind == "tracker_frame":
        e = TrackerFrame()
        e.set_fitted(rng.normal(0, 0.01, 6))
    elif kind == "registration":
        e = TrackerScale()
        e.set_fitted(rng.normal(0, 30.0, 1))
    elif kind == "joint_reference":
        e = JointReference()
        e.set_fitted(rng.normal(0, 1e-4, len(e.param_names)))
    else:
        return None
    return e


KINDS = sorted(k for k in registered_effects() if k != "joint_rbf")


@st.composite
def programs(draw):
    n = draw(st.integers(1, 14))
    seed = draw(st.integers(0, 10_000))
    q = point_plan(ROBOT, np.zeros(3), 2 * n + 2, seed=seed)
    rng = np.random.default_rng(seed)
    tools = draw(st.lists(st.integers(0, 2), min_size=1, max_size=3, unique=True))
    use_wobj = draw(st.booleans())
    wobj = _frame((650, -100, 200), (0.9238795, 0, 0, 0.3826834)) if use_wobj else np.eye(4)
    decls, body = [], []
    i = 0
    for k in range(n):
        tool = tools[int(rng.integers(len(tools)))]
        tool_frame = _frame(*TOOL_FRAMES[tool])
        speed = "v200" + draw(st.sampled_from(["", "\\V:=150", "\\T:=2"]))
        zone = draw(st.sampled_from(["fine", "z1", "z10"])) + draw(
            st.sampled_from(["", "\\Z:=5", "\\Inpos:=inpos20"]))
        tail = f"{speed}, {zone}, t{'ABC'[tool]}" + ("\\WObj:=wT" if use_wobj else "")
        # optional arguments before the target: concurrent, synchronized (numbered)
        lead = draw(st.sampled_from(["", "", "\\Conc, ", f"\\ID:={10 * k + 10}, ",
                                     f"\\Conc \\ID:={10 * k + 10}, "]))
        if draw(st.booleans()) and k % 3 == 1:
            body.append(f"    GripLoad {'lBox' if k % 2 else 'load0'};")
        if draw(st.integers(0, 9)) == 0:
            body.append(draw(st.sampled_from(["    PDispSet pShift;", "    PDispOff;"])))
        kind = draw(st.sampled_from(["L", "J", "C", "AbsJ", "Offs", "RelTool", "inline"]))
        if kind == "C" and i + 1 >= len(q):
            kind = "L"
        rows = 2 if kind == "C" else 1
        tcp = np.linalg.inv(wobj) @ ROBOT.fk(q[i:i + rows]) @ tool_frame
        lits = robtarget_literals(tcp, ROBOT.confdata(q[i:i + rows]), np.full((rows, 6), 9e9))
        names = [f"p{i + r}" for r in range(rows)]
        if kind == "AbsJ":
            deg = ", ".join(f"{v:.4f}" for v in np.degrees(q[i]))
            decls.append(f"  CONST jointtarget j{i}:=[[{deg}],[9E9,9E9,9E9,9E9,9E9,9E9]];")
            body.append(f"    MoveAbsJ {lead}j{i}, {tail};")
        elif kind == "inline":
            body.append(f"    MoveL {lead}{lits[0]}, {tail};")
        else:
            decls += [f"  CONST robtarget {nm}:={lit};" for nm, lit in zip(names, lits)]
            if kind == "C":
                body.append(f"    MoveC {lead}{names[0]}, {names[1]}, {tail};")
            elif kind == "Offs":
                body.append(f"    MoveL {lead}Offs({names[0]},0,0,0), {tail};")
            elif kind == "RelTool":
                body.append(f"    MoveJ {lead}RelTool({names[0]},0,0,0), {tail};")
            else:
                body.append(f"    Move{kind} {lead}{names[0]}, {tail};")
        i += rows
    lines = ["MODULE Prop", *(f"  {TOOLS[t]}" for t in range(3)), f"  {WOBJ}",
             f"  {LOAD}", "  VAR pose pShift:=[[0,0,1],[1,0,0,0]];", *decls,
             "  PROC main()", *body, "  ENDPROC",
             "  PROC other()", *body[-2:], "  ENDPROC", "ENDMODULE"]
    # RAPID does not care where a line ends: some lines joined to the next one
    joins = draw(st.sets(st.integers(0, len(lines) - 2), max_size=len(lines) // 3))
    text = "".join(line + (" " if k in joins else "\n") for k, line in enumerate(lines))
    if draw(st.booleans()):  # nor about blanks: `MoveJ\Conc,p1,...` written tight
        text = re.sub(r"(Move\w*) (\\(?:Conc|ID:=\d+)(?: \\ID:=\d+)?), ", r"\1\2,", text)
    return text


def _numbers(text: str) -> list[str]:
    """The `\\ID` numbers of a program's moves, in order."""
    return re.findall(r"\\ID:=(\d+)", text)


@st.composite
def models(draw):
    kinds = draw(st.lists(st.sampled_from(KINDS), min_size=1, max_size=4, unique=True))
    rng = np.random.default_rng(draw(st.integers(0, 10_000)))
    effects = [e for e in (_effect(k, rng) for k in kinds) if e is not None]
    return ErrorModel(ROBOT.name, effects)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(programs(), models(), st.sampled_from([None, 23.5]),
       st.sampled_from(["jointtargets", "robtargets"]), st.booleans())
def test_any_model_rewrites_any_program_or_says_why(text, model, temperature, emit, approach):
    comp = Compensator(ROBOT, model, "random.json", "0" * 64)
    if approach and emit == "robtargets":
        # approach points are joint positions: refused before anything is read, with the
        # one-line error naming the option, never recorded in a header without them
        with pytest.raises(InvalidOption, match="approach needs emit 'jointtargets'") as err:
            RewriteOptions(emit=emit, temperature_c=temperature, approach=approach)
        assert "\n" not in str(err.value)
        return
    options = RewriteOptions(emit=emit, temperature_c=temperature, approach=approach)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OutsideRangeWarning)
            result = rewrite_source(text.encode(), "prop.mod", comp, options)
    except RapidfixError as err:  # the project's one-line error is an answer too
        assert "\n" not in str(err)
        assert "rapidfix bug" not in str(err)  # ... but not one that reports a bug
        return
    assert result.moves_total >= result.moves_compensated
    # the whole output parses (nothing lands in a comment or after ENDMODULE), every move
    # of the input still in it
    assert len(parse_program(result.data, "out.mod").motions) >= len(
        parse_program(text.encode(), "prop.mod").motions)
    # a synchronized move keeps its number, and no move is added among them
    out = result.data.decode()
    assert _numbers(out) == _numbers(text)
    dangling = re.search(r"(?m)^\s*Move\w*\s*,", out)  # no comma left by a dropped argument
    assert dangling is None, out[dangling.start() - 60:dangling.end() + 60]
    if result.moves_compensated:
        # independent of the solve: the forward model through the written joints
        assert result.worst_predicted_mm is not None and result.worst_predicted_mm < 1e-3
    needs = model.context_fields()
    if "temp_c" in needs and temperature is None:
        assert any("RewriteOptions.temperature_c" in w for w in result.warnings)
    if "temp_c" in needs and temperature is not None:
        assert result.header.conditions["temperature_c"] == "23.5"
    if "temp_c" not in needs and temperature is not None and result.moves_compensated:
        assert any("changes nothing" in note for note in result.report_lines())


def test_measurement_effects_never_move_a_program():
    """A target-ball offset and the tracker's frame describe the measurement: a model made
    only of them leaves every commanded joint where the nominal robot has it."""
    rng = np.random.default_rng(4)
    model = ErrorModel(ROBOT.name, [_effect("tool_offset", rng), _effect("tracker_frame", rng),
                                    _effect("registration", rng)])
    assert model.separable and not model.robot_effects
    q = point_plan(ROBOT, np.zeros(3), 20, seed=2)
    from rapidfix.error_model.compensate import compensate

    assert np.array_equal(compensate(model, ROBOT, q), q)


def test_approach_with_robtargets_is_a_usage_error_on_the_command_line(cell, samples, tmp_path,
                                                                       capsys):
    from rapidfix.cli import main

    out = tmp_path / "o.mod"
    code = main(["rewrite", str(samples / "ballbar.mod"), "--model", str(cell["model_path"]),
                 "-o", str(out), "--emit", "robtargets", "--approach"])
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    assert err.count("\n") == 1 and "--approach needs --emit jointtargets" in err
    # with joint targets the same options rewrite and the header records them
    assert main(["rewrite", str(samples / "ballbar.mod"), "--model", str(cell["model_path"]),
                 "-o", str(out), "--approach"]) in (0, 3)
    assert "approach=fine_points" in out.read_text()
