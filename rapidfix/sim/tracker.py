"""A virtual laser tracker: where it stands (unknown to the fitter) and how it measures.

Frame convention, shared with `rapidfix.measure.registration`:
p_tracker = (1 + scale) · R · p_robot + t, i.e. p_robot = R.T (p_tracker − t) / (1 + scale)
(the paper's eq. 6 p = Q⁻¹(p' − T) with Q = R, T = t, and scale = 0 for a perfect tracker).
Noise: independent, per axis, σ = sigma0 + sigma_per_m × range (5 µm + 2.5 µm/m).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation


@dataclass(frozen=True)
class VirtualTracker:
    """A tracker pose (R, t) with scale error and its range-dependent noise model."""

    R: np.ndarray
    t: np.ndarray
    scale_ppm: float = 0.0
    sigma0_mm: float = 0.005
    sigma_per_m_mm: float = 0.0025

    @classmethod
    def place(cls, rng: np.random.Generator, scale_ppm: float = 0.0) -> VirtualTracker:
        """Somewhere 2–4 m from the base, at tripod height, any heading, tilted < 0.5°."""
        distance = rng.uniform(2000.0, 4000.0)
        azimuth = rng.uniform(0.0, 2.0 * np.pi)
        origin = np.array([distance * np.cos(azimuth), distance * np.sin(azimuth),
                           rng.uniform(200.0, 1200.0)])
        heading = Rotation.from_euler("z", rng.uniform(0.0, 2.0 * np.pi))
        tilt_axis = np.array([*rng.normal(size=2), 0.0])
        tilt = Rotation.from_rotvec(tilt_axis / np.linalg.norm(tilt_axis)
                                    * np.radians(rng.uniform(0.05, 0.5)))
        # R maps robot-frame vectors into the tracker frame (the tracker's axes are
        # the robot's turned by heading then tilt).
        R = (tilt * heading).inv().as_matrix()
        t = -R @ origin
        return cls(R=R, t=t, scale_ppm=scale_ppm)

    @property
    def origin_mm(self) -> np.ndarray:
        """Where the tracker head is, in the robot base frame."""
        return -self.R.T @ self.t

    @property
    def scale(self) -> float:
        return 1.0 + 1e-6 * self.scale_ppm

    def to_tracker(self, p_robot: np.ndarray) -> np.ndarray:
        """Robot-frame points (N, 3) as the tracker reports them (no noise)."""
        return self.scale * (np.asarray(p_robot) @ self.R.T) + self.t

    def sigma_mm(self, p_robot: np.ndarray) -> np.ndarray:
        """Per-axis noise σ (N,) of a measurement of robot-frame points (N, 3)."""
        rng_m = np.linalg.norm(np.asarray(p_robot) - self.origin_mm, axis=-1) * 1e-3
        return self.sigma0_mm + self.sigma_per_m_mm * rng_m

    def to_dict(self) -> dict[str, Any]:
        """JSON data: R, t, quaternion [w, x, y, z], origin, scale and noise model."""
        x, y, z, w = Rotation.from_matrix(self.R).as_quat()
        return {"convention": "p_tracker = (1 + scale_ppm*1e-6) * R @ p_robot + t",
                "R": self.R.tolist(), "t_mm": self.t.tolist(),
                "quaternion_wxyz": [w, x, y, z], "origin_in_robot_mm": self.origin_mm.tolist(),
                "scale_ppm": self.scale_ppm, "sigma0_mm": self.sigma0_mm,
                "sigma_per_m_mm": self.sigma_per_m_mm}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> VirtualTracker:
        return cls(R=np.asarray(d["R"], dtype=float), t=np.asarray(d["t_mm"], dtype=float),
                   scale_ppm=float(d.get("scale_ppm", 0.0)),
                   sigma0_mm=float(d.get("sigma0_mm", 0.005)),
                   sigma_per_m_mm=float(d.get("sigma_per_m_mm", 0.0025)))
