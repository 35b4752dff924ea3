"""The picture of where adaptive sampling put its samples: a render's spp map as a small PNG
(:func:`write_spp_map_png`, drawn with Pillow alone) and the bench's figure of image and spp map
side by side (:func:`spp_figure`, matplotlib)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import exr
from .tonemap import VIRIDIS, auto_exposure, to_srgb

def spp_figure(spp: np.ndarray, image: np.ndarray | None = None):
    """The spp map (log2 scale, viridis, colour bar), beside the image's preview when given
    (a ``matplotlib.figure.Figure``)."""
    # Imported here, not at the top: matplotlib adds ~0.4 s to the start of every command
    # that plans (planner.choice imports this module), and only the bench draws this figure
    # (a render's own spp map is write_spp_map_png; measured: `python -X importtime`).
    from matplotlib.figure import Figure

    h, w = spp.shape
    panels = 1 if image is None else 2
    fig = Figure(figsize=(min(12.0, panels * max(3.0, 3.4 * w / h) + 1.0), 3.6),
                 layout="constrained")
    axes = fig.subplots(1, panels, squeeze=False)[0]
    if image is not None:
        srgb = to_srgb(image, auto_exposure(image, darken_only=True))
        axes[0].imshow(srgb, cmap="gray" if srgb.ndim == 2 else None, interpolation="nearest")
        axes[0].set_title("image", fontsize=9)
    ax = axes[-1]
    im = ax.imshow(np.log2(np.maximum(spp, 1)), cmap="viridis", interpolation="nearest")
    fig.colorbar(im, ax=ax, shrink=0.85, label="log2 samples per pixel")
    ax.set_title(f"spp map: mean {spp.mean():.0f}, min {spp.min()}, max {spp.max()}",
                 fontsize=9)
    for a in axes:
        a.set_xticks([])
        a.set_yticks([])
    return fig


def write_spp_png(path: str | Path, spp: np.ndarray, image: np.ndarray | None = None) -> Path:
    """Write :func:`spp_figure` (the spp map, beside the image when given) as a PNG,
    atomically: the report's figure (:mod:`phonglab.bench.adaptive_sweeps`)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with exr.atomic_path(path, ".png") as tmp:
        spp_figure(spp, image).savefig(tmp, dpi=110, format="png")
    return path


#: The spp map preview is scaled up by a whole factor until its shorter side has this many
#: pixels (nearest neighbour: each film pixel stays a uniform square).
SPP_PNG_MIN_SIDE = 256
#: ... but its longer side never beyond this many: a 4096 x 4 film made a 262144-pixel-wide
#: preview; a film larger than this is shown at every k-th pixel (k = ⌈side / this⌉).
SPP_PNG_MAX_SIDE = 2048


def write_spp_map_png(path: str | Path, spp: np.ndarray) -> Path:
    """Write :func:`spp_map_image` of ``spp`` as a PNG, atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with exr.atomic_path(path, ".png") as tmp:
        spp_map_image(spp).save(tmp, format="PNG")
    return path


def spp_map_image(spp: np.ndarray):
    """The spp map of an adaptive render as a Pillow image: log2 samples per pixel in
    matplotlib's viridis, one film pixel a square of whole pixels, over a colour bar labelled
    at the powers of two from the map's least to its most samples, under a line giving mean,
    min and max.

    Drawn with Pillow and :data:`phonglab.engine.tonemap.VIRIDIS`, without matplotlib: a matplotlib
    figure (:func:`write_spp_png`) cost every adaptive command ~0.5 s of imports and layout,
    and importing matplotlib for its colour table alone ~0.1 s (measured: cProfile of a
    planned glass_slab render, 128²); this takes ~0.02 s.
    """
    from PIL import Image, ImageDraw, ImageFont

    spp = np.asarray(spp)
    h, w = spp.shape
    lo, hi = np.log2(max(int(spp.min()), 1)), np.log2(max(int(spp.max()), 1))
    span = max(hi - lo, 1e-9)
    lut = VIRIDIS
    level = np.round((np.log2(np.maximum(spp, 1)) - lo) / span * 255).astype(np.int64)
    step = -(-max(h, w) // SPP_PNG_MAX_SIDE)        # a film wider than the preview: every step-th
    level = level[::step, ::step]
    scale = max(1, min(-(-SPP_PNG_MIN_SIDE // min(level.shape)),
                       SPP_PNG_MAX_SIDE // max(level.shape)))
    body = np.repeat(np.repeat(lut[np.clip(level, 0, 255)], scale, axis=0), scale, axis=1)
    font = ImageFont.load_default()
    width = max(body.shape[1], 320)
    line = 14
    canvas = Image.new("RGB", (width, line + body.shape[0] + 8 + 12 + 2 * line + 6), "white")
    canvas.paste(Image.fromarray(body), ((width - body.shape[1]) // 2, line))
    draw = ImageDraw.Draw(canvas)
    draw.text((4, 1), f"spp map: mean {spp.mean():.0f}, min {spp.min()}, max {spp.max()}",
              fill="black", font=font)
    top = line + body.shape[0] + 8
    bar = lut[np.linspace(0, 255 if hi > lo else 0, width - 20).astype(np.int64)]
    canvas.paste(Image.fromarray(np.repeat(bar[None], 12, axis=0)), (10, top))
    for e in range(int(np.ceil(lo)), int(np.floor(hi)) + 1):   # ticks at powers of two
        x = 10 + round((e - lo) / span * (width - 21)) if hi > lo else width // 2
        draw.line([(x, top + 12), (x, top + 15)], fill="black")
        label = str(2 ** e)
        draw.text((min(max(x - 3 * len(label), 0), width - 6 * len(label)), top + 16), label,
                  fill="black", font=font)
    draw.text((4, top + 16 + line), "samples per pixel (log2 scale)", fill="black", font=font)
    return canvas
