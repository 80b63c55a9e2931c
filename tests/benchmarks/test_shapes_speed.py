"""Benchmark matrix: parse and rewrite speed on every program shape (issue 18).

Run (about 200,000 lines per shape; RAPIDFIX_BENCH_LINES scales it down):

    OMP_NUM_THREADS=1 pytest tests/benchmarks/test_shapes_speed.py -n 0 -s

For each shape of tests/benchmarks/program_shapes.py, in one process:

- parse: plain Lark LALR building a parse tree from grammars/rapid.lark (the
  baseline) and `parse_program` (syntax tree and the full program model), lines
  per second of CPU time and their ratio (targets: >= 60,000 lines/s and >= 8x);
- rewrite: `rapidfix rewrite` as a fresh process (start-up and imports
  included), lines per second of the child's CPU time and wall time (target:
  >= 30,000 lines/s), with numpy's kernels (what `pip install .` runs) and, where
  numba is installed, with the compiled ones too; the time per step of
  `rewrite_file` in this process, and the same in a fresh process with start-up,
  imports, system time and page faults (process_phases.py);
- start-up: `rapidfix --help` and `rapidfix check` of a small file (target < 0.3 s).

Only correctness is asserted, never time.
"""

from __future__ import annotations

import gc
import importlib.util
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import pytest
from lark import Lark

sys.path.insert(0, str(Path(__file__).parent))
from batch_timing import batch_timings
from more_shapes import MORE_SHAPES, more_program
from process_phases import time_steps
from program_shapes import SHAPES, shape_program

from rapidfix import pipeline
from rapidfix.compiled import BACKEND_ENV
from rapidfix.error_model.model_file import save_model
from rapidfix.rapid import parse_program
from rapidfix.rapid.grammar import grammar_text
from rapidfix.rapid.source import decode_source
from rapidfix.sim import simulate_cell

LINES = int(os.environ.get("RAPIDFIX_BENCH_LINES", "200000"))
ONLY = [s for s in os.environ.get("RAPIDFIX_BENCH_SHAPES", "").split(",") if s] or list(SHAPES)


def _cpu(fn, *args):
    gc.collect()
    c = time.process_time()
    result = fn(*args)
    return result, time.process_time() - c


def _suffix(shape: str) -> str:
    return ".prg" if shape == "prg" else ".mod"


def any_program(shape: str, lines: int) -> str:
    """A benchmark shape's program, or one of the more shapes' (RAPIDFIX_BENCH_SHAPES may
    name either: `mixed` is the issue's own mixed program)."""
    return (more_program if shape in MORE_SHAPES else shape_program)(shape, lines)


def test_parse_matrix():
    _parse_rows(ONLY, any_program)


def test_parse_more_shapes():
    """The same on shapes the fast path was not tuned on (tests/benchmarks/more_shapes.py):
    VAR/PERS targets with \\V speeds, inline targets in exponent form, MoveAbsJ, arrays of
    robtargets, TriggL/SearchL, nested Offs(RelTool(...)), comments inside statements,
    routines with parameters calling each other."""
    more = [s for s in os.environ.get("RAPIDFIX_BENCH_MORE_SHAPES", "").split(",") if s]
    _parse_rows(more or list(MORE_SHAPES), more_program)


