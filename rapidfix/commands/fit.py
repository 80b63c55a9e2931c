"""`rapidfix fit`: a per-joint error model from laser-tracker sweeps."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rapidfix.cli import EXIT_STATUS_EPILOG
from rapidfix.paths import check_input_file, check_output_dir, check_output_file


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `fit` command."""
    parser = subparsers.add_parser(
        "fit",
        help="fit a joint motion error model from joint sweeps",
        description="Register the tracker, recover every joint's actual angle from the "
        "sweeps, fit one cross-validated Gaussian RBF network per joint and write the "
        "model file (JSON). Prints per joint the valid range, the cross-validated RMS "
        "and the repeatability. Exit status 3 when the model warned (e.g. a validation "
        "angle outside the fitted range, clamped), printed as 'rapidfix: warning: …'.",
        epilog=EXIT_STATUS_EPILOG,
    )
    parser.add_argument("setup", metavar="SETUP", help="setup.toml of the measurement set")
    parser.add_argument("sweeps", metavar="SWEEPS", nargs="+", help="sweeps CSV file(s)")
    parser.add_argument("-o", "--output", required=True, metavar="MODEL.json",
                        help="model file to write")
    parser.add_argument("--robot", metavar="NAME",
                        help="robot model name or robot file (default: the setup's robot)")
    parser.add_argument("--outside-range", choices=("clamp", "refuse"), default="clamp",
                        help="what the model does with a joint angle outside the measured "
                        "range: clamp to the edge with a warning (default) or refuse")
    parser.add_argument("--validation", metavar="POINTS.csv",
                        help="measured points not used in the fit: print the error before "
                        "and the residual the model predicts after compensation")
    parser.add_argument("--report", metavar="DIR",
                        help="also write report.html and report.json (fit statistics, "
                        "the Δθ-θ figure per joint, the validation numbers) into DIR")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Fit, save, print the summary; exit status 3 if the model warned."""
    from rapidfix.pipeline import model_warnings

    with model_warnings() as messages:
        _fit(args)
    for text in messages:
        print(f"rapidfix: warning: {text}", file=sys.stderr)
    return 3 if messages else 0


def _fit(args: argparse.Namespace) -> None:
    """The work of `run`: every path checked first, the model written last, nothing
    written when any step fails."""
    from rapidfix import pipeline
    from rapidfix.error_model import save_model
    from rapidfix.report import validation_section, write_report

    output = Path(args.output)
    inputs = [Path(args.setup), *map(Path, args.sweeps)]
    for path in inputs:
        check_input_file(path, "measurement file")
    if args.validation:
        check_input_file(args.validation, "validation file")
        inputs.append(Path(args.validation))
    check_output_file(output, inputs=inputs, what="model file")
    if args.report:
        check_output_dir(args.report, "report folder")
        for name in ("report.html", "report.json"):
            check_output_file(Path(args.report) / name, inputs=inputs, what="report")
    outcome = pipeline.fit_from_files(args.setup, args.sweeps, robot=args.robot,
                                      policy=args.outside_range)
    validation = None
    if args.validation:
        validation = pipeline.predicted_before_after(outcome, args.validation)
    lines = [outcome.model.summary(), pipeline.fit_summary(outcome.model)]
    reg = outcome.model.statistics.get("sweep_analysis", {}).get("registration", {})
    if isinstance(reg, dict) and reg.get("rms_mm") is not None:
        lines.append(f"tracker registration: RMS {reg['rms_mm']:.4f} mm")
        outliers = reg.get("outlier_rows") or []
        if outliers:
            lines.append(f"outlier rows left out ({len(outliers)}): "
                         f"{', '.join(str(r) for r in outliers[:20])}"
                         f"{' …' if len(outliers) > 20 else ''}")
    report = None
    if args.report:
        report = pipeline.accuracy_report_for(
            outcome, validation=validation, title=f"rapidfix fit: {output.name}",
            notes=["Validation 'after' is predicted, not executed: the measured position "
                   "minus the model's prediction, i.e. what compensation would leave."]
            if validation is not None else [])
    if validation is not None:
        _, numbers = validation_section(validation)
        lines.append(pipeline.before_after_table({"validation": numbers}, after_label="after*"))
        lines.append("* predicted: measured minus model prediction, what compensation "
                     "would leave")
    print("\n".join(lines))
    if report is not None:
        html_path, json_path = write_report(report, args.report)
        print(f"wrote {html_path} and {json_path}")
    save_model(outcome.model, output)
    print(f"wrote {output}")
