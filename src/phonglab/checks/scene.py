"""Check 3, ``scene``: a whole Cornell box rendered with ``lambert`` and with ``diffuse``.

check_cornell_lambert.xml is rendered with each plugin in independent passes (per-pixel
standard errors).  The two renders use DIFFERENT seeds: with the same seed the two plugins
consume the same random numbers identically and produce the same image (measured:
bit-identical at 64 spp), which tests nothing statistical.  A Welch t test per pixel and
channel (:func:`phonglab.stats.welch_pvalues`) with Holm's correction
(:func:`phonglab.stats.holm`) at α = 0.01 must reject nothing, and the mean difference of each
channel must lie within z·SE (Šidák over the 3 channels).  On failure the difference and t
images are written to ``cfg.out_dir``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import stats
from ..engine import exr
from ..verdict import Row
from .common import Config, Rows, render


def check_scene(cfg: Config) -> list[Row]:
    """``lambert`` against ``diffuse`` in the Cornell box, per pixel and on the mean."""
    rows = Rows("scene")
    passes = max(cfg.passes, 16)
    cfg.note("scene: lambert render")
    a = render(cfg, "check_cornell_lambert", 400, bsdf=cfg.lambert, passes=passes)
    cfg.note("scene: diffuse render")
    b = render(cfg, "check_cornell_lambert", 401, bsdf="diffuse", passes=passes)
    p, t = stats.welch_pvalues(a.image, a.stderr, b.image, b.stderr, passes, passes)
    adj = stats.holm(p)
    rejected = int(np.sum(adj <= stats.ALPHA))
    diff = a.image.astype(np.float64) - b.image.astype(np.float64)
    details: dict[str, Any] = {"min_holm_p": float(adj.min()), "pixels": int(p.size),
                               "passes": passes, "seeds": "different (see docs)"}
    row_px = rows.exact(f"{cfg.lambert} vs diffuse: per-pixel", f"Cornell box, all {cfg.lambert} "
                        f"vs all diffuse: pixels×channels rejected by Welch t (Holm, α=0.01)",
                        rejected, 0, "same BSDF: equal expected images", 0.0, **details)
    se_ch = np.sqrt(np.sum(a.stderr.astype(np.float64) ** 2 + b.stderr.astype(np.float64) ** 2,
                           axis=(0, 1))) / (diff.shape[0] * diff.shape[1])
    mean_ch = diff.mean(axis=(0, 1))
    worst = int(np.argmax(np.abs(mean_ch) / np.maximum(se_ch, 1e-300)))
    row_mean = rows.stat(f"{cfg.lambert} vs diffuse: mean difference", "Cornell box: mean "
                         f"difference over the image (worst of R, G, B: {'RGB'[worst]})",
                         float(mean_ch[worst]), 0.0, "same BSDF: expected difference 0",
                         float(se_ch[worst]), tests=3, mean_per_channel=mean_ch.tolist())
    result = rows.finish()
    if not (row_px.status == "pass" and row_mean.status == "pass"):
        path = _write_failure_images(cfg, diff, t)
        row_px.details["difference_image"] = str(path)
        row_mean.details["difference_image"] = str(path)
    return result


def _write_failure_images(cfg: Config, diff: np.ndarray, t: np.ndarray):
    """The difference and Welch t images in ``cfg.out_dir``; returns the difference's path."""
    cfg.out_dir.mkdir(parents=True, exist_ok=True)
    path = cfg.out_dir / f"scene_{cfg.lambert}_vs_diffuse_diff.exr"
    exr.write(path, diff.astype(np.float32), {"what": "lambert − diffuse"})
    exr.write(cfg.out_dir / f"scene_{cfg.lambert}_vs_diffuse_t.exr", t.astype(np.float32),
              {"what": "Welch t statistic"})
    return path
