"""The diagnosis report: error before and after on validation, every candidate's evidence.

Tables: validation (and calibration) error before and after (mean, RMS, max, per
axis); each candidate in each round with its evidence (effective parameters
added, BIC gain, significance on validation, share of the residual above noise
it explains, verdict); each accepted effect's parameters with their standard
deviations. Figures: the validation errors before/after and, per accepted
effect, the residual against the feature that exposed it. The summary (JSON)
holds every number, and a plain statement of the outcome.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rapidfix.diagnose.features import along, exposing_feature
from rapidfix.diagnose.plots import evidence_figure
from rapidfix.diagnose.selection import (
    BIC_MARGIN,
    SHARE_MIN,
    Z_MIN,
    Selection,
    Trial,
)
from rapidfix.diagnose.structured import ranking_records
from rapidfix.error_model import Effect, LinkGeometry, MeasuredPoints, error_names
from rapidfix.kinematics import RobotModel
from rapidfix.report import Report, Table, position_error_figure


def interface_units(names: tuple[str, ...] | list[str], values: np.ndarray,
                    std: np.ndarray | None) -> list[dict[str, Any]]:
    """Parameters with radians turned into degrees (names follow)."""
    out = []
    for i, name in enumerate(names):
        value = float(values[i])
        sd = None if std is None else float(std[i])
        if "_rad" in name:
            name = name.replace("_rad", "_deg")
            value = float(np.degrees(value))
            sd = None if sd is None else float(np.degrees(sd))
        out.append({"name": name, "value": value, "std": sd})
    return out


def effect_parameters(effect: Effect) -> list[dict[str, Any]]:
    """An effect's parameters in interface units; screw errors for link geometry."""
    if isinstance(effect, LinkGeometry):
        return interface_units(error_names(), effect.errors(), effect.errors_uncertainty())
    return interface_units(effect.param_names, effect.params(), effect.uncertainty)


def trial_record(trial: Trial) -> dict[str, Any]:
    """JSON data of one candidate trial."""
    def num(v: float) -> float | None:
        return float(v) if np.isfinite(v) else None

    record: dict[str, Any] = {
        "candidate": trial.kind, "round": trial.round, "physics": trial.physics,
        "detail": trial.detail, "variants_screened": trial.variants,
        "tried_on_top_of": trial.after or None,
        "accepted": trial.accepted, "verdict": trial.verdict,
    }
    if trial.stage is not None:
        effect = trial.stage.model.effects[-1]
        record.update({
            "added_parameters": trial.added_rank, "bic_gain": num(trial.delta_bic),
            "validation_z": num(trial.z), "share_of_residual_above_noise": num(trial.share),
            "share_of_validation_residual": num(trial.explained),
            "validation_mean_mm_with_it": trial.stage.validation.mean_mm,
            "calibration_rms_mm_with_it": trial.stage.calibration.rms_mm,
            "parameters": effect_parameters(effect),
        })
    return record


def alternatives(sel: Selection) -> dict[str, list[str]]:
    """For each accepted effect, the candidates of its round that passed every test too
    and gained within `BIC_MARGIN` of it: explanations these data do not tell apart
    (a tracker scale and thermal growth when the temperature hardly varied, say)."""
    out: dict[str, list[str]] = {}
    for chosen in sel.accepted:
        rivals = [t.kind for t in sel.trials
                  if t.round == chosen.round and t is not chosen and not t.accepted
                  and not t.after and t.stage is not None and _passes(t)
                  and t.kind not in (a.kind for a in sel.accepted)
                  and chosen.delta_bic - t.delta_bic <= BIC_MARGIN]
        if rivals:
            out[chosen.kind] = rivals
    return out


def _passes(trial: Trial) -> bool:
    return trial.verdict == "passes" or trial.verdict.endswith("candidate is preferred")


def trial_name(trial: Trial) -> str:
    """What an accepted effect is, in words: its kind, or for a structured effect where
    it acts and what drives it, with its leading parameter."""
    effect = getattr(trial, "effect", None)
    sentence = getattr(effect, "sentence", None)
    if not callable(sentence):
        return trial.kind
    return f"{getattr(effect, 'type_name', trial.kind)}: {sentence()}"


