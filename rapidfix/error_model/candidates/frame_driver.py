"""Structured effects that act on a frame, not a joint: the tool, the base, a link.

Where the joint model cannot reach, an effect moves a whole frame by a small rigid
motion driven by a physical quantity (issue #14: where it acts, what drives it):

- ``tool`` / ``gravity``: the tool (everything beyond the flange) bends at a
  compliant mount under the gravity moment of its own weight and the payload's.
  The bend is a small rotation about a hinge on the tool axis (flange z) at
  ``hinge_mm``, perpendicular to the axis (torsion about the axis is stiff):
  ω = a (ẑ × ĝ) + k · P⊥[(c − h ẑ) × m g ĝ], ĝ gravity's direction in the flange
  frame, c and m the payload's centre of gravity and mass. ``a`` is the bend of
  the tool's own weight held horizontal (rad), ``k`` the mount's compliance
  (rad/N·m). tool0 moves by it, so every rigid tool and the target ball on it do.
- ``base`` / ``overturning``: the foundation yields, the base tilts about the
  horizontal axes through a pivot ``pivot_depth_mm`` below the base origin by
  ω = k · M_h, M_h the horizontal overturning moment about the base origin of the
  payload (known mass at its centre of gravity) and of the arm's own links, whose
  unknown mass moments enter linearly (the lower arm, upper arm and the flange
  body, each: mass moment along x, y, z and mass; the products k·m·c are fitted).
- ``link`` / ``temperature``: one link grows with the temperature,
  ΔL = 1e-6 · (c0 + c1 (T − T_ref)) · L along the link (the vector between the two
  joint-axis points it joins, or from the last axis to tool0): every later axis
  point and tool0 shift by it (c1 ≈ 11.5 ppm/K for steel).

All three change the geometry per pose, so a model holding them is compensated by
the general solve (matching tool0's pose matches every rigid tool on it). Gravity
and moments are taken from the nominal kinematics of the commanded pose.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from rapidfix.error_model.candidates.gravity import (
    DOWN,
    GRAVITY_MS2,
    link_transforms,
    nominal_robot,
)
from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import Context
from rapidfix.error_model.effect import Geometry
from rapidfix.exceptions import ModelError

#: links whose own unknown mass moments load the foundation (0-based: the lower arm, the
#: upper arm with the wrist; a tool's fixed body is part of the payload)
BASE_LINKS = (1, 2)
_ARM = tuple(f"arm_l{link + 1}_{axis}_rad" for link in BASE_LINKS
             for axis in ("x", "y", "z", "m"))
#: frame → (driver, parameter names, finite-difference steps, context fields read)
FRAMES: dict[str, tuple[str, tuple[str, ...], tuple[float, ...], frozenset[str]]] = {
    "tool": ("gravity", ("own_weight_rad", "k_rad_per_nm", "hinge_mm"), (1e-5, 5e-7, 5.0),
             frozenset({"payload_kg", "payload_cog_mm"})),
    "base": ("overturning", ("k_rad_per_nm", *_ARM, "pivot_depth_mm"),
             (1e-8,) + (1e-7,) * len(_ARM) + (20.0,),
             frozenset({"payload_kg", "payload_cog_mm"})),
    "link": ("temperature", ("scale_ppm", "growth_ppm_per_k"), (1.0, 1.0),
             frozenset({"temp_c"})),
}
Z = np.array([0.0, 0.0, 1.0])


def _rotations(omega: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of rotation vectors (N, 3)."""
    from scipy.spatial.transform import Rotation  # when used: start-up time

    return Rotation.from_rotvec(omega).as_matrix()


def _about(R: np.ndarray, point: np.ndarray) -> np.ndarray:
    """(N, 4, 4) rigid motions: rotation R (N, 3, 3) about the points (N, 3) mm."""
    out = np.broadcast_to(np.eye(4), (R.shape[0], 4, 4)).copy()
    out[:, :3, :3] = R
    out[:, :3, 3] = point - np.einsum("nij,nj->ni", R, point)
    return out


def _per_pose(a: np.ndarray, n: int) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    return np.broadcast_to(a, (n, *a.shape[-2:])) if a.ndim == 2 else a


