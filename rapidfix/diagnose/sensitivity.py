"""How the predicted points move when one joint's error changes: d(point)/d(Δθ_j).

Screens (which joint pair couples, which joint a driver acts on) project the
residual on these derivatives times a driver's regressors instead of refitting
every variant.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from rapidfix.error_model import ErrorModel, MeasuredPoints, OutsideRangeWarning, jacobian, predict
from rapidfix.kinematics import RobotModel


def joint_derivatives(model: ErrorModel, robot: RobotModel, data: MeasuredPoints) -> np.ndarray:
    """d(predicted point)/d(joint j error) (6, 3N) by forward differences."""
    base = predict(model, robot, data).ravel()
    out = np.empty((6, base.shape[0]))
    h = 1e-6
    q_prev = data.ctx.q_prev
    for j in range(6):  # six joints
        dq = np.zeros(6)
        dq[j] = h
        ctx = data.ctx if q_prev is None else data.ctx.with_q_prev(q_prev + dq)
        moved = data.moved(data.q + dq, ctx)
        out[j] = (predict(model, robot, moved).ravel() - base) / h
    return out


@dataclass(frozen=True)
class ResidualOffModel:
    """The current model's residual `r` (3N,) on the points, `basis` (3N, k) spanning
    what its free parameters can still move, `r_perp` the residual off that span, and
    `grads` (6, 3N) the points' joint derivatives: what a screen regresses on."""

    r: np.ndarray
    basis: np.ndarray
    r_perp: np.ndarray
    grads: np.ndarray

    def off_model(self, cols: np.ndarray) -> np.ndarray:
        """Columns (3N, m) with the part the model's parameters could fit removed."""
        return cols - self.basis @ (self.basis.T @ cols)


def residual_off_model(model: ErrorModel, robot: RobotModel,
                       data: MeasuredPoints) -> ResidualOffModel:
    """The residual a new effect must explain, beyond a refit of the model's own
    parameters (edge-of-range warnings of the per-joint networks silenced)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        r, jac = jacobian(model, robot, data, model.free_params())
        grads = joint_derivatives(model, robot, data)
    basis = np.linalg.qr(jac)[0] if jac.size else np.zeros((r.size, 0))
    return ResidualOffModel(r, basis, r - basis @ (basis.T @ r), grads)
