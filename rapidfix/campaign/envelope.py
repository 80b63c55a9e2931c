"""The work envelope: where calibration and validation poses may put the ball.

A box in the robot base frame or in a work object's frame, a floor plane (no
part of the ball below it, base frame z) and keep-out boxes (base frame) where
nothing may go: fixtures, the tracker's tripod, walls. All lengths mm.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rapidfix.exceptions import RapidfixError


@dataclass(frozen=True)
class Box:
    """An axis-aligned box: corners `lo` (3,) and `hi` (3,), mm."""

    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def parse(cls, text: str, what: str = "--box") -> Box:
        """`xmin,ymin,zmin,xmax,ymax,zmax` in mm."""
        try:
            v = np.array([float(s) for s in text.replace(";", ",").split(",")])
        except ValueError:
            raise RapidfixError(f"{what} needs six numbers xmin,ymin,zmin,xmax,ymax,zmax "
                                f"(mm), got {text!r}") from None
        if v.shape != (6,) or not np.all(np.isfinite(v)):
            raise RapidfixError(f"{what} needs six numbers xmin,ymin,zmin,xmax,ymax,zmax "
                                f"(mm), got {text!r}")
        if np.any(v[3:] <= v[:3]):
            raise RapidfixError(f"{what}: each max must exceed its min, got {text!r}")
        return cls(v[:3], v[3:])

    def contains(self, p: np.ndarray) -> np.ndarray:
        """Mask (N,) of points (N, 3) inside the box (faces included)."""
        p = np.atleast_2d(p)
        return np.all((p >= self.lo) & (p <= self.hi), axis=1)

    @property
    def size(self) -> np.ndarray:
        return self.hi - self.lo


@dataclass(frozen=True)
class Envelope:
    """Box (in the frame `frame`, a (4, 4) base-from-frame transform), floor, keep-outs.

    `box` None means no box (only floor and keep-outs restrict the ball).
    """

    box: Box | None = None
    frame: np.ndarray = field(default_factory=lambda: np.eye(4))
    floor_z_mm: float | None = None
    keep_out: tuple[Box, ...] = ()
    margin_mm: float = 0.0

    def to_frame(self, p_base: np.ndarray) -> np.ndarray:
        """Base-frame points (N, 3) in the box's frame."""
        R, t = self.frame[:3, :3], self.frame[:3, 3]
        return (np.atleast_2d(p_base) - t) @ R

    def safe(self, p_base: np.ndarray) -> np.ndarray:
        """Mask (N,): above the floor and outside every keep-out box (any pose, sweeps too)."""
        p = np.atleast_2d(p_base)
        ok = np.ones(len(p), dtype=bool)
        if self.floor_z_mm is not None:
            ok &= p[:, 2] >= self.floor_z_mm + self.margin_mm
        for box in self.keep_out:
            grown = Box(box.lo - self.margin_mm, box.hi + self.margin_mm)
            ok &= ~grown.contains(p)
        return ok

    def contains(self, p_base: np.ndarray) -> np.ndarray:
        """Mask (N,): safe and inside the box (where calibration poses may go)."""
        ok = self.safe(p_base)
        if self.box is not None:
            ok &= self.box.contains(self.to_frame(p_base))
        return ok

    def box_corners_base(self) -> np.ndarray | None:
        """The box's 8 corners (8, 3) in the base frame, or None."""
        if self.box is None:
            return None
        idx = np.array([[i >> 2 & 1, i >> 1 & 1, i & 1] for i in range(8)])
        local = np.where(idx == 1, self.box.hi, self.box.lo)
        return local @ self.frame[:3, :3].T + self.frame[:3, 3]
