"""The library of candidate effects: how each is set up on the data at hand.

Each builder looks at the calibration set and the current model and returns a
`Candidate`: a fresh effect ready to be fitted, or the reason it cannot be tried
(e.g. no temperature or time column for thermal drift). Builders that choose
among variants (which joint pair couples) say how many they screened, so the
selection can charge for the choice.
"""

from __future__ import annotations

import copy
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rapidfix.diagnose.sensitivity import joint_derivatives
from rapidfix.diagnose.structured import screen
from rapidfix.error_model import (
    N_ERRORS,
    Backlash,
    Effect,
    ErrorModel,
    JointCompliance,
    JointCoupling,
    LinkGeometry,
    MeasuredPoints,
    OutsideRangeWarning,
    ThermalDrift,
    ToolOffset,
    TrackerScale,
    identifiable_modes,
    jacobian,
    last_motion_direction,
)
from rapidfix.kinematics import RobotModel

#: a context variable must vary by more than this to drive thermal drift (K, or s)
MIN_SPREAD = {"temp_c": 0.2, "time_s": 60.0}


@dataclass(frozen=True)
class Setting:
    """What builders may look at: the robot, the calibration points, the default payload."""

    robot: RobotModel
    calibration: MeasuredPoints
    default_payload_kg: float


@dataclass
class Candidate:
    """One candidate effect to try (or why not), with the number of variants screened."""

    kind: str
    physics: str
    effect: Effect | None
    variants: int = 1
    reason: str = ""
    detail: str = ""


def _compliance(model: ErrorModel, s: Setting) -> Candidate:
    physics = "joints 2 and 3 deflect under the gravity torque of the links and the payload"
    eff = JointCompliance(s.robot.name, s.calibration.ball_mm, s.default_payload_kg)
    return Candidate("joint_compliance", physics, eff)


def _geometry(model: ErrorModel, s: Setting) -> Candidate:
    physics = "the joint screws (link lengths, offsets, axis tilts) differ from nominal"
    probe = copy.deepcopy(model)
    full = LinkGeometry(s.robot.name, np.eye(N_ERRORS))
    full.steps = np.array(([1e-6, 1e-6, 1e-3, 1e-3] * 5) + [1e-3] * 3 + [1e-6] * 3)
    probe.effects.append(full)
    _, jac = jacobian(probe, s.robot, s.calibration, probe.free_params())
    modes, _ = identifiable_modes(jac[:, -N_ERRORS:], jac[:, :-N_ERRORS])
    if modes.shape[1] == 0:
        return Candidate("link_geometry", physics, None, reason="no identifiable screw error")
    return Candidate("link_geometry", physics, LinkGeometry(s.robot.name, modes),
                     detail=f"{modes.shape[1]} identifiable modes of {N_ERRORS} screw errors")


def _tool_offset(model: ErrorModel, s: Setting) -> Candidate:
    return Candidate("tool_offset", "the target ball / TCP is not where the setup declares it",
                     ToolOffset())


def _backlash(model: ErrorModel, s: Setting) -> Candidate:
    physics = "joint errors flip sign with the direction the joint last moved"
    direction = last_motion_direction(s.calibration.q, s.calibration.ctx.q_prev)
    both = (direction > 0).any(axis=0) & (direction < 0).any(axis=0)
    if not both.any():
        return Candidate("backlash", physics, None,
                         reason="no joint moved both ways in the calibration set")
    return Candidate("backlash", physics, Backlash())


def _thermal(model: ErrorModel, s: Setting) -> Candidate:
    physics = "link lengths grow with temperature (or time while warming up)"
    ctx = s.calibration.ctx
    for variable in ("temp_c", "time_s"):
        value = getattr(ctx, variable)
        if value is not None and np.ptp(value) > MIN_SPREAD[variable]:
            return Candidate("thermal_drift", physics,
                             ThermalDrift(variable, float(np.mean(value))),
                             detail=f"driven by {variable}")
    return Candidate("thermal_drift", physics, None,
                     reason="the calibration set has no temp_c or time_s column that varies")


def _registration(model: ErrorModel, s: Setting) -> Candidate:
    physics = "the tracker's length scale is off (its frame is always fitted)"
    return Candidate("registration", physics, TrackerScale())


def _coupling(model: ErrorModel, s: Setting) -> Candidate:
    physics = "one joint's error depends on another joint's angle"
    data = s.calibration
    r, jac = jacobian(model, s.robot, data, model.free_params())
    basis, _ = np.linalg.qr(jac) if jac.size else (np.zeros((r.size, 0)), None)
    r_perp = r - basis @ (basis.T @ r)
    grads = joint_derivatives(model, s.robot, data)
    best, best_gain = (0, 1), -1.0
    pairs = [(a, b) for a in range(6) for b in range(6) if a != b]
    for src, dst in pairs:  # 30 pairs, each a (3N, 2) least-squares screen
        theta = np.repeat(data.q[:, src], 3)
        cols = np.column_stack([grads[dst] * np.sin(theta), grads[dst] * np.cos(theta)])
        cols -= basis @ (basis.T @ cols)
        coef, *_ = np.linalg.lstsq(cols, r_perp, rcond=None)
        gain = float(np.sum((cols @ coef) ** 2))
        if gain > best_gain:
            best, best_gain = (src, dst), gain
    src, dst = best
    return Candidate("joint_coupling", physics, JointCoupling(src, dst), variants=len(pairs),
                     detail=f"joint {dst + 1} against joint {src + 1} (best of {len(pairs)} "
                            "pairs)")


def _structured(model: ErrorModel, s: Setting) -> Candidate:
    physics = "one joint's error follows one driver (see the detail)"
    screened = screen(model, s.robot, s.calibration, s.default_payload_kg)
    if not screened:
        return Candidate("joint_driver", physics, None, reason="no driver varies")
    best = screened[0]
    return Candidate("joint_driver", best.label, best.effect, variants=len(screened),
                     detail=f"{best.label} (best of {len(screened)} joint × driver variants)")


BUILDERS: dict[str, Callable[[ErrorModel, Setting], Candidate]] = {
    "joint_compliance": _compliance,
    "link_geometry": _geometry,
    "tool_offset": _tool_offset,
    "backlash": _backlash,
    "thermal_drift": _thermal,
    "joint_coupling": _coupling,
    "registration": _registration,
    "joint_driver": _structured,
}
#: structured effects: tried in every round, more than one may be accepted
REPEATABLE: tuple[str, ...] = ("joint_driver",)
CANDIDATES: tuple[str, ...] = tuple(BUILDERS)


def build(kind: str, model: ErrorModel, setting: Setting) -> Candidate:
    """Set up candidate `kind` on the current (fitted) model and the calibration data."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        return BUILDERS[kind](model, setting)
