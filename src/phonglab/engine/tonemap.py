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


#: matplotlib's ``viridis`` colour map (van der Walt & Smith, CC0) as 256 sRGB 8-bit colours,
#: ``round(colormaps["viridis"](linspace(0, 1, 256))[:, :3] * 255)``, stored here because
#: importing matplotlib for this table cost every adaptive command ~0.1 s (cProfile of a
#: planned glass_slab render, 128²); ``tests/test_adaptive.py`` holds it equal to matplotlib's.
VIRIDIS = np.frombuffer(bytes.fromhex(
    "44015444025645045745055946075a46085c460a5d460b5e470d60470e61471063471164471365481467481668481769"
    "48186a481a6c481b6d481c6e481d6f481f70482071482173482374482475482576482677482878482979472a7a472c7a"
    "472d7b472e7c472f7d46307e46327e46337f463480453581453781453882443983443a83443b84433d84433e85423f85"
    "4240864241864142874144874045884046883f47883f48893e49893e4a893e4c8a3d4d8a3d4e8a3c4f8a3c508b3b518b"
    "3b528b3a538b3a548c39558c39568c38588c38598c375a8c375b8d365c8d365d8d355e8d355f8d34608d34618d33628d"
    "33638d32648e32658e31668e31678e31688e30698e306a8e2f6b8e2f6c8e2e6d8e2e6e8e2e6f8e2d708e2d718e2c718e"
    "2c728e2c738e2b748e2b758e2a768e2a778e2a788e29798e297a8e297b8e287c8e287d8e277e8e277f8e27808e26818e"
    "26828e26828e25838e25848e25858e24868e24878e23888e23898e238a8d228b8d228c8d228d8d218e8d218f8d21908d"
    "21918c20928c20928c20938c1f948c1f958b1f968b1f978b1f988b1f998a1f9a8a1e9b8a1e9c891e9d891f9e891f9f88"
    "1fa0881fa1881fa1871fa28720a38620a48621a58521a68522a78522a88423a98324aa8325ab8225ac8226ad8127ad81"
    "28ae8029af7f2ab07f2cb17e2db27d2eb37c2fb47c31b57b32b67a34b67935b77937b87838b9773aba763bbb753dbc74"
    "3fbc7340bd7242be7144bf7046c06f48c16e4ac16d4cc26c4ec36b50c46a52c56954c56856c66758c7655ac8645cc863"
    "5ec96260ca6063cb5f65cb5e67cc5c69cd5b6ccd5a6ece5870cf5773d05675d05477d1537ad1517cd2507fd34e81d34d"
    "84d44b86d54989d5488bd6468ed64590d74393d74195d84098d83e9bd93c9dd93ba0da39a2da37a5db36a8db34aadc32"
    "addc30b0dd2fb2dd2db5de2bb8de29bade28bddf26c0df25c2df23c5e021c8e020cae11fcde11dd0e11cd2e21bd5e21a"
    "d8e219dae319dde318dfe318e2e418e5e419e7e419eae51aece51befe51cf1e51df4e61ef6e620f8e621fbe723fde725"), dtype=np.uint8).reshape(256, 3)


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


#: CIE XYZ -> linear sRGB (IEC 61966-2-1, D65), for previews of ``pixel_format="xyz"`` films.
XYZ_TO_SRGB = np.array([[3.2404542, -1.5371385, -0.4985314],
                        [-0.9692660, 1.8760108, 0.0415560],
                        [0.0556434, -0.2040259, 1.0572252]])


def preview_png(path: str | Path, image: np.ndarray, exposure: float = 0.0,
                channels: list[str] | None = None) -> Path:
    """Write an 8-bit sRGB preview (exposure in stops, clipped) of a linear image.

    ``channels`` names the image's channels when they are not R, G, B (a film's
    ``pixel_format``): X, Y, Z (and A) are converted to sRGB first.
    """
    image = np.asarray(image)
    if channels and list(channels[:3]) == ["X", "Y", "Z"]:
        rgb = image[..., :3] @ XYZ_TO_SRGB.T
        image = np.concatenate([rgb, image[..., 3:]], axis=-1)
    srgb = to_srgb(image, exposure)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.round(srgb * 255.0).astype(np.uint8)).save(path, format="PNG")
    return path
