"""`rapidfix diagnose`: find what the model misses, name the effect, add it, report."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from rapidfix.exceptions import OutputExistsError, RapidfixWarning
from rapidfix.paths import check_input_file, check_output_dir, check_output_file


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `diagnose` command."""
    from rapidfix.diagnose import CANDIDATES

    parser = subparsers.add_parser(
        "diagnose",
        help="trace the residual error to a missing physical effect and add it",
        description="Fit every candidate effect (" + ", ".join(CANDIDATES) + ") on the "
        "calibration points only, judge it on the validation points, add the effects that "
        "explain the residual significantly, refit, save the extended model and write an "
        "HTML + JSON report with the error before and after.",
    )
    parser.add_argument("--model", required=True, metavar="MODEL.json",
                        help="the current model (e.g. from `rapidfix fit`)")
    parser.add_argument("--setup", required=True, metavar="SETUP",
                        help="setup.toml of the measurement set")
    parser.add_argument("calibration", metavar="CALIBRATION.csv",
                        help="points the candidates are fitted on")
    parser.add_argument("validation", metavar="VALIDATION.csv",
                        help="points that only judge (never fitted)")
    parser.add_argument("-o", "--out", required=True, metavar="OUT",
                        help="output folder: model.json, diagnosis.html, diagnosis.json")
    parser.add_argument("--robot", metavar="NAME",
                        help="robot model name or robot file (default: the setup's robot)")
    parser.add_argument("--candidates", metavar="LIST",
                        help="comma-separated subset of the candidate effects to try")
    parser.add_argument("--force", action="store_true",
                        help="replace model.json / diagnosis.* already in OUT")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Diagnose, save, print the summary."""
    from rapidfix.diagnose import CANDIDATES, diagnose_files, summary_lines

    out = Path(args.out)
    outputs = [out / "model.json", out / "diagnosis.html", out / "diagnosis.json"]
    inputs = [Path(p) for p in (args.model, args.setup, args.calibration, args.validation)]
    for path, what in zip(inputs, ("model file", "setup file", "calibration file",
                                   "validation file")):
        check_input_file(path, what)
    check_output_dir(out)
    for target in outputs:
        if any(p.exists() and target.exists() and target.resolve() == p.resolve()
               for p in inputs):
            raise OutputExistsError("would overwrite an input", file=target)
        if target.exists() and not args.force:
            raise OutputExistsError("already exists", file=target,
                                    hint="choose another --out or pass --force")
        check_output_file(target, inputs=inputs)
    if inputs[2].resolve() == inputs[3].resolve():
        warnings.warn(f"{args.calibration} is both the calibration and the validation file: "
                      "the validation numbers are not independent of the fit", RapidfixWarning,
                      stacklevel=2)
    candidates = CANDIDATES
    if args.candidates:
        candidates = tuple(c.strip() for c in args.candidates.split(",") if c.strip())
    from tqdm import tqdm

    with tqdm(desc="rapidfix diagnose", unit="fit", leave=False,
              disable=not sys.stderr.isatty()) as bar:

        def progress(message: str) -> None:
            bar.set_postfix_str(message)
            bar.update()

        result = diagnose_files(args.model, args.setup, args.calibration, args.validation, out,
                                robot=args.robot, candidates=candidates, progress=progress)
    print("\n".join(summary_lines(result)))
    for key, label in (("model", "model"), ("report", "report"), ("report_data", "report data")):
        print(f"{label + ':':<13}{result.files[key]}")
    return 0
