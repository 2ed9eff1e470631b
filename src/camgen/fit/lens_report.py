"""A one-page picture of a lens fit: per-view errors, corner residuals and the model comparison.

Written with matplotlib's object API (`matplotlib.figure.Figure` on the Agg canvas), never pyplot, so
it holds no global figure state and needs no display.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from camgen.fit.frames import listing
from camgen.fit.lens import Detection, LensFit, reprojection_residuals_px
from camgen.io.files import atomic_path

KEPT_COLOUR = "tab:blue"
REJECTED_COLOUR = "tab:red"
CHOSEN_COLOUR = "tab:green"


def write_lens_report(fit: LensFit, detections: Sequence[Detection], path: str | Path, *, dpi: int = 110) -> Path:
    """Write a PNG summarising `fit` to `path` (atomically) and return the path.

    Four panels: (1) RMS reprojection error per view, rejected outlier views in red, the screening
    threshold dashed; (2) the residual of every corner of the kept views as an arrow at its place in
    the image, magnified so the largest is a twentieth of the image width; (3) the same residuals as
    a scatter, with the RMS circle; (4) held-out and training RMS of each candidate model, the
    selected one marked. Every view's residuals come from `reprojection_residuals_px` with the fitted
    intrinsics (pose only), so rejected views are shown against the final fit.

    Parameters
    ----------
    fit : the fit to show.
    detections : the views passed to `fit_lens` (kept and rejected).
    path : where the PNG goes.
    dpi : resolution of the 12 × 9 inch figure, dots per inch.
    """
    path = Path(path)
    rejected = dict(fit.rejected)
    residuals = {d.name: reprojection_residuals_px(d, fit.K_px, fit.distortion) for d in detections}
    view_rms_px = {name: float(np.sqrt(np.mean(np.sum(r**2, axis=1)))) for name, r in residuals.items()}
    kept = [d for d in detections if d.name not in rejected]

    figure = Figure(figsize=(12, 9), layout="constrained")
    (views_axes, arrows_axes), (scatter_axes, models_axes) = figure.subplots(2, 2)
    title = (
        f"lens fit: model {fit.model}, fx {fit.K_px[0, 0]:.2f} px, fy {fit.K_px[1, 1]:.2f} px, "
        f"RMS {fit.rms_px:.3f} px over {len(kept)} views"
    )
    left_out = [name for name, _ in fit.rejected if name not in view_rms_px]
    if left_out:
        title += f"\nleft out (no board or unreadable): {listing(left_out)}"
    figure.suptitle(title)

    names = [d.name for d in detections]
    colours = [REJECTED_COLOUR if name in rejected else KEPT_COLOUR for name in names]
    views_axes.bar(range(len(names)), [view_rms_px[n] for n in names], color=colours)
    views_axes.axhline(fit.outlier_threshold_px, color=REJECTED_COLOUR, linestyle="--", label="outlier threshold")
    views_axes.set_xticks(range(len(names)), names, rotation=90, fontsize=7)
    views_axes.set_ylabel("RMS reprojection error, px")
    views_axes.set_yscale("log")
    views_axes.set_title("per view (red: rejected)")
    views_axes.legend(loc="upper right")

    width, height = fit.size_px
    points = np.concatenate([d.corners_px.reshape(-1, 2) for d in kept])
    vectors = np.concatenate([residuals[d.name] for d in kept])
    longest = float(np.hypot(*vectors.T).max()) or 1.0
    scale = width / 20 / longest
    arrows_axes.quiver(
        points[:, 0], points[:, 1], vectors[:, 0], vectors[:, 1], angles="xy", scale_units="xy", scale=1 / scale
    )
    arrows_axes.set_xlim(-0.5, width - 0.5)
    arrows_axes.set_ylim(height - 0.5, -0.5)
    arrows_axes.set_aspect("equal")
    arrows_axes.set_xlabel("u, px")
    arrows_axes.set_ylabel("v, px")
    arrows_axes.set_title(f"corner residuals (detected − projected) × {scale:.3g}")

    scatter_axes.scatter(vectors[:, 0], vectors[:, 1], s=3, alpha=0.5, color=KEPT_COLOUR)
    angle = np.linspace(0, 2 * math.pi, 181)
    scatter_axes.plot(fit.rms_px * np.cos(angle), fit.rms_px * np.sin(angle), color="black", label="RMS")
    scatter_axes.set_aspect("equal")
    scatter_axes.set_xlabel("Δu, px")
    scatter_axes.set_ylabel("Δv, px")
    scatter_axes.set_title("residuals of the kept views")
    scatter_axes.legend(loc="upper right")

    models = [c.name for c in fit.candidates]
    x = np.arange(len(models))
    held_out = [c.held_out_rms_px for c in fit.candidates]
    models_axes.bar(
        x - 0.2,
        held_out,
        width=0.4,
        color=[CHOSEN_COLOUR if c.name == fit.model else KEPT_COLOUR for c in fit.candidates],
        label="held out (selected green)",
    )
    models_axes.bar(x + 0.2, [c.training_rms_px for c in fit.candidates], width=0.4, color="grey", label="training")
    models_axes.set_xticks(x, [f"{c.name}\n{c.parameters} par." for c in fit.candidates])
    finite = [v for v in held_out if math.isfinite(v)]
    if finite:
        low, high = min(finite), max(finite)
        models_axes.set_ylim(0, high * 1.15 if high > 3 * low else low * 1.5)
    models_axes.set_ylabel("RMS reprojection error, px")
    models_axes.set_title("candidate models (cross-validated over views)")
    models_axes.legend(loc="upper right")

    with atomic_path(path) as temporary:
        figure.savefig(temporary, dpi=dpi, format="png")
    return path
