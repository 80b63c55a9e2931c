"""Frames and ABB conventions: quaternions, poses, tooldata, wobjdata, Offs, RelTool.

Interfaces use mm, degrees and quaternions in ABB order [q1, q2, q3, q4] =
[w, x, y, z], normalised with q1 ≥ 0. Inside everything is a 4×4 transform in mm.
Quaternion <-> matrix conversions are plain numpy, the same arithmetic in the same
order as scipy's Rotation (bit for bit, tests compare them), so that a rewrite does
not import scipy (half a second of start-up); Euler angles and the rare matrix that
is not orthogonal to round-off go through scipy's Rotation, imported when needed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

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
    "matrix_to_rotvec",
    "offs",
    "pose",
    "pose_to_pos_quat",
    "quat_to_matrix",
    "reltool",
    "rotation_xyz",
    "rotvec_to_matrix",
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


def _unit_xyzw(q: np.ndarray) -> np.ndarray:
    """Each [x, y, z, w] row (N, 4) divided by its norm, summed in scipy's order."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    norm = np.sqrt(((x * x + y * y) + z * z) + w * w)
    return q / norm[:, None]


def _xyzw_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of unit [x, y, z, w] quaternions (N, 4)."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    x2, y2, z2, w2 = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    m = np.empty((q.shape[0], 3, 3))
    m[:, 0, 0] = x2 - y2 - z2 + w2
    m[:, 1, 0] = 2 * (xy + zw)
    m[:, 2, 0] = 2 * (xz - yw)
    m[:, 0, 1] = 2 * (xy - zw)
    m[:, 1, 1] = -x2 + y2 - z2 + w2
    m[:, 2, 1] = 2 * (yz + xw)
    m[:, 0, 2] = 2 * (xz + yw)
    m[:, 1, 2] = 2 * (yz - xw)
    m[:, 2, 2] = -x2 - y2 + z2 + w2
    return m


#: a matrix farther than this from orthogonal (max |R Rᵀ − I|) is converted by scipy,
#: which first makes it orthogonal; well below where scipy starts doing so
_ORTHOGONAL_TOL = 1e-14


def _matrix_xyzw(m: np.ndarray) -> np.ndarray:
    """Unit [x, y, z, w] quaternions (N, 4) of rotation matrices (N, 3, 3), by the
    largest of the diagonal and the trace (Shepperd's choice, as scipy makes it)."""
    n = m.shape[0]
    decision = np.empty((n, 4))
    decision[:, 0], decision[:, 1], decision[:, 2] = m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]
    decision[:, 3] = (m[:, 0, 0] + m[:, 1, 1]) + m[:, 2, 2]
    choice = np.argmax(decision, axis=1)
    q = np.empty((n, 4))
    for i in range(3):  # the three diagonal cases, each vectorised over its rows
        rows = np.flatnonzero(choice == i)
        j, k = (i + 1) % 3, (i + 2) % 3
        s = m[rows]
        q[rows, i] = 1 - decision[rows, 3] + 2 * s[:, i, i]
        q[rows, j] = s[:, j, i] + s[:, i, j]
        q[rows, k] = s[:, k, i] + s[:, i, k]
        q[rows, 3] = s[:, k, j] - s[:, j, k]
    rows = np.flatnonzero(choice == 3)
    s = m[rows]
    q[rows, 0] = s[:, 2, 1] - s[:, 1, 2]
    q[rows, 1] = s[:, 0, 2] - s[:, 2, 0]
    q[rows, 2] = s[:, 1, 0] - s[:, 0, 1]
    q[rows, 3] = 1 + decision[rows, 3]
    return _unit_xyzw(q)


def quat_to_matrix(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) from [w, x, y, z] quaternions (normalised first)."""
    q = _as_quat(quat)
    xyzw = np.concatenate([q[..., 1:], q[..., :1]], axis=-1).reshape(-1, 4)
    return _xyzw_matrix(_unit_xyzw(xyzw)).reshape((*q.shape[:-1], 3, 3))


def _rotation_xyzw(flat: np.ndarray) -> np.ndarray:
    """Unit [x, y, z, w] quaternions (N, 4) of matrices (N, 3, 3); a matrix that is not
    a rotation to round-off goes through scipy (its projection, or its error)."""
    gram = flat @ np.swapaxes(flat, 1, 2)
    gram[:, [0, 1, 2], [0, 1, 2]] -= 1.0
    off = ~(np.abs(gram).max(axis=(1, 2), initial=0.0) <= _ORTHOGONAL_TOL) | ~(
        np.linalg.det(flat) > 0.0)
    xyzw = _matrix_xyzw(flat)
    if off.any():
        from scipy.spatial.transform import Rotation  # when used: start-up time

        xyzw[off] = Rotation.from_matrix(flat[off]).as_quat()
    return xyzw


def matrix_to_quat(rot: np.ndarray) -> np.ndarray:
    """[w, x, y, z] quaternions (..., 4), unit length with q1 ≥ 0, from rotation matrices."""
    R = np.asarray(rot, dtype=float)
    xyzw = _rotation_xyzw(R.reshape(-1, 3, 3))
    wxyz = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
    return canonical_quat(wxyz).reshape((*R.shape[:-2], 4))


#: below this angle (rad) the rotation-vector scale is its Taylor series (as scipy's)
_SMALL_ANGLE = 1e-3


def matrix_to_rotvec(rot: np.ndarray) -> np.ndarray:
    """Rotation vectors (N, 3) rad, angle in [0, π], of rotation matrices (N, 3, 3)
    (scipy's `Rotation.from_matrix(rot).as_rotvec()`, the same arithmetic)."""
    q = _rotation_xyzw(np.asarray(rot, dtype=float).reshape(-1, 3, 3))
    q = np.where((q[:, 3] < 0)[:, None], -q, q)
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    angle = 2 * np.arctan2(np.sqrt((x * x + y * y) + z * z), w)
    angle2 = angle * angle
    small = 2 + angle2 / 12 + 7 * angle2 * angle2 / 2880
    with np.errstate(divide="ignore", invalid="ignore"):
        large = angle / np.sin(angle / 2)
    scale = np.where(angle <= _SMALL_ANGLE, small, large)
    return scale[:, None] * q[:, :3]


def rotvec_to_matrix(rotvec: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of rotation vectors (N, 3) rad
    (scipy's `Rotation.from_rotvec(rotvec).as_matrix()`, the same arithmetic)."""
    v = np.asarray(rotvec, dtype=float).reshape(-1, 3)
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    angle = np.sqrt((x * x + y * y) + z * z)
    angle2 = angle * angle
    small = 0.5 - angle2 / 48 + angle2 * angle2 / 3840
    with np.errstate(divide="ignore", invalid="ignore"):
        large = np.sin(angle / 2) / angle
    scale = np.where(angle <= _SMALL_ANGLE, small, large)
    q = np.empty((v.shape[0], 4))
    q[:, :3] = scale[:, None] * v
    q[:, 3] = np.cos(angle / 2)
    return _xyzw_matrix(q)


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
    from scipy.spatial.transform import Rotation

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