def statement(sel: Selection) -> str:
    """The outcome in one or two plain sentences."""
    before = sel.before.validation.mean_mm
    floor = sel.floor_mm
    if sel.accepted and sel.final is not None:
        names = " and ".join(trial_name(t) for t in sel.accepted)
        after = sel.final.validation.mean_mm
        text = (f"The residual is explained by {names}: the mean error on the validation "
                f"points falls from {before:.4f} mm to {after:.4f} mm (measurement noise "
                f"alone would leave about {floor:.4f} mm).")
        for kind, rivals in alternatives(sel).items():
            text += (f" {' or '.join(rivals)} explains it nearly as well as {kind} (BIC "
                     f"within {BIC_MARGIN:g}): these data do not tell them apart.")
        return text
    if before <= 1.25 * floor:
        return (f"The residual is already at the noise floor: {before:.4f} mm mean on the "
                f"validation points, where measurement noise alone leaves about {floor:.4f} "
                "mm. Nothing is left to explain; the model is unchanged.")
    if before <= 1.5 * floor:
        return (f"The residual is close to the noise floor ({before:.4f} mm mean on the "
                f"validation points, noise alone about {floor:.4f} mm) and no candidate effect "
                "explains what is left; nothing is worth adding, the model is unchanged.")
    lead = ""
    ranking = getattr(sel, "ranking", [])
    if ranking:
        lead = (f" What it follows most closely: {ranking[0].label} "
                f"({100 * ranking[0].share:.0f} % of the calibration residual), not "
                "enough to pass the tests.")
    return (f"No candidate effect explains the residual ({before:.4f} mm mean on the "
            f"validation points; noise alone would leave about {floor:.4f} mm). Its cause "
            "is not in the library of candidates; the model is unchanged." + lead +
            " See each candidate's evidence below.")


#: rows of the fallback's ranking shown in the report and the JSON
FALLBACK_ROWS = 12


def fallback_record(sel: Selection) -> dict[str, Any] | None:
    """JSON data of the fallback's search, when it was tried: settings searched, what
    it proposed (or why nothing), its ranking, and the domain of an accepted one."""
    proposal = sel.fallback
    if proposal is None:
        return None
    accepted = next((t for t in sel.accepted if t.kind == "rbf_correction"), None)
    effect = None if accepted is None else accepted.effect
    return {"settings_searched": proposal.variants,
            "proposed": proposal.detail or None,
            "reason": proposal.reason or None,
            "settings": proposal.settings[:FALLBACK_ROWS],
            "accepted": accepted is not None,
            "domain": None if effect is None else getattr(effect, "domain", None)}


def _error_table(title: str, rows: list[tuple[str, dict[str, Any]]]) -> Table:
    body = []
    for label, s in rows:
        axes = s["per_axis"]
        body.append([label, s["mean_mm"], s["rms_mm"], s["max_mm"], axes["x"]["rms_mm"],
                     axes["y"]["rms_mm"], axes["z"]["rms_mm"]])
    return Table(title, ["", "mean", "RMS", "max", "RMS x", "RMS y", "RMS z"], body,
                 "Residual = measured − predicted ball position, in the robot base frame: what "
                 "the robot still misses by after compensation with that model.")


