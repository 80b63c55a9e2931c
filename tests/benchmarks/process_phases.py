"""Run `rapidfix ARGS` in this fresh process with a timer on each step of the rewrite.

    python tests/benchmarks/process_phases.py rewrite prog.mod --model m.json -o out.mod

prints, as the last line of its standard output, one JSON object: the CPU seconds of
each step of `rewrite_source` (parse + model, plan, path check, emission, render, read
back, predicted deviation), of what comes before it (interpreter start-up, imports,
loading the model file) and after it (the atomic write, the report), of importing the
compiled kernels (numba), the process's user and system time, its minor page faults and
its peak resident size: where the time of a whole `rapidfix rewrite` goes, as a user
waits for it (test_shapes_speed.py prints them per shape). The timers cost microseconds.
"""

from __future__ import annotations

import json
import resource
import sys
import time

_spent: dict[str, float] = {}


def timed(spent: dict[str, float], label: str, fn):
    """`fn`, adding the CPU seconds of each call to spent[label]."""
    def wrapper(*args, **kwargs):
        start = time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            spent[label] = spent.get(label, 0.0) + time.process_time() - start
    return wrapper


#: (label, module, attribute) of the steps timed, in the order a rewrite takes them
STEPS = (
    # 'a|b': the first the tree has (b in trees before a)
    ("parse + model", "rapidfix.postprocess.rewrite", "parse_owned|parse_program"),
    ("plan", "rapidfix.postprocess.rewrite", "plan_program"),
    ("path check", "rapidfix.postprocess.rewrite", "refine_paths"),
    ("emission", "rapidfix.postprocess.rewrite", "emit_edits"),
    ("render", "rapidfix.rapid.edit", "Editor.render"),
    ("read back", "rapidfix.postprocess.rewrite", "read_back"),
    ("deviation", "rapidfix.postprocess.rewrite", "predicted_deviation"),
    ("write", "rapidfix.postprocess.rewrite", "write_bytes_atomic"),
    ("rewrite_source", "rapidfix.postprocess.rewrite", "_rewrite_owned|rewrite_source"),
)


def time_steps(spent: dict[str, float], steps: tuple[tuple[str, str, str], ...],
               patch=setattr) -> None:
    """Put a timer (`timed`) on each (label, module, attribute path) of `steps`, with
    `patch` (setattr here; a test's monkeypatch.setattr, which undoes it after). An
    attribute 'a|b' is the first of those names the tree has (an older tree's name)."""
    import importlib

    for label, module_name, attribute in steps:
        owner = importlib.import_module(module_name)
        *path, names = attribute.split(".")
        for part in path:
            owner = getattr(owner, part)
        name = present_name(owner, names)
        if name is None:
            raise AttributeError(f"{module_name} has none of {names}")
        patch(owner, name, timed(spent, label, getattr(owner, name)))


def present_name(owner: object, names: str) -> str | None:
    """Of `names` ('a' or 'a|b': b in trees before a), the first `owner` has, or None."""
    return next((name for name in names.split("|") if hasattr(owner, name)), None)


def _time_kernel_imports() -> None:
    """Time the imports of the compiled kernels' modules (numba's import with them),
    which `rapidfix.compiled.load_kernel` makes through importlib.import_module."""
    import importlib

    plain = importlib.import_module

    kernel_import = timed(_spent, "kernel imports", plain)

    def import_module(name: str, package: str | None = None):
        return (kernel_import if name.endswith("_compiled") else plain)(name, package)

    importlib.import_module = import_module


def _peak_kb() -> int:
    """This process's own high-water mark (ru_maxrss is inherited through fork and exec:
    it would be the benchmark's own where that was larger)."""
    with open("/proc/self/status") as status:
        return int(next(line for line in status if line.startswith("VmHWM")).split()[1])


def main(argv: list[str]) -> int:
    import rapidfix.cli as cli  # light: imports neither numpy nor a command

    getattr(cli, "prepare_process", lambda: None)()  # as the console script, if the tree has it
    _time_kernel_imports()
    time_steps(_spent, STEPS)
    status = cli.main(argv)
    usage = resource.getrusage(resource.RUSAGE_SELF)
    total = usage.ru_utime + usage.ru_stime
    inner = ("parse + model", "plan", "path check", "emission", "render", "read back",
             "deviation")
    row = {label: round(_spent.get(label, 0.0), 3) for label in inner}
    row["other steps"] = round(_spent.get("rewrite_source", 0.0)
                               - sum(_spent.get(label, 0.0) for label in inner), 3)
    row["write"] = round(_spent.get("write", 0.0), 3)
    row["start-up, imports, report"] = round(
        total - _spent.get("rewrite_source", 0.0) - _spent.get("write", 0.0), 3)
    row["kernel imports"] = round(_spent.get("kernel imports", 0.0), 3)
    row.update(total=round(total, 3), user=round(usage.ru_utime, 3),
               system=round(usage.ru_stime, 3), minor_faults=usage.ru_minflt,
               peak_mb=round(_peak_kb() / 1024), code=status)
    print(json.dumps(row))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
