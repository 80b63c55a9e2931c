"""RAPID literals for many targets at once, written the way rapidfix.rapid.format writes one.

A CAM program has a hundred thousand targets: each jointtarget is formatted
with one C-level `%` operation and the trailing zeros of the whole block are
cut by a few plain replacements, which gives exactly the text
`rapidfix.rapid.format.format_jointtarget` gives for each (tests compare them).
"""

from __future__ import annotations

import numpy as np

from rapidfix.kinematics.frames import pose_to_pos_quat
from rapidfix.rapid.format import format_num, format_robtarget

_JOINTS = "[[" + ",".join(["%.6f"] * 6) + "],"


def _trim(text: str) -> str:
    """Trailing zeros and dots cut from numbers written with `%.6f`, each followed by
    ',' or ']'; '-0' written '0'.

    Every number has exactly six decimals, so six passes take every trailing zero of
    the fractions and none of an integer part (the '.' still stands before it). A
    '-' stands only at the start of a number, so '-0.000000' is a negative zero.
    """
    text = text.replace("-0.000000", "0.000000")
    for _ in range(6):
        text = text.replace("0,", ",").replace("0]", "]")
    return text.replace(".,", ",").replace(".]", "]")


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
    joints = [_JOINTS % tuple(row) for row in q_deg.tolist()]
    block = _trim("\n".join(joints)).split("\n") if joints else []
    return [j + e for j, e in zip(block, ext_text)]


def robtarget_literals(tcp: np.ndarray, conf: np.ndarray, extax: np.ndarray) -> list[str]:
    """Robtarget literals for TCP poses (K,4,4) in their work objects, confdata (K,4)."""
    pos, quat = pose_to_pos_quat(np.asarray(tcp, dtype=float)) if len(tcp) else ([], [])
    return [
        format_robtarget(p, q, c, e)
        for p, q, c, e in zip(np.asarray(pos).tolist(), np.asarray(quat).tolist(),
                              np.asarray(conf).tolist(), np.asarray(extax).tolist())
    ]
