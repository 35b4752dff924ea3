"""The files a render writes: checked before any work starts, replaced as one set.

``phonglab render -o out/x.exr`` writes ``x.exr`` (the image), ``x.stderr.exr`` (its per-pixel
standard error, when the render has two or more passes) and ``x.png`` (a preview).  Two rules:

* **Checked first.**  Every path is checked before the scene is loaded: it must not be a
  folder; an existing file must be writable (its owner's write bit set: a file or folder made
  read-only is never written, even by root); the nearest existing folder above it must be a
  writable folder in which a file can actually be created (probed with a temporary file).  A problem is one
  sentence, and nothing has been computed yet.
* **Replaced as a set.**  Every file is written to a temporary beside its target, and the
  temporaries are renamed over the targets only once all of them are complete
  (:func:`phonglab.exr.atomic_path`).  A render without a standard error removes an old
  ``x.stderr.exr``; every EXR of the set carries the same ``render_id`` in its header, so a
  standard-error file left by another render is recognised (``phonglab compare`` refuses it).
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from . import exr
from .errors import PhonglabError
from .tonemap import preview_png


def check_file(path: Path, what: str = "output") -> None:
    """Raise :class:`PhonglabError` when ``path`` is a folder or a read-only file."""
    path = Path(path)
    if path.is_dir():
        raise PhonglabError(f"the {what} {path} is a folder; give a file name instead")
    if path.exists() and not path.stat().st_mode & stat.S_IWUSR:
        raise PhonglabError(f"the {what} {path} is read-only; make it writable "
                            f"(chmod u+w) or choose another output name")


def check_folder(path: Path, what: str = "output") -> None:
    """Raise :class:`PhonglabError` unless a file can be created where ``path`` goes."""
    path = Path(path)
    folder = path.parent
    while not folder.exists():
        folder = folder.parent
    if not folder.is_dir():
        raise PhonglabError(f"cannot create the {what} {path}: {folder} is a file, not a "
                            f"folder; choose another output path")
    if not folder.stat().st_mode & stat.S_IWUSR:
        raise PhonglabError(f"the folder {folder} is read-only; make it writable (chmod u+w) "
                            f"or choose another folder for the {what}")
    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".phonglab-probe-"):
            pass
    except OSError as exc:
        raise PhonglabError(f"cannot create files in {folder} ({exc.strerror}); choose a "
                            f"writable folder for the {what}") from None


@dataclass(frozen=True)
class RenderOutputs:
    """The file set of one render: image, standard error, preview."""

    image: Path
    stderr: Path
    png: Path | None

    @classmethod
    def beside(cls, out: str | Path, png: bool = True) -> "RenderOutputs":
        out = Path(out)
        return cls(out, exr.stderr_path(out), out.with_suffix(".png") if png else None)

    def check(self) -> None:
        """Every file of the set can be written (see the module docstring)."""
        check_file(self.image, "output image")
        check_file(self.stderr, "standard-error image")
        if self.png is not None:
            check_file(self.png, "PNG preview")
        check_folder(self.image, "output image")     # the three files share one folder

    def write(self, image: np.ndarray, stderr: np.ndarray | None, metadata: dict[str, Any],
              exposure: float = 0.0) -> str:
        """Write the set (temporaries first, then the renames); returns its render id."""
        render_id = uuid.uuid4().hex
        meta = dict(metadata, render_id=render_id)
        self.image.parent.mkdir(parents=True, exist_ok=True)
        with contextlib.ExitStack() as stack:
            exr.write_file(stack.enter_context(exr.atomic_path(self.image, ".tmp")), image, meta)
            if stderr is not None:
                exr.write_file(stack.enter_context(exr.atomic_path(self.stderr, ".tmp")),
                               stderr, meta)
            if self.png is not None:
                preview_png(stack.enter_context(exr.atomic_path(self.png, ".png")), image,
                            exposure=exposure, channels=meta.get("channels"))
        if stderr is None and self.stderr.exists():
            os.unlink(self.stderr)          # a stale standard error of an earlier render
        return render_id
