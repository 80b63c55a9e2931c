"""The generic fitter recovers known parameters and counts degenerate ones once."""

import numpy as np
from scipy.spatial.transform import Rotation

from rapidfix.error_model.candidates.compliance import JointCompliance
from rapidfix.error_model.candidates.registration import TrackerFrame
from rapidfix.error_model.candidates.tool_offset import ToolOffset
from rapidfix.error_model.context import Context
from rapidfix.error_model.fit_effects import MeasuredPoints, fit_free_effects
from rapidfix.error_model.model import ErrorModel
from rapidfix.kinematics import load_robot

ROBOT = load_robot("IRB1600-10/1.45")
BALL = np.array([60.0, 80.0, 90.0])


def _data(n=40, seed=0):
    rng = np.random.default_rng(seed)
    q = rng.uniform(np.radians(-50), np.radians(50), (n, 6))
    ctx = Context.from_rows(q, payload_kg=rng.uniform(0, 10, n))
    return q, ctx


def _truth():
    frame = TrackerFrame.from_pose(
        Rotation.from_euler("z", 130, degrees=True).as_matrix(), np.array([2000.0, 1500.0, -400.0])
    )
    tool = ToolOffset()
    tool.set_fitted(np.array([0.25, -0.4, 0.15]))
    comp = JointCompliance(ROBOT.name, BALL)
    comp.set_fitted(np.array([1.2e-6, 0.8e-6, 1e-4, -2e-4, 5e-5, 1e-4]))
    return ErrorModel(ROBOT.name, [frame, tool, comp])


def test_recovers_known_parameters_from_exact_data():
    q, ctx = _data()
    truth = _truth()
    xyz = truth.predict_ball(ROBOT, q, BALL, ctx, frame="world")
    start = _truth()
    guess = start.effects[0].params()
    guess[:3] += 1e-3  # a registration a milliradian off, other effects at zero
    start.effects[0].set_fitted(guess)
    for eff in start.effects[1:]:
        eff.set_fitted(np.zeros(len(eff.param_names)))
    fit = fit_free_effects(start, ROBOT, MeasuredPoints(q, xyz, ctx, BALL))
    assert fit.converged
    assert fit.rank == 6 + 3 + 6
    np.testing.assert_allclose(fit.params, truth.free_params(), rtol=1e-5, atol=1e-9)
    assert np.sqrt(fit.rss / fit.n_obs) < 1e-6


def test_noise_gives_honest_uncertainties_and_duplicates_count_once():
    q, ctx = _data(60, seed=1)
    truth = _truth()
    rng = np.random.default_rng(5)
    sigma = 0.01
    xyz = truth.predict_ball(ROBOT, q, BALL, ctx, frame="world") + rng.normal(0, sigma, (60, 3))
    model = _truth()
    model.effects = [model.effects[0], ToolOffset(), ToolOffset("tool_again"), model.effects[2]]
    fit = fit_free_effects(model, ROBOT, MeasuredPoints(q, xyz, ctx, BALL))
    assert fit.rank == 6 + 3 + 6  # the second tool offset adds nothing
    tool = model.effects[1].params() + model.effects[2].params()
    err = tool - truth.effects[1].params()
    std = model.effects[1].uncertainty
    assert np.all(np.abs(err) < 5 * np.hypot(std, model.effects[2].uncertainty))
    assert 0.7 * sigma < np.sqrt(fit.rss / (fit.n_obs - fit.rank)) < 1.3 * sigma



def _counted_fixed_compliance(calls):
    """A fixed compliance effect whose evaluations are counted in `calls`."""
    fixed = JointCompliance(ROBOT.name, BALL, free=False)
    fixed.set_fitted(np.array([2e-6, -1e-6, 3e-4, 1e-4, -5e-5, 2e-4]))
    plain = fixed.joint_delta

    def joint_delta(q, ctx):
        calls.append(1)
        return plain(q, ctx)

    fixed.joint_delta = joint_delta
    return fixed


def test_fixed_effects_are_evaluated_once_per_fit_and_the_fit_is_unchanged():
    """A fit holds the fixed effects' joint errors for its own points: the same numbers as
    evaluating them every time (the fitter's inner routine, unheld), far fewer calls."""
    from rapidfix.error_model.fit_effects import _fit

    q, ctx = _data(50, seed=3)
    truth = _truth()
    xyz = truth.predict_ball(ROBOT, q, BALL, ctx, frame="world") + 0.01
    fits, calls = [], []
    for held in (False, True):
        model = _truth()
        counted = []
        model.effects.append(_counted_fixed_compliance(counted))
        data = MeasuredPoints(q, xyz, ctx, BALL)
        fits.append(fit_free_effects(model, ROBOT, data) if held
                    else _fit(model, ROBOT, data, 25, 1e-7))
        calls.append(len(counted))
        assert model._held is None  # released after the fit
    np.testing.assert_array_equal(fits[0].params, fits[1].params)
    np.testing.assert_array_equal(fits[0].residuals, fits[1].residuals)
    assert calls[1] == 1 < calls[0]


def test_a_held_model_computes_other_joints_afresh():
    """Inside the hold, other joints (or another context) are not served the held values."""
    q, ctx = _data(20, seed=4)
    model = _truth()
    counted = []
    model.effects.append(_counted_fixed_compliance(counted))
    unheld = ErrorModel(ROBOT.name, model.effects)
    other, other_ctx = _data(20, seed=5)
    with model.fixed_effects_held(q, ctx):
        np.testing.assert_array_equal(model.delta(q, ctx), unheld.delta(q, ctx))
        np.testing.assert_array_equal(model.delta(other, other_ctx),
                                      unheld.delta(other, other_ctx))
        np.testing.assert_array_equal(model.delta(q.copy(), ctx), unheld.delta(q, ctx))
    assert len(counted) == 6  # held once; the other joints and the copy computed afresh
