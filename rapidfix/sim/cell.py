"""A simulated calibration session: run the plans on a virtual robot, write the set.

One session executes, in this order and as one continuous run (row order = time
order, each row `seconds_per_row` after the last): the sweeps, the calibration
points, the validation points and the ballbar semicircle. `simulate_set` keeps
everything in memory; `simulate_cell` writes it in the shared file format:

    setup.toml  sweeps.csv  calibration.csv  validation.csv
    ballbar.toml  ballbar.csv  truth.json

truth.json holds what no fitter is told: the true errors, the tracker pose (also in
the joint-1 gauge the measurement processing uses), the outlier rows and the
noise floor — the mean TCP distance error that noise and repeatability alone
leave on the validation points.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rapidfix.atomic import write_text_atomic
from rapidfix.exceptions import OutputExistsError, RapidfixError
from rapidfix.kinematics import RobotModel
from rapidfix.measure import (
    PointTable,
    Setup,
    SweepTable,
    round_joints_deg,
    write_points,
    write_setup,
    write_sweeps,
)
from rapidfix.paths import check_output_dir
from rapidfix.sim.plans import BallbarPlan, ballbar_plan, point_plan, sweep_plan
from rapidfix.sim.virtual_robot import (
    DEFAULT_ROBOT,
    DEFAULT_SMR_OFFSET_MM,
    SECOND_SMR_OFFSET_MM,
    RunConditions,
    VirtualRobot,
)

FILES = ("setup.toml", "sweeps.csv", "calibration.csv", "validation.csv", "ballbar.toml",
         "ballbar.csv", "truth.json")
MAX_PAYLOAD_KG = 10.0


@dataclass
class SimulatedSet:
    """A measurement set in memory, with the robot that made it and its truth."""

    setup: Setup
    sweeps: SweepTable
    calibration: PointTable
    validation: PointTable
    ballbar: BallbarPlan
    ballbar_points: PointTable
    robot: VirtualRobot
    truth: dict[str, Any] = field(default_factory=dict)


def joint1_gauge(R: np.ndarray, t: np.ndarray, offset_rad: float, robot: RobotModel,
                 scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Tracker pose after moving a joint-1 error `offset_rad` into the registration.

    A constant joint-1 error c cannot be told from a tracker turned about axis 1:
    R f(θ + c e1) + t = R' f(θ) + t' with R' = R·Rot(w1, c), t' = t + s R (a1 − Rot(w1, c) a1).
    """
    w, a = robot.axis_dirs[0], robot.axis_points[0]
    rot = Rotation.from_rotvec(w * offset_rad).as_matrix()
    return R @ rot, t + scale * R @ (a - rot @ a)


def _conditions(payload: np.ndarray | None, time: np.ndarray | None,
                temp: np.ndarray | None, q: np.ndarray, q_before: np.ndarray | None
                ) -> RunConditions:
    q_prev = np.vstack([q[:1] if q_before is None else q_before[None], q[:-1]])
    return RunConditions(payload_kg=payload, time_s=time, temp_c=temp, q_prev=q_prev)


