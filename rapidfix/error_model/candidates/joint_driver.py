"""A structured effect: one joint's error as a low-order function of one driver.

Δθ_j = F(q, ctx) · p, with F the regressors physics suggests for the driver:

- ``gravity``: the joint is a torsion spring loaded by gravity — the payload's
  torque about joint j (payload_kg at payload_cog_mm, taken from the nominal
  kinematics of the commanded pose) times a compliance, plus the torque of the
  bodies it carries whose masses are unknown: one fixed to link j (its mass moment,
  three regressors) and one fixed to the flange (a tool: mass moment and mass, four)
  (`gravity`);
- ``temperature`` / ``time``: a zero and a scale that drift with the arm's
  temperature (or, without one, the time since the start, as a warm-up):
  (x − x_ref) and (x − x_ref) · θ_j, and the scale at x_ref, θ_j (the sweeps ran at
  another temperature; the re-referenced first harmonic holds only part of a scale);
- ``payload``: proportional to the payload mass, m − m_ref;
- ``direction``: an offset per direction another joint (source) last moved, d_s = ±1;
- ``angle``: first and second harmonics of another joint's (source) angle; the
  source's own sweep moved the joint through the same harmonics and took them for
  its own error, so the source joint gets a second harmonic of its angle too (its
  first harmonic is re-referenced already): the effect acts on both joints;
- ``own_angle``: the second harmonic of the joint's own angle, beyond what its sweep
  held (the re-referenced per-joint model carries the offset and first harmonic): a
  sweep bent by an effect of another joint leaves such a term.

Missing context is taken at its reference (temperature, time, payload) or midway
between the directions (direction unknown). The effect is not separable (its
error depends on more than θ_j), so it is compensated by the general solve.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from rapidfix.error_model.candidates.gravity import (
    DOWN,
    body_torque_regressors,
    nominal_robot,
    payload_torques,
)
from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import Context
from rapidfix.exceptions import ModelError

#: driver → (parameter names, finite-difference steps, context fields read)
DRIVERS: dict[str, tuple[tuple[str, ...], tuple[float, ...], frozenset[str]]] = {
    "gravity": (("k_rad_per_nm", "link_x_rad", "link_y_rad", "link_z_rad",
                 "flange_x_rad", "flange_y_rad", "flange_z_rad", "flange_mass_rad"),
                (1e-7,) + (1e-6,) * 7, frozenset({"payload_kg", "payload_cog_mm"})),
    "temperature": (("offset_rad_per_k", "scale_ppm_per_k", "scale_ppm"), (1e-6, 1.0, 1.0),
                    frozenset({"temp_c"})),
    "time": (("offset_rad_per_h", "scale_ppm_per_h", "scale_ppm"), (1e-6, 1.0, 1.0),
             frozenset({"time_s"})),
    "payload": (("offset_rad_per_kg",), (1e-7,), frozenset({"payload_kg"})),
    "direction": (("half_shift_rad",), (2e-6,), frozenset({"last_direction"})),
    "angle": (("sin1_rad", "cos1_rad", "sin2_rad", "cos2_rad", "source_sin2_rad",
               "source_cos2_rad"), (2e-6,) * 6, frozenset()),
    "own_angle": (("sin2_rad", "cos2_rad"), (2e-6,) * 2, frozenset()),
}
#: drivers that read another joint
WITH_SOURCE = ("direction", "angle")


class JointDriver(VectorEffect):
    """Δθ_joint = F_driver(q, ctx) · p (see the module docstring); joints 0-based inside."""

    type_name: ClassVar[str] = "joint_driver"
    adds_joint_delta: ClassVar[bool] = True

    def __init__(self, joint: int, driver: str, *, source: int | None = None,
                 robot: str = "", reference: float = 0.0,
                 payload_point_mm: np.ndarray | tuple = (0.0, 0.0, 0.0),
                 default_payload_kg: float = 0.0, name: str | None = None,
                 free: bool = True) -> None:
        if driver not in DRIVERS:
            raise ModelError(f"unknown joint driver {driver!r}",
                             hint=f"known: {', '.join(DRIVERS)}")
        if not 0 <= joint < 6:
            raise ModelError(f"joint {joint + 1} is not one of 1..6")
        if driver in WITH_SOURCE and (source is None or not 0 <= source < 6 or source == joint):
            raise ModelError(f"a {driver} driver needs another joint as its source")
        if driver == "gravity" and not robot:
            raise ModelError("a gravity driver needs the robot's name")
        names, steps, _ = DRIVERS[driver]
        if name is None:
            name = f"joint_driver_j{joint + 1}_{driver}" + (
                "" if source is None else f"_j{source + 1}")
        super().__init__(names, name, steps=list(steps), free=free)
        self.joint = int(joint)
        self.driver = driver
        self.source = None if source is None else int(source)
        self.robot = str(robot)
        self.reference = float(reference)
        self.payload_point_mm = np.asarray(payload_point_mm, dtype=float).reshape(3)
        self.default_payload_kg = float(default_payload_kg)
        self._cache: tuple[tuple, np.ndarray] | None = None

    # -- regressors ---------------------------------------------------------------
    def _column(self, value: np.ndarray | None, n: int, unit: float = 1.0) -> np.ndarray:
        if value is None:
            return np.zeros(n)
        return (np.broadcast_to(np.asarray(value, dtype=float), (n,)) - self.reference) * unit

    def _payload(self, ctx: Context, n: int) -> np.ndarray:
        m = self.default_payload_kg if ctx.payload_kg is None else ctx.payload_kg
        return np.broadcast_to(np.asarray(m, dtype=float), (n,))

    def _gravity(self, q: np.ndarray, ctx: Context) -> np.ndarray:
        robot = nominal_robot(self.robot)
        point = (self.payload_point_mm if ctx.payload_cog_mm is None
                 else np.asarray(ctx.payload_cog_mm, dtype=float))
        payload = self._payload(ctx, q.shape[0])
        key = (q.shape, hash(q.tobytes()), hash(np.ascontiguousarray(payload).tobytes()),
               hash(np.ascontiguousarray(point).tobytes()))
        if self._cache is not None and self._cache[0] == key:  # fitters ask again and again
            return self._cache[1]
        tau = payload_torques(robot, q, point, payload, DOWN)[:, self.joint]
        link = body_torque_regressors(robot, q, self.joint, self.joint)[:, :3]
        flange = body_torque_regressors(robot, q, self.joint, 5)
        out = np.column_stack([tau, link, flange])
        self._cache = (key, out)
        return out

    def regressors(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """F (N, P): the joint's error is F · params."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        n = q.shape[0]
        if self.driver == "gravity":
            return self._gravity(q, ctx)
        if self.driver in ("temperature", "time"):
            unit = 1.0 if self.driver == "temperature" else 1.0 / 3600.0
            x = self._column(ctx.temp_c if self.driver == "temperature" else ctx.time_s, n, unit)
            own = q[:, self.joint]
            return np.column_stack([x, 1e-6 * x * own, 1e-6 * own])
        if self.driver == "payload":
            return self._column(None if ctx.payload_kg is None else self._payload(ctx, n),
                                n)[:, None]
        if self.driver == "own_angle":
            own = q[:, self.joint]
            return np.column_stack([np.sin(2 * own), np.cos(2 * own)])
        assert self.source is not None
        if self.driver == "direction":
            return ctx.direction(q)[:, [self.source]]
        s = q[:, self.source]
        return np.column_stack([np.sin(s), np.cos(s), np.sin(2 * s), np.cos(2 * s),
                                np.sin(2 * s), np.cos(2 * s)])

    @property
    def acts_on(self) -> np.ndarray:
        """The joint (0-based) each parameter's regressor acts on, (P,)."""
        out = np.full(len(self._names), self.joint)
        if self.driver == "angle":
            out[4:] = self.source
        return out

    def joint_delta(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """The driven joint's error (rad) (and the source's, for an angle), zero elsewhere."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        out = np.zeros_like(q)
        terms = self.regressors(q, ctx) * self._p
        for joint in np.unique(self.acts_on):  # one or two joints
            out[:, joint] = terms[:, self.acts_on == joint].sum(axis=1)
        return out

    def context_fields(self) -> frozenset[str]:
        """What this effect reads from the context."""
        return DRIVERS[self.driver][2]

    # -- words ----------------------------------------------------------------------
    def what(self) -> str:
        """Where it acts and what drives it, in words."""
        j = self.joint + 1
        src = None if self.source is None else self.source + 1
        return {
            "gravity": f"joint {j}'s error grows with the gravity torque about joint {j} "
                       "(payload and carried links)",
            "temperature": f"joint {j}'s zero and angle scale drift with the temperature",
            "time": f"joint {j}'s zero and angle scale drift with the time since the start",
            "payload": f"joint {j}'s error grows with the payload mass",
            "direction": f"joint {j}'s zero shifts with the direction joint {src} last moved",
            "angle": f"joint {j}'s error follows joint {src}'s angle (harmonics 1 and 2)",
            "own_angle": f"joint {j}'s error has a second harmonic of its own angle that "
                         "its sweep did not show",
        }[self.driver]

    def sentence(self) -> str:
        """`what()` with the leading parameter and its standard deviation."""
        p = self._p
        sd = None if self.uncertainty is None else np.asarray(self.uncertainty, dtype=float)

        def pm(i: int, fmt: str, degrees: bool = True) -> str:
            conv = np.degrees if degrees else float
            text = format(abs(conv(p[i])) if self.driver == "direction" else conv(p[i]), fmt)
            return text if sd is None else f"{text} ± {format(conv(sd[i]), fmt)}"

        if self.driver == "gravity":
            if p[0] == 0.0 and (sd is None or sd[0] == 0.0):  # the payload never varied
                return (f"{self.what()}: from the carried tool and links' weight (the "
                        "payload did not vary)")
            return f"{self.what()}: {pm(0, '.5f')}°/N·m of payload torque"
        if self.driver in ("temperature", "time"):
            per = "K" if self.driver == "temperature" else "h"
            return (f"{self.what()}: {pm(1, '.1f', False)} ppm/{per} of its angle, "
                    f"{pm(0, '.5f')}°/{per}")
        if self.driver == "payload":
            return f"{self.what()}: {pm(0, '.5f')}°/kg"
        if self.driver == "direction":
            return f"{self.what()}: ±{pm(0, '.4f')}°"
        amp = np.degrees(np.hypot(p[0::2], p[1::2]))
        if self.driver == "own_angle":
            return f"{self.what()}: {amp[0]:.4f}°"
        return (f"{self.what()}: {amp[0]:.4f}° (first harmonic), {amp[1]:.4f}° "
                f"(second harmonic); joint {self.source + 1}'s sweep took "
                f"{amp[2]:.4f}° of a second harmonic for its own")

    def describe(self) -> str:
        """One line for summaries."""
        return f"{self.name} ({self.what()})"

    # -- serialisation -----------------------------------------------------------------
    def _state(self) -> dict[str, Any]:
        return {"joint": self.joint + 1, "driver": self.driver,
                "source_joint": None if self.source is None else self.source + 1,
                "robot": self.robot, "reference": self.reference,
                "payload_point_mm": self.payload_point_mm.tolist(),
                "default_payload_kg": self.default_payload_kg}

    @classmethod
    def _from_state(cls, name: str, state: dict[str, Any]) -> JointDriver:
        source = state.get("source_joint")
        return cls(int(state["joint"]) - 1, str(state["driver"]),
                   source=None if source is None else int(source) - 1,
                   robot=str(state.get("robot", "")), reference=float(state.get("reference", 0.0)),
                   payload_point_mm=np.asarray(state.get("payload_point_mm", (0, 0, 0)), float),
                   default_payload_kg=float(state.get("default_payload_kg", 0.0)), name=name)