def build_report(sel: Selection, robot: RobotModel, calibration: MeasuredPoints,
                 validation: MeasuredPoints, *, noise_source: str,
                 title: str = "rapidfix diagnosis", notes: list[str] | None = None,
                 extra_summary: dict[str, Any] | None = None) -> Report:
    """Assemble the diagnosis report (tables, figures, summary) from a selection."""
    final = sel.final or sel.before
    text = statement(sel)
    if sel.noise_refined:
        noise_source = (f"scatter of the best model's calibration residuals (smaller than "
                        f"the {noise_source})")
    summary: dict[str, Any] = {
        "statement": text,
        "accepted": [t.kind for t in sel.accepted],
        "indistinguishable_from": alternatives(sel),
        "validation": {"points": len(validation), "before": sel.before.validation.stats(),
                       "after": final.validation.stats()},
        "calibration": {"points": len(calibration),
                        "before": sel.before.calibration.stats(),
                        "after": final.calibration.stats()},
        "noise": {"sigma_per_axis_mm": sel.noise_sigma_mm, "source": noise_source,
                  "floor_mean_mm": sel.floor_mm},
        "criteria": {"bic_margin": BIC_MARGIN, "validation_z_min": Z_MIN,
                     "share_of_validation_residual_min": SHARE_MIN},
        "baseline_validation_mean_mm": sel.baseline.validation.mean_mm,
        "candidates": [trial_record(t) for t in sel.trials],
        "residual_follows": ranking_records(sel.ranking),
        "fallback": fallback_record(sel),
    }
    summary.update(extra_summary or {})
    report = Report(title, summary, notes=[text, *(notes or [])])
    report.tables.append(_error_table(
        f"Error on {len(validation)} validation points, never fitted (mm)",
        [("before (given model)", summary["validation"]["before"]),
         ("after (extended model)", summary["validation"]["after"])]))
    report.tables.append(_error_table(
        f"Error on {len(calibration)} calibration points, fitted (mm)",
        [("before", summary["calibration"]["before"]),
         ("after", summary["calibration"]["after"])]))
    rows = []
    for t in sel.trials:
        if t.stage is None:
            rows.append([t.round, t.kind, t.detail, None, None, None, None, None, None,
                         t.verdict])
            continue
        rows.append([t.round, t.kind, t.detail, t.added_rank, t.delta_bic, t.z,
                     100.0 * t.explained, 100.0 * t.share, t.stage.validation.mean_mm,
                     t.verdict])
    report.tables.append(Table(
        "Candidate effects, fitted on calibration, judged on validation",
        ["round", "candidate", "detail", "parameters added", "BIC gain", "validation z",
         "% of validation residual explained", "% of it above noise",
         "validation mean (mm)", "verdict"],
        rows,
        f"Accepted when the BIC gain exceeds {BIC_MARGIN:g} (after a charge for screened "
        f"variants), the validation residual follows the change it predicts (z ≥ {Z_MIN:g}) and "
        f"it explains at least {100 * SHARE_MIN:.0f} % of the mean squared validation "
        f"residual. Noise level: {sel.floor_mm:.4f} mm mean, from the {noise_source}."))
    if sel.ranking:
        report.tables.append(Table(
            "What the residual left follows: joint × driver, best first",
            ["joint", "driver", "source joint", "description", "linear BIC gain",
             "% of calibration residual", "parameters"],
            [[r["joint"], r["driver"], r["source_joint"], r["description"],
              r["linear_bic_gain"], 100.0 * r["share_of_calibration_residual"],
              r["parameters"]] for r in ranking_records(sel.ranking)],
            "Each variant's regressors (times the points' sensitivity to that joint's "
            "error, off everything the final model fits) regressed on the final model's "
            "calibration residual; a ranking, not a test (the tests are the candidates')."))
    if sel.fallback is not None and sel.fallback.settings:
        report.tables.append(Table(
            "What the residual depends on: a smooth correction of one joint over two "
            "joints, best first",
            ["joint acted on", "depends on", "centres", "width (unit box)", "parameters",
             "CV RMS without (mm)", "CV RMS with (mm)"],
            [[r["joint"], ", ".join(r["depends_on"]), r["centres"], r["width_unit"],
              r["parameters"], r["cv_rms_mm_without"], r["cv_rms_mm"]]
             for r in sel.fallback.settings[:FALLBACK_ROWS]],
            "Each joint × pair of joints (and the context that varies): a Gaussian RBF "
            "correction, its centres, width and number of parameters chosen by "
            "cross-validation on the calibration points, projected off everything the "
            "model fits; the RMS per coordinate of the calibration residual predicted out "
            "of fold. The top one is the fallback candidate; a ranking, not a test."))
    for trial in sel.accepted:
        effect = trial.stage.model.effects[-1] if trial.stage else None
        if effect is None:
            continue
        params = effect_parameters(effect)
        report.tables.append(Table(
            f"{trial_name(trial)}: fitted parameters (± 1σ)", ["parameter", "value", "σ"],
            [[p["name"], p["value"], p["std"]] for p in params], trial.physics))
    report.figures.append(position_error_figure(sel.before.validation.vectors,
                                                final.validation.vectors))
    for k, trial in enumerate(sel.accepted):
        if trial.stage is None or trial.previous is None:
            continue
        # what adding the effect (and refitting) changed in the prediction, per point
        move = trial.previous.validation.vectors - trial.stage.validation.vectors
        feature = exposing_feature(trial.stage.model.effects[-1], validation)
        report.figures.append(evidence_figure(
            trial.kind, feature.values, feature.label,
            along(trial.previous.validation.vectors, move), along(move, move),
            along(trial.stage.validation.vectors, move), discrete=feature.discrete, seed=k))
    return report
