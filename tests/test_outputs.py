"""A render's outputs: checked before the render (read-only, a parent that is a file, a PNG path
that is a folder), written as one set (a stale ``.stderr.exr`` removed, the spp map a member,
the previous set kept on any failure), a full disk one sentence with nothing left behind
(phonglab.engine.outputs, phonglab.engine.exr)."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from phonglab import cli
from phonglab.engine import exr

from helpers import fails_in_one_sentence as _fails_in_one_sentence


# --- stale files -------------------------------------------------------------------------------

def test_a_render_without_stderr_removes_the_old_one(tmp_path, capsys):
    out = tmp_path / "x.exr"
    assert cli.main(["render", "gray_direct", "--spp", "16", "-o", str(out)]) == 0
    assert exr.stderr_path(out).is_file()
    assert cli.main(["render", "gray_direct", "--spp", "4", "-o", str(out)]) == 0
    capsys.readouterr()
    assert out.is_file() and not exr.stderr_path(out).exists()
    # The image and its (absent) stderr belong to one render: compare uses pixel differences.
    assert cli.main(["compare", str(out), str(out), "--json"]) == 0
    assert '"pixel differences"' in capsys.readouterr().out


def test_compare_refuses_a_stderr_file_of_another_render(tmp_path, capsys):
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    for out, seed in ((a, "0"), (b, "1")):
        assert cli.main(["render", "gray_direct", "--spp", "16", "--seed", seed, "-o", str(out)]) == 0
    ids = {exr.read(p)[1]["render_id"] for p in (a, exr.stderr_path(a), b)}
    assert len(ids) == 2                     # a and a.stderr share one id, b has another
    exr.stderr_path(b).replace(exr.stderr_path(a))  # a stale stderr now sits beside a
    capsys.readouterr()
    _fails_in_one_sentence(capsys, ["compare", str(a), str(a)], "belongs to another render")


# --- outputs are checked before the render -----------------------------------------------------

def test_a_read_only_output_is_refused_and_kept(tmp_path, capsys):
    out = tmp_path / "x.exr"
    out.write_bytes(b"keep me")
    out.chmod(stat.S_IRUSR | stat.S_IRGRP)
    _fails_in_one_sentence(capsys, ["render", "gray_direct", "-o", str(out)], "read-only")
    assert out.read_bytes() == b"keep me"


def test_a_read_only_folder_is_refused(tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(stat.S_IRUSR | stat.S_IXUSR)
    try:
        _fails_in_one_sentence(capsys, ["render", "gray_direct", "-o", str(folder / "x.exr")],
                               "read-only")
    finally:
        folder.chmod(stat.S_IRWXU)
    assert os.listdir(folder) == []


def test_a_parent_that_is_a_file_is_refused(tmp_path, capsys):
    (tmp_path / "f").write_text("")
    _fails_in_one_sentence(capsys, ["render", "gray_direct", "-o", str(tmp_path / "f" / "x.exr")],
                           "is a file, not a folder")


def test_a_png_path_that_is_a_folder_is_refused(tmp_path, capsys):
    (tmp_path / "x.png").mkdir()
    _fails_in_one_sentence(capsys, ["render", "gray_direct", "-o", str(tmp_path / "x.exr")],
                           "is a folder")
    assert not (tmp_path / "x.exr").exists()


# --- a full disk: one sentence, the previous files byte-identical, nothing left behind ---------

@pytest.fixture
def small_disk(tmp_path):
    """A folder on a real 256 KiB tmpfs (root can mount one here; skipped where it cannot)."""
    mnt = tmp_path / "disk"
    mnt.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(mnt)],
                          capture_output=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], check=False)


def _fill(folder: Path) -> None:
    """Write a filler file until the file system refuses another byte."""
    with open(folder / "filler", "wb", buffering=0) as f:
        for size in (65536, 4096, 512, 1):
            try:
                while True:
                    f.write(b"\0" * size)
            except OSError:
                continue


def test_a_render_onto_a_full_disk_fails_in_one_sentence_and_keeps_the_old_set(small_disk,
                                                                                capsys):
    """On a full disk OpenEXR's failed close is noticed: the old image stays (not a 0-byte
    file) and `render` says why, not exit 0."""
    out = small_disk / "x.exr"
    assert cli.main(["render", "gray_direct", "--spp", "16", "-o", str(out)]) == 0
    files = sorted(small_disk.iterdir())
    before = {p.name: p.read_bytes() for p in files}
    assert {"x.exr", "x.stderr.exr", "x.png"} <= before.keys()
    _fill(small_disk)
    capsys.readouterr()
    _fails_in_one_sentence(capsys, ["render", "gray_direct", "--spp", "16", "--seed", "3",
                                    "-o", str(out)], "cannot write", str(small_disk), "unchanged")
    assert sorted(p.name for p in small_disk.iterdir()) == sorted([*before, "filler"])
    assert {n: (small_disk / n).read_bytes() for n in before} == before


@pytest.mark.parametrize("limit", [0, 200, 2000])
def test_exr_write_beyond_the_file_size_limit_is_refused(tmp_path, limit):
    """RLIMIT_FSIZE (a full disk where no tmpfs can be mounted): the write fails at any byte,
    the previous file stays byte-identical and no temporary is left."""
    path = tmp_path / "x.exr"
    exr.write(path, np.zeros((2, 2, 3), np.float32))
    old = path.read_bytes()
    code = ("import resource, sys, numpy as np\nfrom phonglab.engine import exr\n"
            "from phonglab.errors import WriteError\n"
            f"resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))\n"
            "try:\n"
            f"    exr.write({str(path)!r}, np.random.default_rng(0).random((64, 64, 3)))\n"
            "except WriteError as e:\n    print(e); sys.exit(3)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 3, (done.stdout, done.stderr)
    assert f"cannot write {path}" in done.stdout and "\n" not in done.stdout.strip()
    assert path.read_bytes() == old and sorted(p.name for p in tmp_path.iterdir()) == ["x.exr"]


# --- one render, one file set: the spp map is a member --------------------------------------------

def test_a_uniform_render_removes_the_spp_map_of_an_earlier_adaptive_one(tmp_path, capsys):
    """A uniform render removes an earlier adaptive render's x.spp.exr / x.spp.png, which
    would otherwise sit beside its new image."""
    out = tmp_path / "x.exr"
    assert cli.main(["render", "gray_direct", "--adaptive", "--target-noise", "0.2",
                     "-D", "res=16", "-o", str(out)]) == 0
    spp_map, spp_png = tmp_path / "x.spp.exr", tmp_path / "x.spp.png"
    assert exr.read(spp_map)[1]["render_id"] == exr.read(out)[1]["render_id"]
    assert spp_png.is_file()
    assert cli.main(["render", "gray_direct", "--spp", "16", "-D", "res=16", "-o",
                     str(out)]) == 0
    assert not spp_map.exists() and not spp_png.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.exr", "x.png", "x.stderr.exr"]


def test_a_failing_member_leaves_the_whole_previous_set(tmp_path, capsys, monkeypatch):
    """The members were renamed one by one as each finished: a failure in the last (the spp
    map preview) left a new image beside an old spp map."""
    from phonglab.engine import adaptive

    out = tmp_path / "x.exr"
    assert cli.main(["render", "gray_direct", "--adaptive", "--target-noise", "0.2",
                     "-D", "res=16", "-o", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def broken(spp):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(adaptive, "spp_map_image", broken)
    capsys.readouterr()
    _fails_in_one_sentence(capsys, ["render", "gray_direct", "--adaptive", "--target-noise",
                                    "0.2", "-D", "res=16", "--seed", "4", "-o", str(out)],
                           "No space left on device")
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
