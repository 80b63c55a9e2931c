"""What the rewrite writes, in one place: literals, declarations and MoveAbsJ statements.

Each form is written out for speed and has a general counterpart it must equal
(tests/postprocess/test_emission_forms.py compares them):

- jointtarget literals for many targets at once, their digits built in numpy for the
  whole block (`micro_units`, `_joint_blocks`) — exactly the text
  `rapidfix.rapid.format.format_jointtarget` gives for each;
- robtarget literals, as `format_robtarget` writes them, their positions and
  orientations likewise built in numpy (`number_rows`);
- the jointtarget and robtarget declarations, `format_declaration("CONST", ...)`;
- a MoveL/MoveJ/MoveC statement turned into MoveAbsJ (`joint_statement`), the
  statement `statement_variant` makes from the general edits (`joint_edits`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rapidfix.kinematics import pose_to_pos_quat
from rapidfix.postprocess.resolve import Site
from rapidfix.rapid import MotionInstruction, Program, format_num, format_robtarget

# The ASCII digits of 0..9999 packed in little-endian integers (bytes in text order), and
# of 0..99: the digits of many numbers are looked up at once, not formatted one by one.
_DIGITS4 = np.frombuffer("".join(f"{i:04d}" for i in range(10000)).encode(), np.uint32)
_DIGITS2 = np.frombuffer("".join(f"{i:02d}" for i in range(100)).encode(), np.uint16)
# One number as fixed-width bytes: sign, 8 integer digits, '.', 6 decimals, separator.
_NUMBER = np.dtype([("sign", "u1"), ("int", "u4", 2), ("dot", "u1"), ("dec4", "u4"),
                    ("dec2", "u2"), ("sep", "u1")])
_WIDTH = _NUMBER.itemsize  # 17
# Which integer digits a number of 1..8 digits keeps (leading zeros go); which decimals
# a fraction of 0..6 significant decimals keeps (trailing zeros go).
_INT_KEEP = np.array([[c >= 8 - n for c in range(8)] for n in range(9)], bool)
_DEC_KEEP = np.array([[c < n for c in range(6)] for n in range(7)], bool)
#: rows built at once by `_joint_blocks`: its arrays take about 1 KB a row, which a
#: million-line program would otherwise hold all at once at the emission's peak
_BLOCK_ROWS = 1 << 14


def micro_units(x: np.ndarray, decimals: int = 6) -> np.ndarray:
    """x (|x| < 1e8) in units of 10^-decimals (millionths by default), rounded exactly as
    `'%.{decimals}f' % x` rounds (int64).

    `rint(x * 10^decimals)` is that rounding unless the product lies within its own
    rounding error of a half; those few numbers are formatted by Python and read back.
    """
    y = x * 10.0 ** decimals
    m = np.rint(y)
    near = np.abs(np.abs(y - m) - 0.5) <= np.abs(y) * 1e-15 + 1e-9
    m = m.astype(np.int64)
    if near.any():
        flat = m.reshape(-1)
        idx = np.flatnonzero(near.ravel())
        flat[idx] = [int(f"{v:.{decimals}f}".replace(".", ""))
                     for v in x.ravel()[idx].tolist()]
    return m


_POWERS = 10 ** np.arange(16, dtype=np.int64)


def number_rows(x: np.ndarray, decimals: int) -> list[str] | None:
    """`a,b,c` for each row of x (K,n), every number as `format_num(v, decimals)` writes
    it, built for all rows at once (sign, digits, '.', decimals, separator as bytes, and
    a mask of those a number writes); None when a number is not finite or not below
    1e8 (written with an exponent: format_num's)."""
    rows, n = x.shape
    if not (np.isfinite(x).all() and (np.abs(x) < 1e8).all()):
        return None
    m = micro_units(x, decimals).reshape(-1)
    whole, frac = np.divmod(np.abs(m), _POWERS[decimals])
    if len(whole) and whole.max() >= _POWERS[8]:  # rounded up to 1e8
        return None
    width = 11 + decimals  # sign, 8 digits, '.', decimals, separator
    chars = np.empty((len(m), width), np.uint8)
    chars[:, 0] = ord("-")
    chars[:, 1:9] = whole[:, None] // _POWERS[7::-1] % 10 + ord("0")
    chars[:, 9] = ord(".")
    chars[:, 10:-1] = frac[:, None] // _POWERS[decimals - 1::-1] % 10 + ord("0")
    chars[:, -1] = ord(",")
    chars[n - 1::n, -1] = ord("\n")
    n_int = 1 + (whole[:, None] >= _POWERS[1:8]).sum(axis=1)
    n_dec = decimals - (frac[:, None] % _POWERS[1:decimals + 1] == 0).sum(axis=1)
    keep = np.ones((len(m), width), bool)
    keep[:, 0] = m < 0  # a number that rounds to 0 is written '0'
    keep[:, 1:9] = np.arange(8) >= 8 - n_int[:, None]
    keep[:, 9] = n_dec > 0
    keep[:, 10:-1] = np.arange(decimals) < n_dec[:, None]
    return chars[keep].tobytes().decode("ascii").split("\n")[:rows]


def _joint_blocks(q_deg: np.ndarray) -> list[str]:
    """`[[j1,...,j6],` for each row of q_deg (K,6), |q| < 1e8, numbers as `format_num`
    writes them: all numbers' bytes are built at once in numpy (sign, digits looked up
    four at a time, '.', decimals) and the bytes a number does not write (its sign when
    positive, leading zeros, trailing zeros of the fraction, a '.' without decimals)
    are dropped by one mask."""
    rows = q_deg.shape[0]
    m = micro_units(q_deg).reshape(-1)
    whole, frac = np.divmod(np.abs(m), 1_000_000)
    number = np.empty(len(m), _NUMBER)
    number["sign"] = ord("-")
    high, low = np.divmod(whole, 10_000)
    digits = number["int"]
    digits[:, 0] = _DIGITS4[high]
    digits[:, 1] = _DIGITS4[low]
    number["dot"] = ord(".")
    four, two = np.divmod(frac, 100)
    number["dec4"] = _DIGITS4[four]
    number["dec2"] = _DIGITS2[two]
    number["sep"] = ord(",")
    n_int = 1 + sum((whole >= 10 ** k).view(np.int8) for k in range(1, 8))
    n_dec = 6 - sum((frac % 10 ** k == 0).view(np.int8) for k in range(1, 7))
    keep = np.empty((len(m), _WIDTH), bool)
    keep[:, 0] = m < 0  # a number that rounds to 0 is written '0'
    keep[:, 1:9] = _INT_KEEP[n_int]
    keep[:, 9] = n_dec > 0
    keep[:, 10:16] = _DEC_KEEP[n_dec]
    keep[:, 16] = True
    width = 6 * _WIDTH
    chars = number.view(np.uint8).reshape(rows, width)
    chars[:, width - 1] = ord("]")  # the sixth number's separator
    line = np.empty((rows, width + 4), np.uint8)
    line[:, :2] = ord("[")
    line[:, 2:-2] = chars
    line[:, -2] = ord(",")
    line[:, -1] = ord("\n")
    kept = np.ones((rows, width + 4), bool)
    kept[:, 2:-2] = keep.reshape(rows, width)
    return line[kept].tobytes().decode("ascii").split("\n")[:-1]


def _distinct_texts(rows: np.ndarray, text: Callable[[list], str]) -> list[str]:
    """text(row) for each row of `rows` (K,n), each distinct row written once."""
    if not len(rows):
        return []
    if (rows == rows[0]).all():
        distinct, inverse = rows[:1], np.zeros(len(rows), int)
    elif rows.dtype.kind in "iu" and rows.ndim == 2 and np.prod(
            rows.max(axis=0).astype(float) - rows.min(axis=0).astype(float) + 1) < 2.0 ** 62:
        # integer rows (confdata): one integer per row, the rows' digits in mixed radix,
        # found distinct in one dimension (a sort of rows as rows is several times slower)
        low = rows.min(axis=0)
        radix = (rows.max(axis=0) - low + 1).astype(np.int64)
        weights = np.concatenate([[1], np.cumprod(radix[:-1])]).astype(np.int64)
        key = ((rows - low).astype(np.int64) * weights).sum(axis=1)
        _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
        distinct = rows[first]
    else:
        distinct, inverse = np.unique(rows, axis=0, return_inverse=True)
    texts = [text(row) for row in distinct.tolist()]
    return [texts[i] for i in inverse.reshape(-1).tolist()]


def _extax_texts(extax: np.ndarray) -> list[str]:
    """`[e1,...,e6]]` for each row of extax (K,6); each distinct row formatted once."""
    return _distinct_texts(extax, lambda row: "[" + ",".join(map(format_num, row)) + "]]")


def jointtarget_literals(q_deg: np.ndarray, extax: np.ndarray) -> list[str]:
    """`[[j1,...,j6],[e1,...,e6]]` for joints (K,6) in degrees and external axes (K,6)."""
    q_deg = np.asarray(q_deg, dtype=float)
    ext_text = _extax_texts(np.asarray(extax, dtype=float).reshape(-1, 6))
    if q_deg.size and not np.abs(q_deg).max() < 1e8:  # not finite, or written with E
        joints = ["[[" + ",".join(format_num(v) for v in row) + "]," for row in q_deg.tolist()]
        return [j + e for j, e in zip(joints, ext_text)]
    q_deg = q_deg.reshape(-1, 6)
    out: list[str] = []
    for a in range(0, len(q_deg), _BLOCK_ROWS):  # a block's arrays are ~1 KB a row
        out += map(str.__add__, _joint_blocks(q_deg[a:a + _BLOCK_ROWS]),
                   ext_text[a:a + _BLOCK_ROWS])
    return out


def robtarget_literals(tcp: np.ndarray, conf: np.ndarray, extax: np.ndarray) -> list[str]:
    """Robtarget literals for TCP poses (K,4,4) in their work objects, confdata (K,4):
    what `format_robtarget` writes, the positions and orientations of all rows built at
    once (number_rows), confdata and external axes once per distinct row."""
    if not len(tcp):
        return []
    pos, quat = pose_to_pos_quat(np.asarray(tcp, dtype=float))
    conf, extax = np.asarray(conf), np.asarray(extax, dtype=float)
    trans = number_rows(np.asarray(pos, dtype=float), 4)
    rot = number_rows(np.asarray(quat, dtype=float), 9)
    if trans is None or rot is None:  # a number written with an exponent
        return [format_robtarget(p, q, c, e)
                for p, q, c, e in zip(np.asarray(pos).tolist(), np.asarray(quat).tolist(),
                                      conf.tolist(), extax.tolist())]
    confs = _distinct_texts(conf, lambda row: "[" + ",".join(str(int(c)) for c in row) + "]")
    axes = _distinct_texts(extax, lambda row: "[" + ",".join(format_num(v, 4) for v in row)
                           + "]]")
    return [f"[[{t}],[{r}],{c},{e}" for t, r, c, e in zip(trans, rot, confs, axes)]


def jointtarget_declaration(name: str, literal: str) -> str:
    """`format_declaration("CONST", "jointtarget", name, literal)`, written out."""
    return f"CONST jointtarget {name}:={literal};"


def robtarget_declaration(name: str, literal: str) -> str:
    """`format_declaration("CONST", "robtarget", name, literal)`, written out."""
    return f"CONST robtarget {name}:={literal};"


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
