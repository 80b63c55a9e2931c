"""A network's Gaussian sums read from a table of quintics: what a large batch takes.

`RBFNetwork.value` and `.derivative` sum K Gaussians per angle (K up to 150), one
exp() per angle and centre: in numpy about 30 ns a term. A program's hundreds of
thousands of angles instead read the sums from a table made once per network: at
nodes σ/`TABLE_NODES_PER_WIDTH` apart over the valid range it holds the sum and its
first three derivatives (each term its own exp()), and between two nodes the
quintic that matches the sum and its first two derivatives at both (the slope sum
likewise, from the derivatives one higher). The quintic differs from the sum by at
most |f⁽⁶⁾|·(h/2)⁶/720 ≤ 15·Σ|w_k|·(h/2σ)⁶/720, about 3e-18·Σ|w_k| at h = σ/200:
below the rounding of the sum itself (tests compare both). Reading it costs a few
vector operations an angle, whatever K.

The compiled kernel (`rbf_compiled`) makes the node sums in one pass and reads the
table in a loop; here both are numpy, with the same terms in the same order, so a
table and its readings are the kernel's to rounding (to the bit where the node
sums agree).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

#: table nodes per Gaussian width (h = σ / this; see the module's docstring)
TABLE_NODES_PER_WIDTH = 200

#: (lo, 1/h, the sum's pieces (n−1, 6), the slope sum's pieces (n−1, 6))
Table = tuple[float, float, np.ndarray, np.ndarray]
#: node_sums(nodes, centres, 1/σ, weights, out (4, n)): the node sums in place
NodeSums = Callable[[np.ndarray, np.ndarray, float, np.ndarray, np.ndarray], None]


def quintic_pieces(value: np.ndarray, slope: np.ndarray, curvature: np.ndarray,
                   h: float) -> np.ndarray:
    """(n−1, 6) coefficients c of the quintic c₀ + c₁t + … + c₅t⁵ on each interval
    (t = 0…1 over h) matching `value`, `slope` and `curvature` (per unit of x) at both
    of its nodes: the pieces of a network's table."""
    p0, d0, s0 = value[:-1], h * slope[:-1], h * h * curvature[:-1]
    p1, d1, s1 = value[1:], h * slope[1:], h * h * curvature[1:]
    rise = p1 - p0
    return np.ascontiguousarray(np.stack([
        p0, d0, 0.5 * s0,
        10.0 * rise - 6.0 * d0 - 4.0 * d1 - 1.5 * s0 + 0.5 * s1,
        -15.0 * rise + 8.0 * d0 + 7.0 * d1 + 1.5 * s0 - s1,
        6.0 * rise - 3.0 * d0 - 3.0 * d1 - 0.5 * s0 + 0.5 * s1], axis=1))


def node_sums(nodes: np.ndarray, centres: np.ndarray, inv_width: float, weights: np.ndarray,
              out: np.ndarray) -> None:
    """out[n, m] = Σ_k weights[k]·He_n(d_k)·g_k at nodes[m], n = 0…3 (He_n the Hermite
    polynomials 1, d, d²−1, d³−3d), each term its own exp(), summed centre by centre
    as `rbf_compiled.node_sums` sums them: the sum's n-th derivative there is
    (−1/σ)ⁿ·out[n, m]."""
    out[...] = 0.0
    s0, s1, s2, s3 = out
    for centre, weight in zip(centres.tolist(), weights.tolist()):
        d = (nodes - centre) * inv_width
        dd = d * d
        g = np.exp(dd * -0.5) * weight
        s0 += g
        s1 += g * d
        s2 += g * (dd - 1.0)
        s3 += g * d * (dd - 3.0)


def sum_tables(centres: np.ndarray, width: float, weights: np.ndarray, lo: float,
               hi: float, sums: NodeSums = node_sums) -> Table:
    """The table of a network over [lo, hi], its node sums made by `sums`: nodes
    σ/`TABLE_NODES_PER_WIDTH` apart at most, the first at lo and the last at hi."""
    n = math.ceil((hi - lo) / width * TABLE_NODES_PER_WIDTH) + 1
    nodes = np.linspace(lo, hi, n)
    h = (hi - lo) / (n - 1)
    made = np.empty((4, n))
    sums(nodes, np.ascontiguousarray(centres, dtype=float), 1.0 / width,
         np.ascontiguousarray(weights, dtype=float), made)
    iw = 1.0 / width
    # the sum's derivatives are S1·(−1/σ), S2/σ², S3·(−1/σ³); the slope sum Σw·g·d is
    # −σ times the first, so its own derivatives are S2·(−1/σ) and S3/σ²
    value = quintic_pieces(made[0], -made[1] * iw, made[2] * iw * iw, h)
    slope = quintic_pieces(made[1], -made[2] * iw, made[3] * iw * iw, h)
    return lo, 1.0 / h, value, slope


def table_sums(x: np.ndarray, lo: float, inv_h: float, pieces: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """(on the table (M,), the quintics' values there (M,)) at angles x (M,): each
    the Horner sum `rbf_compiled.table_sums` forms; an angle off the table (or NaN)
    is not on it, and its value is left to the caller."""
    u = (x - lo) * inv_h
    last = pieces.shape[0]
    on = (u >= 0.0) & (u <= last)
    if not on.all():
        u = np.where(on, u, 0.0)
    j = np.minimum(u.astype(np.intp), last - 1)
    t = u - j
    c = pieces[j]
    out = c[:, 4] + t * c[:, 5]
    for k in (3, 2, 1, 0):
        out *= t
        out += c[:, k]
    return on, out


__all__ = ["TABLE_NODES_PER_WIDTH", "Table", "node_sums", "quintic_pieces", "sum_tables",
           "table_sums"]