def _parse_rows(shapes, make, size=None, count=None, suffix=None):
    """Parse + model of each shape's program of about `size` lines (LINES) made by `make`
    against plain Lark on the same file; `count(shape, data)` its lines (the newlines),
    `suffix(shape)` its file name's end (`_suffix`)."""
    plain = Lark(grammar_text(), parser="lalr", lexer="contextual", cache=True)
    parse_program("MODULE M\nENDMODULE\n")
    rows = []
    for shape in shapes:
        data = make(shape, size or LINES).encode()
        lines = data.count(b"\n") if count is None else count(shape, data)
        text = decode_source(data, "x").text
        tree, base = _cpu(plain.parse, text)
        del tree
        best = None
        for _ in range(2):
            program, ours = _cpu(parse_program, data, f"x{(suffix or _suffix)(shape)}")
            assert program.motions
            assert program.to_bytes() == data
            del program
            best = ours if best is None else min(best, ours)
        rows.append((shape, lines, lines / base, lines / best, base / best))
    print(f"\nparse + model, lines/s of CPU time, {size or LINES:,} lines per shape")
    print(f"{'shape':10s} {'lines':>8s} {'plain Lark':>11s} {'parse_program':>14s} {'ratio':>6s}")
    for shape, lines, base, ours, ratio in rows:
        print(f"{shape:10s} {lines:8,d} {base:11,.0f} {ours:14,.0f} {ratio:5.1f}x")
    print(f"slowest: {min(r[3] for r in rows):,.0f} lines/s, lowest ratio "
          f"{min(r[4] for r in rows):.1f}x (targets 60,000 lines/s, 8x)")


@pytest.fixture(scope="module")
def model_path(tmp_path_factory):
    root = tmp_path_factory.mktemp("bench_cell")
    folder = simulate_cell(root / "cell", seed=5)
    outcome = pipeline.fit_from_files(folder / "setup.toml", [folder / "sweeps.csv"])
    return save_model(outcome.model, root / "model.json")


def _user_env() -> dict[str, str]:
    """The environment of a user's run: Python's bytecode cache allowed (an installed
    package has its .pyc files; a machine that sets PYTHONDONTWRITEBYTECODE would have
    every run compile rapidfix from source, 0.1-0.5 s that no user waits for)."""
    return {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def _run_cli(*args: str, env: dict[str, str] | None = None
             ) -> tuple[float, float, subprocess.CompletedProcess]:
    """(child CPU seconds, wall seconds, result) of `rapidfix ARGS` in a fresh process,
    with `env` added to the user's environment."""
    subprocess.run([sys.executable, "-c", "import rapidfix.cli"], env=_user_env(), check=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "rapidfix.cli", *args],
                          capture_output=True, text=True, env={**_user_env(), **(env or {})})
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall, done


def _routes() -> list[tuple[str, dict[str, str]]]:
    """The kernels a user's install runs: numpy alone (`pip install .`), and the compiled
    ones too where numba is installed here (`pip install ".[fast]"`)."""
    routes = [("numpy", {BACKEND_ENV: "numpy"})]
    if importlib.util.find_spec("numba") is not None:
        routes.append(("numba", {BACKEND_ENV: "auto"}))
    return routes


def test_rewrite_matrix(model_path, tmp_path):
    rows = []
    routes = _routes()
    for shape in ONLY:
        source = tmp_path / f"{shape}{_suffix(shape)}"
        source.write_bytes(any_program(shape, LINES).encode())
        lines = source.read_bytes().count(b"\n")
        out = tmp_path / f"{shape}.out{_suffix(shape)}"
        for route, env in routes:
            cpu, wall, done = _run_cli("rewrite", str(source), "--model", str(model_path),
                                       "-o", str(out), "--force", env=env)
            assert done.returncode in (0, 3), done.stderr
            rows.append((shape, route, lines, lines / cpu, lines / wall, done.returncode))
    print(f"\nrapidfix rewrite, whole process, {LINES:,} lines per shape "
          "(numpy: the kernels of `pip install .`; numba: of `pip install \".[fast]\"`)")
    print(f"{'shape':10s} {'kernels':7s} {'lines':>8s} {'lines/s CPU':>12s} "
          f"{'lines/s wall':>13s} exit")
    for shape, route, lines, cpu, wall, code in rows:
        print(f"{shape:10s} {route:7s} {lines:8,d} {cpu:12,.0f} {wall:13,.0f} {code:4d}")
    for route, _ in routes:
        slowest = min(r[3] for r in rows if r[1] == route)
        print(f"slowest ({route}): {slowest:,.0f} lines/s CPU (target 30,000)")


