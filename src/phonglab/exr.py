"""OpenEXR images that carry their provenance, written atomically.

Images are float32, linear, ``(H, W)`` (channel ``Y``), ``(H, W, 3)`` (``RGB``) or
``(H, W, 4)`` (``RGBA``).  Metadata goes into the header as string attributes
prefixed ``phonglab:`` (scene file and its hash, variant, spp, seed, integrator,
max depth, render time, versions), each value JSON-encoded; :func:`read`
returns it as a dict of Python values.

A write goes to a temporary file in the destination folder (same file system),
is flushed to disk (``fsync``), then ``os.replace`` renames it over the target,
which POSIX makes atomic: an interrupted render never leaves a truncated EXR,
and the previous file survives intact.  The temporary file is removed on any
failure, including ``KeyboardInterrupt``.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import OpenEXR

from .errors import ExrError

PREFIX = "phonglab:"
#: The four bytes every OpenEXR file starts with (OpenEXR file layout, "magic number").
MAGIC = b"\x76\x2f\x31\x01"


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
    raise ExrError(f"cannot write an image of shape {image.shape} as EXR; pass an array of "
                   f"shape (H, W), (H, W, 1), (H, W, 3) or (H, W, 4)")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: Path, suffix: str):
    """A temporary file beside ``path`` to write into; renamed over ``path`` on success.

    The bytes are fsync'ed before the rename and the file gets the usual permissions
    (mkstemp creates 0600); on any error the temporary file is removed and a previous file
    at ``path`` stays untouched.
    """
    fd, tmp = tempfile.mkstemp(prefix="." + path.name + ".", suffix=suffix, dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        with open(tmp, "rb") as f:       # the bytes reach the disk before the rename
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write(path: str | os.PathLike, image, metadata: Mapping[str, Any] | None = None) -> Path:
    """Write ``image`` as a float32 EXR with ``metadata`` in its header, atomically.

    Args:
        path: destination; its folder is created when missing.
        image: (H, W), (H, W, 1), (H, W, 3) or (H, W, 4) array, linear values.
        metadata: header entries, stored as ``phonglab:<key>`` = JSON text of the value
            (values JSON cannot encode are stored as their ``str``).

    Returns:
        the final path.  The file appears complete or not at all; a previous file at
        ``path`` is replaced only once the new one is fully on disk.
    """
    path = Path(path)
    if path.is_dir():
        raise ExrError(f"{path} is a folder; give a file name ending in .exr")
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path, ".tmp") as tmp:
        write_file(tmp, image, metadata)
    return path


def write_file(path: str | os.PathLike, image, metadata: Mapping[str, Any] | None = None) -> None:
    """Write the EXR straight to ``path`` (no temporary: callers that replace a set of files
    write each into an :func:`atomic_path` temporary with this)."""
    header: dict[str, Any] = {"compression": OpenEXR.ZIP_COMPRESSION,
                              "type": OpenEXR.scanlineimage}
    for key, value in (metadata or {}).items():
        header[PREFIX + str(key)] = json.dumps(value, default=str)
    OpenEXR.File(header, _channels(np.asarray(image))).write(str(path))


def stderr_path(path: str | os.PathLike) -> Path:
    """The standard-error image written beside an image: ``x.exr`` -> ``x.stderr.exr``."""
    path = Path(path)
    return path.with_name(path.stem + ".stderr.exr")


def is_exr(path: str | os.PathLike) -> bool:
    """Whether ``path`` starts with the OpenEXR magic number."""
    try:
        with open(path, "rb") as f:
            return f.read(4) == MAGIC
    except OSError:
        return False


def read(path: str | os.PathLike) -> tuple[np.ndarray, dict[str, Any]]:
    """Read an EXR: (float32 image, phonglab metadata).

    Returns:
        the image, (H, W) for one channel, (H, W, 3) for RGB or (H, W, 4) for RGBA
        (other channel sets in alphabetical order), and the ``phonglab:`` header
        entries as Python values (the raw string where one is not JSON).

    Raises:
        FileNotFoundError: no such file.
        ExrError: the file is not an OpenEXR image, or is truncated or damaged.
    """
    path = Path(path)
    if path.is_dir():
        raise ExrError(f"{path} is a folder, not an EXR file; give the path of an .exr file")
    if not path.is_file():
        raise FileNotFoundError(f"no such EXR file: {path}; check the path "
                                f"(`phonglab render` writes out/<scene>.exr by default)")
    if not is_exr(path):
        raise ExrError(f"{path} is not an OpenEXR file (it lacks the EXR magic number); "
                       f"give the .exr file phonglab render wrote, not its .png preview")
    try:
        with OpenEXR.File(str(path)) as f:
            header = dict(f.header())
            channels = {name: np.array(ch.pixels, dtype=np.float32)
                        for name, ch in f.channels().items()}
    except Exception as exc:  # OpenEXR raises plain exceptions for broken files
        raise ExrError(f"{path} is a damaged or truncated OpenEXR file ({exc}); "
                       f"render it again") from exc
    if not channels:
        raise ExrError(f"{path} holds no image channels; render it again")
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


def read_image(path: str | os.PathLike) -> np.ndarray:
    """The image of :func:`read` as (H, W, C), C >= 1, so that channels index uniformly."""
    image, _ = read(path)
    return image if image.ndim == 3 else image[..., None]
