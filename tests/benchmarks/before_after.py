"""A change's effect in the same run: `rapidfix` commands on a few program shapes in
fresh processes, alternately with an earlier tree of the code (BASE, e.g.
`git archive <commit> | tar -x -C /tmp/base`) and this one.

    python tests/benchmarks/before_after.py --base /tmp/base --model model.json [--set S]

For each case it prints the median CPU seconds of the whole process and of the set's
timed steps for both trees, and checks that both wrote the same bytes. The sets:

- emission (default): `named` and `inline` at 40,000 lines with `--emit robtargets`,
  the odd shape `stacked` at 20,000 lines (half its moves keep a filtered robtarget;
  both emit modes), `comments` at 200,000 lines (both emit modes); timed `emit_edits`,
  the filtered robtargets' emission and `count_identifiers`.
- language: the odd shapes `messages` and `conditions` (strings, conditions, the heads
  of compound statements) and `control` at 20,000 lines, and `rapidfix check` of the
  sample cell program (a small file: start-up); timed the parse.
- rewrite: the three shapes furthest from the rewrite target (`inline`, `offs`, `movec`)
  at 200,000 lines, `named` at 60,000 and the odd shapes `five_axis` and `feeds` at
  20,000 (programs below the compiled kernels' threshold); timed the parse, the plan,
  the path check and the emission.
- kept: instructions kept with filtered robtargets: the odd shape `arc_weld` (its weld
  moves have no joint-target form) at 100,000 lines, `named` and `inline` at 200,000
  and `movec` and the odd shape `scoped` at 100,000 with `--emit robtargets`; timed the
  emission and the read-back.
- odd: the odd shapes slowest per line at 100,000 lines (arithmetic in the robtargets,
  records in Offs arguments, statements stacked on IF lines, a distinct argument tail
  per move, conditions, switches before the target, whitespace inside the targets,
  targets that fail their confdata) and `flips` at 30,000 (lines the path check cannot
  close); timed the parse, the plan and the emission.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
TREE = HERE.parents[1]
# per set: (case, shape, lines, odd shape?, emit; "check" to check the sample cell)
CASES = {
    "emission": (
        ("named 40k robtargets", "named", 40_000, False, "robtargets"),
        ("inline 40k robtargets", "inline", 40_000, False, "robtargets"),
        ("stacked 20k", "stacked", 20_000, True, "jointtargets"),
        ("stacked 20k robtargets", "stacked", 20_000, True, "robtargets"),
        ("comments 200k", "comments", 200_000, False, "jointtargets"),
        ("comments 200k robtargets", "comments", 200_000, False, "robtargets"),
    ),
    "language": (
        ("messages 20k", "messages", 20_000, True, "jointtargets"),
        ("conditions 20k", "conditions", 20_000, True, "jointtargets"),
        ("control 20k", "control", 20_000, False, "jointtargets"),
        ("check samples/cell.mod", "cell", 0, False, "check"),
    ),
    "rewrite": (
        ("inline 200k", "inline", 200_000, False, "jointtargets"),
        ("offs 200k", "offs", 200_000, False, "jointtargets"),
        ("movec 200k", "movec", 200_000, False, "jointtargets"),
        ("named 60k", "named", 60_000, False, "jointtargets"),
        ("five_axis 20k", "five_axis", 20_000, True, "jointtargets"),
        ("feeds 20k", "feeds", 20_000, True, "jointtargets"),
    ),
    "kept": (
        ("arc_weld 100k", "arc_weld", 100_000, True, "jointtargets"),
        ("named 200k robtargets", "named", 200_000, False, "robtargets"),
        ("inline 200k robtargets", "inline", 200_000, False, "robtargets"),
        ("movec 100k robtargets", "movec", 100_000, False, "robtargets"),
        ("scoped 100k robtargets", "scoped", 100_000, True, "robtargets"),
    ),
    "odd": (
        ("expressions 100k", "expressions", 100_000, True, "jointtargets"),
        ("records 100k", "records", 100_000, True, "jointtargets"),
        ("stacked 100k", "stacked", 100_000, True, "jointtargets"),
        ("tails 100k", "tails", 100_000, True, "jointtargets"),
        ("conditions 100k", "conditions", 100_000, True, "jointtargets"),
        ("concurrent 100k", "concurrent", 100_000, True, "jointtargets"),
        ("spaced 100k", "spaced", 100_000, True, "jointtargets"),
        ("failing 100k", "failing", 100_000, True, "jointtargets"),
        ("flips 30k", "flips", 30_000, True, "jointtargets"),
    ),
}
# what the child process times (CPU seconds, summed over calls), per set
_TIMED = {
    "emission": (("rapidfix.postprocess.rewrite", None, "emit_edits"),
                 ("rapidfix.postprocess.emission", "_Emitter", "_filtered"),
                 ("rapidfix.postprocess.emission", None, "count_identifiers")),
    "language": (("rapidfix.rapid.parse", None, "parse_source"),),
    # 'a|b': the first the tree has (b in trees before a), reported as a
    "rewrite": tuple(("rapidfix.postprocess.rewrite", None, name) for name in
                     ("parse_owned|parse_program", "plan_program", "refine_paths",
                      "emit_edits")),
    "odd": tuple(("rapidfix.postprocess.rewrite", None, name) for name in
                 ("parse_owned|parse_program", "plan_program", "emit_edits")),
    "kept": tuple(("rapidfix.postprocess.rewrite", None, name) for name in
                  ("emit_edits", "read_back")),
}


def _label(names: str) -> str:
    """How a timed step ('a' or 'a|b') is reported: by its first name."""
    return names.split("|")[0]


def _child(timed_set: str, argv: list[str]) -> None:
    """Run `rapidfix ARGV` in this process with the steps of `_TIMED[timed_set]` timed,
    as the tree's console script runs it; print their CPU seconds as JSON on stderr."""
    import importlib

    from rapidfix import cli  # light: imports neither numpy nor a command

    console = getattr(cli, "console_main", None)
    # what it sets before numpy is imported, which the timers below import
    getattr(cli, "prepare_process", lambda: None)()
    from process_phases import present_name, timed  # this script's folder: sys.path[0]

    spent: dict[str, float] = {}
    for module_name, owner, names in _TIMED[timed_set]:
        target = importlib.import_module(module_name)
        if owner is not None:
            target = getattr(target, owner, None)
        name = None if target is None else present_name(target, names)
        if name is not None:
            setattr(target, name, timed(spent, _label(names), getattr(target, name)))
    sys.argv = ["rapidfix", *argv]
    try:
        console() if console is not None else cli.main(argv)
    except SystemExit:
        pass
    print("TIMED " + json.dumps(spent), file=sys.stderr)


