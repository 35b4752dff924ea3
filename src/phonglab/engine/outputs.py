"""The files a render writes: checked before any work starts, replaced as one set.

``phonglab render -o out/x.exr`` writes ``x.exr`` (the image), ``x.stderr.exr`` (its per-pixel
standard error, when the render has two or more passes) and ``x.png`` (a preview).  Two rules:

* **Checked first.**  Every path is checked before the scene is loaded: it must not be a
  folder; an existing file must be writable (its owner's write bit set: a file or folder made
  read-only is never written, even by root); the nearest existing folder above it must be a
  writable folder in which a file can actually be created (probed with a temporary file).  A problem is one
  sentence, and nothing has been computed yet.  Every command checks its outputs this way,
  before its work: :func:`check_output_file` for a file (a name ending in ``/`` names a
  folder and is refused), :func:`check_output_folder` for a folder of results.  An output
  that is a symbolic link is checked, and written, at the file it points to: the link stays
  (:func:`phonglab.engine.exr.atomic_paths` replaces the target, not the link).
* **Never harm what is there.**  A write is a new file renamed over the target, and a rename
  replaces *whatever* the name holds: run as root, ``--json /dev/null`` would turn the null
  device into a regular file, and ``--json /dev/full`` would "succeed".  So an output must be, or
  become, a regular file: a character or block device, a FIFO or a socket (or a link to one)
  is refused before the work, as a folder is.  An output that is one of the command's own
  inputs (the ``--plugin`` file, the scene, an image compared) is refused too: overwriting
  an input is never what a user meant.  An empty name is refused (it names nothing: skipping
  it would end with exit 0 and no output).  :func:`check_output_file` and
  :func:`check_output_folder` are the one home of these rules; every command's every output
  option goes through them, and :func:`phonglab.engine.exr.atomic_paths` refuses a rename
  over anything but a regular file at the last moment too.
* **Replaced as a set.**  Every file is written to a temporary beside its target, and the
  temporaries are renamed over the targets only once all of them are complete: written,
  fsync'ed and checked (:func:`phonglab.engine.exr.atomic_paths`).  The set is the image, its
  standard error, the preview and, for an adaptive render, the spp map ``x.spp.exr`` and its
  preview ``x.spp.png`` (:func:`spp_paths`).  A member this render does not produce is
  removed once the new set is in place (an old ``x.stderr.exr`` beside a one-pass render, an
  old spp map beside a uniform one), so no file of another render is left beside the new
  image; every EXR of the set carries the same ``render_id`` in its header, so a file left
  by another render is recognised (``phonglab compare`` refuses it).
"""

from __future__ import annotations

import json
import os
import stat
import tempfile
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from . import exr
from ..errors import PhonglabError
from .tonemap import preview_png
from ..verdict import jsonable


