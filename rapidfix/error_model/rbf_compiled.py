"""The Gaussian sums of `joint_rbf` compiled with numba: one pass per angle, few exp().

`RBFNetwork.value` and `.derivative` evaluate Σ_k w_k·g_k (and Σ_k w_k·g_k·d_k) with
g_k = exp(−d_k²/2), d_k = (θ − c_k)/σ, on every target of a program, several times
per target (compensation, path checks, the predicted deviation). numpy spends about
30 ns per angle and centre there, most of it in exp(). On centres spread evenly,
consecutive Gaussians differ by a factor that itself changes by a constant factor:

    g_{k+1} = g_k · r_k,   r_{k+1} = r_k · exp(−s²),   r_k = exp(s·d_k − s²/2),   s = h/σ

(h the spacing), so the sum needs two exp() per run of `RESTART` centres, each run
started exactly at a centre from that centre's own d_k. Runs go outward from the
centre nearest θ, where g is largest, so g only falls along a run (no overflow) and
a run ends when g underflows to zero. The products differ from exp() of each term by
a few hundred ulp at most (relative 1e-13, where g is 1): rounding, not a different
function; tests compare both routes. Centres that are not evenly spaced to rounding
(a hand-edited model) take one exp() per term, in the same compiled pass.

A program of many targets evaluates each network at hundreds of thousands of angles;
large batches read the network from a table instead (`rbf_tables`: its node sums
made here by `node_sums`, read by `table_sums`). A quintic costs a few ns an angle,
the sum about 2 ns a centre. `rbf_tables` makes and reads the table with the same
sums in numpy, where numba is not installed: a change to either belongs there too.

This module imports numba; `joint_rbf` imports it only when numba is installed.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rapidfix.error_model import rbf_tables
from rapidfix.error_model.rbf_tables import TABLE_NODES_PER_WIDTH, Table

#: centres per run of products between two exact exp() (bounds the rounding they add)
RESTART = 16


@njit(cache=True)
def gaussian_sums(x: np.ndarray, centres: np.ndarray, inv_width: float, weights: np.ndarray,
                  step: float, even: bool, slope: bool, out: np.ndarray) -> None:
    """out[i] = Σ_k weights[k]·g_k(x[i]) (slope: ·d_k as well), for every angle x[i].

    `step` is the centres' spacing over the width (s above); `even` whether the
    centres are evenly spaced to rounding, else every term is its own exp()."""
    k = centres.shape[0]
    q = math.exp(-step * step)
    half_s2 = 0.5 * step * step
    for i in range(x.shape[0]):
        xi = x[i]
        acc = 0.0
        if not even or k < 2:
            for j in range(k):
                d = (xi - centres[j]) * inv_width
                g = math.exp(d * d * -0.5)
                acc += g * d * weights[j] if slope else g * weights[j]
            out[i] = acc
            continue
        nearest = math.floor((xi - centres[0]) * inv_width / step + 0.5)
        first = int(min(max(nearest, 0.0), k - 1.0))
        # upward from the nearest centre, then downward from the one below it
        for direction in (1, -1):
            j = first if direction == 1 else first - 1
            while 0 <= j < k:
                d = (xi - centres[j]) * inv_width
                g = math.exp(d * d * -0.5)
                if g == 0.0:
                    break  # further out every term underflows too
                r = math.exp(direction * step * d - half_s2)  # g_{j±1} / g_j
                for _ in range(RESTART):
                    acc += g * d * weights[j] if slope else g * weights[j]
                    j += direction
                    if not 0 <= j < k:
                        break
                    g *= r
                    r *= q
                    if slope:
                        d = (xi - centres[j]) * inv_width
        out[i] = acc


@njit(cache=True)
def gaussian_sums_both(x: np.ndarray, centres: np.ndarray, inv_width: float,
                       weights: np.ndarray, step: float, even: bool, out: np.ndarray,
                       out_slope: np.ndarray) -> None:
    """`gaussian_sums` without and with the slope in one pass (the Newton step needs
    both at one angle): the same terms in the same order, so each equals its own call."""
    k = centres.shape[0]
    q = math.exp(-step * step)
    half_s2 = 0.5 * step * step
    for i in range(x.shape[0]):
        xi = x[i]
        acc = 0.0
        acc_s = 0.0
        if not even or k < 2:
            for j in range(k):
                d = (xi - centres[j]) * inv_width
                g = math.exp(d * d * -0.5)
                acc += g * weights[j]
                acc_s += g * d * weights[j]
            out[i] = acc
            out_slope[i] = acc_s
            continue
        nearest = math.floor((xi - centres[0]) * inv_width / step + 0.5)
        first = int(min(max(nearest, 0.0), k - 1.0))
        for direction in (1, -1):
            j = first if direction == 1 else first - 1
            while 0 <= j < k:
                d = (xi - centres[j]) * inv_width
                g = math.exp(d * d * -0.5)
                if g == 0.0:
                    break
                r = math.exp(direction * step * d - half_s2)
                for _ in range(RESTART):
                    acc += g * weights[j]
                    acc_s += g * d * weights[j]
                    j += direction
                    if not 0 <= j < k:
                        break
                    g *= r
                    r *= q
                    d = (xi - centres[j]) * inv_width
        out[i] = acc
        out_slope[i] = acc_s


def evenly_spaced(centres: np.ndarray) -> bool:
    """Whether the centres are c_0 + k·h to rounding (as `np.linspace` makes them)."""
    k = centres.shape[0]
    if k < 2:
        return True
    h = (centres[-1] - centres[0]) / (k - 1)
    if not h > 0.0:
        return False
    ideal = centres[0] + np.arange(k) * h
    scale = max(1.0, float(np.abs(centres).max()))
    return bool(np.abs(centres - ideal).max() <= 64.0 * np.finfo(float).eps * scale)


@njit(cache=True)
def node_sums(nodes: np.ndarray, centres: np.ndarray, inv_width: float, weights: np.ndarray,
              out: np.ndarray) -> None:
    """out[n, m] = Σ_k weights[k]·He_n(d_k)·g_k at nodes[m], n = 0…3 (He_n the Hermite
    polynomials 1, d, d²−1, d³−3d), each term its own exp(): the sum's n-th derivative
    there is (−1/σ)ⁿ·out[n, m]."""
    for m in range(nodes.shape[0]):
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        s3 = 0.0
        for j in range(centres.shape[0]):
            d = (nodes[m] - centres[j]) * inv_width
            g = math.exp(d * d * -0.5) * weights[j]
            s0 += g
            s1 += g * d
            s2 += g * (d * d - 1.0)
            s3 += g * d * (d * d - 3.0)
        out[0, m] = s0
        out[1, m] = s1
        out[2, m] = s2
        out[3, m] = s3


def sum_tables(centres: np.ndarray, width: float, weights: np.ndarray, lo: float,
               hi: float) -> Table:
    """`rbf_tables.sum_tables` with the node sums compiled: the table for `table_sums`."""
    return rbf_tables.sum_tables(centres, width, weights, lo, hi, node_sums)


@njit(cache=True)
def _exact(xi: float, centres: np.ndarray, inv_width: float, weights: np.ndarray,
           slope: bool) -> float:
    """One angle's sum (slope: its slope sum), each term its own exp()."""
    acc = 0.0
    for j in range(centres.shape[0]):
        d = (xi - centres[j]) * inv_width
        g = math.exp(d * d * -0.5)
        acc += g * d * weights[j] if slope else g * weights[j]
    return acc


