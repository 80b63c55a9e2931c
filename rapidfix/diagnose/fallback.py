"""The non-parametric fallback: a smooth correction for a residual no cause describes.

When no physical candidate and no structured effect (one joint, one driver)
passes, but the residual may still have structure, the search proposes one
`RBFCorrection`: one joint's error as a Gaussian RBF expansion over two joint
angles and the context that varies (payload, temperature). Which joints: every
(joint acted on, pair of joints it depends on) is ranked by how much of the
calibration residual a cross-validated correction over it predicts, and the top
one is proposed. (The structured ranking, `rapidfix.diagnose.structured.screen`,
scores low-order driver forms, which an unknown cause need not follow: on a
joint-5 error depending on joints 4 and 6 together its top entries named joints
5, 1, 4 and 2, not 6; so the joints are ranked here by the correction's own form.)

Every (joint acted on, feature pair) and every centre count and width is scored
by k-fold cross-validation on the calibration points only, without refitting the
model: the design Φ(u) times the points' sensitivity to that joint's error,
projected off everything the current model fits, regressed on the residual by
truncated SVD with m = 0, 1, … components. m is the regularisation: the
correction keeps only the m leading directions of the design, so it has m
parameters and the selection charges it m ln n (BIC) plus 2 ln v for the v
settings searched. The best setting is returned as an effect; it is then fitted
with everything else and judged by the same tests as any candidate, on
validation points it never fitted.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rapidfix.diagnose.sensitivity import residual_off_model
from rapidfix.diagnose.structured import MIN_SPREAD
from rapidfix.error_model import (
    CONTEXT_FEATURES,
    JOINT_FEATURES,
    ErrorModel,
    MeasuredPoints,
    RBFCorrection,
    feature_label,
    feature_values,
    gaussian_design,
)
from rapidfix.kinematics import RobotModel

PHYSICS = "a smooth correction of one joint over a few features; its cause is unknown"
#: centre counts and widths (unit box [−1, 1] per feature) searched
CENTRE_COUNTS = (9, 16, 25)
WIDTHS = (0.3, 0.5, 0.8, 1.2)
#: most parameters (kept directions) a correction may have
MAX_PARAMS = 16
FOLDS = 5
#: singular values below this fraction of the largest are not kept
RCOND = 1e-6
#: fitted and judged only when cross-validation predicts it removes at least this share
#: of the calibration residual (the relevance test asks 20 % of the validation one)
MIN_CV_SHARE = 0.3


@dataclass
class Proposal:
    """The search's outcome: the effect to fit (or why none), the settings searched."""

    effect: RBFCorrection | None
    variants: int
    detail: str = ""
    reason: str = ""
    #: best cross-validated setting per (joint acted on, features), best first
    settings: list[dict[str, Any]] = field(default_factory=list)


def farthest_points(u: np.ndarray, count: int) -> np.ndarray:
    """`count` points of u (N, d) spread over the data: the one nearest the middle, then
    each time the one farthest from those chosen (deterministic)."""
    count = min(count, u.shape[0])
    chosen = [int(np.argmin(np.sum(u**2, axis=1)))]
    dist = np.sum((u - u[chosen[0]]) ** 2, axis=1)
    for _ in range(count - 1):
        nxt = int(np.argmax(dist))
        chosen.append(nxt)
        dist = np.minimum(dist, np.sum((u - u[nxt]) ** 2, axis=1))
    return u[chosen].copy()


def cv_errors(designs: np.ndarray, r: np.ndarray, n_points: int, max_params: int,
              folds: int = FOLDS) -> np.ndarray:
    """k-fold CV sums of squares (B, M+1) of truncated least-squares fits of r with the
    m = 0..M leading directions of each design (B, 3N, K); folds are interleaved
    points (3 rows each). The directions are the eigenvectors of the training rows'
    normal matrix (the right singular vectors), batched over the B designs."""
    designs = np.asarray(designs, dtype=float)
    fold_of = np.repeat(np.arange(n_points) % folds, 3)
    k = designs.shape[2]
    m_max = min(max_params, k)
    out = np.zeros((designs.shape[0], m_max + 1))
    for f in range(folds):
        test = fold_of == f
        train = designs[:, ~test]
        train_t = train.transpose(0, 2, 1)
        evals, evecs = np.linalg.eigh(train_t @ train)
        evals, evecs = evals[:, ::-1], evecs[:, :, ::-1]  # largest first
        keep = evals > RCOND**2 * evals[:, :1]
        proj = (evecs.transpose(0, 2, 1) @ (train_t @ r[~test])[:, :, None])[:, :, 0]
        coef = np.where(keep, proj / np.where(keep, evals, 1.0), 0.0)[:, :m_max]
        parts = (designs[:, test] @ evecs[:, :, :m_max]) * coef[:, None]
        resid = r[test][None, :, None] - np.cumsum(parts, axis=2)
        rt = r[test]
        out[:, 0] += float(rt @ rt)
        out[:, 1:] += np.sum(resid**2, axis=1)
    return out


