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
