"""The thin layer the commands use: measurement files → error model → report.

Each step is one function so `rapidfix fit`, `rapidfix demo` (and later commands)
read as a short sequence of calls. Nothing here does numerics of its own beyond
glue: measurement processing lives in rapidfix.measure, the model in
rapidfix.error_model, the figures in rapidfix.report.
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rapidfix.digest import sha256_file
from rapidfix.error_model import (
    Context,
    ErrorModel,
    JointRBF,
    OutsideRangeWarning,
    fit_error_model,
    solve_compensation,
    sweep_gaps,
)
from rapidfix.exceptions import MeasurementError, ModelError
from rapidfix.kinematics import RobotModel, is_shipped, load_robot
from rapidfix.measure import (
    PointTable,
    Setup,
    SweepTable,
    ball_offsets,
    read_points,
    read_setup,
    read_sweeps,
    robot_reach_mm,
)
from rapidfix.report import (
    BallbarRun,
    BeforeAfter,
    Report,
    Table,
    accuracy_report,
    ballbar_deviation,
)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib


@contextmanager
def model_warnings() -> Iterator[list[str]]:
    """Collect the model's warnings (angles outside the valid range) as messages.

    Commands print them as `rapidfix: warning: …` lines and finish with exit
    status 3 instead of letting Python print its own warning format.
    """
    messages: list[str] = []
    caught: list[warnings.WarningMessage] = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", OutsideRangeWarning)
            yield messages
    finally:
        # Outside the recording context: a warning passed on here must not be recorded
        # into the list being read (that loop never ended and ate all memory).
        for w in caught:
            if issubclass(w.category, OutsideRangeWarning):
                text = str(w.message)
                if text not in messages:
                    messages.append(text)
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


@dataclass
class FitOutcome:
    """A fitted model with what it was fitted from."""

    model: ErrorModel
    robot: RobotModel
    setup: Setup
    analysis: Any  # rapidfix.measure.sweeps.SweepAnalysis


def robot_for(setup: Setup, robot: str | None = None) -> RobotModel:
    """The robot model: `robot` (a name or robot file) if given, else the setup's."""
    return load_robot(robot or setup.robot)


def merge_sweeps(tables: Sequence[SweepTable]) -> SweepTable:
    """One table from several sweep files (rows keep their order, file after file).

    Row numbers stay those of each file; with several files an outlier row is
    reported by its row number in its own file (the first file's name is kept).
    """
    if len(tables) == 1:
        return tables[0]

    def join(name: str) -> np.ndarray | None:
        values = [getattr(t, name) for t in tables]
        if all(v is None for v in values):
            return None
        if any(v is None for v in values):
            raise MeasurementError(f"column {name!r} is in some sweep files but not in others",
                                   file=tables[0].path, column=name)
        return np.concatenate(values)

    names = ("sweep_joint", "q", "repeat", "xyz", "rows", "payload_kg", "time_s", "temp_c")
    return SweepTable(**{n: join(n) for n in names}, path=tables[0].path)


def fit_from_files(
    setup_path: str | Path,
    sweep_paths: Sequence[str | Path],
    *,
    robot: str | None = None,
    policy: str = "clamp",
) -> FitOutcome:
    """Read the setup and sweeps, analyse the sweeps, fit the per-joint model."""
    from rapidfix.measure import analyse_sweeps

    setup = read_setup(setup_path, check_robot=robot is None)  # `robot` overrides the setup's
    robot_model = robot_for(setup, robot)
    tables = [read_sweeps(p, reach_mm=robot_reach_mm(robot_model)) for p in sweep_paths]
    analysis = analyse_sweeps(setup, merge_sweeps(tables), robot_model)
    data_files = [{"name": Path(setup_path).name, "sha256": sha256_file(setup_path),
                   "role": "setup"}]
    data_files += [{"name": Path(p).name, "sha256": sha256_file(p), "role": "sweeps"}
                   for p in sweep_paths]
    extra = {"sweep_analysis": _jsonable(analysis.report())}
    model = fit_error_model(robot_model.name, list(analysis.joints), data_files=data_files,
                            extra_statistics=extra, policy=policy)
    if not is_shipped(robot_model):  # a user's robot file: the model carries the robot
        model.robot_definition = robot_model.definition
    return FitOutcome(model, robot_model, setup, analysis)