def _leading_directions(design: np.ndarray, m: int) -> np.ndarray:
    """The m leading right singular vectors (K, m) of a design (3N, K)."""
    evals, evecs = np.linalg.eigh(design.T @ design)
    order = np.argsort(evals)[::-1]
    keep = [i for i in order[:m] if evals[i] > RCOND**2 * evals[order[0]]]
    return evecs[:, keep]


def _context_features(data: MeasuredPoints) -> list[str]:
    out = []
    for name in CONTEXT_FEATURES:
        value = getattr(data.ctx, name)
        if value is not None and np.ptp(value) > MIN_SPREAD[name]:
            out.append(name)
    return out


def propose(model: ErrorModel, robot: RobotModel, data: MeasuredPoints) -> Proposal:
    """The best cross-validated correction of unknown cause on the current model's
    calibration residual (see the module docstring)."""
    targets = list(range(6))
    context = _context_features(data)
    pairs = list(itertools.combinations(range(6), 2))
    variants = max(len(targets) * len(pairs) * len(CENTRE_COUNTS) * len(WIDTHS), 1)
    res = residual_off_model(model, robot, data)
    r_perp, grads = res.r_perp, res.grads
    n = len(data)
    settings = []
    best: dict[str, Any] | None = None
    for pair in pairs:
        names = [JOINT_FEATURES[j] for j in pair] + context
        reference = [0.0] * len(pair) + [float(np.mean(getattr(data.ctx, c)))
                                         for c in context]
        x = feature_values(names, data.q, data.ctx, reference)
        lo, hi = x.min(axis=0), x.max(axis=0)
        if np.any(hi - lo <= 1e-9):
            continue
        u = (x - 0.5 * (hi + lo)) / (0.5 * (hi - lo))
        for count in CENTRE_COUNTS:
            centres = farthest_points(u, count)
            for width in WIDTHS:
                phi = gaussian_design(u, centres, width)
                centring = phi.mean(axis=0)
                phi -= centring
                cols = np.repeat(phi, 3, axis=0)
                designs = grads[:, :, None] * cols[None]  # (6, 3N, K): each joint acted on
                designs = res.off_model(designs)
                sse = cv_errors(designs, r_perp, n, MAX_PARAMS)
                for j in targets:
                    m = int(np.argmin(sse[j]))
                    item = {"joint": j, "features": names, "centres": centres,
                            "width": width, "m": m, "cv_sse": float(sse[j, m]),
                            "cv_sse_none": float(sse[j, 0])}
                    settings.append(item)
                    if best is None or item["cv_sse"] < best["cv_sse"]:
                        best = {**item, "reference": reference, "lo": lo, "hi": hi,
                                "centring": centring, "design": designs[j].copy()}
    settings.sort(key=lambda s: s["cv_sse"])
    # one row per (joint acted on, features): its best setting, best first
    seen: set[tuple[int, tuple[str, ...]]] = set()
    records = []
    for item in settings:
        key = (item["joint"], tuple(item["features"]))
        if key not in seen:
            seen.add(key)
            records.append(_record(item, n))
    if best is None or best["m"] == 0:
        return Proposal(None, variants, reason="cross-validation finds no smooth structure "
                        "over any pair of joints", settings=records)
    share = 1.0 - best["cv_sse"] / best["cv_sse_none"]
    if share < MIN_CV_SHARE:
        return Proposal(None, variants, reason=(
            f"cross-validated, the best correction ({feature_label(best['features'][0])} and "
            f"{feature_label(best['features'][1])}, on joint {best['joint'] + 1}) predicts only "
            f"{100 * share:.0f} % of the calibration residual (< {100 * MIN_CV_SHARE:.0f} %)"),
            settings=records)
    directions = _leading_directions(best["design"], best["m"])
    keep = directions.shape[1]
    cv = {"cv_rms_mm": float(np.sqrt(best["cv_sse"] / (3 * n))),
          "cv_rms_mm_without": float(np.sqrt(best["cv_sse_none"] / (3 * n))),
          "folds": float(FOLDS)}
    effect = RBFCorrection(best["joint"], best["features"], best["lo"], best["hi"],
                           best["centres"], best["width"], directions,
                           centring=best["centring"], reference=best["reference"], cv=cv)
    detail = (f"{effect.what()}: {best['centres'].shape[0]} centres, width "
              f"{best['width']:g}, {keep} parameters (best of {variants} settings by "
              f"{FOLDS}-fold cross-validation: {cv['cv_rms_mm_without']:.4f} → "
              f"{cv['cv_rms_mm']:.4f} mm RMS per coordinate)")
    return Proposal(effect, variants, detail=detail, settings=records)


def _record(setting: dict[str, Any], n: int) -> dict[str, Any]:
    return {"joint": setting["joint"] + 1,
            "depends_on": [feature_label(f) for f in setting["features"]],
            "centres": int(setting["centres"].shape[0]), "width_unit": setting["width"],
            "parameters": setting["m"],
            "cv_rms_mm": float(np.sqrt(setting["cv_sse"] / (3 * n))),
            "cv_rms_mm_without": float(np.sqrt(setting["cv_sse_none"] / (3 * n)))}