class FrameDriver(VectorEffect):
    """A frame (tool, base or one link) moved by a driver; see the module docstring."""

    type_name: ClassVar[str] = "frame_driver"
    changes_geometry: ClassVar[bool] = True

    def __init__(self, frame: str, *, robot: str = "", link: int | None = None,
                 reference: float = 0.0,
                 payload_point_mm: np.ndarray | tuple = (0.0, 0.0, 0.0),
                 default_payload_kg: float = 0.0, name: str | None = None,
                 free: bool = True) -> None:
        if frame not in FRAMES:
            raise ModelError(f"unknown frame {frame!r} for a frame driver",
                             hint=f"known: {', '.join(FRAMES)}")
        if not robot:
            raise ModelError(f"a {frame} frame driver needs the robot's name")
        if frame == "link" and (link is None or not 1 <= link <= 6):
            raise ModelError("a link driver needs a link 1..6 (the link after joint 1..6)")
        driver, names, steps, _ = FRAMES[frame]
        if name is None:
            name = f"frame_driver_{frame}" + ("" if link is None else f"{link}") + f"_{driver}"
        super().__init__(names, name, steps=list(steps), free=free)
        self.frame = frame
        self.driver = driver
        self.link = None if link is None else int(link)
        self.robot = str(robot)
        self.reference = float(reference)
        self.payload_point_mm = np.asarray(payload_point_mm, dtype=float).reshape(3)
        self.default_payload_kg = float(default_payload_kg)
        #: no joint and no source joint: a frame effect acts beyond the joints
        self.joint: int | None = None
        self.source: int | None = None
        self._cache: tuple[tuple, Any] | None = None

    # -- drivers --------------------------------------------------------------------
    def _payload(self, ctx: Context, n: int) -> tuple[np.ndarray, np.ndarray]:
        m = self.default_payload_kg if ctx.payload_kg is None else ctx.payload_kg
        cog = self.payload_point_mm if ctx.payload_cog_mm is None else ctx.payload_cog_mm
        return (np.broadcast_to(np.asarray(m, dtype=float), (n,)),
                np.broadcast_to(np.asarray(cog, dtype=float), (n, 3)))

    def _key(self, q: np.ndarray, *arrays: np.ndarray) -> tuple:
        return (q.shape, hash(q.tobytes()),
                *(hash(np.ascontiguousarray(a).tobytes()) for a in arrays))

    def _tool_terms(self, q: np.ndarray, ctx: Context) -> tuple[np.ndarray, ...]:
        """(ĝ, ẑ × ĝ, payload moment about the flange origin N·m, payload weight
        force N), all in the flange frame, per pose."""
        m, cog = self._payload(ctx, q.shape[0])
        key = self._key(q, m, cog)
        if self._cache is not None and self._cache[0] == key:  # fitters ask again and again
            return self._cache[1]
        R = nominal_robot(self.robot).fk(q)[:, :3, :3]
        g = np.einsum("nji,j->ni", R, DOWN)  # gravity's direction in the flange frame
        force = GRAVITY_MS2 * m[:, None] * g
        out = (g, np.cross(Z, g), np.cross(cog * 1e-3, force), force)
        self._cache = (key, out)
        return out

    def _base_terms(self, q: np.ndarray, ctx: Context) -> np.ndarray:
        """Horizontal overturning moments (N, 2, 1 + 4 · links) N·m about the base
        origin: the payload's, then per unit mass moment (x, y, z) and mass of each
        body in `BASE_LINKS`."""
        m, cog = self._payload(ctx, q.shape[0])
        key = self._key(q, m, cog)
        if self._cache is not None and self._cache[0] == key:
            return self._cache[1]
        robot = nominal_robot(self.robot)
        T = robot.fk(q)
        g = GRAVITY_MS2 * DOWN
        at = (np.einsum("nij,nj->ni", T[:, :3, :3], cog) + T[:, :3, 3]) * 1e-3
        cols = [np.cross(at, m[:, None] * g)]
        rot, shift = link_transforms(robot, q)
        for link in BASE_LINKS:
            R = rot[:, link]
            cols += [np.cross(R[:, :, k], g) for k in range(3)]
            cols.append(np.cross(shift[:, link] * 1e-3, g))
        out = np.stack(cols, axis=2)[:, :2]
        self._cache = (key, out)
        return out

    # -- the frame's motion -----------------------------------------------------------
    def tool_rotation(self, q: np.ndarray, ctx: Context) -> np.ndarray:
        """The tool's bend ω (N, 3) rad in the flange frame, about the hinge."""
        a, k, h = self._p
        _, zg, moment, force = self._tool_terms(q, ctx)
        about_hinge = moment - np.cross(h * 1e-3 * Z, force)
        perp = about_hinge - about_hinge[:, 2:3] * Z
        return a * zg + k * perp

    def base_rotation(self, q: np.ndarray, ctx: Context) -> np.ndarray:
        """The base's tilt ω (N, 3) rad in the base frame (horizontal axes)."""
        cols = self._base_terms(q, ctx)
        omega = np.zeros((q.shape[0], 3))
        omega[:, :2] = cols @ self._p[:-1]
        return omega

    def _growth(self, ctx: Context, n: int) -> np.ndarray:
        t = ctx.temp_c
        x = np.zeros(n) if t is None else (
            np.broadcast_to(np.asarray(t, dtype=float), (n,)) - self.reference)
        return 1e-6 * (self._p[0] + self._p[1] * x)

    def apply_geometry(self, geometry: Geometry, q_cmd: np.ndarray, ctx: Context) -> Geometry:
        """The geometry with this frame moved, per pose."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        n = q.shape[0]
        home = _per_pose(geometry.home, n)
        if self.frame == "tool":
            R = _rotations(self.tool_rotation(q, ctx))
            hinge = np.broadcast_to(self._p[2] * Z, (n, 3))
            return geometry.replaced(home=home @ _about(R, hinge))
        dirs = _per_pose(geometry.axis_dirs, n)
        points = _per_pose(geometry.axis_points, n)
        if self.frame == "base":
            R = _rotations(self.base_rotation(q, ctx))
            pivot = np.broadcast_to(-self._p[-1] * Z, (n, 3))
            B = _about(R, pivot)
            return geometry.replaced(
                axis_dirs=np.einsum("nij,nkj->nki", R, dirs),
                axis_points=np.einsum("nij,nkj->nki", R, points) + B[:, None, :3, 3],
                home=B @ home)
        link = self.link
        assert link is not None
        end = points[:, link] if link < 6 else home[:, :3, 3]
        shift = self._growth(ctx, n)[:, None] * (end - points[:, link - 1])
        points = points.copy()
        points[:, link:] += shift[:, None, :]
        home = home.copy()
        home[:, :3, 3] += shift
        return geometry.replaced(axis_dirs=dirs, axis_points=points, home=home)

    def context_fields(self) -> frozenset[str]:
        """What this effect reads from the context."""
        return FRAMES[self.frame][3]

    # -- words ----------------------------------------------------------------------
    def what(self) -> str:
        """Where it acts and what drives it, in words."""
        if self.frame == "tool":
            return ("the tool bends under its own weight and the payload's, perpendicular "
                    "to its axis (gravity in the tool frame)")
        if self.frame == "base":
            return ("the base tilts with the overturning moment of the arm and its payload "
                    "(a compliant foundation)")
        end = "tool0" if self.link == 6 else f"joint {(self.link or 0) + 1}"
        return (f"link {self.link} (joint {self.link} to {end}) grows with the temperature "
                "(along the link)")

    def sentence(self) -> str:
        """`what()` with its leading parameters and their standard deviations."""
        p = self._p
        sd = None if self.uncertainty is None else np.asarray(self.uncertainty, dtype=float)

        def pm(i: int, scale: float, fmt: str) -> str:
            text = format(p[i] * scale, fmt)
            return text if sd is None else f"{text} ± {format(sd[i] * scale, fmt)}"

        if self.frame == "tool":
            ball = np.linalg.norm(self.payload_point_mm - p[2] * Z) * 1e-3  # m from the hinge
            per_n = f"{abs(p[1]) * ball * ball * 1e6:.2f} µm/N"  # across the axis, at the ball
            if p[1] == 0.0 and (sd is None or sd[1] == 0.0):  # the payload never varied
                return (f"{self.what()}: {pm(0, 1e6, '.0f')} µrad with the tool held "
                        f"horizontal ({abs(p[0]) * ball * 1e6:.0f} µm at the target ball); "
                        "the payload did not vary")
            return (f"{self.what()}: {pm(1, 1e6, '.1f')} µrad/N·m of moment ({per_n} of "
                    f"payload weight at the target ball), {pm(0, 1e6, '.0f')} µrad under "
                    f"its own weight held horizontal, hinge {p[2]:.0f} mm along the axis")
        if self.frame == "base":
            return (f"{self.what()}: {pm(0, 1e6, '.3f')} µrad/N·m of overturning moment, "
                    f"pivot {p[-1]:.0f} mm below the base origin")
        return f"{self.what()}: {pm(1, 1.0, '.1f')} ppm/K of its length"

    def describe(self) -> str:
        """One line for summaries."""
        return f"{self.name} ({self.what()})"

    # -- serialisation -----------------------------------------------------------------
    def _state(self) -> dict[str, Any]:
        return {"frame": self.frame, "link": self.link, "robot": self.robot,
                "reference": self.reference,
                "payload_point_mm": self.payload_point_mm.tolist(),
                "default_payload_kg": self.default_payload_kg}

    @classmethod
    def _from_state(cls, name: str, state: dict[str, Any]) -> FrameDriver:
        link = state.get("link")
        return cls(str(state["frame"]), robot=str(state.get("robot", "")),
                   link=None if link is None else int(link),
                   reference=float(state.get("reference", 0.0)),
                   payload_point_mm=np.asarray(state.get("payload_point_mm", (0, 0, 0)), float),
                   default_payload_kg=float(state.get("default_payload_kg", 0.0)), name=name)