def _run(tree: Path, timed_set: str, args: list[str]) -> tuple[float, dict[str, float]]:
    """(CPU seconds of the whole child process, its timed steps) of one command with
    the code of `tree`."""
    # a user's run: Python's bytecode cache allowed (an installed package has one), so
    # a tree's modules are not compiled again in every child
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env.update(PYTHONPATH=str(tree), OMP_NUM_THREADS="1")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child",
                           timed_set, *args],
                          capture_output=True, text=True, env=env, cwd=tempfile.gettempdir())
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    found = re.search(r"TIMED (.*)", done.stderr)
    if found is None:
        raise RuntimeError(done.stderr[-2000:])
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, json.loads(found.group(1))


def _median(runs: list[tuple[float, dict[str, float]]], step: str | None) -> float:
    """The median CPU seconds of the whole process (`step` None) or of a timed step."""
    return statistics.median(cpu if step is None else steps.get(step, 0.0)
                             for cpu, steps in runs)


def main() -> None:
    """Generate the shapes, run each case alternately with both trees, print medians."""
    if sys.argv[1:2] == ["--child"]:
        _child(sys.argv[2], sys.argv[3:])
        return
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", type=Path, required=True, help="the earlier tree")
    parser.add_argument("--model", type=Path, required=True, help="error model file")
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--set", choices=list(CASES), default="emission", dest="cases")
    parser.add_argument("--only", nargs="*", help="cases whose name contains one of these")
    options = parser.parse_args()
    sys.path.insert(0, str(HERE))
    from odd_shapes import odd_program
    from program_shapes import shape_program

    work = Path(tempfile.mkdtemp(prefix="before_after_"))
    model = str(options.model.resolve())  # the children run in the temporary folder
    trees = {"before": options.base.resolve(), "after": TREE}
    steps = [None, *(_label(names) for _, _, names in _TIMED[options.cases])]
    warm: set[str] = set()
    print(f"{'case':26s} " + " ".join(f"{step or 'whole process':>22s}" for step in steps)
          + "  same bytes")
    for case, shape, lines, odd, emit in CASES[options.cases]:
        if options.only and not any(part in case for part in options.only):
            continue
        source = work / f"{shape}{lines}.mod"
        if emit == "check":
            source = TREE / "samples" / f"{shape}.mod"
        elif not source.exists():
            source.write_text(odd_program(shape, lines) if odd else shape_program(shape, lines))
        runs: dict[str, list[tuple[float, dict[str, float]]]] = {tree: [] for tree in trees}
        same = True
        for _ in range(options.reps):
            written = {}
            for tree, path in trees.items():
                out = work / f"out_{tree}.mod"
                args = (["check", str(source)] if emit == "check" else
                        ["rewrite", str(source), "-o", str(out), "--model", model,
                         "--force", "--emit", emit])
                if tree not in warm:  # bytecode and compiled kernels cached, once a tree
                    _run(path, options.cases, args)
                    warm.add(tree)
                runs[tree].append(_run(path, options.cases, args))
                written[tree] = b"" if emit == "check" else out.read_bytes()
            same = same and written["before"] == written["after"]
        cells = []
        for step in steps:
            a, b = _median(runs["before"], step), _median(runs["after"], step)
            cells.append(f"{a:6.2f} -> {b:5.2f} ({a / b if b else float('nan'):4.2f}x)")
        print(f"{case:26s} " + " ".join(f"{cell:>22s}" for cell in cells) + f"  {same}",
              flush=True)


if __name__ == "__main__":
    main()
