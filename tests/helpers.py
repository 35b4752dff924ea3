"""What several test files share: a tiny film, a whitted scene without a max_depth default, writing
a file, the check that a command failed in one sentence (exit 2, no traceback), and the things
an output path may name that are not regular files (FIFOs, sockets, character devices), made in
a test's own folder."""

from __future__ import annotations

import os
import socket
import stat
import tempfile
from pathlib import Path

import pytest

from phonglab import cli

FILM = ('<sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" '
        'target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm">'
        '<integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>')
WHITTED_NO_DEPTH_DEFAULT = f"""<scene version="3.0.0">
  <integrator type="whitted"><string name="units" value="graphics"/></integrator>
  {FILM}
  <shape type="sphere"><bsdf type="phong"/></shape>
  <emitter type="point"><point name="position" value="0, 2, 3"/><rgb name="intensity" value="5"/></emitter>
</scene>"""


def write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def fails_in_one_sentence(capsys, argv: list[str], *patterns: str) -> str:
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.split("\r")[-1].strip()   # after the progress bar, if any
    assert err.startswith("phonglab: error: ") and "\n" not in err, err
    assert "Traceback" not in err and "malformed XML" not in err, err
    for p in patterns:
        assert p in err, (p, err)
    return err


#: Things at an output path that are not regular files (:func:`make_special`).
SPECIAL_KINDS = ("fifo", "socket", "char_device")


def make_special(path: Path, kind: str) -> int:
    """Make a FIFO, a UNIX socket or a character device (the numbers of /dev/full, 1:7) at
    ``path``, in a test's own folder -- never a real /dev entry; returns its file type
    (``stat.S_IFMT``) to compare after the run.  A character device needs root (skipped
    otherwise)."""
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "socket":
        # AF_UNIX names are limited to ~108 bytes: bound in a short folder, then moved here
        short = tempfile.mkdtemp(prefix="s", dir="/tmp")
        with socket.socket(socket.AF_UNIX) as s:
            s.bind(os.path.join(short, "s"))
        os.rename(os.path.join(short, "s"), path)
        os.rmdir(short)
    elif kind == "char_device":
        if os.geteuid() != 0:
            pytest.skip("making a character device needs root")
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 7))
    else:
        raise AssertionError(kind)
    return stat.S_IFMT(os.lstat(path).st_mode)

