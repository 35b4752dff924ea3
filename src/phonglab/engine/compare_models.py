r"""Graphics versus physics: one scene rendered with the seed's model and with light transport.

Three renders of the same scene, materials and lights:

* ``graphics``: ``whitted`` in graphics units, the seed's formula literally (the scene's own
  ``whitted`` integrator when it has one: ambient, attenuation and shadows as it sets them);
* ``radiance``: ``whitted`` in radiance units, f_r cos θ · I/r² at the first hit plus
  the delta rays (ambient 0, physical 1/r²): what physics says of the same direct light;
* ``path``: Mitsuba's path tracer at the same ``max_depth``: all light transport,
  including the indirect light the ambient term stands in for.

For each pair (a, b) :func:`pair_stats` reports mean |a − b|, max |a − b| and where,
the relative difference mean|a − b| / mean|b|, and, because graphics units are not
radiance, the least-squares scale s = Σab/Σa² that best maps a onto b and the relative
difference left after it (the differences of *shape*: missing cosine, (p+2)/(2π)
normalisation, attenuation, ambient).  Pixel values are compared per channel.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mitsuba as mi
import numpy as np
from matplotlib.figure import Figure

from . import exr
from ..errors import PhonglabError
from .outputs import write_text
from .metrics import luminance
from .render import render_scene
from .scenes import file_hash, load_scene, scene_defaults, scene_path
from .tonemap import auto_exposure, preview_png, to_srgb

MODELS = ("graphics", "radiance", "path")
#: (a, b) pairs compared, b the reference.
PAIRS = (("graphics", "path"), ("radiance", "path"), ("graphics", "radiance"))


@dataclass
class PairStats:
    """How image a differs from reference b."""

    a: str
    b: str
    mean_abs: float           #: mean |a − b| over pixels and channels
    max_abs: float            #: max |a − b|
    where_max: tuple[int, int]  #: (row, column) of the max
    relative: float           #: mean |a − b| / mean |b|
    scale: float              #: s minimising Σ (s a − b)²
    relative_scaled: float    #: mean |s a − b| / mean |b|
    fraction_over: float      #: share of pixels where |s a − b| > 10 % of b's 99th percentile


@dataclass
class ModelComparison:
    images: dict[str, np.ndarray]
    stderr: dict[str, np.ndarray | None]
    stats: list[PairStats]
    integrators: dict[str, dict[str, Any]]
    seconds: dict[str, float]
    files: list[Path] = field(default_factory=list)


def pair_stats(a: np.ndarray, b: np.ndarray, name_a: str = "a", name_b: str = "b") -> PairStats:
    """Differences of image a from reference image b (same shape, (H, W, C))."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if a.shape != b.shape:
        raise PhonglabError(f"cannot compare images of shapes {a.shape} and {b.shape}")
    d = np.abs(a - b)
    ref = max(float(np.mean(np.abs(b))), 1e-12)
    per_pixel = d.max(axis=-1) if d.ndim == 3 else d
    where = np.unravel_index(int(np.argmax(per_pixel)), per_pixel.shape)
    aa = float(np.sum(a * a))
    s = float(np.sum(a * b) / aa) if aa > 0 else 0.0
    ds = np.abs(s * a - b)
    ds_pixel = ds.max(axis=-1) if ds.ndim == 3 else ds
    threshold = 0.1 * max(float(np.percentile(b, 99)), 1e-12)
    return PairStats(name_a, name_b, float(d.mean()), float(d.max()),
                     (int(where[0]), int(where[1])), float(d.mean()) / ref, s,
                     float(ds.mean()) / ref, float(np.mean(ds_pixel > threshold)))


