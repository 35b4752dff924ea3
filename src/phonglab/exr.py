"""OpenEXR images that carry their provenance, written atomically.

Images are float32, linear, ``(H, W)`` (channel ``Y``), ``(H, W, 3)`` (``RGB``) or
``(H, W, 4)`` (``RGBA``).  Metadata goes into the header as string attributes
prefixed ``phonglab:`` (scene file and its hash, variant, spp, seed, integrator,
max depth, render time, versions); :func:`read` returns it as a dict.

A write goes to a temporary file in the destination folder, then
``os.replace`` renames it over the target: an interrupted render never leaves a
truncated EXR, and the previous file survives.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import OpenEXR

PREFIX = "phonglab:"


def _channels(image: np.ndarray) -> dict[str, np.ndarray]:
    image = np.ascontiguousarray(np.asarray(image, dtype=np.float32))
    if image.ndim == 2:
        return {"Y": image}
    if image.ndim == 3 and image.shape[2] == 1:
        return {"Y": np.ascontiguousarray(image[..., 0])}
    if image.ndim == 3 and image.shape[2] == 3:
        return {"RGB": image}
    if image.ndim == 3 and image.shape[2] == 4:
        return {"RGBA": image}
    raise ValueError(f"cannot write an image of shape {image.shape} as EXR: expected "
                     f"(H, W), (H, W, 1), (H, W, 3) or (H, W, 4)")


def write(path: str | os.PathLike, image, metadata: Mapping[str, Any] | None = None) -> Path:
    """Write ``image`` as a float32 EXR with ``metadata`` in its header, atomically.

    Values of ``metadata`` are stored as JSON strings (non-JSON values via ``str``).
    Returns the final path.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    header: dict[str, Any] = {"compression": OpenEXR.ZIP_COMPRESSION,
                              "type": OpenEXR.scanlineimage}
    for key, value in (metadata or {}).items():
        header[PREFIX + str(key)] = json.dumps(value, default=str)
    channels = _channels(np.asarray(image))
    fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        OpenEXR.File(header, channels).write(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def read(path: str | os.PathLike) -> tuple[np.ndarray, dict[str, Any]]:
    """Read an EXR: (float32 image, phonglab metadata).

    The image is (H, W) for one channel, (H, W, 3) or (H, W, 4) otherwise.
    Metadata values written by :func:`write` come back as Python values.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such EXR file: {path}")
    try:
        with OpenEXR.File(str(path)) as f:
            header = dict(f.header())
            channels = {name: np.array(ch.pixels, dtype=np.float32)
                        for name, ch in f.channels().items()}
    except Exception as exc:  # OpenEXR raises plain exceptions for broken files
        raise ValueError(f"{path} is not a readable OpenEXR file ({exc})") from exc
    if len(channels) == 1:
        image = next(iter(channels.values()))
    else:
        order = [c for c in ("R", "G", "B", "A") if c in channels] or sorted(channels)
        image = np.stack([channels[c] for c in order], axis=-1)
    meta: dict[str, Any] = {}
    for key, value in header.items():
        if isinstance(key, str) and key.startswith(PREFIX):
            try:
                meta[key[len(PREFIX):]] = json.loads(value)
            except (TypeError, ValueError):
                meta[key[len(PREFIX):]] = value
    return image, meta