def _through_links(path: Path) -> Path:
    """Where a write to ``path`` lands: a symbolic link's target, else ``path``."""
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def special_kind(path: str | Path) -> str | None:
    """What ``path`` is when it exists and is neither a regular file nor a folder ("a
    character device", "a FIFO (named pipe)", ...), links followed; None otherwise."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    for test, words in ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                        (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return words
    return None if stat.S_ISREG(mode) or stat.S_ISDIR(mode) else "not a regular file"


def _refuse_empty(path, what: str, thing: str) -> None:
    """An empty (or blank) name names nothing: one sentence, never a silent skip."""
    if not str(path).strip():
        raise PhonglabError(f"the {what} is an empty name; give the name of a {thing}, or "
                            f"leave the option out")


def check_file(path: Path, what: str = "output") -> None:
    """Raise :class:`PhonglabError` when ``path`` is a folder, a device, FIFO or socket (a
    rename over it would replace it), a read-only file, or a symbolic link to a file in a
    folder that does not exist (a write through it fails, after the work)."""
    link = Path(path)
    path = _through_links(link)
    if link.is_symlink() and not path.parent.is_dir():
        raise PhonglabError(f"the {what} {link} is a symbolic link to {path}, whose folder "
                            f"does not exist; remove the link or choose another name")
    if path.is_dir():
        raise PhonglabError(f"the {what} {path} is a folder; give a file name instead")
    special = special_kind(path)
    if special is not None:
        via = f"{link} (a symbolic link to {path})" if link != path else str(path)
        raise PhonglabError(f"the {what} {via} is {special}, not a regular file, and phonglab "
                            f"writes a new file and renames it into place, which would replace "
                            f"it; give the name of a regular file (to discard the output, leave "
                            f"the option out)")
    if path.exists() and not path.stat().st_mode & stat.S_IWUSR:
        raise PhonglabError(f"the {what} {path} is read-only; make it writable "
                            f"(chmod u+w) or choose another output name")


def check_folder(path: Path, what: str = "output") -> None:
    """Raise :class:`PhonglabError` unless a file can be created where ``path`` goes."""
    _check_creatable(_through_links(Path(path)).parent, Path(path), what)


def _check_creatable(folder: Path, path: Path, what: str) -> None:
    """A file can be created in ``folder``, or in the folders that would be made for it."""
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


#: An input of a command, for :func:`check_not_input`: (its path, what it is).
Input = tuple[Any, str]


def check_not_input(path: str | Path, inputs, what: str = "output") -> None:
    """Raise :class:`PhonglabError` when the output ``path`` is the same file as one of
    ``inputs`` [(path, what it is)] (links and hard links followed): writing it would destroy
    that input."""
    if not os.path.lexists(path):
        return
    for source, kind in inputs:
        if source is None or not str(source):
            continue
        try:
            same = os.path.samefile(path, source)
        except (OSError, ValueError):
            same = False
        if same:
            raise PhonglabError(f"the {what} {path} is the {kind} {source}, one of this "
                                f"command's inputs, and writing it would destroy that input; "
                                f"choose another output name")


def check_output_file(path: str | Path, what: str = "output", inputs=()) -> Path:
    """One output file, checked before the work that fills it: not empty, not a name ending
    in ``/`` (a folder's, refused rather than written as a file named like the folder), not
    a folder, device, FIFO or socket, nor read-only (:func:`check_file`), in a folder where a
    file can be created (:func:`check_folder`), and none of the command's ``inputs``
    (:func:`check_not_input`)."""
    _refuse_empty(path, what, "file")
    if str(path).endswith(("/", os.sep)):
        raise PhonglabError(f"the {what} {path} ends in '/', which names a folder; give the "
                            f"name of a file (in that folder, or elsewhere)")
    check_file(Path(path), what)
    check_folder(Path(path), what)
    check_not_input(path, inputs, what)
    return Path(path)


def check_output_files(outputs, inputs=()) -> None:
    """Each given output of ``outputs`` [(path or None, what)] by :func:`check_output_file`
    against the command's ``inputs``, and no two of them the same file (the second write
    would replace the first)."""
    seen: dict[str, str] = {}
    for path, what in outputs:
        if path is None:
            continue
        check_output_file(path, what, inputs)
        key = os.path.realpath(path)
        if key in seen:
            raise PhonglabError(f"the {seen[key]} and the {what} are the same file {path}; "
                                f"give each its own name")
        seen[key] = what


def check_output_folder(path: str | Path, what: str = "output folder") -> Path:
    """A folder of results: a folder already, or one that can be made, with files creatable
    in it; an existing file (or device, FIFO, socket) there is refused before the work, not
    met by ``mkdir``; an empty name is refused."""
    _refuse_empty(path, what, "folder")
    real = _through_links(Path(path))
    if real.exists() and not real.is_dir():
        special = special_kind(real)
        raise PhonglabError(f"the {what} {path} is {special or 'a file'}, not a folder; give "
                            f"a folder name" + ("" if special else ", or move the file away"))
    _check_creatable(real, Path(path), what)
    return Path(path)


def check_input_file(path: str | Path, what: str = "input file") -> Path:
    """A file to read: it exists and is not a folder (each said as such)."""
    _refuse_empty(path, what, "file")
    path = Path(path)
    if path.is_dir():
        raise PhonglabError(f"the {what} {path} is a folder; give the path of a file")
    if not path.is_file():
        raise PhonglabError(f"the {what} {path} does not exist; check the path")
    return path


def spp_paths(out: str | Path) -> tuple[Path, Path]:
    """The spp map beside an output EXR: ``x.spp.exr`` (channel Y) and ``x.spp.png``."""
    out = Path(out)
    return out.with_name(out.stem + ".spp.exr"), out.with_name(out.stem + ".spp.png")


#: A member of a set written by a render's own code: (path, temporary suffix, write(tmp, meta)).
Extra = tuple[Path, str, Callable[[str, dict[str, Any]], Any]]


@dataclass(frozen=True)
class RenderOutputs:
    """The file set of one render: image, standard error, preview, spp map and its preview."""

    image: Path
    stderr: Path
    png: Path | None
    spp_map: Path
    spp_png: Path

    @classmethod
    def beside(cls, out: str | Path, png: bool = True) -> "RenderOutputs":
        out = Path(out)
        return cls(out, exr.stderr_path(out), out.with_suffix(".png") if png else None,
                   *spp_paths(out))

    def check(self, inputs=()) -> None:
        """Every file of the set can be written, and none is one of the render's ``inputs``
        [(path, what)] (see the module docstring)."""
        check_output_file(self.image, "output image", inputs)
        for path, what in ((self.stderr, "standard-error image"), (self.png, "PNG preview"),
                           (self.spp_map, "spp map"), (self.spp_png, "spp map preview")):
            if path is not None:        # the files share the image's folder
                check_file(path, what)
                check_not_input(path, inputs, what)

    def write(self, image: np.ndarray, stderr: np.ndarray | None, metadata: dict[str, Any],
              exposure: float = 0.0, extras: list[Extra] = ()) -> str:
        """Write the set (temporaries first, then the renames); returns its render id.

        ``extras`` are further members (the spp map), written with the same header.
        """
        render_id = uuid.uuid4().hex
        meta = dict(metadata, render_id=render_id)
        self.image.parent.mkdir(parents=True, exist_ok=True)
        members: list[Extra] = [(self.image, ".tmp", lambda t, m: exr.write_file(t, image, m))]
        if stderr is not None:
            members.append((self.stderr, ".tmp", lambda t, m: exr.write_file(t, stderr, m)))
        if self.png is not None:
            members.append((self.png, ".png", lambda t, m: preview_png(
                t, image, exposure=exposure, channels=m.get("channels"))))
        members += list(extras)
        with exr.atomic_paths([(path, suffix) for path, suffix, _ in members]) as temps:
            for (_, _, write), tmp in zip(members, temps):
                write(tmp, meta)
        written = {Path(path) for path, _, _ in members}
        for stale in (self.stderr, self.spp_map, self.spp_png):
            if stale not in written and stale.exists():
                os.unlink(stale)            # left by an earlier render of another kind
        return render_id

# ----------------------------------------------------------------------------- JSON files

def write_text(path: str | Path, text: str) -> Path:
    """``text`` at ``path`` (UTF-8, folders created), written to the end or not at all
    (:func:`phonglab.engine.exr.atomic_path`: the previous file untouched on any failure)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with exr.atomic_path(path, path.suffix or ".txt") as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return path


def write_json(path: str | Path, data: Any, *, indent: int | None = 1,
               separators: tuple[str, str] | None = None, end: str = "") -> Path:
    """``data`` as strict JSON at ``path`` (folders created): :func:`jsonable` first, never a
    bare NaN (``allow_nan=False``), written to the end or not at all
    (:func:`phonglab.engine.exr.atomic_path`, the previous file untouched on any failure).  ``indent``,
    ``separators`` and ``end`` (a trailing newline) as each file has always been written."""
    return write_text(path, json.dumps(jsonable(data), indent=indent, separators=separators,
                                       allow_nan=False) + end)