@njit(cache=True)
def table_sums(x: np.ndarray, lo: float, inv_h: float, value: np.ndarray,
               slope: np.ndarray, centres: np.ndarray, inv_width: float,
               weights: np.ndarray, which: int, out: np.ndarray,
               out_slope: np.ndarray) -> None:
    """The sums of `gaussian_sums` from the tables of `sum_tables`: `which` 0 the sum
    into `out`, 1 the slope sum into `out_slope`, 2 both. An angle off the table (or
    NaN) takes its terms one exp() each."""
    last = value.shape[0]
    for i in range(x.shape[0]):
        u = (x[i] - lo) * inv_h
        if u >= 0.0 and u <= last:
            j = min(int(u), last - 1)
            t = u - j
            if which != 1:
                c = value[j]
                out[i] = c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4] + t * c[5]))))
            if which != 0:
                c = slope[j]
                out_slope[i] = c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4]
                                                                               + t * c[5]))))
        else:
            if which != 1:
                out[i] = _exact(x[i], centres, inv_width, weights, False)
            if which != 0:
                out_slope[i] = _exact(x[i], centres, inv_width, weights, True)


__all__ = ["RESTART", "TABLE_NODES_PER_WIDTH", "evenly_spaced", "gaussian_sums",
           "gaussian_sums_both", "node_sums", "sum_tables", "table_sums"]
