"""RAPID literals for many targets at once, written the way rapidfix.rapid.format writes one.

A CAM program has a hundred thousand targets: each jointtarget is formatted
with one C-level `%` operation for the whole block, whose trailing zeros are
then cut by one regular-expression pass, which gives exactly the text
`rapidfix.rapid.format.format_jointtarget` gives for each (tests compare them).
"""

from __future__ import annotations

import re

import numpy as np

from rapidfix.kinematics.frames import pose_to_pos_quat
from rapidfix.rapid.format import format_num, format_robtarget

_JOINTS = "[[" + ",".join(["%.6f"] * 6) + "],"


# Trailing zeros of a fraction and then its '.', before the ',' or ']' that ends the number.
_TRAILING = re.compile(r"\.?0+(?=[,\]])")


def _trim(text: str) -> str:
    """Trailing zeros and dots cut from numbers written with `%.6f`, each followed by
    ',' or ']'; '-0' written '0'.

    Every number has exactly six decimals, so its last '0' before ',' or ']' is a
    fraction's: the zeros cut (and the '.' when all six go) never reach an integer
    part, whose digits stand before the '.'. A '-' stands only at the start of a
    number, so '-0.000000' is a negative zero.
    """
    return _TRAILING.sub("", text.replace("-0.000000", "0.000000"))


def jointtarget_literals(q_deg: np.ndarray, extax: np.ndarray) -> list[str]:
    """`[[j1,...,j6],[e1,...,e6]]` for joints (K,6) in degrees and external axes (K,6)."""
    q_deg = np.asarray(q_deg, dtype=float)
    ext_cache: dict[tuple, str] = {}
    ext_text = []
    for row in map(tuple, np.asarray(extax, dtype=float).tolist()):
        text = ext_cache.get(row)
        if text is None:
            text = ext_cache[row] = "[" + ",".join(format_num(v) for v in row) + "]]"
        ext_text.append(text)
    if q_deg.size and not np.abs(q_deg).max() < 1e8:  # not finite, or written with E
        joints = ["[[" + ",".join(format_num(v) for v in row) + "]," for row in q_deg.tolist()]
        return [j + e for j, e in zip(joints, ext_text)]
    # one C-level formatting of every number, one trim of the whole block
    rows = len(q_deg)
    block = _trim("\n".join([_JOINTS] * rows) % tuple(q_deg.ravel().tolist())).split("\n") \
        if rows else []
    return [j + e for j, e in zip(block, ext_text)]


def robtarget_literals(tcp: np.ndarray, conf: np.ndarray, extax: np.ndarray) -> list[str]:
    """Robtarget literals for TCP poses (K,4,4) in their work objects, confdata (K,4)."""
    pos, quat = pose_to_pos_quat(np.asarray(tcp, dtype=float)) if len(tcp) else ([], [])
    return [
        format_robtarget(p, q, c, e)
        for p, q, c, e in zip(np.asarray(pos).tolist(), np.asarray(quat).tolist(),
                              np.asarray(conf).tolist(), np.asarray(extax).tolist())
    ]