def format_table(stats: list[PairStats]) -> str:
    """The printed table: one line per pair."""
    head = (f"{'a − b':<22}{'mean|Δ|':>10}{'max|Δ|':>10}{'at (y,x)':>12}{'rel.':>9}"
            f"{'scale s':>10}{'rel.(s·a)':>11}{'px>10%':>8}")
    lines = [head, "-" * len(head)]
    for st in stats:
        lines.append(f"{st.a + ' − ' + st.b:<22}{st.mean_abs:>10.4g}{st.max_abs:>10.4g}"
                     f"{str(st.where_max):>12}{st.relative:>9.3f}{st.scale:>10.4g}"
                     f"{st.relative_scaled:>11.3f}{st.fraction_over:>8.1%}")
    return "\n".join(lines)


def integrator_dicts(scene, max_depth: int | None = None) -> dict[str, dict[str, Any]]:
    """The three integrators: the scene's ``whitted`` settings for graphics when it has them."""
    own = scene.integrator()
    base = own.parameters() if hasattr(own, "parameters") and hasattr(own, "units") else \
        {"type": "whitted", "max_depth": 5, "shadows": True, "hide_emitters": False}
    depth = int(max_depth if max_depth is not None else base.get("max_depth", 5))
    graphics = dict(base, units="graphics", max_depth=depth)
    radiance = {"type": "whitted", "units": "radiance", "max_depth": depth,
                "shadows": bool(base.get("shadows", True)),
                "hide_emitters": bool(base.get("hide_emitters", False))}
    path = {"type": "path", "max_depth": depth,
            "hide_emitters": bool(base.get("hide_emitters", False))}
    return {"graphics": graphics, "radiance": radiance, "path": path}


def _graphics_integrator(scene, dicts, max_depth):
    """The scene's own graphics-units whitted when it has one at the asked depth (it keeps
    ambient textures and per-material ambient reflectances), else one built from ``dicts``."""
    own = scene.integrator()
    if getattr(own, "units", None) == "graphics" and \
            (max_depth is None or int(max_depth) == own.max_depth):
        return own
    return mi.load_dict(dicts["graphics"])


def compare_models(scene: str | Path, out_dir: str | Path | None = None, spp: int = 16,
                   path_spp: int | None = None, seed: int = 0, max_depth: int | None = None,
                   variant: str | None = None, progress: bool = False,
                   params: dict[str, Any] | None = None) -> ModelComparison:
    """Render ``scene`` three ways and compare; write images and a figure to ``out_dir``.

    Args:
        scene: scene file, or the name of a shipped scene (``cornell_phong``).
        out_dir: folder for the EXR/PNG files and ``figure.png`` (None: write nothing).
        spp: samples per pixel of the two whitted renders (their only noise is pixel
            antialiasing).
        path_spp: samples per pixel of the path tracer (default 8 × spp).
        seed, variant: as in :func:`phonglab.engine.render.render_scene`.
        max_depth: path length for all three (default: the scene's whitted, else 5).
        params: values for the scene's other ``<default>`` entries (width, intensity, ...).
    """
    if spp < 1 or (path_spp is not None and path_spp < 1):
        raise PhonglabError(f"spp must be >= 1, got spp={spp}, path_spp={path_spp}")
    path = scene_path(scene)
    declared = scene_defaults(path)
    # A scene with <default name="integrator"> renders with its whitted settings here.
    unknown = sorted(set(params or {}) - set(declared))
    if unknown:
        raise PhonglabError(f"{path} has no parameter {unknown[0]!r}; its <default> entries are: "
                            f"{', '.join(sorted(declared)) or 'none'}.")
    params = dict(params or {})
    if "integrator" in declared:
        params["integrator"] = "whitted"
    if max_depth is not None and "max_depth" in declared:
        params["max_depth"] = int(max_depth)
    loaded = load_scene(path, variant, **params)
    dicts = integrator_dicts(loaded, max_depth)
    integrators = {"graphics": _graphics_integrator(loaded, dicts, max_depth),
                   "radiance": mi.load_dict(dicts["radiance"]),
                   "path": mi.load_dict(dicts["path"])}
    counts = {"graphics": spp, "radiance": spp, "path": int(path_spp or 8 * spp)}
    images, stderr, seconds = {}, {}, {}
    for name in MODELS:
        t0 = time.perf_counter()
        passes = 8 if counts[name] >= 16 else 1
        result = render_scene(loaded, counts[name], seed=seed, passes=passes,
                              integrator=integrators[name], progress=progress)
        seconds[name] = time.perf_counter() - t0
        images[name], stderr[name] = result.image, result.stderr
    stats = [pair_stats(images[a], images[b], a, b) for a, b in PAIRS]
    comparison = ModelComparison(images, stderr, stats, dicts, seconds)
    if out_dir is not None:
        comparison.files = write_outputs(comparison, Path(out_dir), path, counts, seed)
    return comparison