def _jsonable(value: Any) -> Any:
    """Plain JSON data from nested dicts/lists/arrays/numpy scalars."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def _number(value: float | None, width: int, decimals: int) -> str:
    """A right-aligned number, or 'n/a' (e.g. the repeatability of single measurements)."""
    return f"{'n/a':>{width}}" if value is None else f"{value:>{width}.{decimals}f}"


def fit_summary(model: ErrorModel) -> str:
    """The per-joint table `rapidfix fit` prints (degrees)."""
    lines = [f"{'joint':<6}{'range (°)':>20}{'points':>8}{'max |Δθ| (°)':>14}"
             f"{'CV RMS (°)':>12}{'repeat. (°)':>13}"]
    for s in model.statistics.get("joints", []):
        if not s.get("points"):
            lines.append(f"J{s['joint']:<5}{'not measured':>20}")
            continue
        lo, hi = s["range_deg"]
        lines.append(f"J{s['joint']:<5}{f'{lo:.1f} … {hi:.1f}':>20}{s['points']:>8}"
                     f"{_number(s.get('max_abs_error_deg'), 14, 4)}"
                     f"{_number(s.get('cv_rms_deg'), 12, 5)}"
                     f"{_number(s.get('repeatability_deg'), 13, 5)}")
    for s in model.statistics.get("joints", []):
        for lo, hi in s.get("gaps_deg", []):
            lines.append(f"warning: joint {s['joint']} has no measurements between {lo:.1f}° "
                         f"and {hi:.1f}°; the model only interpolates there")
    return "\n".join(lines)


def joint_curves(model: ErrorModel, joints: Sequence[Any]) -> list[dict[str, np.ndarray] | None]:
    """Figure-7 data in degrees: measured points per joint and the fitted curve."""
    rbf = next((e for e in model.effects if isinstance(e, JointRBF)), None)
    if rbf is None:
        raise ModelError("the model has no per-joint RBF effect to plot")
    out: list[dict[str, np.ndarray] | None] = []
    for j, (net, sweep) in enumerate(zip(rbf.networks, joints)):
        if net is None or sweep is None:
            out.append(None)
            continue
        x = np.linspace(net.lo, net.hi, 400)
        q = np.zeros((x.shape[0], 6))
        q[:, j] = x
        out.append({
            "theta": np.degrees(sweep.theta_cmd),
            "delta": np.degrees(sweep.delta),
            "repeat_std": np.degrees(sweep.repeat_std),
            "curve_theta": np.degrees(x),
            "curve_delta": np.degrees(rbf.joint_delta(q, Context())[:, j]),
            "gaps": np.degrees(np.asarray(sweep_gaps(sweep.theta_cmd)).reshape(-1, 2)),
        })
    return out


def ideal_ball(robot: RobotModel, q: np.ndarray, smr_offset_mm: np.ndarray) -> np.ndarray:
    """Where the nominal robot puts the target ball (N, 3) mm for joints q (N, 6) rad;
    one ball (3,) or each row's own (N, 3)."""
    T = robot.fk(np.atleast_2d(q))
    ball = np.broadcast_to(np.asarray(smr_offset_mm, dtype=float), (T.shape[0], 3))
    return np.einsum("nij,nj->ni", T[:, :3, :3], ball) + T[:, :3, 3]


