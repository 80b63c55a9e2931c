"""The selection's significance test on validation points, on synthetic residuals.

Truth is built in: the residual is noise plus a known displacement δ, and a
candidate either predicts δ (real), predicts a field unrelated to the residual
(fitted noise), or predicts −δ (wrong way).
"""

import numpy as np
import pytest

from rapidfix.diagnose.residuals import Residuals
from rapidfix.diagnose.selection import Z_MIN, validation_z

N_POINTS = 40  # the virtual cell's validation set
SIGMA_MM = 0.016  # per-axis noise of the virtual cell
TRIALS = 1000


def _case(rng, delta_mm, predicted):
    """z for one validation set: residual δ + noise, the candidate moves it by `predicted`."""
    noise = rng.normal(0.0, SIGMA_MM, (N_POINTS, 3))
    before = delta_mm + noise
    after = before - predicted
    return before, after


def test_fitted_noise_is_rarely_significant():
    rng = np.random.default_rng(11)
    z = []
    for _ in range(TRIALS):
        unrelated = rng.normal(0.0, SIGMA_MM, (N_POINTS, 3))  # fitted on other noise
        before, after = _case(rng, np.zeros((N_POINTS, 3)), unrelated)
        z.append(validation_z(Residuals(before), Residuals(after)))
    z = np.asarray(z)
    # the larger of a t statistic (39 degrees of freedom, P(z ≥ 3) ≈ 0.24 %) and a
    # signed-rank z: at most twice that, and centred a little above 0 (a maximum)
    assert np.mean(z >= Z_MIN) < 0.01
    assert -0.05 < np.mean(z) < 0.35
    assert 0.8 < np.std(z) < 1.2


def test_a_small_real_effect_is_seen_twice_as_clearly_as_by_the_fall_of_the_error():
    rng = np.random.default_rng(12)
    score, paired = [], []
    for _ in range(TRIALS // 4):
        direction = rng.normal(size=(N_POINTS, 3))
        delta = 0.6 * SIGMA_MM * direction / np.linalg.norm(direction, axis=1, keepdims=True)
        before, after = _case(rng, delta, delta)  # the candidate predicts δ exactly
        score.append(validation_z(Residuals(before), Residuals(after)))
        fall = np.sum(before**2, axis=1) - np.sum(after**2, axis=1)
        paired.append(fall.mean() / (fall.std(ddof=1) / np.sqrt(N_POINTS)))
    # per point the projection r·δ = |δ|² + δ·noise: mean |δ|², spread σ|δ|
    assert np.mean(score) == pytest.approx(np.sqrt(N_POINTS) * 0.6, rel=0.1)
    assert np.mean(score) > Z_MIN > np.mean(paired)
    assert abs(np.mean(score) / np.mean(paired) - 2.0) < 0.2


def test_a_change_the_wrong_way_is_negative():
    rng = np.random.default_rng(13)
    delta = rng.normal(0.0, 2 * SIGMA_MM, (N_POINTS, 3))
    before, after = _case(rng, delta, -delta)
    assert validation_z(Residuals(before), Residuals(after)) < -Z_MIN


def test_an_effect_carried_by_a_few_points_is_seen_by_the_signed_ranks():
    # a real effect that is large at three validation points and small at the rest
    # (e.g. one joint far from where it was calibrated): the t statistic's spread is
    # then set by those three points and it can stay below 3; the signed ranks do not
    rng = np.random.default_rng(13)
    z, t_only = [], []
    for _ in range(TRIALS // 10):
        direction = rng.normal(size=(N_POINTS, 3))
        size = np.full(N_POINTS, 0.8 * SIGMA_MM)
        size[:3] = 12.0 * SIGMA_MM
        delta = size[:, None] * direction / np.linalg.norm(direction, axis=1, keepdims=True)
        before, after = _case(rng, delta, delta)
        z.append(validation_z(Residuals(before), Residuals(after)))
        c = np.einsum("ij,ij->i", before, before - after)
        t_only.append(c.mean() / (c.std(ddof=1) / np.sqrt(N_POINTS)))
    assert np.mean(np.asarray(t_only) >= Z_MIN) < 0.05
    assert np.mean(np.asarray(z) >= Z_MIN) > 0.95
