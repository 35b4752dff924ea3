"""OpenEXR images that carry their provenance, written atomically.

Images are float32, linear, ``(H, W)`` (channel ``Y``), ``(H, W, 3)`` (``RGB``) or
``(H, W, 4)`` (``RGBA``); an image whose metadata names its channels (``"channels": ["X",
"Y", "Z"]``, a film's other ``pixel_format``) is written one channel per name, and
:func:`read` returns them in that order.  Metadata goes into the header as string attributes
prefixed ``phonglab:`` (scene file and its hash, variant, spp, seed, integrator,
max depth, render time, versions), each value JSON-encoded; :func:`read`
returns it as a dict of Python values.

A write goes to a temporary file in the destination folder (same file system),
is flushed to disk (``fsync``), then ``os.replace`` renames it over the target,
which POSIX makes atomic: an interrupted render never leaves a truncated EXR,
and the previous file survives intact.  The temporary file is removed on any
failure, including ``KeyboardInterrupt``.

Every write is checked to the end.  OpenEXR does not report a failure when the file is
closed, so on a full disk it could leave a 0-byte or truncated file and say nothing: an EXR
is read back from the temporary and compared with what was written, bit for bit, before
the rename; any temporary that ends up empty is refused; an ``OSError`` on the way (no
space, file too large, I/O error), or OpenEXR's own write error, becomes one
:class:`~phonglab.errors.WriteError` sentence.  The previous file is untouched in every case.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import stat
import tempfile
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import OpenEXR

from ..errors import ExrError, WriteError

PREFIX = "phonglab:"
#: The four bytes every OpenEXR file starts with (OpenEXR file layout, "magic number").
MAGIC = b"\x76\x2f\x31\x01"


#: Channel sets written as one OpenEXR channel group named by the image's shape alone.
SHAPE_NAMED = (["Y"], ["R", "G", "B"], ["R", "G", "B", "A"])


def _channels(image: np.ndarray, names: list[str] | None = None) -> dict[str, np.ndarray]:
    """The OpenEXR channels of ``image``: by its shape (Y, RGB, RGBA), or one channel per
    entry of ``names`` (a film's own layout: X, Y, Z; Y, A; ...)."""
    image = np.ascontiguousarray(np.asarray(image, dtype=np.float32))
    if names is not None and list(names) not in SHAPE_NAMED:
        planes = image[..., None] if image.ndim == 2 else image
        if planes.ndim != 3 or planes.shape[2] != len(names) or len(set(names)) != len(names):
            raise ExrError(f"cannot name the {planes.shape[-1]} channels of an image of shape "
                           f"{image.shape} {', '.join(map(str, names))}; give one distinct "
                           f"name per channel")
        return {str(n): np.ascontiguousarray(planes[..., k]) for k, n in enumerate(names)}
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
    at ``path`` stays untouched (:func:`atomic_paths` of one file).
    """
    with atomic_paths([(path, suffix)]) as (tmp,):
        yield tmp


@contextlib.contextmanager
def atomic_paths(targets):
    """Temporaries beside each of ``targets`` [(path, suffix)], renamed over them as one set.

    Every temporary is written, fsync'ed and checked (none may be empty) before the first
    rename, so a failure in any member (a full disk, an exception, Ctrl-C) leaves every
    previous file of the set untouched and no temporary behind.  A target that is a symbolic
    link is written through: the file it points to is replaced, and the link stays.
    """
    paths = [Path(os.path.realpath(p)) if os.path.islink(p) else Path(p) for p, _ in targets]
    temps: list[str] = []
    try:
        for path, (_, suffix) in zip(paths, targets):
            try:
                fd, tmp = tempfile.mkstemp(prefix="." + path.name + ".", suffix=suffix,
                                           dir=path.parent)
            except OSError as exc:
                raise write_error(path, exc) from None
            os.close(fd)
            temps.append(tmp)
        yield list(temps)
        for path, tmp in zip(paths, temps):
            _settle(path, tmp)
        for path in paths:
            _replaceable(path)
        for path, tmp in zip(paths, temps):
            os.replace(tmp, path)
    except (OSError, WriteError) as exc:
        for tmp in temps:
            _remove(tmp)
        if isinstance(exc, WriteError) and exc.path not in map(Path, temps):
            raise                    # already named by its target
        about = getattr(exc, "path", None) or getattr(exc, "filename", None)
        target = dict(zip(map(Path, temps), paths)).get(Path(about) if about else None,
                                                        paths[0])
        raise write_error(target, exc) from None     # named by the target, not a temporary
    except BaseException:
        for tmp in temps:
            _remove(tmp)
        raise


def _settle(path: Path, tmp: str) -> None:
    """``tmp``'s bytes on disk (fsync), not empty, with the usual permissions; else one
    :class:`WriteError` sentence naming ``path``."""
    try:
        with open(tmp, "rb") as f:       # the bytes reach the disk before the rename
            os.fsync(f.fileno())
            empty = os.fstat(f.fileno()).st_size == 0
        os.chmod(tmp, 0o666 & ~_umask())
    except OSError as exc:
        raise write_error(path, exc) from None
    if empty:
        raise write_error(path, "the file came out empty: is the disk full?")


def _replaceable(path: Path) -> None:
    """Nothing but a regular file (or nothing) is at ``path``: a rename over a device, FIFO,
    socket or folder would replace it (as root, ``/dev/null`` became a regular file), so that
    is one :class:`WriteError` sentence, before any member of the set is renamed."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return
    except OSError as exc:
        raise write_error(path, exc) from None
    if not stat.S_ISREG(mode):
        err = WriteError(f"cannot write {path}: it is not a regular file (a device, FIFO, "
                         f"socket or folder), which the write would replace; give the name of "
                         f"a regular file")
        err.reason, err.path = "not a regular file", Path(path)
        raise err


def _remove(tmp: str) -> None:
    if os.path.exists(tmp):
        os.unlink(tmp)


def _advice(cause: BaseException | str) -> str:
    """What to do about a failed write, by its cause (a full disk unless the error says
    otherwise: OpenEXR's errors carry no errno)."""
    code = getattr(cause, "errno", None)
    if code in (errno.EACCES, errno.EPERM, errno.EROFS):
        return "make that folder writable or choose another one"
    if code in (errno.ENOENT, errno.ENOTDIR):
        return "files cannot be created there; choose another folder"
    return "free space on that disk or choose another folder"


def write_error(path: Path, cause: BaseException | str) -> WriteError:
    """The one sentence for a write of ``path`` that failed (``cause``: an exception or words);
    its ``reason`` is kept, so a caller that wrote into a temporary names the real target."""
    if isinstance(cause, str):
        reason = cause
    else:
        reason = getattr(cause, "reason", None) or getattr(cause, "strerror", None) or \
            str(cause).split(". ")[-1].rstrip(".") or type(cause).__name__
    err = WriteError(f"cannot write {path} ({reason}); {_advice(cause)}; the previous "
                     f"{path.name}, if any, is unchanged")
    err.reason, err.path = reason, Path(path)
    return err


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
    channels = _channels(np.asarray(image), (metadata or {}).get("channels"))
    try:
        OpenEXR.File(header, dict(channels)).write(str(path))   # (it wraps the dict's values)
    except (RuntimeError, OSError) as exc:
        raise write_error(Path(path), exc) from None
    try:
        with OpenEXR.File(str(path)) as back:        # checked to the end (module docstring)
            stored = back.channels()
            complete = stored.keys() == channels.keys() and all(
                np.array_equal(stored[k].pixels, v, equal_nan=True) for k, v in channels.items())
    except (RuntimeError, OSError):
        complete = False
    if not complete:
        raise write_error(Path(path), "it does not read back as the image written: is the "
                                      "disk full?")


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
    meta: dict[str, Any] = {}
    for key, value in header.items():
        if isinstance(key, str) and key.startswith(PREFIX):
            try:
                meta[key[len(PREFIX):]] = json.loads(value)
            except (TypeError, ValueError):
                meta[key[len(PREFIX):]] = value
    named = meta.get("channels")
    if len(channels) == 1:
        image = next(iter(channels.values()))
    else:
        order = (named if isinstance(named, list) and sorted(named) == sorted(channels) else
                 [c for c in ("R", "G", "B", "A") if c in channels] or sorted(channels))
        image = np.stack([channels[c] for c in order], axis=-1)
    return image, meta


def read_image(path: str | os.PathLike) -> np.ndarray:
    """The image of :func:`read` as (H, W, C), C >= 1, so that channels index uniformly."""
    image, _ = read(path)
    return image if image.ndim == 3 else image[..., None]
