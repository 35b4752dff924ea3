"""From linear radiance to a picture: the sRGB transfer, automatic exposure, PNG previews.

The sRGB transfer is IEC 61966-2-1: 12.92·x below 0.0031308, 1.055·x^(1/2.4) − 0.055 above.
Previews are clipped to [0, 1] after an exposure of ``2^EV``; :func:`auto_exposure` picks
the EV that puts the 99th percentile at 0.8, which graphics-unit images (whose values the
seed's formula does not bound) need and radiance renders of lit scenes usually do not.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image


def auto_exposure(image: np.ndarray, darken_only: bool = False) -> float:
    """Stops that put the 99th percentile of ``image`` at 0.8 (0 for a black image).

    With ``darken_only`` an image that already fits (99th percentile <= 1) keeps exposure 0,
    so radiance renders are previewed as they are and only graphics-unit images are brought
    into range.
    """
    p = float(np.percentile(np.nan_to_num(np.asarray(image, np.float64)), 99))
    if p <= 0 or (darken_only and p <= 1.0):
        return 0.0
    return float(np.log2(0.8 / p))


def to_srgb(image: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """Linear radiance → display sRGB in [0, 1] (exposure in stops, clipped).

    A one-channel (H, W, 1) image comes back as (H, W).
    """
    img = np.asarray(image, dtype=np.float64) * (2.0 ** exposure)
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[..., 0]
    img = np.clip(np.nan_to_num(img, nan=0.0, posinf=1.0), 0.0, 1.0)
    return np.where(img <= 0.0031308, 12.92 * img, 1.055 * np.power(img, 1 / 2.4) - 0.055)


def preview_png(path: str | Path, image: np.ndarray, exposure: float = 0.0) -> Path:
    """Write an 8-bit sRGB preview (exposure in stops, clipped) of a linear image."""
    srgb = to_srgb(image, exposure)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.round(srgb * 255.0).astype(np.uint8)).save(path, format="PNG")
    return path
