"""How the predicted points move when one joint's error changes: d(point)/d(Δθ_j).

Screens (which joint pair couples, which joint a driver acts on) project the
residual on these derivatives times a driver's regressors instead of refitting
every variant.
"""

from __future__ import annotations

import numpy as np

from rapidfix.error_model.fit_effects import MeasuredPoints, predict
from rapidfix.error_model.model import ErrorModel
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
