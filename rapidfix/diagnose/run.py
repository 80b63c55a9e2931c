"""The diagnosis end to end: files in, extended model and report out.

`diagnose` works on objects (a model, the robot, the setup, two point tables) and
returns a `Diagnosis`; `diagnose_files` reads the files, runs it, saves the
extended model (`rapidfix.error_model.model_file`) and writes the HTML + JSON report.
The calibration points are the only ones fitted; the validation points only
ever judge.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from rapidfix.diagnose.candidate_builders import CANDIDATES
from rapidfix.diagnose.data import measured_points, noise_sigma_mm, with_known_history
from rapidfix.diagnose.gauges import resolve_flange_gauge
from rapidfix.diagnose.report import build_report, statement, trial_record
from rapidfix.diagnose.selection import Selection, select
from rapidfix.digest import sha256_file
from rapidfix.error_model import ErrorModel, MeasuredPoints, load_model, save_model
from rapidfix.exceptions import MeasurementError, ModelError
from rapidfix.kinematics import RobotModel, load_robot
from rapidfix.measure import PointTable, Setup, read_points, read_setup, robot_reach_mm
from rapidfix.report import Report, write_report

#: fewest calibration points accepted (the richest candidate has ~40 parameters)
MIN_CALIBRATION_POINTS = 20
MIN_VALIDATION_POINTS = 5
#: rows of each ranking the command prints
SUMMARY_RANKING = 3


@dataclass
class Diagnosis:
    """A finished diagnosis: the selection, the model to save, its report and statement."""

    selection: Selection
    model: ErrorModel
    report: Report
    statement: str
    calibration: MeasuredPoints
    validation: MeasuredPoints
    files: dict[str, Path] = field(default_factory=dict)

    @property
    def accepted(self) -> list[str]:
        """Names of the accepted effects, in the order they were found."""
        return [t.kind for t in self.selection.accepted]


def extended_model(original: ErrorModel, sel: Selection,
                   data_files: Sequence[dict[str, str]] = ()) -> ErrorModel:
    """The original model plus what the diagnosis accepted, refitted (a new object).

    With nothing accepted the effects are the original ones. The tracker frame
    and the re-referenced joint terms come along with any accepted effect, since
    the effect was fitted together with them.
    """
    model = copy.deepcopy(original)
    if sel.accepted and sel.final is not None:
        fitted = copy.deepcopy(sel.final.model)
        model.effects = model.effects + fitted.effects[len(original.effects):]
    model.data_files = list(original.data_files) + list(data_files)
    final = sel.final or sel.before
    model.statistics = dict(original.statistics)
    model.statistics["diagnosis"] = {
        "accepted": [t.kind for t in sel.accepted],
        "statement": statement(sel),
        "validation_before": sel.before.validation.stats(),
        "validation_after": final.validation.stats(),
        "noise_floor_mean_mm": sel.floor_mm,
        "candidates": [trial_record(t) for t in sel.trials],
    }
    return model


def _check_sizes(table: PointTable, minimum: int, role: str) -> None:
    if len(table) < minimum:
        raise MeasurementError(f"{len(table)} {role} points are too few; at least {minimum} "
                               "are needed", file=table.path)


def _history_note(left_out: int, role: str, what: str) -> list[str]:
    if not left_out:
        return []
    return [f"{left_out} {role} point(s) at the start of the set, reached before every joint "
            f"had moved, were not {what}: their motion direction is unknown, so no model can "
            "predict a direction-dependent error (backlash) there."]


def diagnose(model: ErrorModel, robot: RobotModel, setup: Setup, calibration: PointTable,
             validation: PointTable, *, candidates: Sequence[str] = CANDIDATES,
             data_files: Sequence[dict[str, str]] = (),
             progress: Callable[[str], None] | None = None,
             title: str = "rapidfix diagnosis") -> Diagnosis:
    """Find, fit and judge the missing effects; returns the extended model and report."""
    model.check_robot(robot.name)
    unknown = [c for c in candidates if c not in CANDIDATES]
    if unknown:
        raise ModelError(f"unknown candidate effect(s) {', '.join(unknown)}",
                         hint=f"known: {', '.join(CANDIDATES)}")
    _check_sizes(calibration, MIN_CALIBRATION_POINTS, "calibration")
    _check_sizes(validation, MIN_VALIDATION_POINTS, "validation")
    cal = with_known_history(measured_points(calibration, setup))
    val = with_known_history(measured_points(validation, setup))
    sigma, source = noise_sigma_mm(model.statistics, setup)
    sel = select(model, robot, cal, val, default_payload_kg=setup.payload_kg,
                 noise_sigma_mm=sigma, candidates=candidates, progress=progress)
    extended = extended_model(model, sel, data_files)
    gauge_notes = []
    if sel.accepted:
        change = resolve_flange_gauge(extended, robot, cal)
        if change is not None:
            extended.statistics["diagnosis"]["flange_gauge"] = change.describe()
            gauge_notes.append(change.describe())
    notes = [f"Fitted on {len(cal)} calibration points only; the {len(val)} validation "
             "points are only predicted.",
             *_history_note(len(calibration) - len(cal), "calibration", "fitted"),
             *_history_note(len(validation) - len(val), "validation", "scored"),
             *gauge_notes]
    report = build_report(sel, robot, cal, val, noise_source=source, title=title, notes=notes)
    return Diagnosis(sel, extended, report, statement(sel), cal, val)


def diagnose_files(model_path: str | Path, setup_path: str | Path,
                   calibration_path: str | Path, validation_path: str | Path,
                   out_dir: str | Path, *, model_name: str = "model.json",
                   robot: str | None = None,
                   candidates: Sequence[str] = CANDIDATES,
                   progress: Callable[[str], None] | None = None) -> Diagnosis:
    """Read the files, diagnose, write OUT/model.json and OUT/diagnosis.{html,json}."""
    setup = read_setup(setup_path)
    robot_model = load_robot(robot or setup.robot)
    model = load_model(model_path, robot_model.name)
    reach = robot_reach_mm(robot_model)
    calibration = read_points(calibration_path, reach_mm=reach)
    validation = read_points(validation_path, reach_mm=reach)
    files = [{"name": Path(calibration_path).name, "sha256": sha256_file(calibration_path),
              "role": "calibration"},
             {"name": Path(validation_path).name, "sha256": sha256_file(validation_path),
              "role": "validation (scoring only, never fitted)"}]
    result = diagnose(model, robot_model, setup, calibration, validation,
                      candidates=candidates, data_files=files, progress=progress)
    out = Path(out_dir)
    result.files["model"] = save_model(result.model, out / model_name)
    html_path, json_path = write_report(result.report, out, stem="diagnosis")
    result.files["report"] = html_path
    result.files["report_data"] = json_path
    return result


def summary_lines(result: Diagnosis) -> list[str]:
    """What the command prints: the statement, one line per candidate, the headline."""
    sel = result.selection
    names = [f"{t.after} + {t.kind}" if t.after else t.kind for t in sel.trials]
    w = max([18, *(len(n) + 2 for n in names)])
    lines = [result.statement, ""]
    lines.append(f"{'round':<6}{'candidate':<{w}}{'+params':>8}{'BIC gain':>10}{'z':>7}"
                 f"{'expl.':>7}  verdict")
    for t, name in zip(sel.trials, names):
        if t.stage is None:
            lines.append(f"{t.round:<6}{name:<{w}}{'':>8}{'':>10}{'':>7}{'':>7}  {t.verdict}")
            continue
        lines.append(f"{t.round:<6}{name:<{w}}{t.added_rank:>8}{t.delta_bic:>10.1f}"
                     f"{t.z:>7.1f}{100 * t.explained:>6.0f}%  {t.verdict}")
    final = sel.final or sel.before
    lines += ["", f"validation mean error: {sel.before.validation.mean_mm:.4f} mm before, "
              f"{final.validation.mean_mm:.4f} mm after (noise floor ≈ {sel.floor_mm:.4f} mm)"]
    if sel.ranking:
        lines += ["", "what the residual left follows (joint × driver, linear BIC gain, share "
                  "of the calibration residual):"]
        lines += [f"  {v.score:8.1f} {100 * v.share:4.0f} %  {v.label}"
                  for v in sel.ranking[:SUMMARY_RANKING]]
    if sel.fallback is not None and sel.fallback.settings:
        lines += ["", "what a smooth correction of one joint over two joints predicts "
                  "(cross-validated RMS per coordinate, mm):"]
        lines += [f"  {r['cv_rms_mm_without']:.4f} → {r['cv_rms_mm']:.4f}  joint {r['joint']} "
                  f"over {', '.join(r['depends_on'])}"
                  for r in sel.fallback.settings[:SUMMARY_RANKING]]
    return lines
