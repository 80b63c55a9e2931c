"""Joint coupling: one joint's error depending on another joint's angle.

Wrist axes driven through concentric shafts and bevel gears, or a parallelogram
linkage between axes 2 and 3, make joint t's error vary with joint s's angle.
First harmonic: Δθ_t = a · sin θ_s + b · cos θ_s (rad). The per-joint sweep of t
was taken at one fixed θ_s and already holds that value as part of t's offset;
the re-referenced joint offsets take it out again.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import Context
from rapidfix.exceptions import ModelError


class JointCoupling(VectorEffect):
    """Δθ_target = a sin θ_source + b cos θ_source; joints 0-based inside, 1-based in names."""

    type_name: ClassVar[str] = "joint_coupling"
    adds_joint_delta: ClassVar[bool] = True

    def __init__(self, source: int, target: int, name: str | None = None, *,
                 free: bool = True) -> None:
        if not (0 <= source < 6 and 0 <= target < 6) or source == target:
            raise ModelError(f"joint coupling needs two different joints 1..6, got "
                             f"{source + 1} and {target + 1}")
        super().__init__(("sin_rad", "cos_rad"), name, steps=[2e-6, 2e-6], free=free)
        self.source = int(source)
        self.target = int(target)

    def joint_delta(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """The target joint's error from the source joint's angle."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        out = np.zeros_like(q)
        s = q[:, self.source]
        out[:, self.target] = self._p[0] * np.sin(s) + self._p[1] * np.cos(s)
        return out

    def describe(self) -> str:
        """One line naming the joints."""
        return (f"{self.name} (joint {self.target + 1} error depends on joint "
                f"{self.source + 1}'s angle)")

    def _state(self) -> dict[str, Any]:
        return {"source_joint": self.source + 1, "target_joint": self.target + 1}

    @classmethod
    def _from_state(cls, name: str, state: dict[str, Any]) -> JointCoupling:
        return cls(int(state["source_joint"]) - 1, int(state["target_joint"]) - 1, name)
