"""The diagnosis report's own figure: an accepted effect against the feature that exposed it.

x: the exposing quantity on the validation points; y: the residual the model had
before the effect was added, taken along the direction in which adding it (and
refitting) moved the prediction (red dots), that change itself (blue crosses),
and the residual left afterwards along the same direction (grey). When the
effect is the right explanation the red dots follow the crosses and the grey
ones scatter about zero. Drawn with matplotlib's Agg canvas.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure as MplFigure

from rapidfix.report import AFTER_COLOUR, BEFORE_COLOUR, Figure, finite_list


def evidence_figure(kind: str, feature: np.ndarray, label: str, residual_mm: np.ndarray,
                    predicted_mm: np.ndarray, after_mm: np.ndarray, *,
                    discrete: bool = False, seed: int = 0) -> Figure:
    """Residual before/after along the effect's correction, and the correction, vs the feature."""
    x = np.asarray(feature, dtype=float)
    shown = x
    if discrete:  # spread ±1 a little so the points do not hide each other
        shown = x + np.random.default_rng(seed).uniform(-0.12, 0.12, x.shape)
    fig = MplFigure(figsize=(8, 4.2), layout="constrained")
    ax = fig.subplots()
    ax.axhline(0.0, color="black", lw=0.6)
    ax.plot(shown, residual_mm, "o", ms=4, color=BEFORE_COLOUR,
            label="residual before adding it (along its direction)")
    ax.plot(shown, predicted_mm, "x", ms=5, color=AFTER_COLOUR, label=f"{kind} correction")
    ax.plot(shown, after_mm, ".", ms=4, color="#888888", label="residual after")
    ax.set_xlabel(label)
    ax.set_ylabel("ball displacement (mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return Figure(
        f"evidence_{kind}",
        f"{kind}: the residual against {label}",
        "Validation points (never fitted). Red: what the model before this effect missed, "
        "taken along the direction in which adding the effect moved the prediction; blue: "
        "that correction; grey: what is left along the same direction.",
        {"feature_label": label, "feature": finite_list(x),
         "residual_before_mm": finite_list(residual_mm),
         "correction_mm": finite_list(predicted_mm), "residual_after_mm": finite_list(after_mm)},
        fig,
    )
