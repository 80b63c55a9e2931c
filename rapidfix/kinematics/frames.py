"""Frames and ABB conventions: quaternions, poses, tooldata, wobjdata, Offs, RelTool.

Interfaces use mm, degrees and quaternions in ABB order [q1, q2, q3, q4] =
[w, x, y, z], normalised with q1 ≥ 0. Inside everything is a 4×4 transform in mm.
scipy's Rotation does the conversions (it stores quaternions as x, y, z, w).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics.screws import invert_transform

__all__ = [
    "Tool",
    "WorkObject",
    "canonical_quat",
    "compose",
    "flange_target",
    "invert",
    "matrix_to_quat",
    "offs",
    "pose",
    "pose_to_pos_quat",
    "quat_to_matrix",
    "reltool",
    "rotation_xyz",
    "tcp_pose",
]

invert = invert_transform


def _as_quat(quat: np.ndarray) -> np.ndarray:
    q = np.asarray(quat, dtype=float)
    if q.shape[-1] != 4:
        raise KinematicsError(f"a quaternion needs 4 numbers [w, x, y, z], got shape {q.shape}")
    norm = np.linalg.norm(q, axis=-1)
    if not np.all(np.isfinite(q)) or np.any(norm < 1e-12):
        raise KinematicsError("a quaternion is zero or not finite")
    return q / norm[..., None]


def canonical_quat(quat: np.ndarray) -> np.ndarray:
    """Normalise [w, x, y, z] quaternions and fix the sign: q1 ≥ 0.

    When q1 is exactly 0 the first non-zero component is made positive, so
    equal rotations always give equal quaternions.
    """
    q = _as_quat(quat).copy()
    flat = q.reshape(-1, 4)
    first_nonzero = np.argmax(flat != 0.0, axis=1)
    lead = flat[np.arange(flat.shape[0]), first_nonzero]
    flat *= np.where(lead < 0.0, -1.0, 1.0)[:, None]
    return flat.reshape(q.shape)


def quat_to_matrix(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) from [w, x, y, z] quaternions (normalised first)."""
    q = _as_quat(quat)
    xyzw = np.concatenate([q[..., 1:], q[..., :1]], axis=-1).reshape(-1, 4)
    return Rotation.from_quat(xyzw).as_matrix().reshape((*q.shape[:-1], 3, 3))


def matrix_to_quat(rot: np.ndarray) -> np.ndarray:
    """[w, x, y, z] quaternions (..., 4), unit length with q1 ≥ 0, from rotation matrices."""
    R = np.asarray(rot, dtype=float)
    xyzw = Rotation.from_matrix(R.reshape(-1, 3, 3)).as_quat()
    wxyz = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
    return canonical_quat(wxyz).reshape((*R.shape[:-2], 4))