def simulate_set(seed: int = 0, effects: tuple[str, ...] | list[str] = (),
                 robot: str | RobotModel = DEFAULT_ROBOT, *, n_calibration: int = 60,
                 n_validation: int = 40, repeats: int = 3, step_deg: float = 5.0,
                 n_outliers: int = 0, payload_kg: float = 0.0,
                 smr_offset_mm: tuple[float, float, float] = DEFAULT_SMR_OFFSET_MM,
                 sweep_joints: tuple[int, ...] = (0, 1, 2, 3, 4, 5),
                 seconds_per_row: float = 3.0, balls: int = 2,
                 smr_offsets_mm: Any = None) -> SimulatedSet:
    """Simulate one session on a new virtual robot drawn from `seed` (see module doc).

    `effects` names optional true effects (rapidfix.sim.true_errors.EFFECTS);
    `n_outliers` sweep rows get a gross tracker error (0.3–2 mm), listed in the truth.
    The calibration and validation points are measured on `balls` nests taken in turn,
    row by row (`ball` column): `smr_offset_mm` then SECOND_SMR_OFFSET_MM, or the
    nests `smr_offsets_mm` (K, 3) given; the sweeps and the ballbar use nest 0.
    `balls=1` measures every point on one ball, as before.
    """
    nests = _nests(smr_offset_mm, smr_offsets_mm, balls)
    vr = VirtualRobot.create(robot, seed=seed, effects=effects, smr_offset_mm=nests[0],
                             payload_kg=payload_kg, smr_offsets_mm=nests)
    model = vr.robot
    # One independent stream per purpose, so switching an effect on or off changes
    # nothing else in the session (same poses, same noise).
    cal_ss, val_ss, payload_ss, noise_ss, outlier_ss, sensor_ss, bar_ss = (
        np.random.SeedSequence([seed, 1]).spawn(7))
    smr = vr.smr_offset_mm
    sweeps = sweep_plan(model, smr, step_deg=step_deg, repeats=repeats, joints=sweep_joints)
    swept = np.array([[sweeps.q[:, j].min(), sweeps.q[:, j].max()]
                      if np.any(sweeps.sweep_joint == j) else model.limits[j]
                      for j in range(6)])
    q_cal = point_plan(model, smr, n_calibration, seed=int(cal_ss.generate_state(1)[0]),
                       ranges=swept)
    q_val = point_plan(model, smr, n_validation, seed=int(val_ss.generate_state(1)[0]),
                       ranges=swept)
    bb = ballbar_plan(model, smr)
    blocks = [round_joints_deg(q) for q in (sweeps.q, q_cal, q_val, bb.q)]
    sizes = [len(b) for b in blocks]
    q_all = np.vstack(blocks)
    n_all = len(q_all)

    compliance = bool({"joint_compliance", "wrist_compliance", "tool_bending", "base_tilt"}
                      & set(vr.errors.effects))
    thermal = vr.errors.needs_temperature
    payload = np.full(n_all, payload_kg)
    if compliance:  # calibration and validation points carry random payloads
        start, stop = sizes[0], sizes[0] + sizes[1] + sizes[2]
        drawn = np.random.default_rng(payload_ss).uniform(0.0, MAX_PAYLOAD_KG, stop - start)
        payload[start:stop] = np.round(drawn * 2) / 2
    time = np.arange(n_all) * seconds_per_row
    temp = vr.errors.temperature(time) if thermal else None
    ctx = _conditions(payload, time, temp, q_all, None)
    # calibration and validation points turn through the nests, row by row
    nest = np.concatenate([np.zeros(sizes[0], dtype=int), np.arange(sizes[1]) % len(nests),
                           np.arange(sizes[2]) % len(nests), np.zeros(sizes[3], dtype=int)])
    xyz = vr.measure(q_all, ctx, frame="tracker", seed=int(noise_ss.generate_state(1)[0]),
                     ball=nest)

    outlier_rows: list[int] = []
    if n_outliers > sizes[0]:
        raise RapidfixError(f"{n_outliers} outliers asked for, but the sweeps have only "
                            f"{sizes[0]} rows", hint=f"give at most {sizes[0]}")
    if n_outliers:
        rng = np.random.default_rng(outlier_ss)
        idx = np.sort(rng.choice(sizes[0], n_outliers, replace=False))
        kick = rng.normal(size=(n_outliers, 3))
        kick *= (rng.uniform(0.3, 2.0, n_outliers) / np.linalg.norm(kick, axis=1))[:, None]
        xyz[idx] += kick
        outlier_rows = (idx + 2).tolist()  # file rows: header is row 1

    recorded_temp = None if temp is None else (
        temp + np.random.default_rng(sensor_ss).normal(0.0, 0.02, n_all))
    bounds = np.cumsum([0, *sizes])
    parts = [slice(bounds[i], bounds[i + 1]) for i in range(4)]

    def cond(part: slice) -> dict[str, np.ndarray | None]:
        return {"payload_kg": payload[part] if compliance else None,
                "time_s": time[part] if thermal else None,
                "temp_c": recorded_temp[part] if thermal else None}

    setup = Setup(robot=model.name, smr_offset_mm=smr.copy(),
                  tracker_sigma_mm=vr.tracker.sigma0_mm + 3.0 * vr.tracker.sigma_per_m_mm,
                  payload_kg=payload_kg,
                  smr_offsets_mm=nests.copy() if len(nests) > 1 else None)
    s = parts[0]
    sweep_table = SweepTable(sweep_joint=sweeps.sweep_joint, q=q_all[s], repeat=sweeps.repeat,
                             xyz=xyz[s], rows=np.arange(sizes[0]) + 2, **cond(s))

    def points(part: slice, prefix: str, extra: dict | None = None,
               with_nest: bool = False) -> PointTable:
        n = part.stop - part.start
        ids = np.array([f"{prefix}{i + 1:03d}" for i in range(n)])
        return PointTable(point_id=ids, q=q_all[part], xyz=xyz[part], rows=np.arange(n) + 2,
                          extra=extra or {}, ball=nest[part] if with_nest else None,
                          **cond(part))

    bb_ctx = RunConditions(**{k: (None if v is None else v[parts[3]])
                              for k, v in vars(ctx).items()})
    lengths = vr.ballbar_lengths(q_all[parts[3]], bb.centre_mm, bb_ctx,
                                 seed=int(bar_ss.generate_state(1)[0]))
    val_ctx = RunConditions(**{k: (None if v is None else v[parts[2]])
                               for k, v in vars(ctx).items()})
    truth = vr.truth()
    c = float(vr.errors.joint(np.zeros((1, 6)))[0, 0])
    R_g, t_g = joint1_gauge(vr.tracker.R, vr.tracker.t, c, model, vr.tracker.scale)
    truth.update({
        "gauge": {"rule": "the joint-1 error is zero at theta1 = 0; the rest is in the "
                          "tracker pose", "joint1_error_at_zero_deg": float(np.degrees(c)),
                  "R": R_g.tolist(), "t_mm": t_g.tolist()},
        "outlier_rows": {"sweeps.csv": outlier_rows},
        "noise_floor": vr.noise_floor(q_all[parts[2]], val_ctx, seed=seed,
                                      ball=nest[parts[2]] if len(nests) > 1 else None),
        "session": {"seconds_per_row": seconds_per_row, "order": [*FILES[1:4], "ballbar.csv"],
                    "rows": sizes},
    })
    multi = len(nests) > 1
    return SimulatedSet(setup=setup, sweeps=sweep_table,
                        calibration=points(parts[1], "C", with_nest=multi),
                        validation=points(parts[2], "V", with_nest=multi),
                        ballbar=bb, ballbar_points=points(parts[3], "B", {"length_mm": lengths}),
                        robot=vr, truth=truth)


