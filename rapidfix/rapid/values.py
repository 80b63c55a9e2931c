"""RAPID data types the post-processor needs, as typed views of evaluated values.

An evaluated RAPID value is a float, bool, str or a tuple of values (records
and arrays alike). `RECORD_FIELDS` names the components of the built-in
records so that `p10.trans.x` can be evaluated; `typed_value` turns a value of
a known type into one of the dataclasses below (quaternions [w, x, y, z]).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import repeat
from typing import Any

Value = Any  # float | bool | str | tuple[Value, ...]

# record type -> ((component, component type), ...) as in the RAPID reference
RECORD_FIELDS: dict[str, tuple[tuple[str, str], ...]] = {
    "pos": (("x", "num"), ("y", "num"), ("z", "num")),
    "orient": (("q1", "num"), ("q2", "num"), ("q3", "num"), ("q4", "num")),
    "confdata": (("cf1", "num"), ("cf4", "num"), ("cf6", "num"), ("cfx", "num")),
    "extjoint": tuple((f"eax_{c}", "num") for c in "abcdef"),
    "robjoint": tuple((f"rax_{i}", "num") for i in range(1, 7)),
    "pose": (("trans", "pos"), ("rot", "orient")),
    "robtarget": (("trans", "pos"), ("rot", "orient"), ("robconf", "confdata"),
                  ("extax", "extjoint")),
    "jointtarget": (("robax", "robjoint"), ("extax", "extjoint")),
    "loaddata": (("mass", "num"), ("cog", "pos"), ("aom", "orient"), ("ix", "num"),
                 ("iy", "num"), ("iz", "num")),
    "tooldata": (("robhold", "bool"), ("tframe", "pose"), ("tload", "loaddata")),
    "wobjdata": (("robhold", "bool"), ("ufprog", "bool"), ("ufmec", "string"),
                 ("uframe", "pose"), ("oframe", "pose")),
    "speeddata": (("v_tcp", "num"), ("v_ori", "num"), ("v_leax", "num"), ("v_reax", "num")),
    "zonedata": (("finep", "bool"), ("pzone_tcp", "num"), ("pzone_ori", "num"),
                 ("pzone_eax", "num"), ("zone_ori", "num"), ("zone_leax", "num"),
                 ("zone_reax", "num")),
}

# Types whose declarations are motion targets.
TARGET_TYPES = ("robtarget", "jointtarget")


@dataclass(frozen=True)
class Pose:
    trans: tuple[float, float, float]
    rot: tuple[float, float, float, float]  # [w, x, y, z]


@dataclass(frozen=True)
class RobTarget:
    trans: tuple[float, float, float]
    rot: tuple[float, float, float, float]  # [w, x, y, z]
    robconf: tuple[int, int, int, int]
    extax: tuple[float, float, float, float, float, float]


@dataclass(frozen=True)
class JointTarget:
    robax: tuple[float, float, float, float, float, float]  # degrees
    extax: tuple[float, float, float, float, float, float]


@dataclass(frozen=True)
class LoadData:
    mass: float
    cog: tuple[float, float, float]
    aom: tuple[float, float, float, float]
    ix: float
    iy: float
    iz: float


@dataclass(frozen=True)
class ToolData:
    robhold: bool
    tframe: Pose
    tload: LoadData


@dataclass(frozen=True)
class WobjData:
    robhold: bool
    ufprog: bool
    ufmec: str
    uframe: Pose
    oframe: Pose


@dataclass(frozen=True)
class SpeedData:
    v_tcp: float
    v_ori: float
    v_leax: float
    v_reax: float


@dataclass(frozen=True)
class ZoneData:
    finep: bool
    pzone_tcp: float
    pzone_ori: float
    pzone_eax: float
    zone_ori: float
    zone_leax: float
    zone_reax: float


class ValueShapeError(ValueError):
    """A value whose structure does not fit its declared type."""


def _nums(value: Value, n: int) -> tuple[float, ...]:
    if not isinstance(value, tuple) or len(value) != n:
        raise ValueShapeError(f"expected {n} numbers, got {value!r}")
    if not all(map(isinstance, value, repeat(float))):  # (a bool is never a float)
        raise ValueShapeError(f"expected {n} numbers, got {value!r}")
    return value


def _parts(value: Value, n: int) -> tuple:
    if not isinstance(value, tuple) or len(value) != n:
        raise ValueShapeError(f"expected a record of {n} components, got {value!r}")
    return value


def _num(value: Value) -> float:
    if not isinstance(value, float):
        raise ValueShapeError(f"expected a number, got {value!r}")
    return value


def _bool(value: Value) -> bool:
    if not isinstance(value, bool):
        raise ValueShapeError(f"expected TRUE or FALSE, got {value!r}")
    return value


def to_pose(value: Value) -> Pose:
    trans, rot = _parts(value, 2)
    return Pose(_nums(trans, 3), _nums(rot, 4))


def to_robtarget(value: Value) -> RobTarget:
    trans, rot, conf, extax = _parts(value, 4)
    conf = _nums(conf, 4)
    if not all(map(math.isfinite, conf)):
        raise ValueShapeError(f"expected whole numbers in confdata, got {conf!r}")
    return RobTarget(_nums(trans, 3), _nums(rot, 4), tuple(map(int, conf)), _nums(extax, 6))


def to_jointtarget(value: Value) -> JointTarget:
    robax, extax = _parts(value, 2)
    return JointTarget(_nums(robax, 6), _nums(extax, 6))


def to_loaddata(value: Value) -> LoadData:
    mass, cog, aom, ix, iy, iz = _parts(value, 6)
    return LoadData(_num(mass), _nums(cog, 3), _nums(aom, 4), _num(ix), _num(iy), _num(iz))


def to_tooldata(value: Value) -> ToolData:
    robhold, tframe, tload = _parts(value, 3)
    return ToolData(_bool(robhold), to_pose(tframe), to_loaddata(tload))


def to_wobjdata(value: Value) -> WobjData:
    robhold, ufprog, ufmec, uframe, oframe = _parts(value, 5)
    if not isinstance(ufmec, str):
        raise ValueShapeError(f"expected a string, got {ufmec!r}")
    return WobjData(_bool(robhold), _bool(ufprog), ufmec, to_pose(uframe), to_pose(oframe))


def to_speeddata(value: Value) -> SpeedData:
    return SpeedData(*_nums(value, 4))


def to_zonedata(value: Value) -> ZoneData:
    finep, *rest = _parts(value, 7)
    return ZoneData(_bool(finep), *(_num(v) for v in rest))


_CONVERTERS = {
    "robtarget": to_robtarget,
    "jointtarget": to_jointtarget,
    "tooldata": to_tooldata,
    "wobjdata": to_wobjdata,
    "loaddata": to_loaddata,
    "speeddata": to_speeddata,
    "zonedata": to_zonedata,
    "pose": to_pose,
}


# Robtargets of a CAM program share their orientation, confdata and external-axes
# tuples (rapidfix.rapid.fastpath reads them once): a verdict on such a shared rest is
# kept, with the tuples themselves so that their ids cannot be reused.
_REST_FITS: dict[int, tuple] = {}


def _robtarget_fits(value: Value) -> bool:
    if type(value) is not tuple or len(value) != 4:
        return False
    trans, rot, conf, extax = value
    if type(trans) is not tuple or len(trans) != 3:
        return False
    x, y, z = trans
    if not ((type(x) is float and type(y) is float and type(z) is float)
            or all(map(isinstance, trans, repeat(float)))):  # (float's subclasses too)
        return False
    known = _REST_FITS.get(id(rot))
    if known is not None and known[0] is rot and known[1] is conf and known[2] is extax:
        return True
    if not type(rot) is type(conf) is type(extax) is tuple:
        return False
    if (len(rot), len(conf), len(extax)) != (4, 4, 6):
        return False
    fits = (all(map(isinstance, rot + conf + extax, repeat(float)))
            and all(map(math.isfinite, conf)))
    if fits:
        if len(_REST_FITS) >= 256:
            _REST_FITS.clear()
        _REST_FITS[id(rot)] = (rot, conf, extax)
    return fits


def _jointtarget_fits(value: Value) -> bool:
    if type(value) is not tuple or len(value) != 2:
        return False
    robax, extax = value
    if not type(robax) is type(extax) is tuple or len(robax) != 6 or len(extax) != 6:
        return False
    return all(map(isinstance, robax + extax, repeat(float)))


# Quick tests for the types programs hold by the hundred thousand.
_FITS = {"robtarget": _robtarget_fits, "jointtarget": _jointtarget_fits}


def fits_type(type_name: str, value: Value) -> bool:
    """True when `typed_value(type_name, value)` certainly succeeds, tested
    without building the typed view; False means only: ask typed_value."""
    key = type_name.lower()
    fits = _FITS.get(key)
    if fits is None:
        return key not in _CONVERTERS
    return fits(value)


def typed_value(type_name: str, value: Value) -> Any:
    """A typed view of `value` for the known types, else the value itself.

    Raises ValueShapeError when the value does not fit the type.
    """
    convert = _CONVERTERS.get(type_name.lower())
    return value if convert is None else convert(value)