_PHASES = (  # (label, module, attribute) of rewrite_source's steps, in order
    ("parse + model", "rapidfix.postprocess.rewrite", "parse_owned"),
    ("plan (IK, compensation)", "rapidfix.postprocess.rewrite", "plan_program"),
    ("path check", "rapidfix.postprocess.rewrite", "refine_paths"),
    ("emit (edits)", "rapidfix.postprocess.rewrite", "emit_edits"),
    ("run statement", "rapidfix.postprocess.rewrite", "_run_statement"),
    ("read back", "rapidfix.postprocess.rewrite", "read_back"),
    ("predicted deviation", "rapidfix.postprocess.rewrite", "predicted_deviation"),
    ("atomic write", "rapidfix.postprocess.rewrite", "write_bytes_atomic"),
)


def test_rewrite_phases(model_path, tmp_path, monkeypatch):
    """CPU seconds of each step of `rewrite_file` in this (warm) process, per shape."""
    from rapidfix.postprocess.compensator import Compensator
    from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_file

    spent: dict[str, float] = {}
    time_steps(spent, _PHASES, monkeypatch.setattr)
    c = time.process_time()
    comp = Compensator.load(model_path)
    load = time.process_time() - c
    warm = tmp_path / "warm.mod"  # first-call costs (compiled kernels, caches) apart
    warm.write_bytes(shape_program("named", 200).encode())
    rewrite_file(warm, tmp_path / "warm.out.mod", comp, RewriteOptions(force=True))
    print(f"\nrewrite_file per phase, CPU s, {LINES:,} lines per shape "
          f"(Compensator.load once: {load:.2f} s)")
    labels = [p[0] for p in _PHASES]
    print(f"{'shape':10s} " + " ".join(f"{lab[:11]:>11s}" for lab in labels)
          + f" {'other':>7s} {'total':>7s}")
    for shape in ONLY:
        source = tmp_path / f"{shape}{_suffix(shape)}"
        source.write_bytes(any_program(shape, LINES).encode())
        spent.clear()
        c = time.process_time()
        rewrite_file(source, tmp_path / f"out{_suffix(shape)}", comp, RewriteOptions(force=True))
        total = time.process_time() - c
        other = total - sum(spent.values())
        print(f"{shape:10s} " + " ".join(f"{spent.get(lab, 0.0):11.2f}" for lab in labels)
              + f" {other:7.2f} {total:7.2f}")


def test_rewrite_phases_whole_process(model_path, tmp_path):
    """Where the time of `rapidfix rewrite` goes, as a user runs it: each step's CPU
    seconds in a fresh process (tests/benchmarks/process_phases.py), with start-up and
    imports, the compiled kernels' import, system time, page faults and peak memory."""
    import json

    script = Path(__file__).parent / "process_phases.py"
    rows = []
    for shape in ONLY:
        source = tmp_path / f"{shape}{_suffix(shape)}"
        source.write_bytes(any_program(shape, LINES).encode())
        lines = source.read_bytes().count(b"\n")
        subprocess.run([sys.executable, "-c", "import rapidfix.cli"], env=_user_env(),
                       check=True)
        done = subprocess.run(
            [sys.executable, str(script), "rewrite", str(source), "--model", str(model_path),
             "-o", str(tmp_path / f"out{_suffix(shape)}"), "--force"],
            capture_output=True, text=True, env=_user_env())
        row = json.loads(done.stdout.strip().splitlines()[-1])
        assert row["code"] in (0, 3), done.stderr
        rows.append((shape, lines, row))
    labels = ("parse + model", "plan", "path check", "emission", "render", "read back",
              "deviation", "other steps", "write", "start-up, imports, report")
    print(f"\nrapidfix rewrite, whole process, CPU s per step, {LINES:,} lines per shape")
    print(f"{'shape':10s} " + " ".join(f"{lab[:10]:>10s}" for lab in labels)
          + f" {'total':>6s} {'(system)':>8s} {'numba imp':>9s} {'faults':>8s} {'peak MB':>7s}"
          + f" {'lines/s':>8s}")
    for shape, lines, row in rows:
        print(f"{shape:10s} " + " ".join(f"{row[lab]:10.2f}" for lab in labels)
              + f" {row['total']:6.2f} {row['system']:8.2f} {row['kernel imports']:9.2f}"
              + f" {row['minor_faults']:8,d} {row['peak_mb']:7,d} {lines / row['total']:8,.0f}")


