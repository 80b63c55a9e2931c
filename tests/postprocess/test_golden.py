"""Golden tests on the samples: rewritten files parse, change only what they must, and
carry jointtargets that put the TCP on the original targets (checked by forward
kinematics through the fitted model, not against a stored copy of the output)."""

from __future__ import annotations

import difflib
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_file
from rapidfix.rapid import load_program

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
PROGRAMS = sorted(p.name for p in SAMPLES.iterdir() if p.suffix.lower() in (".mod", ".prg"))
NEW_LINE = re.compile(
    r"^\s*(!\s*rapidfix-compensated \w+:.*"
    r"|(LOCAL\s+)?CONST\s+jointtarget\s+jt_\w+\s*:=\s*\[\[[^\]]*\],\[[^\]]*\]\];"
    r"|(LOCAL\s+)?CONST\s+robtarget\s+ft_\w+\s*:=\s*\[(\[[^\]]*\],?){4}\];"
    r"|MoveAbsJ\s+jt_\w+,.*;)\s*$"
)


def frame(trans, rot_wxyz) -> np.ndarray:
    T = np.eye(4)
    w, x, y, z = rot_wxyz
    T[:3, :3] = Rotation.from_quat([x, y, z, w]).as_matrix()
    T[:3, 3] = trans
    return T


@pytest.fixture(scope="module")
def outputs(comp, tmp_path_factory):
    folder = tmp_path_factory.mktemp("golden")
    done = {}
    for name in PROGRAMS:
        result = rewrite_file(SAMPLES / name, folder / name, comp, RewriteOptions())
        done[name] = (result, folder / name)
    return done


def destinations(program, inserted):
    """Output motions that are not inserted intermediate points, in order."""
    lowered = {n.lower() for n in inserted}
    return [
        m
        for m in program.motions
        if not (m.target is not None and m.target.text.lower() in lowered)
    ]


def whole_line(text, start, end):
    """(line start, line end incl. newline) when start..end is alone on its line, else None."""
    ls = text.rfind("\n", 0, start) + 1
    le = text.find("\n", end)
    le = len(text) if le < 0 else le + 1
    if text[ls:start].strip() or text[end:le].strip():
        return None
    return ls, le


def restored(before, after, result) -> str:
    """The output with every change undone: must give the input text exactly."""
    text = after.text
    edits = []
    inserted = {n.lower() for n in result.inserted}
    for m in after.motions:
        if m.target is not None and m.target.text.lower() in inserted:
            span = whole_line(text, m.span.start, m.span.end)
            edits.append(span if span else (m.span.start, m.span.end + 1))
    for m_in, m_out in zip(before.motions, destinations(after, result.inserted)):
        old = before.text[m_in.span.start : m_in.span.end]
        if text[m_out.span.start : m_out.span.end] != old:
            edits.append((m_out.span.start, m_out.span.end, old))
    old_decls = {(d.routine, d.name.lower()): d for d in before.declarations}
    for d in after.declarations:
        orig = old_decls.get((d.routine, d.name.lower()))
        if orig is None:
            assert d.storage == "CONST" and d.type_key in ("jointtarget", "robtarget")
            edits.append(whole_line(text, d.span.start, d.span.end))
        elif d.span.text != orig.span.text:
            assert d.type_key == "robtarget"  # a filtered robtarget, replaced in place
            edits.append((d.span.start, d.span.end, orig.span.text))
    for match in re.finditer(r"\n[ \t]*! rapidfix-compensated [^\n]*", text):
        edits.append((match.start(), match.end()))
    out = text
    for edit in sorted(edits, key=lambda e: e[0], reverse=True):
        start, end = edit[0], edit[1]
        out = out[:start] + (edit[2] if len(edit) == 3 else "") + out[end:]
    return out


