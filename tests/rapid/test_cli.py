"""`rapidfix check` and `rapidfix targets` as a user runs them."""

from __future__ import annotations

import csv
import io
import json

from rapidfix.cli import main


def test_check_samples_ok(rapid_samples, capsys):
    assert main(["check", *map(str, rapid_samples)]) == 0
    out = capsys.readouterr().out
    assert out.count(": ok (") == len(rapid_samples)


def test_check_counts_lines_as_its_messages_do(tmp_path, capsys):
    """The line count `check` prints is that of an editor and of the messages' line
    numbers, for each line ending and with or without a last LF (read from the line
    table, not by splitting a million-line text into a list of lines)."""
    body = "MODULE M\nPROC main()\n  MoveJ p10, v100, z10, tool0;\nENDPROC\nENDMODULE"
    for newline in ("\n", "\r\n", "\r"):
        for final in ("", newline):
            path = tmp_path / "lines.mod"
            path.write_bytes((body + final).replace("\n", newline).encode())
            assert main(["check", str(path)]) == 0
            assert "ok (5 lines, module M, 0 declarations" in capsys.readouterr().out


def test_check_reports_each_bad_file_and_continues(tmp_path, rapid_samples, capsys):
    bad = tmp_path / "bad.mod"
    bad.write_text("MODULE M\nPROC main()\n  MoveL p10 v100, z10, tool0;\nENDPROC\nENDMODULE\n")
    binary = tmp_path / "blob.mod"
    binary.write_bytes(b"\x00\x01\x02")
    good = rapid_samples[0]
    status = main(["check", str(bad), str(binary), str(good), str(tmp_path / "missing.mod")])
    captured = capsys.readouterr()
    assert status == 1
    errors = captured.err.strip().splitlines()
    assert len(errors) == 3
    assert errors[0].startswith(f"{bad}:3:13: unexpected 'v100'")
    assert errors[1].startswith(f"{binary}:1: not RAPID text")
    assert "missing.mod" in errors[2]
    assert "Traceback" not in captured.err
    assert f"{good}: ok" in captured.out


def _cell_rows(rapid_samples, fmt, capsys):
    cell = next(p for p in rapid_samples if p.name == "cell.mod")
    assert main(["targets", str(cell), "--format", fmt]) == 0
    return capsys.readouterr().out


def test_targets_csv(rapid_samples, capsys):
    rows = list(csv.DictReader(io.StringIO(_cell_rows(rapid_samples, "csv", capsys))))
    by_name = {r["name"]: r for r in rows}
    assert by_name["pInfeedPick"]["kind"] == "robtarget"
    assert by_name["pInfeedPick"]["static"] == "yes"
    assert by_name["pInfeedPick"]["value"].startswith("[[120,85,0],[0,0,1,0],[-1,0,-2,0]")
    assert by_name["jHome"]["kind"] == "jointtarget"
    assert by_name["pCurrent"]["static"] == "no"
    assert "assigned at line" in by_name["pCurrent"]["reason"]
    offs = by_name["Offs(pCurrent, 0, 0, 100)"]
    assert offs["source"] == "MoveL" and offs["static"] == "no"


def test_targets_json(rapid_samples, capsys):
    data = json.loads(_cell_rows(rapid_samples, "json", capsys))
    rows = {r["name"]: r for r in data["targets"]}
    assert rows["pChuck"]["value"][1] == [0.5, -0.5, 0.5, 0.5]
    assert rows["pChuck"]["static"] is True and rows["pChuck"]["reason"] is None
    lines = [r["line"] for r in data["targets"]]
    assert lines == sorted(lines)


def test_targets_of_bad_file_is_one_line_error(tmp_path, capsys):
    bad = tmp_path / "bad.mod"
    bad.write_text("MODULE M\n<SMT>\nENDMODULE\n")
    assert main(["targets", str(bad)]) == 1
    err = capsys.readouterr().err
    assert err.strip() == f"rapidfix: error: {bad}:2:1: RobotStudio placeholder <SMT> " \
                          "cannot stand here (unfinished code: replace it)"
