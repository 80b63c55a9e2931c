"""The structured search: which joint's error, driven by what, the residual follows.

Every variant is a `JointDriver`: a joint and a driver (the gravity torque about
that joint, the temperature or time, the payload, the direction or the angle of
another joint, its own angle's second harmonic). Variants whose driver the
calibration set does not vary are not screened. Each is screened without
refitting: its regressors times the sensitivity of the points to the error of the
joint they act on, projected off everything the current model already fits, are
regressed on the residual (linearised least squares). The score is the linear
model's BIC gain, n ln(RSS / RSS') − k ln n. The best variant is then fitted and
judged like any candidate, charged for the choice among all variants screened;
the whole ranking goes into the report as what the residual correlates with,
whether or not anything is accepted.

Effects that act on a frame rather than a joint (`FrameDriver`: the tool bending
under gravity, the base tilting with the overturning moment, a link growing with
the temperature) are variants too. Their columns are how the predicted points
move per unit of each parameter (forward differences of the model with the
effect added), projected and scored the same way.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from rapidfix.diagnose.sensitivity import residual_off_model
from rapidfix.error_model import (
    Effect,
    ErrorModel,
    FrameDriver,
    JointDriver,
    MeasuredPoints,
    OutsideRangeWarning,
    last_motion_direction,
    nominal_robot,
    predict,
)
from rapidfix.kinematics import RobotModel

#: a context variable must vary by more than this to drive an effect
MIN_SPREAD = {"temp_c": 0.2, "time_s": 60.0, "payload_kg": 0.1}
#: singular values of the unit-scaled, projected regressors below this fraction of the
#: largest are degenerate (the column duplicates what the model already fits)
RCOND = 1e-6
#: links that may grow (1-based: the link after that joint; 6 runs from axis 6 to tool0);
#: those of no length in the nominal model (coincident axis points) are left out
LINKS = (1, 2, 3, 4, 5, 6)


@dataclass(frozen=True)
class Screened:
    """One variant's screen: the effect to fit, its linear BIC gain and share of the residual."""

    effect: JointDriver | FrameDriver
    score: float
    share: float
    rank: int

    @property
    def label(self) -> str:
        """Where it acts and what drives it."""
        return self.effect.what()


def frame_variants(robot_name: str, data: MeasuredPoints, default_payload_kg: float
                   ) -> list[FrameDriver]:
    """The tool and the base moved by gravity (always: the pose turns it), each link
    grown by the temperature (when the set's temperature varies)."""
    out = [FrameDriver(frame, robot=robot_name, payload_point_mm=data.ball_mm,
                       default_payload_kg=default_payload_kg) for frame in ("tool", "base")]
    temp = data.ctx.temp_c
    if temp is not None and np.ptp(temp) > MIN_SPREAD["temp_c"]:
        ref = float(np.mean(temp))
        out += [FrameDriver("link", robot=robot_name, link=link, reference=ref)
                for link in LINKS if _link_length(robot_name, link) > 1.0]
    return out



def _link_length(robot_name: str, link: int) -> float:
    robot = nominal_robot(robot_name)
    points = np.asarray(robot.axis_points, dtype=float)
    end = np.asarray(robot.home)[:3, 3] if link == 6 else points[link]
    return float(np.linalg.norm(end - points[link - 1]))


