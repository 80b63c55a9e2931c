"""The rewrite's steps run on their own: planning, path refinement and emission each take
what the step before returned, and together make every edit `rewrite_source` writes but
its header."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

from rapidfix.error_model.candidates.backlash import Backlash
from rapidfix.error_model.model import ErrorModel
from rapidfix.kinematics import load_robot
from rapidfix.postprocess import emission as emission_module
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.emission import emit_edits
from rapidfix.postprocess.header import MARK
from rapidfix.postprocess.planning import plan_program
from rapidfix.postprocess.refinement import refine_paths
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.rapid import parse_owned, parse_program

from .conftest import SAMPLES

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from program_shapes import shape_program

PROGRAMS = sorted(p.name for p in SAMPLES.iterdir() if p.suffix.lower() in (".mod", ".prg"))
#: a header line as the rewrite inserts it (the same pattern --force strips)
HEADER_LINE = re.compile(rb"\r?\n[ \t]*![ \t]*" + MARK.encode() + rb"[^\r\n]*")


def _backlash_comp() -> Compensator:
    """A model of play only: joints arrive from a side, so refinement follows directions."""
    robot = load_robot("IRB1600-10/1.45")
    play = Backlash()
    play.set_fitted(np.radians([0.02, 0.03, 0.02, 0.01, 0.01, 0.02]))
    return Compensator(robot, ErrorModel(robot.name, [play]), "backlash.json", "0" * 64)


def _steps(data: bytes, name: str, comp: Compensator, options: RewriteOptions):
    program = parse_program(data, name)
    planned = plan_program(program, comp, options.emit, approach=options.approach)
    refined = refine_paths(program, comp.model, comp.robot, planned,
                           options.path_tolerance_mm, options.emit)
    return planned, refined, emit_edits(program, comp, planned, refined)


@pytest.mark.parametrize("emit", ["jointtargets", "robtargets"])
@pytest.mark.parametrize("name", PROGRAMS)
def test_the_steps_make_every_edit_of_the_rewrite_but_its_header(comp, name, emit):
    data = (SAMPLES / name).read_bytes()
    options = RewriteOptions(emit=emit)
    result = rewrite_source(data, name, comp, options)
    _, refined, emission = _steps(data, name, comp, options)
    assert emission.editor.render() == HEADER_LINE.sub(b"", result.data)
    assert refined.points_added() == result.points_added
    assert emission.inserted == result.inserted
    assert len(emission.expected.motion) >= result.moves_compensated


def test_the_emission_gets_the_plans_without_what_only_the_path_check_reads(comp,
                                                                           monkeypatch):
    """The intended flange poses and the plan's own modes go before the emission, the
    rewrite's peak; the test above shows the bytes are those of the steps with them."""
    import rapidfix.postprocess.rewrite as rewrite_module

    seen = []

    def emit(program, comp_, planned, refined):
        seen.append((planned.solved.flange.shape, refined.solved.flange.shape, planned.mode,
                     len(refined.mode)))
        return emit_edits(program, comp_, planned, refined)

    monkeypatch.setattr(rewrite_module, "emit_edits", emit)
    result = rewrite_source((SAMPLES / "milling.mod").read_bytes(), "milling.mod", comp,
                            RewriteOptions())
    assert seen == [((0, 4, 4), (0, 4, 4), {}, result.moves_compensated)]
    assert result.moves_compensated > 0


@pytest.mark.parametrize("name", ["milling.mod", "palletizer.prg", "ballbar.mod"])
def test_refinement_leaves_the_plan_it_was_given_as_it_was(name):
    """Directions along refined paths solve some destinations again: the refinement
    returns them in its own plan, and only destinations of refined moves change."""
    comp = _backlash_comp()
    data = (SAMPLES / name).read_bytes()
    program = parse_program(data, name)
    planned = plan_program(program, comp, "jointtargets")
    before = planned.solved.q_cmd.copy()
    refined = refine_paths(program, comp.model, comp.robot, planned, 0.1, "jointtargets")
    assert np.array_equal(planned.solved.q_cmd, before)
    changed = np.flatnonzero((refined.solved.q_cmd != before).any(axis=1))
    destinations = {planned.sites[i].rows[-1] for i in refined.sites}
    assert set(changed.tolist()) <= destinations
    assert refined.direction is not None and len(refined.direction) == len(refined.points.seg)
    # the rewrite writes the refined plan's joints: what it reads back is where it aims
    result = rewrite_source(data, name, comp, RewriteOptions())
    assert result.worst_predicted_mm is not None and result.worst_predicted_mm < 1e-3


