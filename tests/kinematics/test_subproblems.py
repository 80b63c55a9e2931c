"""Paden–Kahan subproblems against rotations built independently with scipy."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rapidfix.kinematics.subproblems import subproblem1, subproblem2, subproblem3


def rotate(w, r, theta, p):
    """Rotate points p about the line r + s·w by theta (scipy, independent of the code)."""
    R = Rotation.from_rotvec(w * theta[..., None]).as_matrix()
    return np.einsum("...ij,...j->...i", R, p - r) + r


def random_units(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def angle_diff(a, b):
    return np.abs(np.angle(np.exp(1j * (a - b))))


def test_subproblem1_recovers_random_rotations():
    rng = np.random.default_rng(1)
    n = 2000
    w, r, p = random_units(rng, n), rng.normal(size=(n, 3)) * 300, rng.normal(size=(n, 3)) * 500
    theta = rng.uniform(-np.pi, np.pi, n)
    q = rotate(w, r, theta, p)
    got, ok = subproblem1(w, r, p, q)
    assert ok.all()
    assert angle_diff(got, theta).max() < 1e-10


def test_subproblem1_flags_inconsistent_points():
    w, r = np.array([0.0, 0.0, 1.0]), np.zeros(3)
    _, ok = subproblem1(
        w,
        r,
        np.array([[1.0, 0, 0], [1.0, 0, 0], [0, 0, 5.0]]),
        np.array([[0, 2.0, 0], [0, 1.0, 0.5], [0, 0, 5.0]]),
    )
    assert ok.tolist() == [False, False, False]  # other radius, other height, on the axis


def test_subproblem2_returns_both_solutions_of_random_pairs():
    rng = np.random.default_rng(2)
    n = 2000
    w1, w2 = random_units(rng, n), random_units(rng, n)
    r, p = rng.normal(size=(n, 3)) * 100, rng.normal(size=(n, 3)) * 400
    t1, t2 = rng.uniform(-np.pi, np.pi, n), rng.uniform(-np.pi, np.pi, n)
    q = rotate(w1, r, t1, rotate(w2, r, t2, p))
    g1, g2, ok = subproblem2(w1, w2, r, p, q)
    assert ok.all()
    err = np.minimum(
        np.maximum(angle_diff(g1[:, 0], t1), angle_diff(g2[:, 0], t2)),
        np.maximum(angle_diff(g1[:, 1], t1), angle_diff(g2[:, 1], t2)),
    )
    well_posed = np.abs(np.einsum("ij,ij->i", w1, w2)) < 0.99
    assert err[well_posed].max() < 1e-7
    for k in range(2):  # both returned pairs are solutions
        back = rotate(w1, r, g1[:, k], rotate(w2, r, g2[:, k], p))
        assert np.abs(back - q).max() < 1e-8


def test_subproblem2_infeasible_when_distances_differ():
    w1, w2, r = np.array([0, 0, 1.0]), np.array([0, 1.0, 0]), np.zeros(3)
    _, _, ok = subproblem2(w1, w2, r, np.array([1.0, 0, 0]), np.array([0, 0, 2.0]))
    assert not ok


def test_subproblem3_solutions_have_the_asked_distance():
    rng = np.random.default_rng(3)
    n = 2000
    w, r = random_units(rng, n), rng.normal(size=(n, 3)) * 100
    p, q = rng.normal(size=(n, 3)) * 400, rng.normal(size=(n, 3)) * 400
    theta = rng.uniform(-np.pi, np.pi, n)
    delta = np.linalg.norm(rotate(w, r, theta, p) - q, axis=1)
    got, ok = subproblem3(w, r, p, q, delta)
    assert ok.all()
    for k in range(2):
        d = np.linalg.norm(rotate(w, r, got[:, k], p) - q, axis=1)
        assert np.abs(d - delta).max() < 1e-8
    assert np.minimum(angle_diff(got[:, 0], theta), angle_diff(got[:, 1], theta)).max() < 1e-6


@pytest.mark.parametrize(("delta", "feasible"), [(0.4, False), (1.0, True), (2.6, False)])
def test_subproblem3_reach(delta, feasible):
    # p circles the z axis at radius 1 in the plane z = 0; q at radius 1.5: 0.5 ≤ δ ≤ 2.5
    w, r = np.array([0, 0, 1.0]), np.zeros(3)
    _, ok = subproblem3(w, r, np.array([1.0, 0, 0]), np.array([1.5, 0, 0]), np.array(delta))
    assert bool(ok) is feasible


def test_subproblem3_at_the_edge_of_reach_is_exact():
    w, r = np.array([0, 0, 1.0]), np.zeros(3)
    got, ok = subproblem3(w, r, np.array([1.0, 0, 0]), np.array([0, 1.5, 0]), np.array(2.5))
    assert ok
    assert angle_diff(got, -np.pi / 2).max() < 1e-12  # fully stretched: one double root


def test_one_axis_routes_are_the_general_formulas_bit_for_bit():
    """Subproblem 1 without its checks and `rotate_vectors` take one axis's numbers as
    scalars and the vectors by components (the IK's calls): the same products and sums
    in the same order as the general formulas on (..., 3) arrays, so the same bits, with
    broadcasting vectors and angles; subproblem 2 without its checks gives the checked
    call's angles and calls everything feasible."""
    from rapidfix.kinematics.screws import rotate_vectors
    from rapidfix.kinematics.subproblems import _angle, _angle_about

    rng = np.random.default_rng(9)
    w = rng.normal(size=3)
    w /= np.linalg.norm(w)
    u = rng.normal(size=(40, 1, 3)) * 300.0
    v = rng.normal(size=(1, 7, 3)) * 300.0
    v[0, 0] = u[0, 0]  # a zero angle, and -0.0 components
    v[0, 1] = -0.0
    general = _angle(w, u, v)
    assert general.shape == (40, 7)
    assert np.array_equal(_angle_about(w, u, v), general)
    assert np.array_equal(_angle_about(w[None], u, v), _angle(w[None], u, v))
    theta, ok = subproblem1(w, np.zeros(3), u, v, tol=np.inf)
    assert np.array_equal(theta, general) and ok.all()

    angles = rng.uniform(-4.0, 4.0, (40, 7))
    angles[0, :3] = [0.0, -0.0, 1e-12]
    per_row = np.broadcast_to(w, (40, 7, 3))  # the general route: one axis per vector
    got = rotate_vectors(w, angles, u)
    assert got.shape == (40, 7, 3)
    assert np.array_equal(got, rotate_vectors(per_row, angles, u))
    np.testing.assert_allclose(np.linalg.norm(got, axis=-1),
                               np.broadcast_to(np.linalg.norm(u, axis=-1), (40, 7)),
                               rtol=1e-13)

    w1, w2 = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    p = np.array([0.0, 0.0, 1.0])
    q = rng.normal(size=(50, 3))
    q /= np.linalg.norm(q, axis=1)[:, None]
    t1, t2, ok = subproblem2(w1, w2, np.zeros(3), p, q)
    s1, s2, all_ok = subproblem2(w1, w2, np.zeros(3), p, q, tol=np.inf)
    assert np.array_equal(s1, t1) and np.array_equal(s2, t2) and ok.all() and all_ok.all()
    s1, s2, all_ok = subproblem2(w1, w2, np.zeros(3), p, 2.0 * q, tol=np.inf)
    assert all_ok.all()  # no check: a point of another norm is not refused
    assert not subproblem2(w1, w2, np.zeros(3), p, 2.0 * q)[2].any()
