"""RAPID's target functions Offs, RelTool and OrientZYX, evaluated on constant data.

Offs moves the position in the frame the target is given in (the work object);
RelTool moves and turns it in its own tool frame, the rotations done first
about x, then about the new y, then about the new z (intrinsic X-Y'-Z'').
Quaternions are [w, x, y, z] as in RAPID; the results have w >= 0.

Plain float arithmetic on one pose at a time: a program evaluates these once
per call in its text, and importing a rotation library would cost the command
line more start-up time than all the calls of a large program.
"""

from __future__ import annotations

import math

from rapidfix.rapid.values import Value, fits_type, to_robtarget

Quat = tuple[float, float, float, float]


def _mul(a: Quat, b: Quat) -> Quat:
    """Hamilton product a * b (rotation b first, then a)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw)


def _shared_unit(q: tuple[float, ...]) -> Quat:
    """_unit(q), worked out once per orientation tuple that many targets share."""
    known = _UNITS.get(id(q))
    if known is not None and known[0] is q:
        return known[1]
    unit = _unit(q)
    if len(_UNITS) >= 256:
        _UNITS.clear()
    _UNITS[id(q)] = (q, unit)
    return unit


def _unit(q: tuple[float, ...]) -> Quat:
    norm = math.sqrt(sum(v * v for v in q))
    if norm == 0.0 or not math.isfinite(norm):
        raise ValueError("the robtarget's orientation is not a quaternion (all zero)")
    w, x, y, z = (v / norm for v in q)
    return (w, x, y, z)


def _positive(q: Quat) -> Quat:
    w, x, y, z = q
    return q if w >= 0 else (-w, -x, -y, -z)


def _about(axis: int, degrees: float) -> Quat:
    half = math.radians(degrees) / 2
    q = [math.cos(half), 0.0, 0.0, 0.0]
    q[axis] = math.sin(half)
    return (q[0], q[1], q[2], q[3])


def _rotate(q: Quat, v: tuple[float, float, float]) -> tuple[float, float, float]:
    """The vector v turned by the unit quaternion q."""
    w, x, y, z = q
    vx, vy, vz = v
    # t = 2 (q_vec x v); v' = v + w t + q_vec x t
    tx, ty, tz = 2 * (y * vz - z * vy), 2 * (z * vx - x * vz), 2 * (x * vy - y * vx)
    return (vx + w * tx + (y * tz - z * ty),
            vy + w * ty + (z * tx - x * tz),
            vz + w * tz + (x * ty - y * tx))


# Robtargets of a program mostly share their orientation, confdata and external-axes
# tuples (the fast path reads them once): the unit quaternion of a shared orientation,
# and whether a shared confdata is whole, are worked out once, kept with the tuples
# themselves so that their ids cannot be reused.
_UNITS: dict[int, tuple[tuple, Quat]] = {}
_WHOLE_CONF: dict[int, tuple] = {}


def _whole(conf: tuple) -> bool:
    """All of the confdata's numbers whole (the robtarget shape checked already)."""
    known = _WHOLE_CONF.get(id(conf))
    if known is not None and known is conf:
        return True
    if not all(map(float.is_integer, conf)):
        return False
    if len(_WHOLE_CONF) >= 256:
        _WHOLE_CONF.clear()
    _WHOLE_CONF[id(conf)] = conf
    return True


def _parts(target: Value) -> tuple[tuple, tuple, tuple, tuple]:
    """(trans, rot, confdata as whole floats, extax) of a robtarget value; raises
    ValueShapeError. A value of the right shape with whole confdata is taken as it
    is (robtargets read from a program usually are)."""
    if fits_type("robtarget", target) and _whole(target[2]):
        trans, rot, conf, extax = target
        return trans, rot, conf, extax
    rt = to_robtarget(target)
    return rt.trans, rt.rot, tuple(float(c) for c in rt.robconf), rt.extax


def offs(target: Value, dx: float, dy: float, dz: float) -> Value:
    """Offs(p, dx, dy, dz): the robtarget value moved by (dx, dy, dz) mm."""
    trans, rot, conf, extax = _parts(target)
    return ((trans[0] + dx, trans[1] + dy, trans[2] + dz), rot, conf, extax)


def reltool(target: Value, dx: float, dy: float, dz: float,
            rx: float = 0.0, ry: float = 0.0, rz: float = 0.0) -> Value:
    """RelTool(p, dx, dy, dz \\Rx \\Ry \\Rz): displaced and rotated in the tool frame (deg)."""
    trans, rot, conf, extax = _parts(target)
    unit = _shared_unit(rot)
    shift = _rotate(unit, (dx, dy, dz))
    moved = (trans[0] + shift[0], trans[1] + shift[1], trans[2] + shift[2])
    if rx == ry == rz == 0.0:
        return (moved, _positive(unit), conf, extax)
    return (moved, _turned(rot, unit, rx, ry, rz), conf, extax)


# (id of a shared orientation tuple, rx, ry, rz) -> (the tuple, its RelTool turn): a
# program turns many targets of one orientation by the same angles (`\Rz:=90`)
_TURNED: dict[tuple, tuple[tuple, Quat]] = {}


def _turned(rot: tuple, unit: Quat, rx: float, ry: float, rz: float) -> Quat:
    """The orientation `rot` (unit quaternion `unit`) turned by RelTool's angles (deg)."""
    # -0.0 equals 0.0 as a key, but its turn may differ in the sign of a zero: not kept
    kept = all(a != 0.0 or math.copysign(1.0, a) > 0 for a in (rx, ry, rz))
    key = (id(rot), rx, ry, rz)
    known = _TURNED.get(key) if kept else None
    if known is not None and known[0] is rot:
        return known[1]
    turn = _mul(_mul(_about(1, rx), _about(2, ry)), _about(3, rz))
    turned = _positive(_unit(_mul(unit, turn)))
    if kept:
        if len(_TURNED) >= 4096:
            _TURNED.clear()
        _TURNED[key] = (rot, turned)
    return turned


def orient_zyx(ez: float, ey: float, ex: float) -> Quat:
    """OrientZYX(ez, ey, ex): turned about z, then the new y, then the new x (deg)."""
    return _positive(_unit(_mul(_mul(_about(3, ez), _about(2, ey)), _about(1, ex))))