def pose(pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """Homogeneous transforms (..., 4, 4) from positions (..., 3) mm and quaternions (..., 4)."""
    p = np.asarray(pos, dtype=float)
    rot = quat_to_matrix(quat)
    shape = np.broadcast_shapes(p.shape[:-1], rot.shape[:-2])
    out = np.zeros((*shape, 4, 4))
    out[..., :3, :3] = rot
    out[..., :3, 3] = p
    out[..., 3, 3] = 1.0
    return out


def pose_to_pos_quat(T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions (..., 3) mm and canonical [w, x, y, z] quaternions (..., 4) of transforms."""
    T = np.asarray(T, dtype=float)
    return T[..., :3, 3].copy(), matrix_to_quat(T[..., :3, :3])


def compose(*transforms: np.ndarray) -> np.ndarray:
    """Product of transforms left to right (batches broadcast)."""
    out = np.asarray(transforms[0], dtype=float)
    for t in transforms[1:]:
        out = out @ np.asarray(t, dtype=float)
    return out


def rotation_xyz(rx_deg: np.ndarray, ry_deg: np.ndarray, rz_deg: np.ndarray) -> np.ndarray:
    """Rotation (..., 3, 3) about x, then the new y, then the new z (intrinsic), in degrees."""
    angles = np.stack(
        np.broadcast_arrays(*(np.asarray(a, float) for a in (rx_deg, ry_deg, rz_deg))), -1
    )
    flat = angles.reshape(-1, 3)
    return (
        Rotation.from_euler("XYZ", flat, degrees=True)
        .as_matrix()
        .reshape((*angles.shape[:-1], 3, 3))
    )


def offs(target: np.ndarray, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> np.ndarray:
    """RAPID Offs: the target moved by (x, y, z) mm in the work-object frame it is given in."""
    out = np.array(target, dtype=float, copy=True)
    out[..., :3, 3] += np.asarray([x, y, z], dtype=float)
    return out


def reltool(
    target: np.ndarray,
    dx: float = 0.0,
    dy: float = 0.0,
    dz: float = 0.0,
    rx: float = 0.0,
    ry: float = 0.0,
    rz: float = 0.0,
) -> np.ndarray:
    """RAPID RelTool: move (dx, dy, dz) mm and rotate rx, ry, rz degrees in the tool frame.

    The rotations are intrinsic, about the tool's x, then the new y, then the new z,
    as the RAPID manual describes: result = target ∘ [Rx·Ry·Rz | d].
    """
    local = np.eye(4)
    local[:3, :3] = rotation_xyz(rx, ry, rz)
    local[:3, 3] = [dx, dy, dz]
    return np.asarray(target, dtype=float) @ local


@dataclass(frozen=True)
class Tool:
    """RAPID tooldata, geometry part: `tframe` is the TCP in the flange (tool0) frame.

    `robhold` FALSE means a stationary tool: `tframe` is then given in the world frame
    and the robot carries the work object.
    """

    tframe: np.ndarray = field(default_factory=lambda: np.eye(4))
    robhold: bool = True

    @classmethod
    def from_rapid(cls, robhold: bool, trans: np.ndarray, rot: np.ndarray) -> Tool:
        """Build from the tooldata fields robhold, tframe.trans (mm) and tframe.rot (wxyz)."""
        return cls(tframe=pose(trans, rot), robhold=bool(robhold))


@dataclass(frozen=True)
class WorkObject:
    """RAPID wobjdata: object frame = uframe ∘ oframe.

    `robhold` TRUE means the robot holds the work object (uframe is then given in
    the flange frame); `ufprog` FALSE means a user frame moved by a mechanical unit,
    which cannot be resolved without that unit's position.
    """

    uframe: np.ndarray = field(default_factory=lambda: np.eye(4))
    oframe: np.ndarray = field(default_factory=lambda: np.eye(4))
    robhold: bool = False
    ufprog: bool = True
    ufmec: str = ""

    @classmethod
    def from_rapid(
        cls,
        robhold: bool,
        ufprog: bool,
        ufmec: str,
        uframe_trans: np.ndarray,
        uframe_rot: np.ndarray,
        oframe_trans: np.ndarray,
        oframe_rot: np.ndarray,
    ) -> WorkObject:
        """Build from the wobjdata fields (translations mm, rotations [w, x, y, z])."""
        return cls(
            uframe=pose(uframe_trans, uframe_rot),
            oframe=pose(oframe_trans, oframe_rot),
            robhold=bool(robhold),
            ufprog=bool(ufprog),
            ufmec=str(ufmec),
        )

    @property
    def frame(self) -> np.ndarray:
        """The object frame uframe ∘ oframe (4, 4)."""
        return np.asarray(self.uframe, float) @ np.asarray(self.oframe, float)


def _tool(tool: Tool | np.ndarray | None) -> Tool:
    if tool is None:
        return Tool()
    if isinstance(tool, Tool):
        return tool
    return Tool(tframe=np.asarray(tool, dtype=float))


def _wobj(wobj: WorkObject | np.ndarray | None) -> WorkObject:
    if wobj is None:
        return WorkObject()
    if isinstance(wobj, WorkObject):
        return wobj
    return WorkObject(uframe=np.asarray(wobj, dtype=float))


def flange_target(
    target: np.ndarray,
    tool: Tool | np.ndarray | None = None,
    wobj: WorkObject | np.ndarray | None = None,
) -> np.ndarray:
    """tool0 (flange) pose in the base frame that puts the TCP on `target`.

    `target` (..., 4, 4) is the TCP pose in the work-object frame (a robtarget's
    trans and rot). Usual case (robot holds the tool): flange = wobj ∘ target ∘ tool⁻¹.
    Robot-held work object with a stationary tool: tool = flange ∘ wobj ∘ target, so
    flange = tool ∘ target⁻¹ ∘ wobj⁻¹. The base frame is taken as the world frame.
    """
    t, w = _tool(tool), _wobj(wobj)
    if not w.ufprog:
        raise KinematicsError(
            f"work object moved by mechanical unit {w.ufmec!r} (ufprog FALSE) cannot be "
            "resolved without that unit's position"
        )
    target = np.asarray(target, dtype=float)
    if w.robhold:
        if t.robhold:
            raise KinematicsError("work object and tool are both held by the robot")
        return t.tframe @ invert_transform(target) @ invert_transform(w.frame)
    if not t.robhold:
        raise KinematicsError("stationary tool used with a work object the robot does not hold")
    return w.frame @ target @ invert_transform(t.tframe)


def tcp_pose(
    flange: np.ndarray,
    tool: Tool | np.ndarray | None = None,
    wobj: WorkObject | np.ndarray | None = None,
) -> np.ndarray:
    """Inverse of `flange_target`: the TCP pose in the work-object frame for a flange pose."""
    t, w = _tool(tool), _wobj(wobj)
    flange = np.asarray(flange, dtype=float)
    if w.robhold:
        return invert_transform(w.frame) @ invert_transform(flange) @ t.tframe
    return invert_transform(w.frame) @ flange @ t.tframe