def write_outputs(c: ModelComparison, out_dir: Path, scene: Path, counts: dict[str, int],
                  seed: int) -> list[Path]:
    """EXR + PNG per model, one difference PNG per pair, ``figure.png`` and ``table.txt``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    files: list[Path] = []
    for name in MODELS:
        meta = {"scene": str(scene), "scene_sha256": file_hash(scene), "model": name,
                "integrator": c.integrators[name], "spp": counts[name], "seed": seed,
                "variant": mi.variant(), "render_seconds": round(c.seconds[name], 4)}
        files.append(exr.write(out_dir / f"{name}.exr", c.images[name], meta))
        files.append(preview_png(out_dir / f"{name}.png", c.images[name],
                                 exposure=auto_exposure(c.images[name])))
    diffs = {}
    for st in c.stats:
        a, b = c.images[st.a], c.images[st.b]
        scale = 1.0 if st.a == "radiance" else st.scale
        diffs[(st.a, st.b)] = (luminance(scale * a - b), scale)
        fig = Figure(figsize=(4, 3.4))
        ax = fig.subplots()
        _diff_panel(fig, ax, *diffs[(st.a, st.b)], st)
        fig.tight_layout()
        files.append(out_dir / f"diff_{st.a}_{st.b}.png")
        fig.savefig(files[-1], dpi=110)
    h, w = c.images["path"].shape[:2]
    panel = 4.2                                     # inches per panel, titles ≈ 0.9 in
    fig = Figure(figsize=(3 * panel + 1.2, 2 * (panel * h / w + 0.9) + 0.4))
    axes = fig.subplots(2, 3)
    titles = {"graphics": "whitted, graphics units\n(the seed's formula)",
              "radiance": "whitted, radiance units\n(f_r cos θ I/r², direct only)",
              "path": f"path tracer\n(all light, {counts['path']} spp)"}
    for ax, name in zip(axes[0], MODELS):
        ev = auto_exposure(c.images[name])
        img = to_srgb(c.images[name], ev)
        ax.imshow(img[..., :3] if img.ndim == 3 else img, cmap="gray")
        ax.set_title(f"{titles[name]}, exposure {ev:+.1f} EV", fontsize=9)
        ax.axis("off")
    for ax, st in zip(axes[1], c.stats):
        _diff_panel(fig, ax, *diffs[(st.a, st.b)], st)
    fig.suptitle(f"{scene.name}: graphics versus physics (luminance differences, red: a > b)",
                 fontsize=11)
    fig.tight_layout()
    files.append(out_dir / "figure.png")
    fig.savefig(files[-1], dpi=110)
    files.append(out_dir / "table.txt")
    write_text(files[-1], format_table(c.stats) + "\n")
    return files


def _diff_panel(fig, ax, diff: np.ndarray, scale: float, st: PairStats) -> None:
    vmax = float(np.percentile(np.abs(diff), 99.5)) or 1e-6
    im = ax.imshow(diff, cmap="RdBu_r", vmin=-vmax, vmax=vmax)
    label = f"{st.a} − {st.b}" if scale == 1.0 else f"{scale:.3g}·{st.a} − {st.b}"
    rel = st.relative if scale == 1.0 else st.relative_scaled
    ax.set_title(f"{label}\nrelative mean |Δ| = {rel:.3f}", fontsize=9)
    ax.axis("off")
    fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04)
