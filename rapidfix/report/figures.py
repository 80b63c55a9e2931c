"""The report's figures: the data behind each plot and its PNG (matplotlib, Agg).

Each builder returns a `Figure` holding the JSON-ready data it plots (degrees and
mm) and the rendered PNG, so the HTML embeds the picture and the JSON carries
every number. Figures are drawn on `matplotlib.figure.Figure` with the Agg
canvas directly: no pyplot state, no display needed.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure as MplFigure

BEFORE_COLOUR = "#c0392b"
AFTER_COLOUR = "#1f77b4"


@dataclass(frozen=True)
class Figure:
    """One report figure: a file-safe name, a title, a caption, its data and its drawing.

    The PNG is rendered when first read (`png`): a diagnosis run through the API, or a
    report never written, does not pay for drawing (about 0.4 s a figure).
    """

    name: str
    title: str
    caption: str
    data: dict[str, Any]
    drawing: MplFigure = field(repr=False, compare=False)

    @cached_property
    def png(self) -> bytes:
        """The drawing as PNG bytes (rendered once)."""
        return png_bytes(self.drawing)


def png_bytes(fig: MplFigure) -> bytes:
    FigureCanvasAgg(fig)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def finite_list(a: np.ndarray) -> list[float | None]:
    """Floats for JSON; NaN (e.g. a repeat spread from one repeat) becomes None."""
    return [float(v) if np.isfinite(v) else None for v in np.asarray(a, dtype=float).ravel()]


def joint_error_figure(joints: Sequence[dict[str, np.ndarray] | None]) -> Figure:
    """The paper's Figure 7: Δθ against θ per joint, measured points ± repeat spread, fit.

    `joints[j]` holds (degrees) theta, delta, repeat_std of the measured points,
    curve_theta, curve_delta of the fitted network and optionally gaps, an (G, 2)
    array of unmeasured intervals (shaded); or None for an unmodelled joint.
    """
    fig = MplFigure(figsize=(11, 6.5), layout="constrained")
    axes = fig.subplots(2, 3).ravel()
    data: dict[str, Any] = {}
    legend_done = False
    for j, ax in enumerate(axes):
        item = joints[j] if j < len(joints) else None
        ax.set_title(f"joint {j + 1}")
        ax.set_xlabel("θ (°)")
        if j % 3 == 0:
            ax.set_ylabel("Δθ (°)")
        ax.grid(alpha=0.3)
        if item is None:
            ax.text(0.5, 0.5, "not measured", ha="center", va="center", transform=ax.transAxes)
            data[f"joint_{j + 1}"] = None
            continue
        gaps = np.asarray(item.get("gaps", np.zeros((0, 2))), dtype=float).reshape(-1, 2)
        for lo, hi in gaps:
            ax.axvspan(lo, hi, color="#dddddd", zorder=0,
                       label=None if legend_done else "no measurements")
        spread = np.nan_to_num(np.asarray(item["repeat_std"], dtype=float))
        ax.errorbar(item["theta"], item["delta"], yerr=spread, fmt="o", ms=3,
                    color=BEFORE_COLOUR, ecolor="#888888", elinewidth=0.8, capsize=1.5,
                    label="measured (mean ± repeat σ)")
        ax.plot(item["curve_theta"], item["curve_delta"], color=AFTER_COLOUR, lw=1.4,
                label="RBF fit")
        data[f"joint_{j + 1}"] = {key: finite_list(value) for key, value in item.items()
                                  if key != "gaps"}
        data[f"joint_{j + 1}"]["gaps"] = gaps.tolist()
        if not legend_done:
            ax.legend(fontsize=8, loc="best")
            legend_done = True
    fig.suptitle("Joint motion error Δθ = θ_actual − θ_commanded")
    return Figure(
        "joint_errors",
        "Joint motion error per joint (the paper's Figure 7)",
        "Measured joint errors from the sweeps (mean of the repeats, bars: repeat standard "
        "deviation) and the fitted Gaussian RBF network over its valid range. Grey: "
        "stretches of the range without measurements, where the network only interpolates.",
        data,
        fig,
    )


def position_error_figure(before: np.ndarray, after: np.ndarray) -> Figure:
    """Validation points: per-point TCP error before and after compensation (mm)."""
    before = np.asarray(before, dtype=float)
    after = np.asarray(after, dtype=float)
    nb, na = np.linalg.norm(before, axis=1), np.linalg.norm(after, axis=1)
    fig = MplFigure(figsize=(11, 4.2), layout="constrained")
    ax_pts, ax_axes = fig.subplots(1, 2, width_ratios=[1.6, 1])
    idx = np.arange(1, nb.shape[0] + 1)
    ax_pts.plot(idx, nb, "o-", ms=3, lw=0.8, color=BEFORE_COLOUR, label="before")
    ax_pts.plot(idx, na, "o-", ms=3, lw=0.8, color=AFTER_COLOUR, label="after")
    ax_pts.set_xlabel("validation point")
    ax_pts.set_ylabel("|TCP error| (mm)")
    ax_pts.set_ylim(bottom=0)
    ax_pts.grid(alpha=0.3)
    ax_pts.legend()
    width = 0.38
    pos = np.arange(3)
    rms_b = np.sqrt(np.mean(before**2, axis=0))
    rms_a = np.sqrt(np.mean(after**2, axis=0))
    ax_axes.bar(pos - width / 2, rms_b, width, color=BEFORE_COLOUR, label="before")
    ax_axes.bar(pos + width / 2, rms_a, width, color=AFTER_COLOUR, label="after")
    ax_axes.set_xticks(pos, ["x", "y", "z"])
    ax_axes.set_ylabel("RMS error per axis (mm)")
    ax_axes.grid(alpha=0.3, axis="y")
    ax_axes.legend()
    return Figure(
        "validation_errors",
        "TCP position error on the validation points",
        "Distance between the reached and the intended target-ball position at every "
        "validation point, before and after compensation, and the RMS error per base axis.",
        {
            "before_xyz_mm": [finite_list(r) for r in before],
            "after_xyz_mm": [finite_list(r) for r in after],
            "before_norm_mm": finite_list(nb),
            "after_norm_mm": finite_list(na),
        },
        fig,
    )


def ballbar_figure(
    angle_deg: np.ndarray,
    before_mm: np.ndarray,
    after_mm: np.ndarray,
    paper: dict[str, dict[str, float]] | None = None,
) -> Figure:
    """Ballbar length deviation along the semicircle, before and after (mm)."""
    fig = MplFigure(figsize=(8, 4.2), layout="constrained")
    ax = fig.subplots()
    ax.axhline(0.0, color="black", lw=0.6)
    ax.plot(angle_deg, before_mm, "o-", ms=3, lw=0.9, color=BEFORE_COLOUR, label="before")
    ax.plot(angle_deg, after_mm, "o-", ms=3, lw=0.9, color=AFTER_COLOUR, label="after")
    if paper:
        ax.text(0.01, 0.02,
                f"paper: mean |dev| {paper['before']['mean_mm']:.4f} → "
                f"{paper['after']['mean_mm']:.4f} mm, max {paper['before']['max_mm']:.4f} → "
                f"{paper['after']['max_mm']:.4f} mm",
                transform=ax.transAxes, fontsize=8, color="#555555")
    ax.set_xlabel("position along the semicircle (°)")
    ax.set_ylabel("length deviation (mm)")
    ax.grid(alpha=0.3)
    ax.legend()
    return Figure(
        "ballbar",
        "Ballbar test: length deviation before and after compensation",
        "Deviation of the ballbar length (pivot to target ball) from its nominal radius at "
        "each discrete point of the semicircle in the plane inclined 45°.",
        {"angle_deg": finite_list(angle_deg), "before_mm": finite_list(before_mm),
         "after_mm": finite_list(after_mm)},
        fig,
    )
