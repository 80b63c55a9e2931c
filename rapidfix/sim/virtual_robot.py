"""A virtual robot: the nominal model plus chosen true errors, executed and measured.

`VirtualRobot.measure(q_cmd, ctx)` "runs" commanded joints (N, 6) rad on the true
robot and returns where the target ball really is (noise-free) or what a tracker
would report (with joint repeatability and tracker noise). The context gives the
conditions each row ran under — any object or mapping with the optional fields
`payload_kg`, `time_s`, `temp_c` (N,) and `q_prev` (N, 6) rad (the pose before
each row; without it the rows are taken as executed in order). This is the same
shape as `rapidfix.error_model.context.Context`, which is accepted as is.

The flange may carry several target-ball nests (`smr_offsets_mm`, nest 0 first):
`measure(..., ball=index)` measures each row on its own nest. A payload without its
own centre of gravity hangs at nest 0.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rapidfix.kinematics import RobotModel, load_robot
from rapidfix.sim.tracker import VirtualTracker
from rapidfix.sim.true_errors import (
    TrueErrors,
    base_tilt,
    gravity_torque,
    link_growth,
    tool_bend,
    torque_about,
)

DEFAULT_ROBOT = "IRB1600-10/1.45"
#: Target ball in the flange frame, mm: 100 mm off the joint-6 axis so joint 6 draws a circle.
DEFAULT_SMR_OFFSET_MM = (60.0, 80.0, 90.0)
#: A second nest on the other side of the flange, also 100 mm off its axis: one ball
#: cannot show how the flange turns about it, two leave only the turn about the line
#: through both unseen, and this line crosses the flange axis 120 mm out, where tools are.
SECOND_SMR_OFFSET_MM = (-60.0, -80.0, 150.0)
DEFAULT_SMR_OFFSETS_MM = (DEFAULT_SMR_OFFSET_MM, SECOND_SMR_OFFSET_MM)
#: Joint repeatability (1σ, rad): about ±0.01–0.03 mm at the TCP of a 1.45 m arm.
DEFAULT_REPEATABILITY_RAD = 1.0e-5


@dataclass(frozen=True)
class RunConditions:
    """Per-row conditions, each (N,) or None; `q_prev` (N, 6) rad or None."""

    payload_kg: np.ndarray | None = None
    time_s: np.ndarray | None = None
    temp_c: np.ndarray | None = None
    q_prev: np.ndarray | None = None
    #: the payload's centre of gravity in the flange frame (N, 3) mm; None: at the ball
    payload_cog_mm: np.ndarray | None = None


def _field(ctx: Any, name: str) -> Any:
    if ctx is None:
        return None
    if isinstance(ctx, Mapping):
        return ctx.get(name)
    return getattr(ctx, name, None)


def motion_direction(q: np.ndarray, q_prev: np.ndarray | None) -> np.ndarray:
    """Sign (N, 6) of the last motion of each joint, rows executed in order.

    Where a joint did not move (or q_prev is unknown for the first row) it keeps the
    direction of the row before; before any motion the direction is +1.
    """
    if q_prev is None:
        q_prev = np.vstack([q[:1], q[:-1]])
    step = np.sign(np.round(q - q_prev, 12))
    n = len(q)
    idx = np.where(step != 0, np.arange(n)[:, None], -1)
    last = np.maximum.accumulate(idx, axis=0)
    filled = np.take_along_axis(step, np.maximum(last, 0), axis=0)
    return np.where(last >= 0, filled, 1.0)


class VirtualRobot:
    """Nominal model + `TrueErrors` + a `VirtualTracker`; see the module docstring."""

    def __init__(self, robot: RobotModel, errors: TrueErrors, tracker: VirtualTracker,
                 smr_offset_mm: np.ndarray, *, payload_kg: float = 0.0,
                 repeatability_rad: float = DEFAULT_REPEATABILITY_RAD, seed: int = 0,
                 smr_offsets_mm: np.ndarray | None = None) -> None:
        self.robot = robot
        self.errors = errors
        self.tracker = tracker
        self.smr_offset_mm = np.asarray(smr_offset_mm, dtype=float)
        nests = (self.smr_offset_mm[None] if smr_offsets_mm is None
                 else np.asarray(smr_offsets_mm, dtype=float).reshape(-1, 3))
        if not np.allclose(nests[0], self.smr_offset_mm):
            raise ValueError("the first of smr_offsets_mm must be smr_offset_mm")
        #: every nest's declared ball centre (K, 3) mm in the flange frame
        self.smr_offsets_mm = nests
        self.payload_kg = float(payload_kg)
        self.repeatability_rad = float(repeatability_rad)
        self.seed = int(seed)
        self._rng = np.random.default_rng([self.seed, 7])
        if errors.axis_dirs is not None:
            self.actual_model = robot.with_screws(errors.axis_dirs, errors.axis_points,
                                                  errors.home)
        else:
            self.actual_model = robot

    @classmethod
    def create(cls, robot: str | RobotModel = DEFAULT_ROBOT, seed: int = 0,
               effects: tuple[str, ...] | list[str] = (),
               smr_offset_mm: tuple[float, float, float] | np.ndarray = DEFAULT_SMR_OFFSET_MM,
               payload_kg: float = 0.0,
               repeatability_rad: float = DEFAULT_REPEATABILITY_RAD,
               smr_offsets_mm: Any = None) -> VirtualRobot:
        """A robot with random true errors (per-joint always, plus `effects`) and tracker;
        `smr_offsets_mm` (K, 3) its nests (default: `smr_offset_mm` alone)."""
        model = load_robot(robot) if isinstance(robot, str) else robot
        rng = np.random.default_rng(seed)
        errors = TrueErrors.draw(model, tuple(effects), rng)
        tracker = VirtualTracker.place(rng, scale_ppm=errors.scale_ppm)
        nests = None if smr_offsets_mm is None else np.asarray(smr_offsets_mm, dtype=float)
        first = np.asarray(smr_offset_mm, dtype=float) if nests is None else nests[0]
        return cls(model, errors, tracker, first, payload_kg=payload_kg,
                   repeatability_rad=repeatability_rad, seed=seed, smr_offsets_mm=nests)

    # ---- the true robot --------------------------------------------------------------

    @property
    def true_smr_offset_mm(self) -> np.ndarray:
        """Where the ball really is in the flange frame (declared + tool offset error)."""
        if self.errors.tool_offset is None:
            return self.smr_offset_mm
        return self.smr_offset_mm + self.errors.tool_offset

    @property
    def true_smr_offsets_mm(self) -> np.ndarray:
        """Where every nest's ball really is (K, 3) mm: the plate carrying them sits off
        by the tool offset error."""
        if self.errors.tool_offset is None:
            return self.smr_offsets_mm
        return self.smr_offsets_mm + self.errors.tool_offset

    def _nest(self, ball: Any, n: int, true: bool = True) -> np.ndarray:
        """Ball centres (N, 3) (or (3,) for nest 0 everywhere) of per-row nest indices."""
        nests = self.true_smr_offsets_mm if true else self.smr_offsets_mm
        if ball is None:
            return nests[0]
        index = np.broadcast_to(np.asarray(ball, dtype=int), (n,))
        if index.min() < 0 or index.max() >= len(nests):
            raise ValueError(f"ball index outside 0..{len(nests) - 1}")
        return nests[index]

    def temperature(self, ctx: Any, n: int) -> np.ndarray | None:
        """Arm temperature per row: the context's temp_c, else from time_s, else None."""
        temp = _field(ctx, "temp_c")
        if temp is not None:
            return np.broadcast_to(np.asarray(temp, dtype=float), (n,))
        time = _field(ctx, "time_s")
        if time is not None and self.errors.needs_temperature:
            return self.errors.temperature(np.broadcast_to(np.asarray(time, dtype=float), (n,)))
        return None

    def actual_joints(self, q_cmd: np.ndarray, ctx: Any = None,
                      jitter: np.ndarray | None = None) -> np.ndarray:
        """The joint angles (N, 6) rad the robot really takes for commanded q_cmd."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        q_prev = _field(ctx, "q_prev")
        direction = None
        if self.errors.needs_direction:
            direction = motion_direction(q, None if q_prev is None else np.atleast_2d(q_prev))
        temp = self.temperature(ctx, len(q)) if self.errors.encoder is not None else None
        q_act = q + self.errors.joint_delta(q, direction, temp)
        if jitter is not None:
            q_act = q_act + jitter
        if self.errors.wrist is not None:
            q_act = self._wrist_deflection(q_act, ctx)
        if self.errors.compliance is not None:
            payload = _field(ctx, "payload_kg")
            payload = self.payload_kg if payload is None else payload
            dirs, points = self.actual_model.joint_frames(q_act)
            cog = _field(ctx, "payload_cog_mm")
            if cog is None:
                at = self._ball(q_act, 1.0)
            else:
                T = self.actual_model.fk(q_act)
                cog = np.broadcast_to(np.asarray(cog, dtype=float), (len(q), 3))
                at = np.einsum("nij,nj->ni", T[:, :3, :3], cog) + T[:, :3, 3]
            torque = gravity_torque(dirs, points, at, np.broadcast_to(payload, (len(q),)))
            q_act = q_act.copy()
            q_act[:, 1:3] += self.errors.compliance * torque
        return q_act

    def _payload_point(self, T: np.ndarray, ctx: Any) -> np.ndarray:
        """Where the payload's centre of gravity is (N, 3) mm for flange poses T."""
        cog = _field(ctx, "payload_cog_mm")
        local = self.true_smr_offset_mm if cog is None else cog
        local = np.broadcast_to(np.asarray(local, dtype=float), (T.shape[0], 3))
        return np.einsum("nij,nj->ni", T[:, :3, :3], local) + T[:, :3, 3]

    def _wrist_deflection(self, q_act: np.ndarray, ctx: Any) -> np.ndarray:
        """A wrist joint turned by its compliance × the gravity torque of tool and payload."""
        w = self.errors.wrist
        assert w is not None
        j = int(w["joint"])
        n = len(q_act)
        payload = _field(ctx, "payload_kg")
        payload = np.broadcast_to(np.asarray(self.payload_kg if payload is None else payload,
                                             dtype=float), (n,))
        T = self.actual_model.fk(q_act)
        tool = np.einsum("nij,j->ni", T[:, :3, :3], np.asarray(w["tool_cog_mm"])) + T[:, :3, 3]
        positions = np.stack([tool, self._payload_point(T, ctx)], axis=1)
        masses = np.column_stack([np.full(n, w["tool_kg"]), payload])
        dirs, points = self.actual_model.joint_frames(q_act)
        out = q_act.copy()
        out[:, j] += w["k_rad_per_nm"] * torque_about(dirs[:, j], points[:, j], positions,
                                                      masses)
        return out

    def _ball(self, q_act: np.ndarray, scale: np.ndarray | float,
              ball: Any = None) -> np.ndarray:
        T = self.actual_model.fk(q_act)
        local = np.broadcast_to(self._nest(ball, len(q_act)), (len(q_act), 3))
        return (np.einsum("nij,nj->ni", T[:, :3, :3], local)
                + np.reshape(scale, (-1, 1)) * T[:, :3, 3])

    def _positions(self, q_cmd: np.ndarray, ctx: Any, jitter: np.ndarray | None,
                   ball: Any = None) -> np.ndarray:
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        scale = self.errors.thermal_scale(self.temperature(ctx, len(q)))
        q_act = self.actual_joints(q, ctx, jitter)
        if not self._moves_frames:
            return self._ball(q_act, scale, ball)
        T = self._flange(q_act, ctx, scale)
        local = np.broadcast_to(self._nest(ball, len(q_act)), (len(q_act), 3))
        return np.einsum("nij,nj->ni", T[:, :3, :3], local) + T[:, :3, 3]

    # ---- issue #14: effects on frames (tool, base, link) -----------------------------

    @property
    def _moves_frames(self) -> bool:
        e = self.errors
        return (e.tool_bending is not None or e.base_tilt is not None
                or e.link_thermal is not None)

    def _flange(self, q_act: np.ndarray, ctx: Any, scale: np.ndarray | float) -> np.ndarray:
        """The flange poses (N, 4, 4) of actual joints with the arm's growth, a link's
        growth, the tool's bend (the tool frame on the flange) and the base's tilt."""
        e = self.errors
        n = len(q_act)
        T = self.actual_model.fk(q_act)
        T[:, :3, 3] *= np.reshape(scale, (-1, 1))
        if e.link_thermal is not None:
            temp = self.temperature(ctx, n)
            if temp is not None:
                m = self.actual_model
                T[:, :3, 3] += link_growth(e.link_thermal, np.asarray(m.axis_dirs),
                                           np.asarray(m.axis_points), np.asarray(m.home),
                                           q_act, temp)
        if e.tool_bending is None and e.base_tilt is None:
            return T
        payload = _field(ctx, "payload_kg")
        payload = np.broadcast_to(np.asarray(self.payload_kg if payload is None else payload,
                                             dtype=float), (n,))
        at = self._payload_point(T, ctx)
        if e.tool_bending is not None:
            cog = _field(ctx, "payload_cog_mm")
            cog = np.broadcast_to(np.asarray(self.true_smr_offset_mm if cog is None else cog,
                                             dtype=float), (n, 3))
            T = T @ tool_bend(e.tool_bending, T[:, :3, :3], payload, cog)
        if e.base_tilt is not None:
            _, points = self.actual_model.joint_frames(q_act)
            T = base_tilt(e.base_tilt, points, at, payload) @ T
        return T

    def tcp_poses(self, q_cmd: np.ndarray, tool: np.ndarray, ctx: Any = None, *,
                  jitter: np.ndarray | None = None) -> np.ndarray:
        """Where a tool (4,4) or (N,4,4) on the flange really is (N,4,4), base frame, for
        commanded q_cmd (N,6) rad run in `ctx` (the arm grows about the base)."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        scale = self.errors.thermal_scale(self.temperature(ctx, len(q)))
        T = self._flange(self.actual_joints(q, ctx, jitter), ctx, scale)
        return T @ np.asarray(tool, dtype=float)

    def ball_positions(self, q_cmd: np.ndarray, ctx: Any = None, *,
                       ball: Any = None) -> np.ndarray:
        """Noise-free true ball centres (N, 3) mm in the robot base frame (`ball`: each
        row's nest index, default nest 0)."""
        return self._positions(q_cmd, ctx, None, ball)

    def ideal_positions(self, q_cmd: np.ndarray, *, ball: Any = None) -> np.ndarray:
        """Where a perfect robot would put the declared ball: nominal FK, mm, base frame."""
        T = self.robot.fk(np.atleast_2d(np.asarray(q_cmd, dtype=float)))
        local = np.broadcast_to(self._nest(ball, len(T), true=False), (len(T), 3))
        return np.einsum("nij,nj->ni", T[:, :3, :3], local) + T[:, :3, 3]

    def measure(self, q_cmd: np.ndarray, ctx: Any = None, *, noise: bool = True,
                frame: str = "base", seed: int | None = None,
                ball: Any = None) -> np.ndarray:
        """Execute q_cmd (N, 6) rad and measure the ball (N, 3) mm.

        `frame="base"`: in the robot base frame (a perfectly registered tracker);
        `frame="tracker"`: as the tracker reports it (its pose and scale error).
        With `noise`, each row gets joint-repeatability jitter and tracker noise;
        `seed` makes one call reproducible, else the robot's own stream is used.
        `ball` (N,) or scalar: the nest each row measures (default nest 0).
        """
        if frame not in ("base", "tracker"):
            raise ValueError("frame must be 'base' or 'tracker'")
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        rng = self._rng if seed is None else np.random.default_rng(seed)
        jitter = rng.normal(0.0, self.repeatability_rad, q.shape) if noise else None
        p = self._positions(q, ctx, jitter, ball)
        sigma = self.tracker.sigma_mm(p)
        out = self.tracker.to_tracker(p) if frame == "tracker" else p
        if noise:
            out = out + rng.normal(size=out.shape) * sigma[:, None]
        return out

    def ballbar_lengths(self, q_cmd: np.ndarray, centre_mm: np.ndarray, ctx: Any = None, *,
                        noise: bool = True, sigma_mm: float = 0.001,
                        seed: int | None = None) -> np.ndarray:
        """Lengths (N,) mm a ballbar pivoting at `centre_mm` (base frame) would read."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        rng = self._rng if seed is None else np.random.default_rng(seed)
        jitter = rng.normal(0.0, self.repeatability_rad, q.shape) if noise else None
        length = np.linalg.norm(self._positions(q, ctx, jitter) - centre_mm, axis=1)
        return length + (rng.normal(0.0, sigma_mm, len(q)) if noise else 0.0)

    # ---- what the truth file states --------------------------------------------------

    def noise_floor(self, q_cmd: np.ndarray, ctx: Any = None, *, draws: int = 200,
                    seed: int = 0, ball: Any = None) -> dict[str, float]:
        """Expected mean TCP distance error from noise and repeatability alone, mm.

        Monte Carlo over `draws` repeats of the poses: a perfectly compensated robot,
        perfectly registered, still shows this much error on these poses.
        """
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        rng = np.random.default_rng(seed)
        qq = np.tile(q, (draws, 1))
        big_ctx = None
        if ctx is not None:
            fields = {}
            for name in ("payload_kg", "time_s", "temp_c"):
                v = _field(ctx, name)
                fields[name] = None if v is None else np.tile(
                    np.broadcast_to(np.asarray(v, dtype=float), (len(q),)), draws)
            q_prev = _field(ctx, "q_prev")
            fields["q_prev"] = None if q_prev is None else np.tile(np.atleast_2d(q_prev),
                                                                   (draws, 1))
            big_ctx = RunConditions(**fields)
        balls = None if ball is None else np.tile(
            np.broadcast_to(np.asarray(ball, dtype=int), (len(q),)), draws)
        exact = self._positions(qq, big_ctx, None, balls)
        jittered = self._positions(qq, big_ctx,
                                   rng.normal(0.0, self.repeatability_rad, qq.shape), balls)
        tracker = rng.normal(size=exact.shape) * self.tracker.sigma_mm(exact)[:, None]
        return {
            "mean_tcp_error_mm": float(np.mean(np.linalg.norm(jittered + tracker - exact,
                                                              axis=1))),
            "repeatability_only_mm": float(np.mean(np.linalg.norm(jittered - exact, axis=1))),
            "tracker_only_mm": float(np.mean(np.linalg.norm(tracker, axis=1))),
            "tracker_sigma_mean_mm": float(np.mean(self.tracker.sigma_mm(exact))),
        }

    def truth(self) -> dict[str, Any]:
        """JSON data of everything true about this robot (see `from_truth`)."""
        nests = {} if len(self.smr_offsets_mm) == 1 else {
            "declared_smr_offsets_mm": self.smr_offsets_mm.tolist(),
            "true_smr_offsets_mm": self.true_smr_offsets_mm.tolist()}
        return {"robot": self.robot.name, "seed": self.seed,
                "declared_smr_offset_mm": self.smr_offset_mm.tolist(),
                "true_smr_offset_mm": self.true_smr_offset_mm.tolist(), **nests,
                "payload_kg": self.payload_kg,
                "repeatability_rad": self.repeatability_rad,
                "errors": self.errors.to_dict(), "tracker": self.tracker.to_dict()}

    @classmethod
    def from_truth(cls, truth: Mapping[str, Any]) -> VirtualRobot:
        """Rebuild the robot a truth dict (or truth.json's content) describes."""
        return cls(load_robot(truth["robot"]), TrueErrors.from_dict(truth["errors"]),
                   VirtualTracker.from_dict(truth["tracker"]),
                   np.asarray(truth["declared_smr_offset_mm"], dtype=float),
                   payload_kg=float(truth.get("payload_kg", 0.0)),
                   repeatability_rad=float(truth["repeatability_rad"]),
                   seed=int(truth.get("seed", 0)),
                   smr_offsets_mm=truth.get("declared_smr_offsets_mm"))

    def true_joint_error(self, q_cmd: np.ndarray, ctx: Any = None) -> np.ndarray:
        """Δθ = θ_actual − θ_cmd (N, 6) rad, noise-free, in the simulator's own gauge."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        return self.actual_joints(q, ctx) - q
