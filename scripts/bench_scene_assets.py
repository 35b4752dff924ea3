"""Write the textures of the two held-out bench scenes (``textured_room``, ``outdoor_envmap``).

Deterministic (fixed seed), so the committed files can be re-made bit for bit:

* ``src/phonglab/scenes_xml/textures/tiles.png``: 8-bit sRGB floor tiles, 128×128: 4×4 tiles
  of warm ochre/terracotta, each with its own brightness and a little per-texel noise, and dark grout
  lines (the kind of 8-bit texture users bring).
* ``src/phonglab/scenes_xml/textures/sky.exr``: a 128×64 equirectangular (lat-long) sky in
  linear RGB: a blue zenith fading to a pale horizon, a dim brown ground below it, and a sun 3° across at
  35° elevation holding about 40 % of the power it sends in (an outdoor light whose power is
  concentrated: what emitter sampling of an ``envmap`` has to find).

Run: ``.venv/bin/python scripts/bench_scene_assets.py`` (writes both files).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenEXR
from PIL import Image

OUT = Path(__file__).resolve().parents[1] / "src" / "phonglab" / "scenes_xml" / "textures"


def tiles(size: int = 128, n: int = 4, seed: int = 3) -> np.ndarray:
    """(size, size, 3) uint8 sRGB tiles with grout lines."""
    rng = np.random.default_rng(seed)
    base = np.array([[196, 128, 84], [170, 96, 64], [214, 160, 104]], dtype=np.float64)
    img = np.zeros((size, size, 3))
    step = size // n
    for i in range(n):
        for j in range(n):
            colour = base[rng.integers(len(base))] * rng.uniform(0.8, 1.1)
            img[i * step:(i + 1) * step, j * step:(j + 1) * step] = colour
    img *= rng.uniform(0.93, 1.07, size=(size, size, 1))
    grout = (np.arange(size) % step < 2)
    img[grout, :] = 60
    img[:, grout] = 60
    return np.clip(img, 0, 255).astype(np.uint8)


def sky(width: int = 128, height: int = 64) -> np.ndarray:
    """(height, width, 3) float32 linear radiance, Mitsuba's lat-long layout (row 0: zenith)."""
    theta = (np.arange(height) + 0.5) / height * np.pi          # polar angle from +Y (up)
    phi = (np.arange(width) + 0.5) / width * 2 * np.pi
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    elev = np.pi / 2 - th
    up = np.clip(np.sin(elev), 0, 1)[..., None]
    zenith, horizon = np.array([0.25, 0.45, 0.9]), np.array([0.9, 0.95, 1.0])
    img = np.where(elev[..., None] > 0, horizon + (zenith - horizon) * up ** 0.5,
                   np.array([0.12, 0.09, 0.06]))
    sun_elev, sun_phi, radius = np.radians(35.0), np.radians(120.0), np.radians(1.5)
    d = np.stack([np.cos(elev) * np.cos(ph), np.sin(elev), np.cos(elev) * np.sin(ph)], -1)
    s = np.array([np.cos(sun_elev) * np.cos(sun_phi), np.sin(sun_elev),
                  np.cos(sun_elev) * np.sin(sun_phi)])
    sun = np.arccos(np.clip(d @ s, -1, 1)) < radius
    # texels 2.8° tall: the sun covers a few; its radiance puts ~40 % of the power there (solid-angle weighted)
    img[sun] = np.array([400.0, 380.0, 340.0]) * (5.0 / max(int(sun.sum()), 1))
    return img.astype(np.float32)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    Image.fromarray(tiles()).save(OUT / "tiles.png")
    img = sky()
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": img}) as f:
        f.write(str(OUT / "sky.exr"))
    print(f"wrote {OUT / 'tiles.png'} and {OUT / 'sky.exr'}")


if __name__ == "__main__":
    main()
