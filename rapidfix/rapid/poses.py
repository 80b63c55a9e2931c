"""RAPID's target functions Offs and RelTool, evaluated on constant robtargets.

Offs moves the position in the frame the target is given in (the work object);
RelTool moves and turns it in its own tool frame, the rotations done first
about x, then about the new y, then about the new z (intrinsic X-Y'-Z'').
Quaternions are [w, x, y, z] as in RAPID; the result has w >= 0.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from rapidfix.rapid.values import Value, to_robtarget


def _rotation(q_wxyz: tuple[float, ...]) -> Rotation:
    w, x, y, z = q_wxyz
    return Rotation.from_quat([x, y, z, w])


def _wxyz(rotation: Rotation) -> tuple[float, float, float, float]:
    x, y, z, w = rotation.as_quat()
    q = np.array([w, x, y, z])
    if q[0] < 0:
        q = -q
    return tuple(float(v) for v in q)


def offs(target: Value, dx: float, dy: float, dz: float) -> Value:
    """Offs(p, dx, dy, dz): the robtarget value moved by (dx, dy, dz) mm."""
    rt = to_robtarget(target)
    trans = (rt.trans[0] + dx, rt.trans[1] + dy, rt.trans[2] + dz)
    return (trans, rt.rot, tuple(float(c) for c in rt.robconf), rt.extax)


def reltool(target: Value, dx: float, dy: float, dz: float,
            rx: float = 0.0, ry: float = 0.0, rz: float = 0.0) -> Value:
    """RelTool(p, dx, dy, dz \\Rx \\Ry \\Rz): displaced and rotated in the tool frame (deg)."""
    rt = to_robtarget(target)
    if np.linalg.norm(rt.rot) == 0.0:
        raise ValueError("the robtarget's orientation is not a quaternion (all zero)")
    rotation = _rotation(rt.rot)
    moved = np.asarray(rt.trans) + rotation.apply([dx, dy, dz])
    turned = rotation * Rotation.from_euler("XYZ", [rx, ry, rz], degrees=True)
    trans = tuple(float(v) for v in moved)
    return (trans, _wxyz(turned), tuple(float(c) for c in rt.robconf), rt.extax)