@pytest.mark.parametrize("name", PROGRAMS)
def test_output_parses_and_differs_only_where_it_must(outputs, name):
    result, path = outputs[name]
    before, after = load_program(SAMPLES / name), load_program(path)
    assert after.encoding == before.encoding and after.newline == before.newline
    assert "rapidfix-compensated input_sha256" in after.text
    # undoing exactly the changes the post-processor must make gives the input, byte for byte
    assert before.source.encode(restored(before, after, result)) == before.original
    # every rewritten motion kept the arguments after its target, byte for byte
    kept = destinations(after, result.inserted)
    assert len(kept) == len(before.motions)
    for m_in, m_out in zip(before.motions, kept):
        tail_in = before.text[m_in.target.span.end : m_in.span.end]
        tail_out = after.text[m_out.target.span.end : m_out.span.end]
        assert tail_in == tail_out
        if m_out.name != m_in.name:
            assert m_out.name == "MoveAbsJ" and m_in.name in ("MoveL", "MoveJ", "MoveC")
        elif m_out.target.text != m_in.target.text:  # kept, with a filtered robtarget
            assert m_out.target.text.startswith("ft_")
    # inserted lines are the header, new declarations and MoveAbsJ statements only
    old = before.text.splitlines(keepends=True)
    new = after.text.splitlines(keepends=True)
    for tag, _, _, j1, j2 in difflib.SequenceMatcher(a=old, b=new, autojunk=False).get_opcodes():
        if tag == "insert":
            for line in new[j1:j2]:
                assert NEW_LINE.match(line), f"{name}: unexpected inserted line {line!r}"


@pytest.mark.parametrize("name", PROGRAMS)
def test_jointtargets_put_the_tcp_on_the_targets(outputs, cell, name):
    model, robot = cell["model"], cell["robot"]
    result, path = outputs[name]
    before, after = load_program(SAMPLES / name), load_program(path)
    values = {d.name.lower(): d.data for d in after.declarations if d.type_key == "jointtarget"}
    checked = 0
    for m_in, m_out in zip(before.motions, destinations(after, result.inserted)):
        if m_out.name != "MoveAbsJ" or m_in.name == "MoveAbsJ":
            continue
        target = m_in.target.data
        tool = m_in.tool.data
        wobj = m_in.wobj.data if m_in.wobj is not None else None
        tool_T = frame(tool.tframe.trans, tool.tframe.rot)
        wobj_T = (
            frame(wobj.uframe.trans, wobj.uframe.rot) @ frame(wobj.oframe.trans, wobj.oframe.rot)
            if wobj is not None
            else np.eye(4)
        )
        intended = wobj_T @ frame(target.trans, target.rot)
        q = np.radians(np.asarray(values[m_out.target.text.lower()].robax, dtype=float))
        actual = model.actual_flange(robot, q[None])[0] @ tool_T
        nominal = robot.fk(q) @ tool_T
        assert np.linalg.norm(actual[:3, 3] - intended[:3, 3]) < 1e-3
        assert np.abs(actual[:3, :3] - intended[:3, :3]).max() < 1e-6
        assert np.linalg.norm(nominal[:3, 3] - intended[:3, 3]) > 1e-3  # it was compensated
        # the confdata branch is honoured: same quadrants, unless an axis sits within the
        # compensation's reach (0.5 deg) of a quadrant boundary; same cfx
        conf = robot.confdata(q)
        near = np.abs(np.degrees(q[[0, 3, 5]]) / 90.0 - np.round(np.degrees(q[[0, 3, 5]]) / 90.0))
        same = conf[:3] == np.asarray(target.robconf[:3])
        assert np.all(same | (near * 90.0 < 0.5)) and conf[3] == target.robconf[3]
        checked += 1
    assert checked == sum(
        1 for m in destinations(after, result.inserted) if m.name == "MoveAbsJ"
    ) - sum(1 for m in before.motions if m.name == "MoveAbsJ")


def test_ballbar_and_palletizer_are_compensated(outputs):
    """The samples written with consistent confdata are compensated in full."""
    assert outputs["ballbar.mod"][0].moves_compensated == 21
    assert not outputs["ballbar.mod"][0].skipped
    assert outputs["palletizer.prg"][0].moves_compensated >= 3