def to_robot_frame(registration: Any, p_tracker: np.ndarray) -> np.ndarray:
    """Tracker-frame points (N, 3) mapped into the robot base frame by a registration."""
    if hasattr(registration, "to_robot"):
        return np.asarray(registration.to_robot(p_tracker), dtype=float)
    scale = float(getattr(registration, "scale", 1.0))
    return (np.asarray(p_tracker, dtype=float) - registration.t) @ registration.R / scale


def points_context(table: PointTable, setup: Setup, q: np.ndarray) -> Context:
    """The context of a points table executed in row order with commanded joints q."""
    payload = table.payload_kg if table.payload_kg is not None else setup.payload_kg
    return Context.from_rows(q, payload_kg=payload, time_s=table.time_s, temp_c=table.temp_c)


def compensate_table(outcome: FitOutcome, table: PointTable) -> np.ndarray:
    """Compensated commands (N, 6) rad for a table's joints; ModelError lists failed rows."""
    q_ideal = table.q
    result = solve_compensation(outcome.model, outcome.robot, q_ideal,
                                points_context(table, outcome.setup, q_ideal))
    failed = result.failed_rows
    if failed.size:
        rows = table.rows[failed][:10].tolist()
        raise ModelError(f"compensation did not converge for file rows {rows}",
                         file=table.path)
    return result.q_cmd


def accuracy_report_for(
    outcome: FitOutcome,
    *,
    validation: BeforeAfter | None = None,
    ballbar: BallbarRun | None = None,
    title: str = "rapidfix accuracy report",
    notes: Sequence[str] = (),
    summary: dict[str, Any] | None = None,
) -> Report:
    """The before/after report of a fitted model (Figure 7 from its sweeps)."""
    report = accuracy_report(
        title,
        joint_stats=outcome.model.statistics.get("joints"),
        joint_curves=joint_curves(outcome.model, list(outcome.analysis.joints)),
        validation=validation,
        ballbar=ballbar,
        notes=notes,
        summary=summary,
    )
    files = outcome.model.data_files
    if files:
        report.tables.append(Table(
            "Measurements the model was fitted on",
            ["file", "role", "SHA-256"],
            [[f.get("name"), f.get("role"), f.get("sha256")] for f in files],
        ))
    return report


def ballbar_run(
    angle_deg: np.ndarray,
    centre_mm: np.ndarray,
    radius_mm: float,
    before_mm: np.ndarray,
    after_mm: np.ndarray,
) -> BallbarRun:
    """Ballbar deviations from measured ball positions before/after (N, 3) mm, base frame."""
    return BallbarRun(np.asarray(angle_deg, dtype=float),
                      ballbar_deviation(before_mm, centre_mm, radius_mm),
                      ballbar_deviation(after_mm, centre_mm, radius_mm))


def predicted_before_after(outcome: FitOutcome, points_csv: str | Path) -> BeforeAfter:
    """Measured points (e.g. validation.csv) against the nominal and the fitted model.

    before: the measured ball (registered into the robot frame) against where the
    nominal robot puts it; after: the residual the model leaves (measured minus
    model prediction), i.e. the error compensation is predicted to leave. Nothing
    is executed; rows run in file order under the file's conditions.
    """
    table = read_points(points_csv, reach_mm=robot_reach_mm(outcome.robot))
    setup, robot = outcome.setup, outcome.robot
    measured = to_robot_frame(outcome.analysis.registration, table.xyz)
    balls = ball_offsets(table, setup)
    nominal = ideal_ball(robot, table.q, balls)
    predicted = outcome.model.predict_ball(robot, table.q, balls,
                                           points_context(table, setup, table.q))
    return BeforeAfter(nominal, measured, nominal + (measured - predicted))


# ---- executing targets on a robot that can be measured (a virtual cell) -----------------