def test_approach_points_are_planned_and_emitted_for_fine_movej():
    """cell.mod with its MoveJ made fine points: each gets a planned arrival direction
    and one approach point; no MoveL/MoveC does."""
    comp = _backlash_comp()
    text = (SAMPLES / "cell.mod").read_text(encoding="utf-8")
    data = re.sub(r"(MoveJ [^;]*?), z\d+,", r"\1, fine,", text).encode()
    fine_movej = len(re.findall(rb"MoveJ [^;]*, fine,", data))
    assert fine_movej == 3
    planned, refined, emission = _steps(data, "cell.mod", comp, RewriteOptions(approach=True))
    assert len(planned.approach) == fine_movej
    assert all(planned.sites[i].kind == "J" for i in planned.approach)
    play = comp.model.play() > 0
    assert np.all(planned.approach_margin[play] > 2 * comp.model.play()[play])
    approach_points = {n for n in emission.inserted if n.endswith("_app")}
    assert len(approach_points) == sum(refined.mode.get(i) == "joint" for i in planned.approach)
    assert approach_points


def test_approach_and_intermediate_points_are_emitted_as_columns_as_move_by_move(monkeypatch):
    """Fine MoveJ (approach points) between arcs and lines (intermediate points), some
    moves with both: the emission in columns writes what the move-by-move route writes."""
    lines = []
    for k, line in enumerate(shape_program("movec", 240).splitlines()):
        if line.lstrip().startswith("MoveL ") and k % 3 == 0:  # a fine MoveJ between arcs
            line = line.replace("MoveL ", "MoveJ ").replace(", z1,", ", fine,")
        lines.append(line)
    data = ("\n".join(lines) + "\n").encode()
    comp = _backlash_comp()
    options = RewriteOptions(approach=True, force=True)
    columns = rewrite_source(data, "arcs.mod", comp, options)
    monkeypatch.setattr(emission_module._Emitter, "_columns", False)
    one_by_one = rewrite_source(data, "arcs.mod", comp, options)
    assert columns.data == one_by_one.data
    assert columns.points_added > 20
    assert sum(name.endswith("_app") for name in columns.inserted) > 10


@pytest.mark.parametrize("name", ["milling.mod", "palletizer.prg"])
def test_the_output_is_rendered_after_the_program_model_is_gone(comp, name, monkeypatch):
    """The rewrite renders in the memory the syntax tree, the model and the plan held
    (a million-line program's peaks would add up otherwise): at render time nothing
    refers to the program any more, not even through a reference cycle (the rewrite
    runs with the cyclic collector paused, so a cycle would keep it to the end)."""
    import weakref

    import rapidfix.postprocess.rewrite as rewrite_module
    from rapidfix.rapid.edit import Editor

    programs: list[weakref.ref] = []
    alive_at_render: list[bool] = []

    def parse(handed, filename):
        program = parse_owned(handed, filename)
        programs.append(weakref.ref(program))
        return program

    render = Editor.render

    def checked_render(self):
        alive_at_render.append(programs[-1]() is not None)
        return render(self)

    monkeypatch.setattr(rewrite_module, "parse_owned", parse)
    monkeypatch.setattr(Editor, "render", checked_render)
    data = (SAMPLES / name).read_bytes()
    result = rewrite_source(data, name, comp, RewriteOptions())
    assert result.moves_compensated > 0 and alive_at_render == [False]
    monkeypatch.undo()
    # and the bytes are those of the steps run with the model alive throughout
    _, _, emission = _steps(data, name, comp, RewriteOptions())
    assert emission.editor.render() == HEADER_LINE.sub(b"", result.data)


@pytest.mark.parametrize("in_place", [False, True])
def test_the_input_bytes_are_let_go_of_once_decoded(comp, tmp_path, monkeypatch, in_place):
    """rewrite_file hands the file's bytes over to the parse and keeps no reference of
    its own (but for an in-place rewrite's backup), so a large file is not held twice
    while its model is built and used; the program keeps none either, as its text
    encodes back to the same bytes. The output is the same either way."""
    import sys

    import rapidfix.postprocess.rewrite as rewrite_module
    from rapidfix.postprocess.rewrite import rewrite_file

    references: list[int] = []
    kept: list[bytes | None] = []

    def parse(handed, filename):
        references.append(sys.getrefcount(handed[0]) - 1)  # less getrefcount's own
        program = parse_owned(handed, filename)
        kept.append(program.kept_bytes)
        return program

    source = tmp_path / "milling.mod"
    source.write_bytes((SAMPLES / "milling.mod").read_bytes())
    expected = rewrite_source(source.read_bytes(), str(source), comp, RewriteOptions()).data
    monkeypatch.setattr(rewrite_module, "parse_owned", parse)
    target = source if in_place else tmp_path / "out.mod"
    result = rewrite_file(source, target, comp, RewriteOptions(), in_place=in_place)
    # the list handed over, and the backup's copy for in_place
    assert references == [2 if in_place else 1] and kept == [None]
    assert target.read_bytes() == result.data == expected


