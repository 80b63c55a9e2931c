"""The demo's post-processor step: rewrite the sample programs, run them on the virtual robot.

Each sample program is rewritten with the fitted model, then both the original and
the rewritten program are executed on the virtual robot: the joints a nominal
controller commands for them are pushed through the robot's true errors, and the
TCP lands where the true robot puts it. For the ballbar program the pivot is the
origin of its work object and the deviation of the bar length from the radius is
reported as in the source paper.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from rapidfix.atomic import write_text_atomic
from rapidfix.demo.ballbar_program import ballbar_program
from rapidfix.exceptions import RapidfixError
from rapidfix.postprocess import (
    RAPID_SUFFIXES,
    Compensator,
    Execution,
    RewriteOptions,
    align_axis1,
    commanded_motions,
    rewrite_file,
)
from rapidfix.rapid import load_program

BALLBAR = "ballbar.mod"


def _true_flange(virtual: Any, execution: Execution) -> np.ndarray:
    """Flange poses (K,4,4) in the base frame where the virtual robot really goes (noise-free)."""
    return virtual.actual_model.fk(virtual.actual_joints(execution.q_cmd))


def _in_base(frames: Any, flange: np.ndarray) -> np.ndarray:
    """TCP positions (K,3) in the base frame for flange poses, with each move's frames."""
    tcp = frames.tcp(flange)[:, :3, 3]
    return np.einsum("kij,kj->ki", frames.wobj[:, :3, :3], tcp) + frames.wobj[:, :3, 3]


def run_program(virtual: Any, original: Path, rewritten: Path, inserted: set[str]) -> dict:
    """Mean/max TCP error (mm) at the original Cartesian targets, before and after, on the
    virtual robot (MoveAbsJ of the original program are left as written and not counted)."""
    robot = virtual.robot
    before_prog = load_program(original)
    after_prog = load_program(rewritten)
    before = commanded_motions(before_prog, robot)
    after = commanded_motions(after_prog, robot)
    # output motions minus the inserted intermediate points line up with the input's
    kept = [i for i, m in enumerate(after_prog.motions)
            if not (m.target is not None and m.target.text in inserted)]
    position = {out: n for n, out in enumerate(kept)}
    after_index = {position[int(m)]: k for k, m in enumerate(after.motion) if int(m) in position}
    rows_before, rows_after = [], []
    for k, m in enumerate(before.motion.tolist()):
        if before_prog.motions[m].name.lower() == "moveabsj":
            continue  # joint targets are kept as written, not compensated
        if m in after_index:
            rows_before.append(k)
            rows_after.append(after_index[m])
    rb, ra = np.array(rows_before, dtype=int), np.array(rows_after, dtype=int)
    frames = before.placement.take(rb)  # the original moves' tool and work object
    intended = _in_base(frames, robot.fk(before.q_cmd[rb]))
    got_before = align_axis1(robot, _in_base(frames, _true_flange(virtual, before)[rb]), intended)
    got_after = align_axis1(robot, _in_base(frames, _true_flange(virtual, after)[ra]), intended)
    err_before = np.linalg.norm(got_before - intended, axis=1)
    err_after = np.linalg.norm(got_after - intended, axis=1)
    out: dict[str, Any] = {"moves_executed": int(rb.size)}
    if rb.size:
        out.update(before_mean_mm=float(err_before.mean()), before_max_mm=float(err_before.max()),
                   after_mean_mm=float(err_after.mean()), after_max_mm=float(err_after.max()))
    if original.name == BALLBAR and rb.size:
        on_circle = np.array([before.target[k].lower().startswith("pbb") for k in rb.tolist()])
        centre = frames.wobj[on_circle][0, :3, 3]
        radius = float(np.linalg.norm(intended[on_circle][0] - centre))
        for label, got in (("before", got_before), ("after", got_after)):
            dev = np.abs(np.linalg.norm(got[on_circle] - centre, axis=1) - radius)
            out[f"ballbar_{label}_max_mm"] = float(dev.max())
            out[f"ballbar_{label}_mean_mm"] = float(dev.mean())
    return out


def sample_programs(out_dir: Path, samples_dir: str | Path | None = None) -> list[Path]:
    """The programs the demo rewrites: every RAPID file of the samples folder (given, or
    the copy an installed wheel carries in rapidfix/samples, or the source checkout's),
    else the built-in ballbar program."""
    package = Path(__file__).resolve().parents[1]
    candidates = [Path(samples_dir)] if samples_dir is not None else [
        package / "samples", package.parent / "samples"]
    for folder in candidates:
        if folder.is_dir():
            found = sorted(p for p in folder.iterdir() if p.suffix.lower() in RAPID_SUFFIXES)
            if any(p.name == BALLBAR for p in found):
                return found
    builtin = out_dir / "inputs" / BALLBAR
    write_text_atomic(builtin, ballbar_program())
    return [builtin]


def rewrite_and_run(samples_dir: str | Path | None, out_dir: str | Path,
                    model_path: str | Path, virtual: Any) -> dict[str, Any]:
    """Rewrite the sample programs into out_dir and run original and rewritten on `virtual`;
    the summary is also written to out_dir/programs.json."""
    out = Path(out_dir)
    comp = Compensator.load(model_path, virtual.robot.name)
    options = RewriteOptions()
    programs: dict[str, Any] = {}
    for path in sample_programs(out, samples_dir):
        target = out / path.name
        try:
            result = rewrite_file(path, target, comp, options)
        except RapidfixError as err:
            programs[path.name] = {"error": str(err)}
            continue
        entry: dict[str, Any] = {
            "input": str(path),
            "output": str(target),
            "moves": result.moves_total,
            "compensated": result.moves_compensated,
            "skipped": len(result.skipped),
            "points_added": result.points_added,
            "predicted_worst_mm": result.worst_predicted_mm,
        }
        if result.moves_compensated:
            entry.update(run_program(virtual, path, target, result.inserted))
        programs[path.name] = entry
    summary = {"folder": str(out), "programs": programs}
    write_text_atomic(out / "programs.json", json.dumps(summary, indent=1) + "\n")
    return summary


def format_table(summary: dict[str, Any]) -> str:
    """Console table: per program, moves and TCP error before/after (mm)."""
    head = f"{'program':<22}{'moves':>6}{'comp.':>6}{'added':>6}{'before':>9}{'after':>9}"
    lines = [head + "   (mean TCP error at the targets on the virtual robot, mm)"]
    for name, e in summary["programs"].items():
        if "error" in e:
            lines.append(f"{name:<22}error: {e['error']}")
            continue
        before = e.get("before_mean_mm")
        after = e.get("after_mean_mm")
        fmt = (lambda v: f"{v:9.4f}" if v is not None else f"{'-':>9}")  # noqa: E731
        lines.append(f"{name:<22}{e['moves']:>6}{e['compensated']:>6}{e['points_added']:>6}"
                     f"{fmt(before)}{fmt(after)}")
        if "ballbar_before_max_mm" in e:
            lines.append(
                f"{'':<22}ballbar length deviation max {e['ballbar_before_max_mm']:.4f} -> "
                f"{e['ballbar_after_max_mm']:.4f}, mean {e['ballbar_before_mean_mm']:.4f} -> "
                f"{e['ballbar_after_mean_mm']:.4f} mm")
    lines.append(f"rewritten programs: {summary['folder']}")
    return "\n".join(lines)