def execute_before_after(
    outcome: FitOutcome,
    cell_robot: RobotModel,
    table: PointTable,
    *,
    seed: int,
) -> BeforeAfter:
    """Run a table's joints as they are and compensated; measure with the tracker.

    `cell_robot.measure(q, ctx, frame="tracker", seed=...)` executes commanded joints
    and returns tracker-frame ball positions (rapidfix.sim.VirtualRobot does). Both
    runs are mapped into the robot frame with the registration found from the sweeps.
    """
    setup = outcome.setup
    q_ideal = table.q
    q_cmd = compensate_table(outcome, table)
    registration = outcome.analysis.registration
    balls = ball_offsets(table, setup)
    nest = {} if table.ball is None else {"ball": table.ball}
    runs = []
    for k, q in enumerate((q_ideal, q_cmd)):
        ctx = points_context(table, setup, q)
        measured = cell_robot.measure(q, ctx, frame="tracker", seed=seed * 1000 + k, **nest)
        runs.append(to_robot_frame(registration, measured))
    return BeforeAfter(ideal_ball(outcome.robot, q_ideal, balls), *runs)


def run_points_before_after(
    outcome: FitOutcome, cell_robot: RobotModel, points_csv: str | Path, *, seed: int
) -> BeforeAfter:
    """execute_before_after on a points CSV (validation points)."""
    return execute_before_after(outcome, cell_robot, read_points(points_csv), seed=seed)


@dataclass(frozen=True)
class BallbarSetup:
    """A ballbar run's description: its points table, pivot centre and radius (base frame)."""

    points: PointTable
    centre_mm: np.ndarray
    radius_mm: float
    angles_deg: np.ndarray


def read_ballbar(path: str | Path) -> BallbarSetup:
    """Read ballbar.toml (centre_mm, radius_mm, angles_deg, points = CSV beside it)."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise MeasurementError(f"not a valid ballbar TOML file: {err}", file=path) from None
    try:
        points = read_points(path.parent / str(data["points"]))
        centre = np.asarray(data["centre_mm"], dtype=float).reshape(3)
        radius = float(data["radius_mm"])
        angles = np.asarray(data.get("angles_deg", np.arange(points.q.shape[0])), dtype=float)
    except KeyError as err:
        raise MeasurementError(f"missing key {err}", file=path) from None
    except (TypeError, ValueError) as err:
        raise MeasurementError(f"malformed value ({err})", file=path) from None
    if angles.shape[0] != points.q.shape[0]:
        raise MeasurementError(f"{angles.shape[0]} angles for {points.q.shape[0]} points",
                               file=path, column="angles_deg")
    return BallbarSetup(points, centre, radius, angles)


def run_ballbar_before_after(
    outcome: FitOutcome, cell_robot: RobotModel, ballbar_toml: str | Path, *, seed: int
) -> BallbarRun:
    """The ballbar semicircle run before and after compensation (length deviations)."""
    bb = read_ballbar(ballbar_toml)
    run = execute_before_after(outcome, cell_robot, bb.points, seed=seed + 500)
    return ballbar_run(bb.angles_deg, bb.centre_mm, bb.radius_mm, run.before, run.after)


def before_after_table(summary: dict[str, Any], after_label: str = "after") -> str:
    """A short text table of the report's headline numbers (mm)."""
    lines = [f"{'':<28}{'before':>10}{after_label:>10}"]
    val = summary.get("validation")
    if val:
        for key, label in (("mean_mm", "mean"), ("rms_mm", "RMS"), ("max_mm", "max")):
            lines.append(f"{'validation TCP error ' + label:<28}"
                         f"{val['before'][key]:>10.4f}{val['after'][key]:>10.4f}")
    bb = summary.get("ballbar")
    if bb:
        for key, label in (("max_mm", "max"), ("mean_mm", "mean")):
            paper = bb["paper"]
            lines.append(f"{'ballbar |deviation| ' + label:<28}{bb['before'][key]:>10.4f}"
                         f"{bb['after'][key]:>10.4f}   (paper {paper['before'][key]:.4f}"
                         f" → {paper['after'][key]:.4f})")
    return "\n".join(lines)