def test_batch_of_mixed_shapes(model_path, tmp_path):
    """A folder of 200 programs of every shape (about 1,000 lines each), on 1 core and on all."""
    from rapidfix.postprocess.batch import BatchSettings
    from rapidfix.postprocess.rewrite import RewriteOptions

    n_files = int(os.environ.get("RAPIDFIX_BENCH_FILES", "200"))
    src = tmp_path / "in"
    for i in range(n_files):
        shape = SHAPES[i % len(SHAPES)]
        folder = src / f"cell{i % 10}"
        folder.mkdir(parents=True, exist_ok=True)
        text = shape_program(shape, 1000)
        (folder / f"part{i}{_suffix(shape)}").write_bytes(text.encode())
    settings = BatchSettings(str(model_path), None, None, (), RewriteOptions(force=True))
    cores = os.cpu_count() or 1
    timings = batch_timings(src, tmp_path, settings, n_files)
    print(f"\nbatch of {n_files} mixed programs (~1,000 lines each): 1 core {timings[1]:.1f} s, "
          f"{cores} cores {timings[cores]:.1f} s, speed-up {timings[1] / timings[cores]:.2f}x")


_PEAK = (
    "import json, sys\n"
    "def peak_kb():\n"
    "    with open('/proc/self/status') as status:\n"
    "        return int(next(l for l in status if l.startswith('VmHWM')).split()[1])\n"
    "from rapidfix.cli import main\n"
    "code = main(sys.argv[1:])\n"
    "print(json.dumps({'peak_kb': peak_kb(), 'code': code}))\n"
)


def test_memory_of_a_million_lines(model_path, tmp_path):
    """Peak resident size of `rapidfix check` and `rapidfix rewrite` on ~1,000,000 lines."""
    import json

    lines = int(os.environ.get("RAPIDFIX_BENCH_MEMORY_LINES", "1000000"))
    shape = os.environ.get("RAPIDFIX_BENCH_MEMORY_SHAPE", "comments")
    source = tmp_path / f"big{_suffix(shape)}"
    source.write_bytes(shape_program(shape, lines).encode())
    n = source.read_bytes().count(b"\n")
    print()
    for label, args in (("check", ("check", "-q", str(source))),
                        ("rewrite", ("rewrite", str(source), "--model", str(model_path),
                                     "-o", str(tmp_path / "big.out.mod"), "--force"))):
        t0 = time.perf_counter()
        done = subprocess.run([sys.executable, "-c", _PEAK, *args], capture_output=True,
                              text=True)
        wall = time.perf_counter() - t0
        result = json.loads(done.stdout.strip().splitlines()[-1])
        assert result["code"] in (0, 3), done.stderr
        print(f"{label:8s} {n:,} lines ({shape}): peak {result['peak_kb'] / 1024:,.0f} MB, "
              f"{wall:.1f} s wall (target < 1 GB)")


def test_small_program_and_start_up(model_path, tmp_path):
    small = tmp_path / "small.mod"
    small.write_bytes(shape_program("comments", 2000).encode())
    tiny = tmp_path / "tiny.mod"
    tiny.write_bytes(shape_program("named", 60).encode())
    out = tmp_path / "small.out.mod"
    figures = {}
    for label, args in (
        ("rapidfix --help", ("--help",)),
        ("rapidfix check (60 lines)", ("check", str(tiny))),
        ("rapidfix rewrite (2,000 lines)",
         ("rewrite", str(small), "--model", str(model_path), "-o", str(out), "--force")),
    ):
        runs = [_run_cli(*args) for _ in range(3)]
        assert all(r[2].returncode in (0, 3) for r in runs), runs[0][2].stderr
        figures[label] = (min(r[0] for r in runs), min(r[1] for r in runs))
    print()
    for label, (cpu, wall) in figures.items():
        print(f"{label:32s} {cpu:6.2f} s CPU {wall:6.2f} s wall (best of 3)")
