"""What the rewrite writes, in one place: literals, declarations and MoveAbsJ statements.

Each form is written out for speed and has a general counterpart it must equal
(tests/postprocess/test_emission_forms.py compares them):

- jointtarget literals for many targets at once: one C-level `%` for the whole
  block, trailing zeros cut by one regular-expression pass — exactly the text
  `rapidfix.rapid.format.format_jointtarget` gives for each;
- robtarget literals, as `format_robtarget` writes them;
- the jointtarget declaration, `format_declaration("CONST", "jointtarget", ...)`;
- a MoveL/MoveJ/MoveC statement turned into MoveAbsJ (`joint_statement`), the
  statement `statement_variant` makes from the general edits (`joint_edits`).
"""

from __future__ import annotations

import re

import numpy as np

from rapidfix.kinematics import pose_to_pos_quat
from rapidfix.postprocess.resolve import Site
from rapidfix.rapid import MotionInstruction, Program, format_num, format_robtarget

_JOINTS = "[[" + ",".join(["%.6f"] * 6) + "],"


# Trailing zeros of a fraction, before the ',' or ']' that ends the number (a pattern
# that starts with its literal '0' lets the regular-expression engine skip ahead to it).
_TRAILING = re.compile(r"0+(?=[,\]])")


def _trim(text: str) -> str:
    """Trailing zeros and dots cut from numbers written with `%.6f`, each followed by
    ',' or ']'; '-0' written '0'.

    Every number has exactly six decimals, so its last '0' before ',' or ']' is a
    fraction's: the zeros cut never reach an integer part, whose digits stand before
    the '.'; a '.' left just before ',' or ']' lost all six and goes too (nothing
    else in these literals puts a '.' there). A '-' stands only at the start of a
    number, so '-0.000000' is a negative zero.
    """
    cut = _TRAILING.sub("", text.replace("-0.000000", "0.000000"))
    return cut.replace(".,", ",").replace(".]", "]")


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


def jointtarget_declaration(name: str, literal: str) -> str:
    """`format_declaration("CONST", "jointtarget", name, literal)`, written out."""
    return f"CONST jointtarget {name}:={literal};"


def statement_variant(program: Program, motion: MotionInstruction, edits: list[tuple]) -> str:
    """The statement's text with local (start, end, text) edits (absolute offsets)."""
    text = program.text
    syntax = motion.syntax
    out, pos = [], syntax.start
    for a, b, new in sorted(edits):
        out.append(text[pos:a])
        out.append(new)
        pos = b
    out.append(text[pos:syntax.end])
    return "".join(out)


def joint_edits(site: Site, name: str) -> list[tuple]:
    """Edits turning a MoveL/MoveJ/MoveC statement into MoveAbsJ to `name`."""
    syntax = site.motion.syntax
    edits: list[tuple] = [(syntax.start, syntax.start + len(syntax.name), "MoveAbsJ")]
    targets = site.targets
    if len(targets) == 2:
        edits.append((targets[0].argument.start, targets[1].argument.start, ""))
    value = targets[-1].argument.value
    edits.append((value.start, value.end, name))
    return edits


def joint_statement(text: str, site: Site, name: str) -> str:
    """`statement_variant(program, motion, joint_edits(site, name))`, written out for the
    common case (a CAM program's hundred thousand moves)."""
    syntax = site.motion.syntax
    start = syntax.start
    targets = site.targets
    value = targets[-1].argument.value
    if len(targets) == 2:
        head = text[start + len(syntax.name):targets[0].argument.start]
        head += text[targets[1].argument.start:value.start]
    else:
        head = text[start + len(syntax.name):value.start]
    return f"MoveAbsJ{head}{name}{text[value.end:syntax.end]}"
