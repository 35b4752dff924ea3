"""What several test files share: a tiny film, a whitted scene without a max_depth default, writing
a file, the check that a command failed in one sentence (exit 2, no traceback), the things an
output path may name that are not regular files (FIFOs, sockets, character devices), made in a
test's own folder, and plugin files that exit or hang, with the guards that keep such a plugin
from ending or hanging the test run itself."""

from __future__ import annotations

import _thread
import contextlib
import io
import os
import socket
import stat
import tempfile
import threading
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


#: What a plugin may do instead of returning (:func:`acting_plugin`).
PLUGIN_ACTIONS = {"sys_exit": "sys.exit(0)", "sys_exit_3": "sys.exit(3)",
                  "os_exit": "os._exit(0)", "hang": "while True: pass"}
#: Where it may do it: at import, or in a method of the BSDF.
PLUGIN_PLACES = ("import", "__init__", "traverse", "eval", "pdf", "eval_pdf", "sample")
AUTHORS = Path(__file__).parent / "authors"


def acting_plugin(folder: Path, place: str, action: str, name: str | None = None,
                  marker: Path | None = None) -> Path:
    """``tests/authors/my_lambert.py`` (a correct Lambertian) registered as ``name`` that does
    ``action`` of :data:`PLUGIN_ACTIONS` at ``place`` of :data:`PLUGIN_PLACES` (creating the
    file ``marker`` first, when given: whether the command ever reached it); its path."""
    name = name or f"act_{place.strip('_')}_{action}"
    text = (AUTHORS / "my_lambert.py").read_text().replace('"my_lambert"', repr(name))
    code = ["import os, sys", *([f"open({str(marker)!r}, 'a').close()"] if marker else []),
            PLUGIN_ACTIONS[action]]
    if place == "import":
        text = text.replace("import mitsuba as mi\n", "import mitsuba as mi\n"
                            + "".join(f"{line}\n" for line in code), 1)
    else:
        start = text.index(f"    def {place}(self")
        body = text.index(":\n", start) + 2
        text = text[:body] + "".join(f"        {line}\n" for line in code) + text[body:]
    path = folder / f"{name}.py"
    path.write_text(text)
    return path


class ProcessWouldEnd(BaseException):
    """``os._exit`` reached a test: phonglab let a plugin end the process."""


def refuse_process_exit(monkeypatch) -> None:
    """Replace ``os._exit`` for the test by one that raises :class:`ProcessWouldEnd` (nothing
    in phonglab catches it), so a call phonglab lets through fails the test instead of ending
    pytest with status 0 -- a green run that judged nothing."""
    def refuse(status, *args):
        raise ProcessWouldEnd(f"os._exit({status}) would have ended the test process")

    monkeypatch.setattr(os, "_exit", refuse)


@contextlib.contextmanager
def watchdog(seconds: float):
    """Fail the test if the block runs longer than ``seconds`` (a hang a fix should stop): a
    timer thread interrupts the main thread."""
    timer = threading.Timer(seconds, _thread.interrupt_main)
    timer.start()
    try:
        yield
    except KeyboardInterrupt:
        pytest.fail(f"still running after {seconds:g} s: the hang was not stopped")
    finally:
        timer.cancel()


def run_cli(argv, seconds: float = 120) -> tuple[int, str, str]:
    """``phonglab ARGV`` in-process under a :func:`watchdog`: (exit status, stdout, stderr); a
    SystemExit that escapes (a plugin's sys.exit(0) past phonglab's guard) is returned as its
    status, as a shell would see it."""
    out, err = io.StringIO(), io.StringIO()
    with watchdog(seconds), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = cli.main([str(a) for a in argv])
        except SystemExit as exc:
            rc = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    return rc, out.getvalue(), err.getvalue()


def assert_no_green(rc: int, err: str) -> None:
    """Non-zero, and either failing rows (1) or one sentence (2); never a traceback."""
    assert rc in (1, 2), (rc, err[-2000:])
    assert "Traceback" not in err, err[-3000:]
    if rc == 2:
        lines = [ln.split("\r")[-1] for ln in err.splitlines()]      # a progress bar's \r
        lines = [ln for ln in lines if ln.strip()]
        assert len(lines) == 1 and lines[0].startswith("phonglab: error: "), err
