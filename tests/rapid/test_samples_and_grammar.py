"""The samples cover the language and round-trip; the grammar is found at run time."""

from __future__ import annotations

from pathlib import Path

import pytest

from rapidfix.rapid import load_program
from rapidfix.rapid import syntax as s
from rapidfix.rapid.grammar import grammar_text

REPO = Path(__file__).resolve().parents[2]


def test_samples_round_trip_byte_identical(rapid_samples):
    assert len(rapid_samples) >= 6
    for path in rapid_samples:
        program = load_program(path)
        assert program.to_bytes() == path.read_bytes()
        assert program.source.encode() == path.read_bytes()


def test_samples_use_every_construct(rapid_samples):
    seen: set[str] = set()
    encodings = set()
    for path in rapid_samples:
        program = load_program(path)
        encodings.add((program.encoding, program.newline))
        if program.header:
            seen.add("prg header")
        for module in program.syntax.modules:
            for item in module.items:
                seen.add(type(item).__name__)
                if isinstance(item, s.Routine):
                    seen.add(item.kind)
                    seen.update(f"handler {h.kind}" for h in item.handlers)
                    for body in [item.body] + [h.body for h in item.handlers]:
                        for statement, _ in s.walk_statements(body):
                            seen.add(type(statement).__name__)
        for motion in program.motions:
            seen.add(motion.name)
            seen.update(f"target {t.form}" for t in motion.targets)
    needed = {
        "prg header", "DataDecl", "RecordDecl", "AliasDecl", "PROC", "FUNC", "TRAP",
        "handler ERROR", "handler BACKWARD", "handler UNDO", "Assignment", "ProcedureCall",
        "LateCall", "If", "CompactIf", "For", "While", "Test", "Label", "Goto", "Return",
        "Raise", "Exit", "Retry", "TryNext", "Connect", "MoveL", "MoveJ", "MoveC",
        "MoveAbsJ", "target offs", "target reltool", "target name",
    }
    assert needed <= seen, needed - seen
    assert ("cp1252", "\r\n") in encodings


def test_grammar_text_is_the_repository_grammar():
    assert grammar_text() == (REPO / "grammars" / "rapid.lark").read_text(encoding="utf-8")


def test_wheel_ships_the_grammar():
    pyproject = (REPO / "pyproject.toml").read_text(encoding="utf-8")
    assert '"grammars" = "rapidfix/grammars"' in pyproject


def test_installed_package_grammar_is_preferred(tmp_path, monkeypatch):
    """A wheel carries the grammar at rapidfix/grammars/rapid.lark; it wins over the tree."""
    from rapidfix.rapid import grammar

    package = tmp_path / "rapidfix"
    (package / "grammars").mkdir(parents=True)
    (package / "grammars" / "rapid.lark").write_text("// packaged copy\n", encoding="utf-8")
    monkeypatch.setattr(grammar.resources, "files", lambda name: package)
    assert grammar.grammar_text() == "// packaged copy\n"
    (package / "grammars" / "rapid.lark").unlink()
    monkeypatch.setattr(grammar, "SOURCE_TREE_GRAMMAR", REPO / "grammars" / "rapid.lark")
    assert grammar.grammar_text().startswith("// ABB RAPID")


def test_missing_grammar_is_a_clear_error(tmp_path, monkeypatch):
    from rapidfix.exceptions import RapidfixError
    from rapidfix.rapid import grammar

    monkeypatch.setattr(grammar.resources, "files", lambda name: tmp_path)
    monkeypatch.setattr(grammar, "SOURCE_TREE_GRAMMAR", tmp_path / "nowhere" / "rapid.lark")
    with pytest.raises(RapidfixError, match=r"grammar rapid\.lark is missing"):
        grammar.grammar_text()