def variants(robot_name: str, data: MeasuredPoints, default_payload_kg: float
             ) -> list[JointDriver | FrameDriver]:
    """Every joint × driver and frame × driver the calibration set can tell anything about."""
    ctx = data.ctx
    out: list[JointDriver | FrameDriver] = []
    payload = ctx.payload_kg
    for j in range(1, 6):  # joint 1's axis is vertical: gravity never loads it
        out.append(JointDriver(j, "gravity", robot=robot_name, payload_point_mm=data.ball_mm,
                               default_payload_kg=default_payload_kg))
    for driver, field in (("temperature", "temp_c"), ("time", "time_s")):
        value = getattr(ctx, field)
        if value is not None and np.ptp(value) > MIN_SPREAD[field]:
            out += [JointDriver(j, driver, reference=float(np.mean(value))) for j in range(6)]
            break  # time stands in for the temperature only when there is none
    if payload is not None and np.ptp(payload) > MIN_SPREAD["payload_kg"]:
        out += [JointDriver(j, "payload", reference=float(np.mean(payload))) for j in range(6)]
    direction = last_motion_direction(data.q, ctx.q_prev)
    both = (direction > 0).any(axis=0) & (direction < 0).any(axis=0)
    for s in range(6):
        if both[s]:
            out += [JointDriver(j, "direction", source=s) for j in range(6) if j != s]
    for s in range(6):
        out += [JointDriver(j, "angle", source=s) for j in range(6) if j != s]
    out += [JointDriver(j, "own_angle") for j in range(6)]
    return out + frame_variants(robot_name, data, default_payload_kg)


def point_columns(model: ErrorModel, robot: RobotModel, data: MeasuredPoints, effect: Effect,
                  base: np.ndarray) -> np.ndarray:
    """How the predicted points (3N,) move per unit of each parameter of `effect` added
    to the model at zero, (3N, P), by forward differences of its steps."""
    trial = ErrorModel(model.robot, [*model.effects, effect])
    steps = np.asarray(getattr(effect, "steps", np.full(len(effect.param_names), 1e-6)))
    cols = np.empty((base.size, steps.size))
    zero = np.zeros(steps.size)
    for i, h in enumerate(steps):  # a few parameters, each one vectorised evaluation
        p = zero.copy()
        p[i] = h
        effect.set_fitted(p)
        cols[:, i] = (predict(trial, robot, data).ravel() - base) / h
    effect.set_fitted(zero)
    return cols


def screen(model: ErrorModel, robot: RobotModel, data: MeasuredPoints, default_payload_kg: float
           ) -> list[Screened]:
    """Every variant screened on the current (fitted) model's residual, best first."""
    res = residual_off_model(model, robot, data)
    r, r_perp, grads = res.r, res.r_perp, res.grads
    rss = float(r_perp @ r_perp) + 1e-300
    n = r.size
    out = []
    base = r + data.xyz.ravel()  # the current model's predictions
    for eff in variants(model.robot, data, default_payload_kg):  # ~90 small regressions
        if isinstance(eff, FrameDriver):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", OutsideRangeWarning)
                cols = point_columns(model, robot, data, eff, base)
        else:
            F = np.repeat(eff.regressors(data.q, data.ctx), 3, axis=0)
            cols = grads[eff.acts_on].T * F
        before = np.linalg.norm(cols, axis=0)
        cols = res.off_model(cols)
        norms = np.linalg.norm(cols, axis=0)
        fresh = norms > 1e-2 * before  # what the model fits already is not new
        cols = cols[:, fresh] / norms[fresh]
        u, s, _ = np.linalg.svd(cols, full_matrices=False)
        keep = s > RCOND * (s[0] if s.size else np.inf)
        if not keep.any():
            continue
        proj = u[:, keep].T @ r_perp
        gain = min(float(proj @ proj), rss * (1 - 1e-12))
        k = int(keep.sum())
        out.append(Screened(eff, float(n * np.log(rss / (rss - gain)) - k * np.log(n)),
                            gain / rss, k))
    out.sort(key=lambda v: -v.score)
    return out


def ranking_records(screened: list[Screened], top: int = 12) -> list[dict[str, Any]]:
    """JSON rows of the best-ranked variants: where, driven by what, how strongly."""
    return [{"joint": _one_based(getattr(v.effect, "joint", None)),
             "frame": getattr(v.effect, "frame", "joint"), "driver": v.effect.driver,
             "source_joint": _one_based(getattr(v.effect, "source", None)),
             "description": v.label, "linear_bic_gain": v.score,
             "share_of_calibration_residual": v.share, "parameters": v.rank}
            for v in screened[:top]]


def _one_based(index: int | None) -> int | None:
    return None if index is None else index + 1
