"""The rewrite's verification parses only the new statements and declarations.

Checked against the independent route, a full parse of the whole output: every
statement or declaration the output changed is among the check units, and the
targets read back from them are those the whole output commands. A unit that
does not parse stops the rewrite and nothing is written.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rapidfix.exceptions import RapidSemanticError
from rapidfix.postprocess import rewrite as rewrite_module
from rapidfix.postprocess.resolve import motion_targets
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_file, rewrite_source
from rapidfix.rapid import parse_program

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
PROGRAMS = sorted(p.name for p in SAMPLES.iterdir() if p.suffix.lower() in (".mod", ".prg"))


def _rewrite_capturing_units(monkeypatch, data, name, comp, options):
    captured = {}
    original = rewrite_module.parse_units

    def spy(units, filename):
        captured["units"] = units
        captured["motions"] = original(units, filename)
        return captured["motions"]

    monkeypatch.setattr(rewrite_module, "parse_units", spy)
    return rewrite_source(data, name, comp, options), captured


def _text(program, node):
    return program.text[node.span.start:node.span.end]


@pytest.mark.parametrize("emit", ["jointtargets", "robtargets"])
@pytest.mark.parametrize("name", PROGRAMS)
def test_check_units_hold_every_change_and_read_back_what_the_output_commands(
        monkeypatch, comp, name, emit):
    data = (SAMPLES / name).read_bytes()
    result, captured = _rewrite_capturing_units(monkeypatch, data, name, comp,
                                                RewriteOptions(emit=emit))
    before = parse_program(data, name)
    after = parse_program(result.data, name)
    check_text, _ = captured["units"].text()
    check = parse_program(check_text, "check")
    check_decls = {_text(check, d) for d in check.declarations}
    check_motions = {_text(check, m): m for m in captured["motions"]}

    old_decls = {_text(before, d) for d in before.declarations}
    new_decls = [_text(after, d) for d in after.declarations if _text(after, d) not in old_decls]
    assert set(new_decls) <= check_decls
    old_motions = {_text(before, m) for m in before.motions}
    changed = [m for m in after.motions if _text(after, m) not in old_motions]
    assert {_text(after, m) for m in changed} <= set(check_motions)
    if result.moves_compensated:
        assert changed or new_decls

    # same text, same values: the check program reads each target as the output does
    compared = 0
    for motion in after.motions:
        twin = check_motions.get(_text(after, motion))
        if twin is None:
            continue
        for ours, theirs in zip(motion_targets(twin), motion_targets(motion), strict=True):
            assert ours.value == theirs.value
            compared += 1
    assert compared >= len(captured["motions"])


def test_a_rewritten_part_that_does_not_parse_stops_the_rewrite(monkeypatch, comp, tmp_path):
    source = SAMPLES / "ballbar.mod"
    real = rewrite_module.jointtarget_literals

    def broken(q_deg, extax):
        return [text[:-1] for text in real(q_deg, extax)]  # drops the closing bracket

    monkeypatch.setattr(rewrite_module, "jointtarget_literals", broken)
    out = tmp_path / "out.mod"
    with pytest.raises(RapidSemanticError, match="does not parse"):
        rewrite_file(source, out, comp, RewriteOptions())
    assert not out.exists() and not list(tmp_path.iterdir())