@pytest.mark.parametrize("size", [1, 3])
def test_the_peak_steps_in_chunks_give_the_same_rewrite(comp, monkeypatch, size):
    """The new declarations placed after theirs (`chunks.INSERTED_DECLARATIONS` at a
    time) and the model's error of the original moves (`chunks.PREDICTED_BEFORE` targets
    at a time) give the same bytes and figures in chunks of 1 and 3 as in one: the
    figures to their last bits, which follow BLAS's rounding of a product of so many
    rows (the same program always gives the same ones)."""
    from rapidfix import chunks

    data = (SAMPLES / "milling.mod").read_bytes()
    # named targets: a new jointtarget goes after each one's declaration
    assert b"CONST robtarget" in data
    whole = rewrite_source(data, "milling.mod", comp, RewriteOptions())
    monkeypatch.setattr(chunks, "PREDICTED_BEFORE", size)
    monkeypatch.setattr(chunks, "INSERTED_DECLARATIONS", size)
    chunked = rewrite_source(data, "milling.mod", comp, RewriteOptions())
    assert chunked.data == whole.data and whole.moves_compensated > 3
    assert np.allclose(chunked.predicted_before_mm, whole.predicted_before_mm, rtol=1e-12,
                       atol=0.0)


@pytest.mark.parametrize("name", ["milling.mod", "ballbar.mod"])
def test_the_line_bound_in_blocks_of_segments_gives_the_same_rewrite(comp, name, monkeypatch):
    """The path check bounds each segment's bow in blocks of `chunks.LINE_BOUND`
    segments: a bound is its segment's own, so blocks of 1 and 3 segments give the
    same points and bytes as one block of all, and the bounds are those of one call."""
    from rapidfix import chunks
    from rapidfix.postprocess import refinement

    data = (SAMPLES / name).read_bytes()
    calls: list[int] = []
    bound = refinement.line_deviation_bound

    def counted(*args):
        calls.append(len(args[2]))
        return bound(*args)

    monkeypatch.setattr(refinement, "line_deviation_bound", counted)
    whole = rewrite_source(data, name, comp, RewriteOptions())
    segments = calls[:]
    assert segments and len(segments) == 1  # the samples are smaller than one block
    for size in (1, 3):
        monkeypatch.setattr(chunks, "LINE_BOUND", size)
        calls.clear()
        result = rewrite_source(data, name, comp, RewriteOptions())
        assert result.data == whole.data and result.points_added == whole.points_added
        assert sum(calls) == segments[0] and max(calls) <= size


def _multimove_moves(text: str) -> list[tuple[str, str]]:
    """(instruction, `\\ID` number) of each move statement of a program, in order."""
    return re.findall(r"\n\s*(Move\w*)\s*\\ID:=(\d+)\s*,", text)


@pytest.mark.parametrize("approach", [False, True])
def test_synchronized_moves_keep_their_numbers_and_take_no_points(approach):
    """A MultiMove program's coordinated moves (`MoveL \\ID:=10, p, ...`): its other tasks
    run moves of the same numbers, so the rewrite adds none and drops none. An arc whose
    path would need intermediate points keeps its MoveC with filtered robtargets, and a
    fine MoveJ takes no approach point; every move keeps its number, in order. Without
    the numbers, the same arcs and fine points do take points."""
    from odd_shapes import odd_program

    from rapidfix.postprocess.refinement import SYNCHRONIZED

    comp = _backlash_comp()
    text = odd_program("multimove", 300).replace("v500, z10", "v500, fine")
    options = RewriteOptions(approach=approach)
    result = rewrite_source(text.encode(), "coordinated.mod", comp, options)
    out = result.data.decode()
    before, after = _multimove_moves(text), _multimove_moves(out)
    assert [number for _, number in after] == [number for _, number in before]
    assert len(after) == len(before) == result.moves_total
    assert result.points_added == 0
    assert not re.search(r"MoveAbsJ\s*,", out) and "_app" not in out
    arcs = sum(name == "MoveC" for name, _ in before)
    assert arcs and result.filtered_reasons == {SYNCHRONIZED: arcs}
    assert sum(name == "MoveC" for name, _ in after) == arcs
    assert result.worst_predicted_mm is not None and result.worst_predicted_mm < 1e-3
    # the same program unnumbered: its arcs take intermediate points, its fine MoveJ
    # approach points
    plain = re.sub(r"\\ID:=\d+, ", "", text)
    unnumbered = rewrite_source(plain.encode(), "plain.mod", comp, options)
    assert unnumbered.points_added > 0 and SYNCHRONIZED not in unnumbered.filtered_reasons
    assert ("_app" in unnumbered.data.decode()) == approach


