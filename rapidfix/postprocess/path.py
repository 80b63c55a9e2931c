"""Keeping linear and circular paths when a move becomes joint-interpolated.

MoveL and MoveC ask the controller for a straight line or a circular arc of the
TCP. A MoveAbsJ moves every joint linearly between two joint vectors instead,
which bends the path between its end points. This module measures how far the
TCP strays from the intended curve on the commanded joint path (as the error
model predicts the real robot executes it) and inserts intermediate, compensated
points until every piece is within the tolerance.

All segments of a program are refined together: each round evaluates every open
interval at a few interior fractions in one batch, splits those that stray too
far into k ≈ √(deviation / tolerance) pieces (a chord's deviation falls with the
square of its length), solves the new points in one batch and repeats.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rapidfix import chunks
from rapidfix.kinematics import matrix_to_rotvec, rotvec_to_matrix

#: interior fractions of an interval where its deviation is sampled
SAMPLE_FRACTIONS = np.linspace(0.0, 1.0, 7)[1:-1]
#: refine until the sampled deviation is below this share of the tolerance,
#: leaving a margin for the maximum between samples
MARGIN = 0.8
#: intervals straying less than this share of the tolerance at SCREEN_FRACTIONS are not
#: sampled further
SCREEN = 0.1
SCREEN_FRACTIONS = np.array([1.0 / 3.0, 2.0 / 3.0])
#: the sample fractions the screen has not evaluated already (1/3 and 2/3 are both)
_SAMPLES_LEFT = SAMPLE_FRACTIONS[~np.isin(SAMPLE_FRACTIONS, SCREEN_FRACTIONS)]
MAX_ROUNDS = 8
#: the smallest path tolerance (mm) accepted: the model's own resolution is coarser
#: (cross-validated joint errors of ~1e-4° move the TCP by ~0.002 mm at 1 m), and a
#: finer tolerance only multiplies intermediate points and memory without meaning
MIN_PATH_TOLERANCE_MM = 0.001
MAX_SPLIT = 64
#: factor on the curvature bound of a joint-linear move for what the error model adds
#: (joint-error slopes and bends, link and compliance errors: a few % in practice)
BOUND_SAFETY = 2.0


@dataclass(frozen=True)
class Curves:
    """Intended TCP paths of M segments, each in its own work-object frame.

    `start`, `end` (M,4,4) TCP poses; `via` (M,3) the circle point of a MoveC
    (ignored where `circular` is False). Orientation is interpolated from start
    to end (slerp) on both kinds, as the controller does.
    """

    start: np.ndarray
    end: np.ndarray
    via: np.ndarray
    circular: np.ndarray

    def __post_init__(self) -> None:
        a, b, c = self.start[:, :3, 3], self.end[:, :3, 3], self.via
        m = a.shape[0]
        arc = np.zeros(m, dtype=bool)
        centre, u, v, nrm = (np.zeros((m, 3)) for _ in range(4))
        radius, sweep = np.zeros(m), np.zeros(m)
        rows = np.flatnonzero(self.circular)  # the circle's geometry: MoveC segments only
        if rows.size:
            a, b, c = a[rows], b[rows], c[rows]
            n = np.cross(c - a, b - a)
            n_len = np.linalg.norm(n, axis=1)
            scale = np.maximum(np.linalg.norm(b - a, axis=1), 1e-9)
            on = n_len > 1e-9 * scale * scale
            arc[rows] = on
            nrm[rows] = n / np.where(n_len > 0, n_len, 1.0)[:, None]
            # circle centre: the point of the plane equidistant from a, b and c
            # (circumcentre a + (|u|² v×w + |v|² w×u) / 2|w|², u = b−a, v = c−a, w = u×v = −n)
            ab, ac = b - a, c - a
            num = (
                np.sum(ab * ab, axis=1)[:, None] * np.cross(ac, -n)
                + np.sum(ac * ac, axis=1)[:, None] * np.cross(-n, ab)
            )
            centre[rows] = a + num / np.where(on, 2.0 * n_len * n_len, 1.0)[:, None]
            radius[rows] = np.linalg.norm(a - centre[rows], axis=1)
            u[rows] = (a - centre[rows]) / np.where(radius[rows] > 0, radius[rows], 1.0)[:, None]
            v[rows] = np.cross(nrm[rows], u[rows])
            rel_b = b - centre[rows]
            sweep[rows] = np.mod(np.arctan2(np.sum(rel_b * v[rows], axis=1),
                                            np.sum(rel_b * u[rows], axis=1)), 2 * np.pi)
        object.__setattr__(self, "_arc", arc)
        object.__setattr__(self, "_geom", (centre, radius, u, v, nrm, sweep))
        object.__setattr__(self, "_rel", np.zeros((m, 3)))
        object.__setattr__(self, "_rel_known", np.zeros(m, dtype=bool))

    def _turns(self, seg: np.ndarray) -> np.ndarray:
        """(K,3) rotation vectors of the turn from start to end orientation of segments
        seg (K,), R_a^T R_b in the start's frame; each segment's made when a pose along
        it is first asked for (a path the curvature bound settles needs none)."""
        rel, known = self._rel, self._rel_known  # type: ignore[attr-defined]
        new = np.unique(seg[~known[seg]])
        if new.size:
            rot_a = self.start[new, :3, :3]
            rel[new] = matrix_to_rotvec(np.swapaxes(rot_a, 1, 2) @ self.end[new, :3, :3])
            known[new] = True
        return rel[seg]

    @property
    def degenerate(self) -> np.ndarray:
        """(M,) MoveC segments whose three points are (nearly) on one line."""
        return self.circular & ~self._arc  # type: ignore[attr-defined]

    def _split(self, seg: np.ndarray) -> tuple[np.ndarray | slice, np.ndarray | slice]:
        """(rows on a line, rows on an arc) of segments seg: each kind of row is worked
        out by its own formula only (a slice where all rows are of one kind)."""
        arc = self._arc[seg]  # type: ignore[attr-defined]
        if not arc.any():
            return slice(None), slice(0, 0)
        if arc.all():
            return slice(0, 0), slice(None)
        return np.flatnonzero(~arc), np.flatnonzero(arc)

    def positions(self, seg: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Intended TCP positions (K,3) at path fractions s (K,) of segments seg (K,)."""
        out = np.empty((seg.shape[0], 3))
        on_line, on_arc = self._split(seg)
        seg_l, s_l = seg[on_line], s[on_line]
        a, b = self.start[seg_l, :3, 3], self.end[seg_l, :3, 3]
        out[on_line] = a + s_l[:, None] * (b - a)
        seg_c, s_c = seg[on_arc], s[on_arc]
        geom = self._geom  # type: ignore[attr-defined]
        centre, radius, u, v, sweep = (geom[i][seg_c] for i in (0, 1, 2, 3, 5))
        phi = s_c * sweep
        out[on_arc] = centre + radius[:, None] * (np.cos(phi)[:, None] * u
                                                  + np.sin(phi)[:, None] * v)
        return out

    def poses(self, seg: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Intended TCP poses (K,4,4): positions along the curve, orientation by slerp."""
        rot_a, rel = self.start[seg, :3, :3], self._turns(seg)
        out = np.zeros((seg.shape[0], 4, 4))
        out[:, :3, :3] = rot_a @ rotvec_to_matrix(s[:, None] * rel)
        out[:, :3, 3] = self.positions(seg, s)
        out[:, 3, 3] = 1.0
        return out

    def distance(self, seg: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Distance (K,) mm of points (K,3) from the intended curves of segments seg (K,)."""
        out = np.empty(seg.shape[0])
        on_line, on_arc = self._split(seg)
        seg_l, p = seg[on_line], points[on_line]
        a, b = self.start[seg_l, :3, 3], self.end[seg_l, :3, 3]
        ab = b - a
        length2 = np.sum(ab * ab, axis=1)
        t = np.clip(np.sum((p - a) * ab, axis=1) / np.where(length2 > 0, length2, 1.0), 0, 1)
        out[on_line] = np.linalg.norm(p - a - t[:, None] * ab, axis=1)
        seg_c, p = seg[on_arc], points[on_arc]
        geom = self._geom  # type: ignore[attr-defined]
        centre, radius, nrm = (geom[i][seg_c] for i in (0, 1, 4))
        d = p - centre
        h = np.sum(d * nrm, axis=1)
        r = np.linalg.norm(d - h[:, None] * nrm, axis=1)
        out[on_arc] = np.hypot(r - radius, h)
        return out


#: predicted TCP positions (K,3) in the segments' frames for commanded joints (K,6)
Predict = Callable[[np.ndarray, np.ndarray], np.ndarray]
#: solve intended TCP poses (K,4,4) of segments seg (K,) near seed ideal joints (K,6):
#: returns ideal joints (K,6), commanded joints (K,6) and a success mask (K,)
Solve = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Refinement:
    """Intermediate points to insert, sorted by segment and path fraction.

    `seg` (P,), `s` (P,), `q_ideal` (P,6), `q_cmd` (P,6), `pose` (P,4,4) intended
    TCP pose; per segment: `deviation` (M,) the largest sampled deviation left, mm,
    and `failed` (M,) segments whose path could not be brought within tolerance.
    """

    seg: np.ndarray
    s: np.ndarray
    q_ideal: np.ndarray
    q_cmd: np.ndarray
    pose: np.ndarray
    deviation: np.ndarray
    failed: np.ndarray


def chain_span(axis_points: np.ndarray) -> float:
    """An upper bound (mm) of the distance of any joint-axis point from the base origin,
    whatever the joints: |c1| plus the distances between consecutive axis points (each
    pair is fixed in one link)."""
    points = np.asarray(axis_points, dtype=float)
    return float(np.linalg.norm(points[0]) + np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


def wrist_levers(axis_dirs: np.ndarray, axis_points: np.ndarray,
                 home: np.ndarray) -> tuple[np.ndarray, float]:
    """(point on axis 6 in the flange frame, its distance from axes 4 and 5 at most):
    with a spherical wrist, axes 4 and 5 pass within that distance of the point, so a
    carried point's lever about any wrist axis is at most its distance from it plus
    that much, whatever the joints."""
    dirs = np.asarray(axis_dirs, dtype=float)
    points = np.asarray(axis_points, dtype=float)
    w6 = dirs[5] / np.linalg.norm(dirs[5])
    # where axes 4 and 5 meet (the wrist centre), and its foot on axis 6
    a, b = points[3], points[4]
    d4, d5 = dirs[3] / np.linalg.norm(dirs[3]), dirs[4] / np.linalg.norm(dirs[4])
    n = np.cross(d4, d5)
    t = np.dot(np.cross(b - a, d5), n) / max(np.dot(n, n), 1e-300)
    centre = a + t * d4
    foot = points[5] + np.dot(centre - points[5], w6) * w6
    gap = float(np.linalg.norm(centre - foot) + np.linalg.norm(np.cross(centre - a, d4))
                + np.linalg.norm(np.cross(centre - b, d5)))
    home = np.asarray(home, dtype=float)
    return home[:3, :3].T @ (foot - home[:3, 3]), gap


def line_deviation_bound(span_mm: float, wrist: tuple[np.ndarray, float],
                         flange0: np.ndarray, flange1: np.ndarray, point: np.ndarray,
                         dq: np.ndarray) -> np.ndarray:
    """Upper bound (M,) mm of how far a joint-linear move strays from its chord.

    On q(s) = q0 + s·Δq a revolute chain moves a point p with
    p'' = Σᵢⱼ ΔqᵢΔqⱼ ∂²p/∂qᵢ∂qⱼ, and |∂²p/∂qᵢ∂qⱼ| ≤ 2·r_k, r_k the distance of p
    from the more distal axis k = max(i, j); a curve with |p''| ≤ M stays within M/8
    of its chord. r_k is at most |p| plus the chain's span for the arm's axes, and
    for the wrist's at most p's distance from axis 6 (`wrist_levers`), so the
    wrist's large turns count with the wrist's short lever. Both are taken at the
    ends plus what they can change on the way (2·Σ|Δq|·(|p| + span)).
    flange0, flange1 (M,4,4): the flange at the ends; point (M,3) the carried point
    in the flange frame; Δq (M,6) rad. What the error model adds is covered by
    BOUND_SAFETY (tests check the bound against the sampled prediction). A CAM
    program's 0.5 mm steps come out near 10⁻³ mm: they need no sampling.
    """
    foot, gap = wrist

    def ends(flange: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rot, pos = flange[:, :3, :3], flange[:, :3, 3]
        p = np.einsum("nij,nj->ni", rot, point) + pos
        return np.linalg.norm(p, axis=1), np.linalg.norm(p - (rot @ foot + pos), axis=1)

    reach0, wrist0 = ends(flange0)
    reach1, wrist1 = ends(flange1)
    w = np.abs(dq)
    turn = w.sum(axis=1)
    reach = np.maximum(reach0, reach1) + span_mm
    grow = 2.0 * turn * reach
    r = np.empty_like(w)
    r[:, :3] = (reach + grow)[:, None]
    r[:, 3:] = (np.maximum(wrist0, wrist1) + gap + grow)[:, None]
    before = np.cumsum(w, axis=1) - w  # Σ of the more proximal joints' turns
    m = np.sum(r * w * (w + 2.0 * before), axis=1)  # Σᵢⱼ wᵢwⱼ r_max(i,j)
    return BOUND_SAFETY * 2.0 * m / 8.0


def _sampled(curves: Curves, seg: np.ndarray, qc0: np.ndarray, qc1: np.ndarray,
             predict: Predict, f: np.ndarray) -> np.ndarray:
    k, nf = seg.shape[0], f.shape[0]
    step = qc1 - qc0
    dist = np.empty(k * nf)
    # cache-sized batches of the samples (interval, fraction) in order, each made where
    # it is used (the same numbers): all of them at once were (K, F, 6) floats alive
    # together, 20 MB of `hand_offs`' peak at 200,000 lines
    for start in range(0, k * nf, chunks.PREDICT):
        owner, j = np.divmod(np.arange(start, min(start + chunks.PREDICT, k * nf)), nf)
        q = qc0[owner] + f[j][:, None] * step[owner]
        rows = seg[owner]
        dist[start:start + owner.shape[0]] = curves.distance(rows, predict(rows, q))
    return dist.reshape(k, nf).max(axis=1)


def interval_deviation(
    curves: Curves, seg: np.ndarray, qc0: np.ndarray, qc1: np.ndarray, predict: Predict,
    screen: float = 0.0,
) -> np.ndarray:
    """Largest sampled distance (K,) from the curve of a joint-linear move qc0 -> qc1.

    The distance is geometric (to the whole curve), so where along the curve the
    interval lies does not matter: the controller's timing is not the curve's.
    With `screen` > 0 every interval is first looked at a third and two thirds of
    the way (a single parabolic bow shows there at 8/9 of its peak, a sine-shaped
    S crossing the line half way at 87 %); only those straying more than `screen`
    there are sampled
    at all SAMPLE_FRACTIONS, so a CAM program's many short moves cost two
    evaluations each.
    """
    if screen <= 0.0:
        return _sampled(curves, seg, qc0, qc1, predict, SAMPLE_FRACTIONS)
    dev = _sampled(curves, seg, qc0, qc1, predict, SCREEN_FRACTIONS)
    suspect = np.flatnonzero(dev > screen)
    if suspect.size:  # the screen's fractions are among the samples: not again
        dev[suspect] = np.maximum(dev[suspect], _sampled(
            curves, seg[suspect], qc0[suspect], qc1[suspect], predict, _SAMPLES_LEFT))
    return dev


#: rounds in a row in which a segment's worst piece has not fallen below STALL_RATIO of
#: the round before, after which the segment is given up: split into k ≥ 2 pieces, a
#: chord's deviation falls with 1/k², so a piece that does not holds a jump of the joint
#: path (a wrist or branch flip between its knots), which no number of points closes
STALL_ROUNDS = 2
STALL_RATIO = 0.5


def _stalled(seg: np.ndarray, dev: np.ndarray, worst: np.ndarray,
             stalled: np.ndarray) -> np.ndarray:
    """Segments whose worst piece (`dev` over their pieces `seg` still too far) has not
    fallen below STALL_RATIO × `worst` for STALL_ROUNDS rounds; updates `worst` and
    `stalled`."""
    now = np.zeros(worst.shape[0])
    np.maximum.at(now, seg, dev)
    rows = np.unique(seg)
    same = now[rows] > STALL_RATIO * worst[rows]
    stalled[rows] = np.where(same, stalled[rows] + 1, 0)
    worst[rows] = now[rows]
    given_up = np.zeros(worst.shape[0], dtype=bool)
    given_up[rows[stalled[rows] >= STALL_ROUNDS]] = True
    return given_up


def refine(
    curves: Curves, q_ideal: tuple[np.ndarray, np.ndarray], q_cmd: tuple[np.ndarray, np.ndarray],
    tolerance: float, predict: Predict, solve: Solve, bound: np.ndarray | None = None,
    given_up: np.ndarray | None = None, unsplit: np.ndarray | None = None,
) -> Refinement:
    """Intermediate points that keep every segment within `tolerance` mm of its curve.

    q_ideal, q_cmd: (start (M,6), end (M,6)) joints at the segment ends. `bound` (M,)
    an upper bound of each segment's deviation where one is known (inf elsewhere):
    segments it keeps below SCREEN × tolerance are not sampled, and the bound stands
    as their deviation. `given_up` (M,) bool: segments known not to close (failed at
    once, not sampled). `unsplit` (M,) bool: segments that may take no point (failed
    where they would need one).
    """
    m = curves.start.shape[0]
    seg = np.arange(m)
    s0, s1 = np.zeros(m), np.ones(m)
    qi0, qi1 = (np.asarray(x, float) for x in q_ideal)
    qc0, qc1 = (np.asarray(x, float) for x in q_cmd)
    failed = curves.degenerate.copy()
    deviation = np.zeros(m)
    out_seg, out_s, out_qi, out_qc = [], [], [], []
    target = MARGIN * tolerance
    keep = np.ones(m, dtype=bool)
    if bound is not None:
        settled = np.asarray(bound, dtype=float) <= SCREEN * tolerance
        deviation[settled] = np.asarray(bound, dtype=float)[settled]
        keep &= ~settled
    if given_up is not None:
        failed |= given_up
        keep &= ~given_up
    if not keep.all():
        seg, s0, s1, qi0, qi1, qc0, qc1 = (x[keep] for x in (seg, s0, s1, qi0, qi1, qc0, qc1))
    worst = np.full(m, np.inf)  # per segment: its worst piece in the round before
    stalled = np.zeros(m, dtype=int)  # rounds in a row its worst piece has not halved
    for _ in range(MAX_ROUNDS):
        if seg.size == 0:
            break
        dev = interval_deviation(curves, seg, qc0, qc1, predict, SCREEN * tolerance)
        bad = (dev > target) & ~failed[seg]
        if unsplit is not None and bad.any():
            failed[seg[bad & unsplit[seg]]] = True
            bad &= ~failed[seg]
        if bad.any():
            failed |= _stalled(seg[bad], dev[bad], worst, stalled)
            bad &= ~failed[seg]
        np.maximum.at(deviation, seg[~bad], dev[~bad])
        if not bad.any():
            break
        seg, s0, s1, qi0, qi1, qc0, qc1, dev = (
            x[bad] for x in (seg, s0, s1, qi0, qi1, qc0, qc1, dev)
        )
        k = np.clip(np.ceil(np.sqrt(dev / target) * 1.1), 2, MAX_SPLIT).astype(int)
        owner = np.repeat(np.arange(seg.shape[0]), k - 1)
        j = np.arange(owner.shape[0]) - np.repeat(np.cumsum(k - 1) - (k - 1), k - 1) + 1
        frac = j / k[owner]
        new_seg = seg[owner]
        new_s = s0[owner] + frac * (s1 - s0)[owner]
        seed = qi0[owner] + frac[:, None] * (qi1 - qi0)[owner]
        new_qi, new_qc, ok = solve(new_seg, curves.poses(new_seg, new_s), seed)
        failed[new_seg[~ok]] = True
        out_seg.append(new_seg[ok])
        out_s.append(new_s[ok])
        out_qi.append(new_qi[ok])
        out_qc.append(new_qc[ok])
        # the pieces of every split interval: knots s0, new points..., s1
        starts = np.cumsum(k) - k
        knot_count = k + 1
        knot_owner = np.repeat(np.arange(seg.shape[0]), knot_count)
        kn_s = np.empty(knot_owner.shape[0])
        kn_qi = np.empty((knot_owner.shape[0], 6))
        kn_qc = np.empty((knot_owner.shape[0], 6))
        first = starts + np.arange(seg.shape[0])
        last = first + k
        inner = np.ones(knot_owner.shape[0], dtype=bool)
        inner[first] = False
        inner[last] = False
        kn_s[first], kn_s[last] = s0, s1
        kn_qi[first], kn_qi[last] = qi0, qi1
        kn_qc[first], kn_qc[last] = qc0, qc1
        kn_s[inner], kn_qi[inner], kn_qc[inner] = new_s, new_qi, new_qc
        piece = np.ones(knot_owner.shape[0], dtype=bool)
        piece[last] = False  # a piece starts at every knot but the last of its interval
        alive = ~failed[seg][knot_owner[piece]]
        idx = np.nonzero(piece)[0][alive]
        seg = seg[knot_owner[idx]]
        s0, s1 = kn_s[idx], kn_s[idx + 1]
        qi0, qi1 = kn_qi[idx], kn_qi[idx + 1]
        qc0, qc1 = kn_qc[idx], kn_qc[idx + 1]
    else:
        if seg.size:
            dev = interval_deviation(curves, seg, qc0, qc1, predict)
            np.maximum.at(deviation, seg, dev)
            failed[seg[dev > tolerance]] = True

    cat_seg = np.concatenate(out_seg) if out_seg else np.zeros(0, dtype=int)
    cat_s = np.concatenate(out_s) if out_s else np.zeros(0)
    cat_qi = np.concatenate(out_qi) if out_qi else np.zeros((0, 6))
    cat_qc = np.concatenate(out_qc) if out_qc else np.zeros((0, 6))
    drop = failed[cat_seg]
    cat_seg, cat_s, cat_qi, cat_qc = (x[~drop] for x in (cat_seg, cat_s, cat_qi, cat_qc))
    order = np.lexsort((cat_s, cat_seg))
    cat_seg, cat_s, cat_qi, cat_qc = (x[order] for x in (cat_seg, cat_s, cat_qi, cat_qc))
    return Refinement(
        seg=cat_seg, s=cat_s, q_ideal=cat_qi, q_cmd=cat_qc,
        pose=curves.poses(cat_seg, cat_s), deviation=deviation, failed=failed,
    )