def test_filtered_robtargets_in_samples_reach_the_targets(outputs, cell):
    """Moves kept as MoveL/MoveC (start unknown before run time) get filtered robtargets:
    the nominal IK of the filtered pose on its confdata, through the model, hits the target."""
    model, robot = cell["model"], cell["robot"]
    checked = 0
    for name in PROGRAMS:
        result, path = outputs[name]
        before, after = load_program(SAMPLES / name), load_program(path)
        for m_in, m_out in zip(before.motions, destinations(after, result.inserted)):
            if m_out.name != m_in.name or not m_out.target.text.startswith("ft_"):
                continue
            tool = m_in.tool.data
            wobj = m_in.wobj.data if m_in.wobj is not None else None
            tool_T = frame(tool.tframe.trans, tool.tframe.rot)
            wobj_T = (
                (
                    frame(wobj.uframe.trans, wobj.uframe.rot)
                    @ frame(wobj.oframe.trans, wobj.oframe.rot)
                )
                if wobj
                else np.eye(4)
            )
            want, got = m_in.target.data, m_out.target.data
            intended = wobj_T @ frame(want.trans, want.rot)
            commanded = wobj_T @ frame(got.trans, got.rot) @ np.linalg.inv(tool_T)
            q, status = robot.ik_conf(commanded[None], np.asarray([got.robconf]))
            assert status[0] == 0
            actual = model.actual_flange(robot, q)[0] @ tool_T
            assert np.linalg.norm(actual[:3, 3] - intended[:3, 3]) < 2e-3
            checked += 1
    assert checked > 0


@settings(max_examples=12, deadline=None)
@given(data=st.data())
def test_random_programs_change_only_where_they_must(comp, cell, data):
    """Random sequences of the ballbar targets as MoveJ/MoveL with random zones, speeds
    and optional arguments: undoing the changes gives the input, and every jointtarget
    puts the TCP on its robtarget through the fitted model."""
    from rapidfix.demo.ballbar_program import ballbar_program
    from rapidfix.postprocess.rewrite import rewrite_source
    from rapidfix.rapid import parse_program

    model, robot = cell["model"], cell["robot"]
    head, _, _ = ballbar_program().partition("    PROC main()")
    picks = data.draw(st.lists(st.integers(0, 18), min_size=2, max_size=6))
    lines = []
    for k, p in enumerate(picks):
        instr = "MoveJ" if k == 0 else data.draw(st.sampled_from(["MoveL", "MoveJ", "MoveL"]))
        speed = data.draw(st.sampled_from(["v50", "v200\\V:=220", "v100"]))
        zone = data.draw(st.sampled_from(["fine", "z1", "z10\\Z:=8"]))
        conc = data.draw(st.sampled_from(["", "\\Conc, "]))
        lines.append(f"        {instr} {conc}pBB{p:02d}, {speed}, {zone}, "
                     "tBallbar\\WObj:=wobjBallbar;")
    text = head + "    PROC main()\n" + "\n".join(lines) + "\n    ENDPROC\nENDMODULE\n"
    result = rewrite_source(text.encode(), "random.mod", comp, RewriteOptions())
    assert not result.skipped
    before = parse_program(text.encode(), "random.mod")
    after = parse_program(result.data, "random_out.mod")
    assert restored(before, after, result) == before.text
    tool_T = frame((0, 0, 100), (1, 0, 0, 0))
    wobj_T = frame((850, 80, 450), (0.923879533, 0, -0.382683432, 0))
    values = {d.name.lower(): d.data for d in after.declarations if d.type_key == "jointtarget"}
    for m_in, m_out in zip(before.motions, destinations(after, result.inserted)):
        assert m_out.name == "MoveAbsJ"
        want = m_in.target.data
        q = np.radians(np.asarray(values[m_out.target.text.lower()].robax, dtype=float))
        tcp = model.actual_flange(robot, q[None])[0] @ tool_T
        intended = wobj_T @ frame(want.trans, want.rot)
        assert np.linalg.norm(tcp[:3, 3] - intended[:3, 3]) < 1e-3