def _nests(first: Any, given: Any, balls: int) -> np.ndarray:
    """The nests (K, 3) mm a session measures on (see `simulate_set`)."""
    if given is not None:
        nests = np.asarray(given, dtype=float).reshape(-1, 3)
    else:
        nests = np.vstack([np.asarray(first, dtype=float), SECOND_SMR_OFFSET_MM])
    if not 1 <= balls <= len(nests):
        raise RapidfixError(f"{balls} balls asked for, {len(nests)} nests declared",
                            hint="measure on 1 or 2 balls")
    nests = nests[:balls]
    gap = np.linalg.norm(nests[:, None] - nests[None], axis=-1) + 1e9 * np.eye(len(nests))
    if gap.min() < 5.0:
        raise RapidfixError("two nests of the simulated flange coincide",
                            hint="give nests at least 5 mm apart")
    return nests


def write_set(out_dir: str | Path, data: SimulatedSet, *, overwrite: bool = False) -> Path:
    """Write a simulated set in the shared format (see module doc); returns the folder."""
    out = check_output_dir(out_dir, "measurement set folder")
    if not overwrite:
        existing = [name for name in FILES if (out / name).exists()]
        if existing:
            raise OutputExistsError(f"the folder already holds {', '.join(existing)}",
                                    file=out, hint="choose another folder or pass --force")
    write_setup(out / "setup.toml", data.setup)
    write_sweeps(out / "sweeps.csv", data.sweeps)
    write_points(out / "calibration.csv", data.calibration)
    write_points(out / "validation.csv", data.validation)
    write_points(out / "ballbar.csv", data.ballbar_points)
    bb = data.ballbar
    write_text_atomic(out / "ballbar.toml", "\n".join([
        "# Ballbar run: centre and plane in the robot base frame, mm",
        'points = "ballbar.csv"',
        "centre_mm = [" + ", ".join(f"{v:.6f}" for v in bb.centre_mm) + "]",
        f"radius_mm = {bb.radius_mm:.6f}",
        "normal = [" + ", ".join(f"{v:.9f}" for v in bb.normal) + "]",
        "angles_deg = [" + ", ".join(f"{v:.3f}" for v in np.degrees(bb.angles)) + "]",
    ]) + "\n")
    write_text_atomic(out / "truth.json", json.dumps(data.truth, indent=2) + "\n")
    return out


def simulate_cell(out_dir: str | Path, seed: int = 0,
                  effects: tuple[str, ...] | list[str] = (),
                  robot: str | RobotModel = DEFAULT_ROBOT, *, overwrite: bool = False,
                  **options: Any) -> Path:
    """Simulate a session (`simulate_set` options) and write it to `out_dir`; returns it."""
    return write_set(out_dir, simulate_set(seed, effects, robot, **options), overwrite=overwrite)
