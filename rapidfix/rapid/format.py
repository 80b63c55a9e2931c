"""RAPID literals for values the post-processor writes: numbers, aggregates,
robtargets, jointtargets, tooldata and declarations.

Numbers are written with a fixed number of decimals and trailing zeros cut
(`12.5`, `-0.000123`); huge values such as unused external axes as `9E+09`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from rapidfix.rapid.values import Value

UNUSED_AXIS = 9e9
_UNUSED_AXES = (UNUSED_AXIS,) * 6


def format_num(x: float, decimals: int = 6) -> str:
    """A num literal: '12.5', '-3', '0.000001', '9E+09'."""
    if not math.isfinite(x):
        raise ValueError(f"{x!r} cannot be written as a RAPID num")
    if abs(x) >= 1e8:
        mantissa, exponent = f"{x:.6E}".split("E")
        mantissa = mantissa.rstrip("0").rstrip(".")
        sign = exponent[0]
        return f"{mantissa}E{sign}{exponent[1:].lstrip('0').rjust(2, '0')}"
    text = f"{x:.{decimals}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def format_string(text: str) -> str:
    """A string literal with quotes and backslashes doubled."""
    return '"' + text.replace("\\", "\\\\").replace('"', '""') + '"'


def format_value(value: Value, decimals: int = 6) -> str:
    """Any evaluated value (num, bool, string, nested aggregates) as a RAPID literal."""
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, (int, float)):
        return format_num(float(value), decimals)
    if isinstance(value, str):
        return format_string(value)
    return "[" + ",".join(format_value(v, decimals) for v in value) + "]"


def _nums(values: Sequence[float], decimals: int) -> str:
    return "[" + ",".join(format_num(float(v), decimals) for v in values) + "]"


def format_robtarget(trans: Sequence[float], rot: Sequence[float],
                     robconf: Sequence[int] = (0, 0, 0, 0),
                     extax: Sequence[float] = _UNUSED_AXES,
                     *, trans_decimals: int = 4, rot_decimals: int = 9) -> str:
    """`[[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax_a,...,eax_f]]` (mm, [w,x,y,z])."""
    conf = "[" + ",".join(str(int(c)) for c in robconf) + "]"
    return (f"[{_nums(trans, trans_decimals)},{_nums(rot, rot_decimals)},{conf},"
            f"{_nums(extax, trans_decimals)}]")


def format_jointtarget(robax: Sequence[float], extax: Sequence[float] = _UNUSED_AXES,
                       *, decimals: int = 6) -> str:
    """`[[j1,...,j6],[eax_a,...,eax_f]]` with joint angles in degrees."""
    return f"[{_nums(robax, decimals)},{_nums(extax, decimals)}]"


def format_pose(trans: Sequence[float], rot: Sequence[float], *, trans_decimals: int = 4,
                rot_decimals: int = 9) -> str:
    return f"[{_nums(trans, trans_decimals)},{_nums(rot, rot_decimals)}]"


def format_tooldata(trans: Sequence[float], rot: Sequence[float], mass: float = 0.001,
                    cog: Sequence[float] = (0.0, 0.0, 0.001), *, robhold: bool = True) -> str:
    """`[robhold,[[x,y,z],[q1..q4]],[mass,[cog],[1,0,0,0],0,0,0]]`."""
    load = f"[{format_num(mass)},{_nums(cog, 4)},[1,0,0,0],0,0,0]"
    return f"[{'TRUE' if robhold else 'FALSE'},{format_pose(trans, rot)},{load}]"


def format_declaration(storage: str, type_name: str, name: str, literal: str,
                       *, local: bool = False) -> str:
    """`[LOCAL ]CONST jointtarget name:=literal;`"""
    prefix = "LOCAL " if local else ""
    return f"{prefix}{storage.upper()} {type_name} {name}:={literal};"
