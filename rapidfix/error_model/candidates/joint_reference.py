"""The per-joint model re-referenced on new data: zero offsets and first harmonics.

The per-joint model takes each joint's error from its own sweep, measured in the
sweep's conditions: one payload, one motion direction, the other joints held at
fixed angles, the registration found from the sweeps themselves. Whatever differs
between those conditions and later use (a deflection, a play taken up the other
way, an axis that is not where the nominal model puts it, a ball that is not where
it was declared) shifts the ball by a fixed amount during that sweep. The sweep
analysis can only express it as an error of the swept joint, and a fixed shift of
a ball circling an axis projects onto the circle's tangent as
c + a sin θ + b cos θ: an offset and a first harmonic of the swept angle.

This effect carries those terms, fitted again on a point set together with the
effects that explain them: Δθ_j = o_j + a_j sin θ_j + b_j cos θ_j. Joint 1's
offset is left out: it is a turn of the base frame, carried by the tracker
registration (the gauge).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import Context

OFFSET_JOINTS = (1, 2, 3, 4, 5)  # 0-based: joints 2..6


def _names() -> list[str]:
    names = [f"j{j + 1}_offset_rad" for j in OFFSET_JOINTS]
    names += [f"j{j}_sin_rad" for j in range(1, 7)]
    names += [f"j{j}_cos_rad" for j in range(1, 7)]
    return names


class JointReference(VectorEffect):
    """Δθ_j = o_j + a_j sin θ_j + b_j cos θ_j (rad), no offset on joint 1."""

    type_name: ClassVar[str] = "joint_reference"
    separable: ClassVar[bool] = True
    adds_joint_delta: ClassVar[bool] = True

    def __init__(self, name: str | None = None, *, free: bool = True) -> None:
        super().__init__(_names(), name, steps=[2e-6] * 17, free=free)

    def joint_delta(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """Offsets and first harmonics of every joint."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        n = len(OFFSET_JOINTS)
        out = self._p[n:n + 6] * np.sin(q) + self._p[n + 6:] * np.cos(q)
        out[:, list(OFFSET_JOINTS)] += self._p[:n]
        return out

    def joint_delta_derivative(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """∂Δθ_j/∂θ_j of the harmonics."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        n = len(OFFSET_JOINTS)
        return self._p[n:n + 6] * np.cos(q) - self._p[n + 6:] * np.sin(q)
