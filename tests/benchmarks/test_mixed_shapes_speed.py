"""Benchmark: parse and rewrite of random mixes of a cell's statements (issue 18).

The targets are for every shape, and the shapes will be measured again on programs
nobody here wrote; mixed_shapes.py makes one shape per seed (its own weights over some
forty statement templates, routine length and nesting). Run:

    RAPIDFIX_BENCH_MIXED_LINES=100000 OMP_NUM_THREADS=1 \
    pytest tests/benchmarks/test_mixed_shapes_speed.py -n 0 -s

`test_parse_mixes` times parse + model against plain Lark on the same file, one core
(targets 60,000 lines/s and 8x); `test_rewrite_mixes` runs `rapidfix rewrite` as a
fresh process at twice that size (target 30,000 lines/s of the child's CPU time).
RAPIDFIX_BENCH_MIXES (default 8) is how many seeds, from 1. Only correctness is
asserted, never time.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from mixed_shapes import mixed_program
from test_shapes_speed import _parse_rows, _run_cli, model_path  # noqa: F401  (a fixture)

LINES = int(os.environ.get("RAPIDFIX_BENCH_MIXED_LINES", "20000"))
SEEDS = [f"mix{seed}" for seed in range(1, 1 + int(os.environ.get("RAPIDFIX_BENCH_MIXES", "8")))]


def _mix(name: str, lines: int) -> str:
    return mixed_program(int(name[3:]), lines)


def test_parse_mixes():
    _parse_rows(SEEDS, _mix, LINES, suffix=lambda _: ".mod")


def test_rewrite_mixes(model_path, tmp_path):  # noqa: F811
    print(f"\nrapidfix rewrite, whole process, random mixes ({2 * LINES:,} lines)")
    print(f"{'mix':8s} {'lines':>8s} {'lines/s CPU':>12s}")
    for name in SEEDS:
        source = tmp_path / f"{name}.mod"
        source.write_text(_mix(name, 2 * LINES), encoding="utf-8")
        lines = source.read_bytes().count(b"\n")
        cpu, _, done = _run_cli("rewrite", str(source), "--model", str(model_path),
                                "-o", str(tmp_path / "out.mod"), "--force")
        assert done.returncode in (0, 3), done.stderr
        print(f"{name:8s} {lines:8,d} {lines / cpu:12,.0f}")
