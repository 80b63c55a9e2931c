"""ErrorModel: a robot's effects, the full forward model, and how the model was fitted.

The forward model of the real robot for commanded joints θ_cmd:

    θ_act  = θ_cmd + Σ_effects Δθ(θ_cmd, ctx)
    geom   = nominal geometry with every geometry effect applied in order
    T_flange = PoE(geom.axes, θ_act) · geom.home
    TCP    = T_flange · tool · geom.tool          (tool: declared TCP or target ball)
    measured point = geom.world · TCP position   (tracker frame, for predictions only)

Angles in radians and lengths in mm inside; conversions happen at the file and
command-line boundary.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rapidfix.error_model.context import EMPTY, Context
from rapidfix.error_model.effect import Effect, Geometry
from rapidfix.error_model.forward import flange_poses
from rapidfix.exceptions import ModelError
from rapidfix.kinematics import RobotModel


def _joints(q: np.ndarray) -> np.ndarray:
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if q.ndim != 2 or q.shape[1] != 6:
        raise ModelError(f"joint values must have shape (N, 6), got {q.shape}")
    return q


def _point_tool(offset_mm: np.ndarray | None) -> np.ndarray:
    """A pure translation (4, 4) for one offset (3,), or (N, 4, 4) for per-row offsets (N, 3)."""
    if offset_mm is None:
        return np.eye(4)
    offset = np.asarray(offset_mm, dtype=float)
    if offset.shape[-1:] != (3,) or offset.ndim > 2:
        raise ModelError(f"ball offsets must have shape (3,) or (N, 3), got {offset.shape}")
    tool = np.broadcast_to(np.eye(4), (*offset.shape[:-1], 4, 4)).copy()
    tool[..., :3, 3] = offset
    return tool


@dataclass
class ErrorModel:
    """A robot's error model: its effects, fit statistics and the data they came from.

    `data_files` lists {"name", "sha256", "role"} of every measurement file used;
    `statistics` is free-form JSON (per-joint CV RMS, residuals, …) written by the fitter.
    `robot_definition` is the robot itself (a robot file's content) when it is not one
    rapidfix ships, so that the model reloads without that file.
    """

    robot: str
    effects: list[Effect] = field(default_factory=list)
    statistics: dict[str, Any] = field(default_factory=dict)
    data_files: list[dict[str, str]] = field(default_factory=list)
    robot_definition: dict[str, Any] | None = None
    #: while a fit holds them (`fixed_effects_held`): the joints, the context and the
    #: joint errors of the effects it may not change, computed once for them
    _held: tuple[np.ndarray, Context, dict[tuple[str, int], np.ndarray]] | None = field(
        default=None, init=False, repr=False, compare=False)

    # -- structure ----------------------------------------------------------------
    def effect(self, name: str) -> Effect:
        """The effect with this name (ModelError if there is none)."""
        for eff in self.effects:
            if eff.name == name:
                return eff
        raise ModelError(f"the model has no effect named {name!r}",
                         hint=f"it has: {', '.join(e.name for e in self.effects) or 'none'}")

    @property
    def robot_effects(self) -> list[Effect]:
        """The effects of the robot itself: all but those describing the measurement."""
        return [e for e in self.effects if not e.measurement_only]

    @property
    def separable(self) -> bool:
        """True when every robot effect is a per-joint error (compensation joint by joint)."""
        return all(e.separable and not e.changes_geometry for e in self.robot_effects)

    def play(self) -> np.ndarray:
        """Total play (6,) rad of the direction-dependent effects that have one (backlash)."""
        out = np.zeros(6)
        for eff in self.robot_effects:
            play = getattr(eff, "play", None)
            if callable(play):
                out += np.asarray(play(), dtype=float)
        return out

    def context_fields(self) -> frozenset[str]:
        """The context fields the robot effects read (payload, temperature, direction …)."""
        out: frozenset[str] = frozenset()
        for eff in self.robot_effects:
            out |= eff.context_fields()
        return out

    def check_robot(self, robot_name: str) -> None:
        """Refuse to use the model on another robot type."""
        if robot_name != self.robot:
            raise ModelError(
                f"the model was made for robot {self.robot!r}, not {robot_name!r}",
                hint="fit a model on measurements of this robot",
            )

    # -- parameter vector over all free effects (for generic fitters) ---------------
    def free_effects(self) -> list[Effect]:
        """Effects a fitter may change, in model order."""
        return [e for e in self.effects if e.free]

    def free_params(self) -> np.ndarray:
        """Stacked parameter vectors of the free effects."""
        parts = [e.params() for e in self.free_effects()]
        return np.concatenate(parts) if parts else np.zeros(0)

    def free_param_names(self) -> list[str]:
        """'effect.param' names matching free_params()."""
        return [f"{e.name}.{p}" for e in self.free_effects() for p in e.param_names]

    def set_free_params(self, p: np.ndarray, uncertainty: np.ndarray | None = None) -> None:
        """Write a stacked vector (and optionally its uncertainties) back to the free effects."""
        p = np.asarray(p, dtype=float).ravel()
        start = 0
        for eff in self.free_effects():
            n = len(eff.param_names)
            eff.set_fitted(p[start : start + n])
            if uncertainty is not None:
                eff.uncertainty = np.asarray(uncertainty, dtype=float)[start : start + n].copy()
            start += n
        if start != p.shape[0]:
            raise ValueError(f"{p.shape[0]} parameters given, {start} expected")

    # -- forward model ------------------------------------------------------------
    def delta(self, q_cmd: np.ndarray, ctx: Context | None = None) -> np.ndarray:
        """Σ joint errors (N, 6) rad at commanded joints (N, 6) rad."""
        return self._joint_sum("joint_delta", q_cmd, ctx)

    def delta_derivative(self, q_cmd: np.ndarray, ctx: Context | None = None) -> np.ndarray:
        """Σ ∂Δθ_j/∂θ_j (N, 6) of the joint-error effects (exact for separable ones)."""
        return self._joint_sum("joint_delta_derivative", q_cmd, ctx)

    def delta_and_derivative(self, q_cmd: np.ndarray,
                             ctx: Context | None = None) -> tuple[np.ndarray, np.ndarray]:
        """`delta` and `delta_derivative` at the same joints: the same numbers, one pass
        over an effect that can make both at once (`joint_delta_and_derivative`)."""
        q = _joints(q_cmd)
        ctx = EMPTY if ctx is None else ctx
        out = np.zeros_like(q)
        slope = np.zeros_like(q)
        for eff in self.effects:
            if eff.adds_joint_delta:
                both = getattr(eff, "joint_delta_and_derivative", None)
                if both is not None:
                    value, derivative = both(q, ctx)
                else:
                    value, derivative = eff.joint_delta(q, ctx), eff.joint_delta_derivative(q, ctx)
                out += value
                slope += derivative
        return out, slope

    def _joint_sum(self, term: str, q_cmd: np.ndarray, ctx: Context | None) -> np.ndarray:
        """Σ over the joint-error effects of their method `term`(q, ctx), (N, 6)."""
        q = _joints(q_cmd)
        ctx = EMPTY if ctx is None else ctx
        out = np.zeros_like(q)
        held = self._held
        if held is not None and (held[0] is not q or held[1] is not ctx):
            held = None
        for k, eff in enumerate(self.effects):
            if not eff.adds_joint_delta:
                continue
            if held is None or eff.free:
                out += getattr(eff, term)(q, ctx)
                continue
            value = held[2].get((term, k))
            if value is None:
                value = held[2][(term, k)] = getattr(eff, term)(q, ctx)
            out += value
        return out

    @contextmanager
    def fixed_effects_held(self, q_cmd: np.ndarray, ctx: Context) -> Iterator[None]:
        """Inside the block, the joint errors of the effects that are not free are computed
        once for these very joints and context (the same arrays, by identity) and reused.

        A fitter evaluates the model dozens of times at the same points, changing only
        the free effects; the fixed ones (the per-joint networks) need not be evaluated
        again each time. The sum keeps its order: the same numbers to the last bit.
        """
        previous = self._held
        self._held = (q_cmd, ctx, {})
        try:
            yield
        finally:
            self._held = previous

    def geometry(self, robot: RobotModel, q_cmd: np.ndarray,
                 ctx: Context | None = None) -> Geometry:
        """The robot's geometry with every geometry effect applied, in model order."""
        q = _joints(q_cmd)
        ctx = EMPTY if ctx is None else ctx
        geom = Geometry.nominal(robot)
        for eff in self.effects:
            if eff.changes_geometry:
                geom = eff.apply_geometry(geom, q, ctx)
        return geom

    def actual_flange(
        self, robot: RobotModel, q_cmd: np.ndarray, ctx: Context | None = None
    ) -> np.ndarray:
        """Where tool0 really is (N, 4, 4) in the base frame when q_cmd (N, 6) rad is commanded.

        Only the robot's own effects act here: the measurement's (tracker frame and
        scale, target-ball offset) change `Geometry.world` and `Geometry.tool`, which
        tool0 never passes through.
        """
        return self._forward(robot, q_cmd, ctx)[0]

    def flange_and_jacobian(
        self, robot: RobotModel, q_cmd: np.ndarray, ctx: Context | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """`actual_flange` and its approximate space Jacobian (N, 6, 6) with respect to
        the commanded joints (see `actual_tcp`)."""
        T, jac, _ = self._forward(robot, q_cmd, ctx, with_jacobian=True)
        return T, jac * (1.0 + self.delta_derivative(q_cmd, ctx))[:, None, :]

    def actual_tcp(
        self,
        robot: RobotModel,
        q_cmd: np.ndarray,
        ctx: Context | None = None,
        tool: np.ndarray | None = None,
        *,
        with_jacobian: bool = False,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Measured-TCP poses (N, 4, 4) in the base frame for a declared tool (4, 4) or
        (N, 4, 4) (None: tool0), with the measurement's tool correction (a target
        ball's offset error) applied after it: what a tracker would see.

        With `with_jacobian`, also the approximate space Jacobian with respect to
        the commanded joints (N, 6, 6): the actual geometry's Jacobian scaled by
        1 + ∂Δθ_j/∂θ_j (cross-joint terms of non-separable effects are ignored;
        they only slow the general solve's convergence, not its answer).
        """
        T, jac, geom = self._forward(robot, q_cmd, ctx, with_jacobian=with_jacobian)
        declared = np.eye(4) if tool is None else np.asarray(tool, dtype=float)
        if declared.ndim == 3 and declared.shape[0] not in (1, T.shape[0]):
            raise ModelError(f"{declared.shape[0]} tools given for {T.shape[0]} poses")
        tcp = T @ declared @ geom.tool
        if jac is not None:
            jac = jac * (1.0 + self.delta_derivative(q_cmd, ctx))[:, None, :]
        return tcp, jac

    def predict_ball(
        self,
        robot: RobotModel,
        q_cmd: np.ndarray,
        ball_offset_mm: np.ndarray,
        ctx: Context | None = None,
        *,
        frame: str = "base",
    ) -> np.ndarray:
        """Target-ball centres (N, 3) mm: in the robot base frame, or frame="world" (tracker).

        `ball_offset_mm` is one ball (3,) for every row, or each row's own ball (N, 3)
        (a flange with several nests, each row measured on one of them).
        """
        tcp, _ = self.actual_tcp(robot, q_cmd, ctx, _point_tool(ball_offset_mm))
        if frame == "base":
            return tcp[:, :3, 3]
        if frame != "world":
            raise ValueError(f"frame must be 'base' or 'world', not {frame!r}")
        world = self.geometry(robot, q_cmd, ctx).world
        return (world @ tcp)[..., :3, 3]

    def _forward(
        self,
        robot: RobotModel,
        q_cmd: np.ndarray,
        ctx: Context | None,
        *,
        with_jacobian: bool = False,
    ) -> tuple[np.ndarray, np.ndarray | None, Geometry]:
        q = _joints(q_cmd)
        ctx = EMPTY if ctx is None else ctx
        geom = self.geometry(robot, q, ctx)
        T, jac = flange_poses(robot, geom, q + self.delta(q, ctx), with_jacobian=with_jacobian)
        return T, jac, geom

    def summary(self) -> str:
        """A few lines naming the robot and the effects."""
        lines = [f"error model for {self.robot}"]
        lines += [f"  - {e.describe()}" for e in self.effects]
        return "\n".join(lines)
