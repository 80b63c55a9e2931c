"""Generic least-squares fit of every free effect of a model to measured ball positions.

The model predicts where the tracker sees the target ball (`ErrorModel.predict_ball`
with frame="world"); the free effects' stacked parameter vector is fitted to the
measured positions by Levenberg–Marquardt with a finite-difference Jacobian, knowing
nothing of what the effects are. Columns are scaled to unit norm and every step is
solved by a truncated, damped SVD, so parameters the data cannot tell
apart (an effect that duplicates another) are left at their minimum-norm
combination instead of blowing up; the number of directions kept is the fit's
effective parameter count (`rank`), which penalised criteria (BIC) use.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rapidfix.error_model.context import Context
from rapidfix.error_model.model import ErrorModel
from rapidfix.exceptions import ModelError

#: singular values below this fraction of the largest (unit-scaled columns) are degenerate
RCOND = 1e-7
_MAX_ITER = 25
#: stop when a step moves the predicted points by less than this (RMS, mm), far below
#: any tracker's noise
_STEP_TOL_MM = 1e-5


@dataclass(frozen=True)
class MeasuredPoints:
    """Commanded joints q (N, 6) rad, measured ball centres xyz (N, 3) mm in the tracker
    frame, the poses' context and the declared ball offset (3,) mm in the flange frame.

    `ball_mm` is the setup's first ball (nest 0: where a payload without its own
    centre of gravity is taken to hang, and the sweeps' ball). `balls_mm` (N, 3), when
    the flange carries several nests, is the ball each row measured; None: every row
    measured `ball_mm`. Predictions use `row_balls_mm`.
    """

    q: np.ndarray
    xyz: np.ndarray
    ctx: Context
    ball_mm: np.ndarray
    balls_mm: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.q.shape[0])

    @property
    def row_balls_mm(self) -> np.ndarray:
        """The ball each row measured: (N, 3) mm, or (3,) when every row measured one ball."""
        return self.ball_mm if self.balls_mm is None else self.balls_mm

    @property
    def distinct_balls_mm(self) -> np.ndarray:
        """The distinct balls (K, 3) mm the rows measured."""
        return np.unique(np.atleast_2d(self.row_balls_mm), axis=0)

    def take(self, index: np.ndarray | slice) -> MeasuredPoints:
        """The subset of rows `index` (mask, indices or slice)."""
        balls = None if self.balls_mm is None else self.balls_mm[index]
        return MeasuredPoints(self.q[index], self.xyz[index], self.ctx.take(index),
                              self.ball_mm, balls)

    def moved(self, q: np.ndarray, ctx: Context) -> MeasuredPoints:
        """The same measurements taken at other commanded joints and context."""
        return MeasuredPoints(q, self.xyz, ctx, self.ball_mm, self.balls_mm)


@dataclass(frozen=True)
class EffectsFit:
    """Result: parameters and standard deviations (stacked like `free_params()`),
    residuals (N, 3) mm (measured − predicted), residual sum of squares, number of
    coordinates, effective number of parameters, iterations and convergence."""

    params: np.ndarray
    std: np.ndarray
    residuals: np.ndarray
    rss: float
    n_obs: int
    rank: int
    iterations: int
    converged: bool


def predict(model: ErrorModel, robot: object, data: MeasuredPoints) -> np.ndarray:
    """Predicted tracker-frame ball centres (N, 3) mm."""
    return model.predict_ball(robot, data.q, data.row_balls_mm, data.ctx, frame="world")


def _steps(model: ErrorModel, p: np.ndarray) -> np.ndarray:
    parts = []
    for eff in model.free_effects():
        n = len(eff.param_names)
        steps = getattr(eff, "steps", None)
        parts.append(np.asarray(steps, dtype=float) if steps is not None and len(steps) == n
                     else np.full(n, 1e-6))
    h = np.concatenate(parts) if parts else np.zeros(0)
    return np.maximum(h, 1e-9 * np.abs(p))


def jacobian(model: ErrorModel, robot: object, data: MeasuredPoints,
             p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Residual vector (3N,) at p and its Jacobian (3N, P) by forward differences."""
    model.set_free_params(p)
    base = predict(model, robot, data).ravel()
    h = _steps(model, p)
    jac = np.empty((base.shape[0], p.shape[0]))
    for i in range(p.shape[0]):  # one model evaluation per parameter, each vectorised
        step = p.copy()
        step[i] += h[i]
        model.set_free_params(step)
        jac[:, i] = (predict(model, robot, data).ravel() - base) / h[i]
    model.set_free_params(p)
    return base - data.xyz.ravel(), jac


