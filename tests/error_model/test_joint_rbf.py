"""The per-joint RBF network: cross-validated width, derivative, valid-range policy."""

import contextlib
import functools
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.error_model.context import Context
from rapidfix.error_model.joint_rbf import JointRBF, OutsideRangeWarning, fit_network
from rapidfix.exceptions import ModelError

STEP = np.radians(5.0)
X = np.arange(np.radians(-150.0), np.radians(150.0) + 1e-12, STEP)


def _holdout_rms(net, f):
    x = np.linspace(X[0], X[-1], 2001)
    return float(np.sqrt(np.mean((net.value(x) - f(x)) ** 2)))


def test_cv_prefers_wide_kernels_for_smooth_errors_and_narrow_for_rough():
    rng = np.random.default_rng(1)
    noise = np.radians(0.0005)

    def smooth(x):
        return np.radians(0.03 * np.sin(0.8 * x) + 0.01)

    def rough(x):  # a 30° gear harmonic: 6 samples per period
        return np.radians(0.02 * np.sin(12.0 * x))

    net_s, cv_s = fit_network(X, smooth(X) + rng.normal(0, noise, X.shape))
    net_r, cv_r = fit_network(X, rough(X) + rng.normal(0, noise, X.shape))
    assert cv_s.width_factor > cv_r.width_factor
    # between the sweep points both predict to about the measurement noise
    assert _holdout_rms(net_s, smooth) < 1.5 * noise
    assert _holdout_rms(net_r, rough) < 3.0 * noise
    # and the CV estimate is an honest estimate of the prediction error (same order)
    assert cv_r.cv_rms < 5 * noise


def test_cv_smooths_pure_noise_to_its_mean():
    rng = np.random.default_rng(2)
    y = np.radians(0.01) + rng.normal(0, np.radians(0.002), X.shape)
    net, cv = fit_network(X, y)
    x = np.linspace(X[0], X[-1], 500)
    # a fit that chases the noise would wander by ~0.002°; the chosen one stays near 0.01°
    assert np.abs(np.degrees(net.value(x)) - 0.01).max() < 0.0015
    assert cv.smoothing >= 1e-4 or cv.width_factor >= 3.0


@functools.cache
def _wavy_network():
    rng = np.random.default_rng(3)
    y = np.radians(0.02 * np.sin(5 * X) + 0.01 * np.cos(2 * X)) + rng.normal(0, 1e-6, X.shape)
    return fit_network(X, y)[0]


@settings(max_examples=25, deadline=None)
@given(st.floats(-149.0, 149.0))
def test_derivative_matches_finite_difference(theta_deg):
    net = _wavy_network()
    x = np.array([np.radians(theta_deg)])
    h = 1e-6
    fd = (net.value(x + h) - net.value(x - h)) / (2 * h)
    assert net.derivative(x) == pytest.approx(fd, rel=1e-5, abs=1e-9)


def test_value_and_derivative_are_the_fitted_basis_times_the_weights():
    # the fit uses the basis matrices, evaluation computes the same sums in place
    net = _wavy_network()
    x = np.linspace(X[0], X[-1], 777)
    np.testing.assert_allclose(net.value(x), net.design(x) @ net.weights, rtol=0, atol=1e-15)
    np.testing.assert_allclose(net.derivative(x), net.design_derivative(x) @ net.weights,
                               rtol=1e-12, atol=1e-15)


def _effect(policy="clamp"):
    nets = [None] * 6
    nets[2], _ = fit_network(X, np.radians(0.01 * np.sin(X) + 0.02))
    return JointRBF(nets, policy=policy)