def test_a_compact_ifs_move_takes_no_approach_point():
    """`IF b MoveJ p1, v100, fine, tool0;` guards one statement: an approach point put
    before the move would be all the IF guards, and the move would run whatever `b`
    is. The same move in an IF block, or on its own, takes its approach point."""
    from rapidfix.rapid.syntax import CompactIf, If

    comp = _backlash_comp()
    far = "[[600,100,500],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    near = "[[620,100,480],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    text = (f"MODULE C\n  CONST robtarget p1:={far};\n  CONST robtarget p2:={near};\n"
            "  VAR bool b:=TRUE;\n  PROC main()\n    MoveJ p2, v100, fine, tool0;\n"
            "    IF b MoveJ p1, v100, fine, tool0;\n"
            "    IF b THEN MoveJ p2, v100, fine, tool0; ENDIF\n"
            "    IF b MoveJ p2, v100, fine, tool0; MoveJ p1, v100, fine, tool0;\n"
            "  ENDPROC\nENDMODULE\n")
    result = rewrite_source(text.encode(), "guarded.mod", comp, RewriteOptions(approach=True))
    assert result.moves_compensated == 5
    out = parse_program(result.data, "out.mod")
    body = next(r for r in out.syntax.modules[0].items if getattr(r, "name", "") == "main").body
    kinds = [type(statement).__name__ for statement in body]
    # each compact IF still guards one move, to its own target, and no approach point
    compact = [statement for statement in body if isinstance(statement, CompactIf)]
    assert len(compact) == 2
    for statement in compact:
        name = statement.statement.args[0].value.name
        assert name.startswith("jt_") and not name.endswith("_app")
    # the block IF and the moves on their own take theirs: approach, then the move
    block = next(statement for statement in body if isinstance(statement, If))
    names = [s.args[0].value.name for s in block.branches[0][1]]
    assert names[0].endswith("_app") and not names[1].endswith("_app")
    # p2 and p1 on their own, each after its approach point
    assert sum(kind not in ("CompactIf", "If") for kind in kinds) == 4
    assert sum(name.endswith("_app") for name in re.findall(r"jt_\w+", result.data.decode())
               ) >= 3


def test_a_dropped_conc_leaves_a_blank_between_instruction_and_target():
    """`MoveJ\\Conc,p1,...` written tight: the approach and intermediate points leave off
    `\\Conc` with its comma, and their MoveAbsJ still stands apart from its target (it
    came out as `MoveAbsJjt_p1_app,...`, which parses as a call of another name)."""
    comp = _backlash_comp()
    far = "[[600,100,500],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    near = "[[640,160,430],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    text = (f"MODULE T\n  CONST robtarget p1:={far};\n  CONST robtarget p2:={near};\n"
            "  PROC main()\n    MoveJ p2,v100,fine,tool0;\n    MoveJ\\Conc,p1,v100,fine,tool0;\n"
            "    MoveL\\Conc,p2,v100,z1,tool0;\n  ENDPROC\nENDMODULE\n")
    options = RewriteOptions(approach=True, path_tolerance_mm=0.01)
    result = rewrite_source(text.encode(), "tight.mod", comp, options)
    assert result.moves_compensated == 3 and result.points_added > 0
    out = result.data.decode()
    assert "MoveAbsJjt" not in out
    assert re.search(r"MoveAbsJ jt_p1_app,v100,fine,tool0;", out)
    assert re.search(r"MoveAbsJ jt_p2_1,v100,z0,tool0;", out)
    assert "MoveAbsJ\\Conc,jt_p1,v100,fine,tool0;" in out  # the move keeps its \Conc
    whole = parse_program(result.data, "out.mod")  # the whole output parses
    assert len(whole.motions) == 3 + result.points_added + out.count("_app,")


def test_an_approach_statement_that_does_not_parse_is_never_written(monkeypatch):
    """The approach points' statements are checked too, one of each shape: with the
    blank of the test above taken away again, the read-back refuses the rewrite (before,
    it wrote the file and said every move was compensated)."""
    from rapidfix.exceptions import RapidSemanticError

    comp = _backlash_comp()
    far = "[[600,100,500],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    text = (f"MODULE T\n  CONST robtarget p1:={far};\n  PROC main()\n"
            "    MoveJ\\Conc,p1,v100,fine,tool0;\n  ENDPROC\nENDMODULE\n")
    edits = emission_module._intermediate_edits
    monkeypatch.setattr(emission_module, "_intermediate_edits", lambda motion, zone=True: [
        (start, end, new.strip()) for start, end, new in edits(motion, zone)])
    with pytest.raises(RapidSemanticError, match="does not parse"):
        rewrite_source(text.encode(), "tight.mod", comp, RewriteOptions(approach=True))
