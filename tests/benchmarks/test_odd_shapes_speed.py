"""Benchmark: `rapidfix rewrite` on program shapes no other benchmark writes (issue 18).

Run (RAPIDFIX_BENCH_ODD_LINES, default 20,000, is the larger size; the smaller is a
quarter of it; RAPIDFIX_BENCH_ODD_SHAPES=feeds,tails picks shapes):

    OMP_NUM_THREADS=1 pytest tests/benchmarks/test_odd_shapes_speed.py -n 0 -s

For each shape of tests/benchmarks/odd_shapes.py, `rapidfix rewrite` as a fresh
process at two sizes: lines per second of the child's CPU time and how much the cost
per line grows from the smaller to the larger program (1.0: linear; a quadratic step
shows as about 4). `test_parse_odd_shapes` times parse + model of each shape against
plain Lark on the same file (LINES lines), as `test_shapes_speed` does for the named
shapes:

    RAPIDFIX_BENCH_ODD_LINES=100000 OMP_NUM_THREADS=1 \
    pytest tests/benchmarks/test_odd_shapes_speed.py -n 0 -s -k parse_odd

`test_read_ahead` times parse + model of the shapes of control flow and routines with
rapidfix.rapid.fast_blocks' reader and without it (the fast terminals alone), in the
same process (RAPIDFIX_BENCH_ODD_SHAPES picks others):

    RAPIDFIX_BENCH_ODD_LINES=100000 OMP_NUM_THREADS=1 \
    pytest tests/benchmarks/test_odd_shapes_speed.py -n 0 -s -k read_ahead

`test_syntax_error_in_a_large_file` times `rapidfix check` of a
large program with one syntax error against the clean program. Only correctness is
asserted, never time.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from odd_shapes import ODD_SHAPES, odd_lines, odd_program
from test_shapes_speed import _cpu, _parse_rows, _run_cli, model_path  # noqa: F401  (a fixture)

LINES = int(os.environ.get("RAPIDFIX_BENCH_ODD_LINES", "20000"))
ONLY = [s for s in os.environ.get("RAPIDFIX_BENCH_ODD_SHAPES", "").split(",") if s] or list(
    ODD_SHAPES)


def test_rewrite_odd_shapes(model_path, tmp_path):  # noqa: F811
    rows = []
    for shape in ONLY:
        suffix = _odd_suffix(shape)
        per_line = []
        for lines in (LINES // 4, LINES):
            source = tmp_path / f"{shape}_{lines}{suffix}"
            source.write_text(odd_program(shape, lines), encoding="utf-8", newline="")
            data = source.read_bytes()
            count = odd_lines(shape, data)
            # a robot on a track: told its axis carries nothing, so its moves are compensated
            told = ("--static-external-axes",) if shape == "track" else ()
            cpu, _, done = _run_cli("rewrite", str(source), "--model", str(model_path),
                                    "-o", str(tmp_path / f"out{suffix}"), "--force", *told)
            assert done.returncode in (0, 3), done.stderr
            per_line.append((count, cpu / count))
        (_, small), (count, large) = per_line
        rows.append((shape, count, 1.0 / large, large / small))
    print(f"\nrapidfix rewrite, whole process, odd shapes ({LINES:,} and {LINES // 4:,} lines)")
    print(f"{'shape':12s} {'lines':>8s} {'lines/s CPU':>12s} {'cost/line growth':>17s}")
    for shape, count, rate, growth in rows:
        print(f"{shape:12s} {count:8,d} {rate:12,.0f} {growth:16.2f}x")


def _odd_suffix(shape: str) -> str:
    return ".prg" if shape == "modules" else ".mod"


def test_parse_odd_shapes():
    """Parse + model of every odd shape against plain Lark on the same file, one core:
    the issue's 60,000 lines/s and 8x are for every shape, not the named ones only."""
    _parse_rows(ONLY, odd_program, LINES, odd_lines, _odd_suffix)


def test_read_ahead(monkeypatch):
    """Parse + model with the compound statements and routines read ahead of the lexer,
    against the fast terminals alone, on the same file in the same process; `labels`
    has in every routine a statement the reader leaves to the parser (a label), deep in
    a WHILE: what it read there is handed out, not read again."""
    from program_shapes import shape_program

    from rapidfix.rapid import fast_blocks, parse_program

    shapes = [s for s in os.environ.get("RAPIDFIX_BENCH_ODD_SHAPES", "").split(",") if s] or [
        "deep", "many_procs", "labels", "computed", "conditions", "loops", "failing",
        "control"]
    parse_program("MODULE M\nENDMODULE\n")
    rows = []
    for shape in shapes:
        text = shape_program(shape, LINES) if shape == "control" else odd_program(shape, LINES)
        data = text.encode()
        best = {}
        for _ in range(2):
            for read_ahead in (False, True):
                monkeypatch.setattr(fast_blocks, "READ_AHEAD", read_ahead)
                program, cpu = _cpu(parse_program, data, f"x{_odd_suffix(shape)}")
                assert program.to_bytes() == data and program.motions
                del program
                best[read_ahead] = min(cpu, best.get(read_ahead, cpu))
        lines = odd_lines(shape, data)
        rows.append((shape, lines, lines / best[False], lines / best[True]))
    print(f"\nparse + model, lines/s of CPU time, {LINES:,} lines per shape")
    print(f"{'shape':12s} {'lines':>8s} {'fast terminals':>15s} {'read ahead':>11s} "
          f"{'ratio':>6s}")
    for shape, lines, alone, ahead in rows:
        print(f"{shape:12s} {lines:8,d} {alone:15,.0f} {ahead:11,.0f} {ahead / alone:5.2f}x")


def test_syntax_error_in_a_large_file(tmp_path):
    """`rapidfix check` of a large program with one syntax error, early or late, against
    the same program without it: the plain grammar explains the error from its window
    (rapidfix.rapid.error_window), not from the whole file read twice more."""
    from program_shapes import shape_program

    text = shape_program("named", LINES * 5)
    clean = tmp_path / "clean.mod"
    clean.write_text(text, encoding="utf-8", newline="")
    cpu_clean, _, done = _run_cli("check", str(clean))
    assert done.returncode == 0, done.stderr
    print(f"\nrapidfix check, {text.count(chr(10)):,} lines (named): clean {cpu_clean:.2f} s CPU")
    for where, at in (("in the first routine", text.index("MoveL")),
                      ("in the last routine", text.rindex("MoveL"))):
        bad = tmp_path / "bad.mod"
        bad.write_text(text[:at] + "MoveL p1 v100, z1, tMill;\n    " + text[at:],
                       encoding="utf-8", newline="")
        cpu, _, done = _run_cli("check", str(bad))
        line = text[:at].count("\n") + 1
        assert done.returncode == 1 and f"bad.mod:{line}:" in done.stderr, done.stderr
        print(f"  a syntax error {where} (line {line:,}): {cpu:.2f} s CPU, "
              f"{cpu / cpu_clean:.2f}x the clean file")