def test_clamp_policy_uses_the_edge_value_and_warns_once():
    eff = _effect()
    q = np.zeros((3, 6))
    q[:, 2] = [np.radians(170.0), np.radians(200.0), X[-1]]
    with pytest.warns(OutsideRangeWarning, match="joint 3"):
        d = eff.joint_delta(q, Context())
    assert d[0, 2] == pytest.approx(d[2, 2], abs=1e-15)
    assert d[1, 2] == pytest.approx(d[2, 2], abs=1e-15)
    assert np.all(eff.joint_delta_derivative(q, Context())[:2, 2] == 0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        eff.joint_delta(q, Context())  # second time: no warning
    # joints without a network contribute nothing
    assert np.all(d[:, [0, 1, 3, 4, 5]] == 0.0)


def test_refuse_policy_raises_model_error_naming_the_joint():
    eff = _effect("refuse")
    q = np.zeros((1, 6))
    q[0, 2] = np.radians(-151.0)
    with pytest.raises(ModelError, match=r"joint 3 at -151\.000°"):
        eff.joint_delta(q, Context())


def test_too_few_points_is_a_clear_error_and_short_sweeps_still_fit():
    with pytest.raises(ModelError, match="4 distinct measured angles are too few"):
        fit_network(X[:4], np.zeros(4))
    x = np.radians(np.arange(0.0, 61.0, 10.0))  # 7 angles: leave-one-out CV
    net, _ = fit_network(x, np.radians(0.01 + 0.002 * x))
    assert np.degrees(net.value(np.radians([25.0]))) == pytest.approx(
        0.01 + 0.002 * np.radians(25.0), abs=1e-5)


@pytest.mark.parametrize("backend", ["auto", "numpy"])
@pytest.mark.parametrize("factor", [0.5, 1.0, 4.0, 13.0])
@pytest.mark.parametrize("spacing", ["even", "uneven"])
@pytest.mark.parametrize("batch", ["small", "large"])
def test_compiled_sums_are_the_basis_times_the_weights(factor, spacing, batch, backend,
                                                       monkeypatch):
    """Inside `compiled_sums` (the post-processor) the Gaussian sums run compiled when
    numba is installed: products along evenly spaced centres, or one exp per term where
    the centres are not even, and a large batch from the network's table of quintics,
    which numpy reads where numba is not (RAPIDFIX_IK_BACKEND=numpy). Each way they are
    the basis matrix times the weights to rounding, for narrow and wide Gaussians, at
    the ends of the range, at the centres and between."""
    from rapidfix.compiled import BACKEND_ENV
    from rapidfix.error_model.joint_rbf import _TABLE_FROM, RBFNetwork, compiled_sums

    monkeypatch.setenv(BACKEND_ENV, backend)

    rng = np.random.default_rng(7)
    centres = np.linspace(-2.5, 2.8, 120)
    if spacing == "uneven":
        centres = centres + rng.uniform(-1e-3, 1e-3, centres.size) * (centres[1] - centres[0])
    net = RBFNetwork(centres, factor * (centres[1] - centres[0]), -2.5, 2.8, 1e-4)
    net.weights = rng.normal(size=net.n_params) * 1e-3
    size = _TABLE_FROM - 200 if batch == "small" else 3 * _TABLE_FROM
    x = np.concatenate([[-2.5, 2.8], centres[:5], rng.uniform(-2.5, 2.8, size)])
    with compiled_sums():
        value, slope = net.value(x), net.derivative(x)
        both = net.value_and_derivative(x)
    scale = np.abs(net.weights).sum()
    np.testing.assert_allclose(value, net.design(x) @ net.weights, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(slope, net.design_derivative(x) @ net.weights, rtol=0,
                               atol=1e-13 * scale / net.width)
    assert np.array_equal(both[0], value) and np.array_equal(both[1], slope)
    # outside the block: numpy's sums, exactly as before
    assert np.array_equal(net.value(x), _numpy_value(net, x))
    if backend == "numpy":  # a large batch read from the table, a small one summed
        assert np.array_equal(value, net.value(x)) == (batch == "small")


def _numpy_value(net, x):
    k = net.centres.shape[0]
    g = np.exp(-0.5 * np.square(np.subtract.outer(x, net.centres) * (1.0 / net.width)))
    return g @ net.weights[:k] + net.weights[k] + net.weights[k + 1] * net._u(x)


@pytest.mark.parametrize("compiled", [False, True])
@pytest.mark.parametrize("spacing", ["even", "uneven"])
def test_value_and_derivative_at_once_are_each_on_its_own(compiled, spacing):
    """The Newton step takes Δθ and its slope at the same joints from one pass
    (`delta_and_derivative`): the very numbers of the two separate calls, compiled or
    not, with joints outside the range (clamped: slope 0, one warning) and without a
    network."""
    from rapidfix.error_model import ErrorModel
    from rapidfix.error_model.joint_rbf import RBFNetwork, compiled_sums

    rng = np.random.default_rng(11)
    centres = np.linspace(-2.5, 2.8, 90)
    if spacing == "uneven":
        centres = centres + rng.uniform(-1e-3, 1e-3, centres.size) * (centres[1] - centres[0])
    nets = []
    for factor in (0.7, 4.0, 13.0, None, 2.0, 1.0):
        net = None
        if factor is not None:
            net = RBFNetwork(centres, factor * (centres[1] - centres[0]), -2.5, 2.8, 1e-4)
            net.weights = rng.normal(size=net.n_params) * 1e-3
        nets.append(net)
    eff = JointRBF(nets)
    model = ErrorModel("IRB1600-10/1.45", [eff])
    q = rng.uniform(-2.9, 3.1, (500, 6))  # some outside [-2.5, 2.8]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        with compiled_sums() if compiled else contextlib.nullcontext():
            both = model.delta_and_derivative(q)
            eff.reset_warnings()
            apart = model.delta(q), model.delta_derivative(q)
    assert np.array_equal(both[0], apart[0])
    assert np.array_equal(both[1], apart[1])
    outside = (q < -2.5) | (q > 2.8)
    assert outside[:, 0].any() and np.all(both[1][outside[:, 0], 0] == 0.0)
    assert np.all(both[0][:, 3] == 0.0) and np.all(both[1][:, 3] == 0.0)
    assert np.any(both[1][~outside[:, 0], 0] != 0.0)


@pytest.mark.parametrize("backend", ["auto", "numpy"])
def test_the_table_of_a_network_follows_its_weights_and_its_range(backend, monkeypatch):
    """A large batch reads the sums from a table made for the network as it is (made by
    the compiled kernel where numba is installed, by numpy where it is not): made once,
    again for new weights (a model fitted again, or set by a diagnosis) or a new range;
    angles off the table (outside the range, NaN) take their terms one by one. The
    numbers are the basis times the weights each time, by whichever route."""
    from rapidfix.compiled import BACKEND_ENV
    from rapidfix.error_model import rbf_tables
    from rapidfix.error_model.joint_rbf import _TABLE_FROM, RBFNetwork, _kernel, compiled_sums

    monkeypatch.setenv(BACKEND_ENV, backend)
    made = []
    kernel = _kernel()
    owner = rbf_tables if kernel is None else kernel
    real = owner.sum_tables
    monkeypatch.setattr(owner, "sum_tables", lambda *a: made.append(a[3:5]) or real(*a))
    rng = np.random.default_rng(3)
    centres = np.linspace(-1.5, 1.2, 40)
    net = RBFNetwork(centres, 2.0 * (centres[1] - centres[0]), -1.5, 1.2, 1e-4)
    x = np.concatenate([rng.uniform(-1.5, 1.2, _TABLE_FROM), [-1.9, 1.6]])
    for _ in range(2):
        net.weights = rng.normal(size=net.n_params) * 1e-3
        for _ in range(2):
            with compiled_sums():
                value = net.value(x)
            scale = np.abs(net.weights).sum()
            np.testing.assert_allclose(value, net.design(x) @ net.weights, rtol=0,
                                       atol=1e-13 * scale)
    net.lo, net.hi = -1.0, 1.0  # a narrower table: the ends of x are off it
    with compiled_sums():
        value = net.value(np.concatenate([x, [np.nan]]))
    np.testing.assert_allclose(value[:-1], net.design(x) @ net.weights, rtol=0,
                               atol=1e-13 * scale)
    assert np.isnan(value[-1])
    assert made == [(-1.5, 1.2)] * 2 + [(-1.0, 1.0)]


def test_quintic_pieces_are_exact_on_a_quintic():
    """The table's pieces match the value and its first two derivatives at both nodes
    of each interval: a polynomial of degree five is given back to rounding anywhere."""
    from rapidfix.error_model.rbf_tables import quintic_pieces

    coef = np.array([0.3, -1.2, 0.7, 2.0, -0.9, 0.25])  # c0 + c1 x + ... + c5 x^5
    f = np.polynomial.Polynomial(coef)
    nodes = np.linspace(-1.0, 2.0, 7)
    h = nodes[1] - nodes[0]
    pieces = quintic_pieces(f(nodes), f.deriv(1)(nodes), f.deriv(2)(nodes), h)
    t = np.linspace(0.0, 1.0, 11)
    for j in range(nodes.size - 1):
        got = np.polynomial.polynomial.polyval(t, pieces[j])
        np.testing.assert_allclose(got, f(nodes[j] + t * h), rtol=0, atol=1e-12)
