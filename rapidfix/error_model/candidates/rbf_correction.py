"""A correction whose cause is unknown: one joint's error as a smooth function of a few features.

The non-parametric fallback of the diagnosis (issue #14, section 2; the source
paper's RBF network over joint space). When neither a physical candidate nor a
structured effect (one joint, one driver) explains a residual that has structure,
the error of one joint j is taken as a Gaussian radial-basis expansion over the
features the residual depends on — two joint angles and the context that varies
(payload, temperature):

    Δθ_j = fade(x) · Σ_k w_k (exp(−|u(x) − c_k|² / (2 w²)) − μ_k),   w = B · p

u(x) scales each feature to [−1, 1] over the range the calibration points covered
(the valid domain, stored per feature); c_k are centres in that unit box, w the
width, μ_k the mean of the k-th Gaussian over the calibration points (so the
correction holds no constant: the joint's offset is the per-joint model's, and a
constant made of wide Gaussians would only trade off against it). The weights are
not free one by one: they are confined to the m leading
directions B (K × m) of the calibration design, chosen by cross-validation (the
regularisation), so the effect has m parameters and the selection charges m for
it. Outside the domain the features are clamped to its edge and the correction
fades out (a Gaussian of the distance beyond the edge, in widths): nothing was
measured there, so nothing is extrapolated; every evaluation outside warns once
per feature with `OutsideRangeWarning`, which `rewrite` and `batch` report.

Missing context (a rewrite without a payload or a temperature) is taken at the
calibration mean. The error depends on more than θ_j, so it is compensated by
the general solve.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import Context
from rapidfix.error_model.joint_rbf import OutsideRangeWarning
from rapidfix.exceptions import ModelError

#: features a correction may depend on: joint angles (rad) and context fields
JOINT_FEATURES: tuple[str, ...] = ("q1", "q2", "q3", "q4", "q5", "q6")
CONTEXT_FEATURES: tuple[str, ...] = ("payload_kg", "temp_c")
FEATURES: tuple[str, ...] = JOINT_FEATURES + CONTEXT_FEATURES
#: features within this fraction of the domain's half-width outside it count as inside
_EDGE_TOL = 1e-6


def feature_values(names: Sequence[str], q_cmd: np.ndarray, ctx: Context,
                   reference: Sequence[float]) -> np.ndarray:
    """The named features (N, d) of poses q (N, 6) rad in context ctx; missing context at
    its reference value."""
    q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
    n = q.shape[0]
    cols = []
    for name, ref in zip(names, reference):
        if name in JOINT_FEATURES:
            cols.append(q[:, JOINT_FEATURES.index(name)])
            continue
        value = getattr(ctx, name, None) if ctx is not None else None
        cols.append(np.full(n, float(ref)) if value is None
                    else np.broadcast_to(np.asarray(value, dtype=float), (n,)))
    return np.column_stack(cols) if cols else np.zeros((n, 0))


def gaussian_design(u: np.ndarray, centres: np.ndarray, width: float) -> np.ndarray:
    """exp(−|u − c_k|² / (2 width²)) (N, K) for unit-box features u (N, d)."""
    d2 = np.sum((u[:, None, :] - centres[None, :, :]) ** 2, axis=2)
    return np.exp(-0.5 * d2 / width**2)


def feature_label(name: str) -> str:
    """A feature in words: "joint 5" or "payload"."""
    if name in JOINT_FEATURES:
        return f"joint {JOINT_FEATURES.index(name) + 1}"
    return {"payload_kg": "payload", "temp_c": "temperature"}[name]


class RBFCorrection(VectorEffect):
    """Δθ_joint = fade · Φ(u(x)) · B · p over features x (see the module docstring)."""

    type_name: ClassVar[str] = "rbf_correction"
    adds_joint_delta: ClassVar[bool] = True

    def __init__(self, joint: int, features: Sequence[str], lo: Sequence[float],
                 hi: Sequence[float], centres: np.ndarray, width: float, basis: np.ndarray,
                 *, centring: Sequence[float] | None = None,
                 reference: Sequence[float] | None = None, cv: dict[str, float] | None = None,
                 name: str | None = None, free: bool = True) -> None:
        features = tuple(str(f) for f in features)
        d = len(features)
        unknown = [f for f in features if f not in FEATURES]
        if unknown or not 1 <= d <= 4 or len(set(features)) != d:
            raise ModelError(f"features {list(features)!r}: 1 to 4 distinct of "
                             f"{', '.join(FEATURES)} expected", column="features")
        if not 0 <= int(joint) < 6:
            raise ModelError(f"joint {int(joint) + 1} is not one of 1..6", column="joint")
        lo_a = np.asarray(lo, dtype=float).reshape(-1)
        hi_a = np.asarray(hi, dtype=float).reshape(-1)
        if lo_a.shape != (d,) or hi_a.shape != (d,) or not np.all(np.isfinite(lo_a)) \
                or not np.all(np.isfinite(hi_a)) or not np.all(hi_a > lo_a):
            raise ModelError("the domain needs lo < hi for every feature", column="domain_low")
        c = np.asarray(centres, dtype=float)
        if c.ndim != 2 or c.shape[1] != d or not 1 <= c.shape[0] <= 200 \
                or not np.all(np.isfinite(c)):
            raise ModelError(f"centres must be (K, {d}) finite unit-box points, K ≤ 200",
                             column="centres_unit")
        b = np.asarray(basis, dtype=float)
        if b.ndim != 2 or b.shape[0] != c.shape[0] or not 1 <= b.shape[1] <= c.shape[0] \
                or not np.all(np.isfinite(b)):
            raise ModelError(f"basis must be (K={c.shape[0]}, m ≤ K) finite numbers",
                             column="basis")
        if not (np.isfinite(width) and 0.0 < float(width) <= 100.0):
            raise ModelError(f"width {width!r} must be positive", column="width_unit")
        mu = np.zeros(c.shape[0]) if centring is None else np.asarray(centring, dtype=float)
        if mu.shape != (c.shape[0],) or not np.all(np.isfinite(mu)):
            raise ModelError("centring needs one finite value per centre", column="centring")
        ref = np.zeros(d) if reference is None else np.asarray(reference, dtype=float)
        if ref.shape != (d,) or not np.all(np.isfinite(ref)):
            raise ModelError("reference needs one finite value per feature", column="reference")
        names = [f"c{i + 1:02d}_rad" for i in range(b.shape[1])]
        super().__init__(names, name or f"rbf_correction_j{int(joint) + 1}",
                         steps=[1e-6] * b.shape[1], free=free)
        self.joint = int(joint)
        self.features = features
        self.lo, self.hi = lo_a, hi_a
        self.centres = c
        self.width = float(width)
        self.basis = b
        self.centring = mu
        self.reference = ref
        self.cv = dict(cv or {})
        self._warned: set[str] = set()

    # -- evaluation -----------------------------------------------------------------
    def _unit(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Clamped unit-box features (N, d) and the fade factor (N,) beyond the domain."""
        half = 0.5 * (self.hi - self.lo)
        u = (x - 0.5 * (self.hi + self.lo)) / half
        over = np.maximum(np.abs(u) - 1.0, 0.0)
        outside = over > _EDGE_TOL
        for i in np.flatnonzero(outside.any(axis=0)):
            name = self.features[i]
            if name in self._warned:
                continue
            self._warned.add(name)
            worst = x[outside[:, i], i][np.argmax(over[outside[:, i], i])]
            scale, unit = (np.degrees, "°") if name in JOINT_FEATURES else (float, "")
            warnings.warn(
                f"{feature_label(name)} at {scale(worst):.3f}{unit} is outside the domain the "
                f"correction of unknown cause (on joint {self.joint + 1}) was fitted over "
                f"[{scale(self.lo[i]):.3f}{unit}, {scale(self.hi[i]):.3f}{unit}]; the "
                "correction fades out there", OutsideRangeWarning, stacklevel=4)
        fade = np.exp(-0.5 * np.sum(over**2, axis=1) / self.width**2)
        return np.clip(u, -1.0, 1.0), fade

    def regressors(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """F (N, m): the joint's error is F · params."""
        x = feature_values(self.features, q_cmd, ctx, self.reference)
        u, fade = self._unit(x)
        phi = gaussian_design(u, self.centres, self.width) - self.centring
        return (phi @ self.basis) * fade[:, None]

    def joint_delta(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """The joint's correction (rad), zero on the other joints."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        out = np.zeros_like(q)
        out[:, self.joint] = self.regressors(q, ctx) @ self._p
        return out

    def context_fields(self) -> frozenset[str]:
        """The context features it reads."""
        return frozenset(f for f in self.features if f in CONTEXT_FEATURES)

    def reset_warnings(self) -> None:
        """Warn again (once per feature) from now on."""
        self._warned.clear()

    @property
    def domain(self) -> list[dict[str, Any]]:
        """The valid domain per feature, in interface units (degrees for angles)."""
        out = []
        for name, lo, hi in zip(self.features, self.lo, self.hi):
            conv = np.degrees if name in JOINT_FEATURES else float
            out.append({"feature": name, "label": feature_label(name),
                        "low": float(conv(lo)), "high": float(conv(hi)),
                        "unit": "deg" if name in JOINT_FEATURES else name.split("_")[-1]})
        return out

    # -- words ------------------------------------------------------------------------
    def what(self) -> str:
        """What it depends on and where it acts, in words."""
        labels = [feature_label(f) for f in self.features]
        depends = labels[0] if len(labels) == 1 else (", ".join(labels[:-1]) + " and "
                                                      + labels[-1])
        return (f"a correction whose cause is unknown, depending on {depends}, acting on "
                f"joint {self.joint + 1}")

    def sentence(self) -> str:
        """`what()` with its size, its flexibility and its domain."""
        span = ", ".join(f"{d['label']} {d['low']:.0f}…{d['high']:.0f}"
                         + ("°" if d["unit"] == "deg" else f" {d['unit']}")
                         for d in self.domain)
        size = self.cv.get("rms_deg")
        size_text = "" if size is None else f"{size:.4f}° RMS on the calibration points, "
        return (f"{self.what()} ({size_text}Gaussian RBF with {self.centres.shape[0]} "
                f"centres, {self.basis.shape[1]} cross-validated parameters; valid over "
                f"{span})")

    def describe(self) -> str:
        """One line for summaries."""
        return f"{self.name} ({self.what()})"

    # -- serialisation ------------------------------------------------------------------
    def _state(self) -> dict[str, Any]:
        return {"joint": self.joint + 1, "features": list(self.features),
                "domain_low": self.lo.tolist(), "domain_high": self.hi.tolist(),
                "centres_unit": self.centres.tolist(), "width_unit": self.width,
                "basis": self.basis.tolist(), "centring": self.centring.tolist(),
                "reference": self.reference.tolist(),
                "cross_validation": dict(self.cv)}

    @classmethod
    def _from_state(cls, name: str, state: dict[str, Any]) -> RBFCorrection:
        return cls(int(state["joint"]) - 1, list(state["features"]),
                   state["domain_low"], state["domain_high"],
                   np.asarray(state["centres_unit"], dtype=float), float(state["width_unit"]),
                   np.asarray(state["basis"], dtype=float), centring=state.get("centring"),
                   reference=state.get("reference"),
                   cv={str(k): float(v) for k, v in dict(state.get("cross_validation",
                                                                    {})).items()},
                   name=name)