def _svd(jac: np.ndarray, rcond: float) -> tuple[np.ndarray, ...]:
    """SVD of the unit-column-scaled Jacobian, truncated at rcond; returns scale, u, s, vt."""
    norms = np.linalg.norm(jac, axis=0)
    scale = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 0.0)
    u, s, vt = np.linalg.svd(jac * scale, full_matrices=False)
    keep = s > rcond * (s[0] if s.size else 0.0)
    return scale, u[:, keep], s[keep], vt[keep]


def fit_free_effects(model: ErrorModel, robot: object, data: MeasuredPoints, *,
                     max_iter: int = _MAX_ITER, rcond: float = RCOND) -> EffectsFit:
    """Fit the free effects' parameters to the measured points; writes them into the model.

    The uncertainties (also written to each effect's `uncertainty`) are the
    Gauss–Newton covariance scaled by the residual variance per coordinate.
    """
    with model.fixed_effects_held(data.q, data.ctx):
        return _fit(model, robot, data, max_iter, rcond)


def _fit(model: ErrorModel, robot: object, data: MeasuredPoints, max_iter: int,
         rcond: float) -> EffectsFit:
    p = model.free_params()
    if p.size == 0:
        r = predict(model, robot, data) - data.xyz
        return EffectsFit(p, p, -r, float(np.sum(r**2)), r.size, 0, 0, True)
    n_obs = 3 * len(data)
    if n_obs <= p.size:
        raise ModelError(f"{len(data)} points are too few to fit {p.size} parameters")
    r, jac = jacobian(model, robot, data, p)
    rss = float(r @ r)
    converged = False
    damping = 1e-4  # Levenberg–Marquardt λ, relative to the scaled curvature
    iterations = 0
    while iterations < max_iter and not converged:
        iterations += 1
        scale, u, s, vt = _svd(jac, rcond)
        ur = u.T @ r
        improved = False
        for _ in range(12):  # raise λ until the step lowers the residual
            step = -scale * (vt.T @ (ur * s / (s**2 + damping)))
            model.set_free_params(p + step)
            r_new = predict(model, robot, data).ravel() - data.xyz.ravel()
            rss_new = float(r_new @ r_new)
            if rss_new <= rss:
                improved = True
                break
            damping *= 10.0
        if not improved:
            model.set_free_params(p)
            converged = True
            break
        change = np.sqrt(np.mean((jac @ step) ** 2))
        p, r = p + step, r_new
        converged = change < _STEP_TOL_MM or rss - rss_new < 1e-9 * rss
        rss = rss_new
        damping = max(damping / 10.0, 1e-12)
        if not converged:
            r, jac = jacobian(model, robot, data, p)
            rss = float(r @ r)
    r, jac = jacobian(model, robot, data, p)
    scale, _, s, vt = _svd(jac, rcond)
    rank = int(s.size)
    rss = float(r @ r)
    sigma2 = rss / max(n_obs - rank, 1)
    cov_diag = (scale**2) * np.sum((vt / s[:, None]) ** 2, axis=0) * sigma2
    std = np.sqrt(cov_diag)
    model.set_free_params(p, std)
    return EffectsFit(p, std, -r.reshape(-1, 3), rss, n_obs, rank, iterations, converged)
