"""The feature that exposes each effect, and residual components along a correction.

For the report: each accepted effect is shown as the residual it explains
against the quantity that drives it — payload for compliance, the motion
direction for backlash, temperature or time for thermal drift, the source
joint's angle for coupling, the joint-6 angle for a tool offset (the error
turns with the flange), the distance from the points' centre for a scale error,
the joint-2 angle for link geometry; a structured effect's driver; for a correction
of unknown cause, the correction itself (its value on the joint it acts on).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rapidfix.error_model import Effect, MeasuredPoints, last_motion_direction


@dataclass(frozen=True)
class Feature:
    """Values (N,) of the exposing quantity, its label and whether it is discrete (±1)."""

    values: np.ndarray
    label: str
    discrete: bool = False


def exposing_feature(effect: Effect, data: MeasuredPoints) -> Feature:
    """The quantity that drives `effect` on these points (see the module docstring)."""
    kind = effect.type_name
    q = data.q
    ctx = data.ctx
    if kind == "joint_compliance":
        payload = ctx.payload_kg
        if payload is not None and np.ptp(payload) > 0:
            return Feature(np.asarray(payload, dtype=float), "payload (kg)")
        return Feature(np.degrees(q[:, 1] + q[:, 2]), "θ2 + θ3, upper-arm angle (°)")
    if kind == "backlash":
        play = np.abs(effect.params())
        j = int(np.argmax(play))
        direction = last_motion_direction(q, ctx.q_prev)[:, j]
        return Feature(direction, f"direction joint {j + 1} last moved (−1 / +1)", True)
    if kind == "thermal_drift":
        variable = getattr(effect, "variable", "temp_c")
        values = getattr(ctx, variable)
        label = "temperature (°C)" if variable == "temp_c" else "time (s)"
        return Feature(np.asarray(values, dtype=float), label)
    if kind == "joint_coupling":
        src = int(getattr(effect, "source", 0))
        return Feature(np.degrees(q[:, src]), f"joint {src + 1} angle (°)")
    if kind in ("joint_driver", "frame_driver"):
        return _driver_feature(effect, data)
    if kind == "tool_offset":
        return Feature(np.degrees(q[:, 5]), "joint 6 angle (°)")
    if kind == "rbf_correction":
        joint = int(getattr(effect, "joint", 0))
        value = effect.joint_delta(q, ctx)[:, joint]
        return Feature(np.degrees(value), f"the correction of joint {joint + 1} (°)")
    if kind == "registration":
        centre = data.xyz.mean(axis=0)
        return Feature(np.linalg.norm(data.xyz - centre, axis=1),
                       "distance from the points' centre (mm)")
    return Feature(np.degrees(q[:, 1]), "joint 2 angle (°)")


def _driver_feature(effect: Effect, data: MeasuredPoints) -> Feature:
    """A structured effect's driver: temperature, time, payload, the source joint's
    direction or angle, or the joint's own angle (for gravity: the payload)."""
    driver = getattr(effect, "driver", "")
    ctx = data.ctx
    source = getattr(effect, "source", None)
    joint = int(getattr(effect, "joint", None) or 0)
    if driver == "direction" and source is not None:
        direction = last_motion_direction(data.q, ctx.q_prev)[:, source]
        return Feature(direction, f"direction joint {source + 1} last moved (−1 / +1)", True)
    if driver == "angle" and source is not None:
        return Feature(np.degrees(data.q[:, source]), f"joint {source + 1} angle (°)")
    for name, field, label in (("temperature", "temp_c", "temperature (°C)"),
                               ("time", "time_s", "time (s)"),
                               ("gravity", "payload_kg", "payload (kg)"),
                               ("payload", "payload_kg", "payload (kg)"),
                               ("overturning", "payload_kg", "payload (kg)")):
        value = getattr(ctx, field)
        if driver == name and value is not None:
            return Feature(np.asarray(value, dtype=float), label)
    return Feature(np.degrees(data.q[:, joint]), f"joint {joint + 1} angle (°)")


def along(vectors: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Component (N,) of `vectors` along the unit vectors of `directions` (0 where none)."""
    norm = np.linalg.norm(directions, axis=1)
    unit = np.where(norm[:, None] > 0, directions / np.where(norm > 0, norm, 1.0)[:, None], 0.0)
    return np.einsum("ni,ni->n", vectors, unit)
