"""The demo's post-processor step and the ballbar program it always has."""

from __future__ import annotations

import json

from rapidfix.demo import format_table, rewrite_and_run
from rapidfix.demo.ballbar_program import ballbar_program


def test_sample_ballbar_is_the_generated_program(samples):
    assert (samples / "ballbar.mod").read_text() == ballbar_program()


def test_demo_step_rewrites_and_runs_the_ballbar(cell, tmp_path):
    # no samples folder: the built-in ballbar program is used
    summary = rewrite_and_run(
        tmp_path / "no-samples-here", tmp_path / "programs", cell["model_path"], cell["virtual"]
    )
    entry = summary["programs"]["ballbar.mod"]
    assert entry["compensated"] == 21 and entry["skipped"] == 0
    assert entry["after_mean_mm"] <= 0.2 * entry["before_mean_mm"]
    assert entry["ballbar_after_max_mm"] < entry["ballbar_before_max_mm"]
    assert json.loads((tmp_path / "programs" / "programs.json").read_text()) == summary
    assert "ballbar.mod" in format_table(summary)


def test_rapidfix_demo_rewrites_and_runs_the_programs(tmp_path, capsys):
    from rapidfix.cli import main

    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out)]) in (0, 3)
    printed = capsys.readouterr().out
    assert "ballbar length deviation" in printed
    summary = json.loads((out / "programs" / "programs.json").read_text())
    ballbar = summary["programs"]["ballbar.mod"]
    assert ballbar["after_mean_mm"] <= 0.2 * ballbar["before_mean_mm"]
    assert (out / "programs" / "ballbar.mod").read_text().count("MoveAbsJ") >= 21
