"""Property-based fuzzing of the command line (hypothesis): whatever the option values, a run
ends either in a finite image (exit 0) or in one clean sentence with exit 2 — never a
traceback, a crash, NaN pixels, a lost file or a stale one.

Properties checked on every example:
* exit 0: the EXR exists, every value is finite, and its ``.stderr.exr`` exists exactly when
  the render had two or more passes (no stale sibling);
* exit 2: the last line of stderr says ``error:`` and there is no traceback; a file that was
  at the output path before is byte-for-byte unchanged.
The default suite runs a bounded, derandomized profile (reproducible in CI); the ``slow``
test reruns the same properties with many more examples.

Outputs never harm what is there: every output option of every command given a FIFO, a
socket, a character device (made in the test's own folder), a link to one, one of the command's
own inputs (the same file, a hard link or a symbolic link to it), an empty name or a name
ending in '/' is refused in one sentence (exit 2) and leaves what was there as it was; a link
to a regular file is written through, the link kept.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import stat
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from phonglab import cli

from phonglab.engine import exr

from helpers import SPECIAL_KINDS, make_special

TINY = """<scene version="3.0.0">
  <default name="spp" value="4"/>
  <default name="max_depth" value="3"/>
  <integrator type="path"><integer name="max_depth" value="$max_depth"/></integrator>
  <sensor type="perspective">
    <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
  </sensor>
  <shape type="sphere"><bsdf type="phong"/></shape>
  <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>
</scene>
"""

FAST = settings(max_examples=20, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])
LONG = settings(max_examples=200, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])

#: Integers a user may type: ordinary, zero, negative, huge, and words.
INTS = st.one_of(st.integers(-5, 40), st.sampled_from([0, -1, 2**31, 10**12]),
                 st.sampled_from(["abc", "1.5", "", "nan"]))
FLOATS = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                   st.sampled_from([0.0, -1.0, 1e-45, 1e300, "shiny"]))


def run(argv: list[str]) -> tuple[int, str]:
    """``phonglab ARGV`` in-process: (exit code, stderr); argparse's exits are caught."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            rc = cli.main(argv)
        except SystemExit as exc:       # argparse: bad option syntax
            rc = int(exc.code or 0)
    return rc, err.getvalue()


def check_outcome(rc: int, err: str, out: Path, before: bytes | None) -> None:
    assert "Traceback" not in err, err
    if rc == 0:
        image, meta = exr.read(out)
        assert np.all(np.isfinite(image)), meta
        assert exr.stderr_path(out).exists() == (int(meta["passes"]) > 1)
    else:
        assert rc == 2, (rc, err)
        last = err.strip().splitlines()[-1]
        assert "error:" in last, err
        if before is not None:
            assert out.read_bytes() == before


@pytest.fixture
def tiny(tmp_path_factory) -> Path:
    p = tmp_path_factory.mktemp("fuzz") / "tiny.xml"
    p.write_text(TINY)
    return p


def _render_case(tiny: Path, spp, seed, depth, keep: bool) -> None:
    out = tiny.with_name("out.exr")
    before = b"previous render" if keep else None
    for p in (out, exr.stderr_path(out)):
        p.unlink(missing_ok=True)
    if keep:
        out.write_bytes(before)
        out.chmod(0o444)
    argv = ["render", str(tiny), "-o", str(out)]
    for flag, value in (("--spp", spp), ("--seed", seed), ("--max-depth", depth)):
        if value is not None:
            argv += [flag, str(value)]
    rc, err = run(argv)
    check_outcome(rc, err, out, before)
    if keep:
        out.chmod(0o644)


@FAST
@given(spp=st.none() | INTS, seed=st.none() | INTS, depth=st.none() | INTS, keep=st.booleans())
def test_render_options(tiny, variant_llvm_rgb, spp, seed, depth, keep):
    _render_case(tiny, spp, seed, depth, keep)


@pytest.mark.slow
@LONG
@given(spp=st.none() | INTS, seed=st.none() | INTS, depth=st.none() | INTS, keep=st.booleans())
def test_render_options_long(tiny, variant_llvm_rgb, spp, seed, depth, keep):
    _render_case(tiny, spp, seed, depth, keep)


@FAST
@given(eps=FLOATS)
def test_compare_eps(tmp_path_factory, variant_llvm_rgb, eps):
    folder = tmp_path_factory.mktemp("cmp")
    a = folder / "a.exr"
    exr.write(a, np.full((4, 4, 3), 0.5, np.float32))
    rc, err = run(["compare", str(a), str(a), "--eps", str(eps)])
    assert "Traceback" not in err
    ok = isinstance(eps, float) and math.isfinite(eps) and eps > 0
    assert rc == (0 if ok else 2), (eps, rc, err)


# --- paths: folders, symlinks, unwritable folders, missing parents, not only numbers ---------

#: The kinds of path a user may type where phonglab reads or writes a file.
PATH_KINDS = ("fresh", "missing_parent", "parent_is_file", "folder", "symlink_to_folder",
              "symlink_to_file", "dangling_symlink", "unwritable_folder", "readonly_file",
              "spaces_unicode", "empty", "long_name", "dot", "trailing_slash")


def make_path(base: Path, kind: str, suffix: str, content: bytes | None = None) -> str:
    """A path of ``kind`` under ``base`` (created fresh per example); ``content``: what an
    existing regular file there holds (an input), None for an output."""
    import os
    base.mkdir(parents=True, exist_ok=True)
    name = f"f{suffix}"
    target = base / "target"
    if kind == "fresh":
        p = base / name
        if content is not None:
            p.write_bytes(content)
        return str(p)
    if kind == "missing_parent":
        return str(base / "no" / "such" / "dir" / name)
    if kind == "parent_is_file":
        (base / "plain").write_text("x")
        return str(base / "plain" / name)
    if kind == "folder":
        (base / f"d{suffix}").mkdir(exist_ok=True)
        return str(base / f"d{suffix}")
    if kind == "symlink_to_folder":
        target.mkdir(exist_ok=True)
        (base / name).unlink(missing_ok=True)
        (base / name).symlink_to(target, target_is_directory=True)
        return str(base / name)
    if kind == "symlink_to_file":
        target.write_bytes(content if content is not None else b"old")
        (base / name).unlink(missing_ok=True)
        (base / name).symlink_to(target)
        return str(base / name)
    if kind == "dangling_symlink":
        (base / name).unlink(missing_ok=True)
        (base / name).symlink_to(base / "gone" / "nothing")
        return str(base / name)
    if kind == "unwritable_folder":
        d = base / "locked"
        d.mkdir(exist_ok=True)
        if content is not None:
            (d / name).write_bytes(content)
        os.chmod(d, 0o555)                  # root writes anyway: the outcome is still 0/1/2
        return str(d / name)
    if kind == "readonly_file":
        p = base / name
        p.write_bytes(content if content is not None else b"old")
        p.chmod(0o444)
        return str(p)
    if kind == "spaces_unicode":
        d = base / "a folder ü ✓"
        d.mkdir(exist_ok=True)
        if content is not None:
            (d / name).write_bytes(content)
        return str(d / name)
    if kind == "empty":
        return ""
    if kind == "long_name":
        return str(base / ("x" * 300 + suffix))
    if kind == "dot":
        return "."
    if kind == "trailing_slash":
        return str(base / name) + "/"
    raise AssertionError(kind)


def unlock(base: Path) -> None:
    import os
    locked = base / "locked"
    if locked.exists():
        os.chmod(locked, 0o755)


def check_any_outcome(rc: int, err: str) -> None:
    """Exit 0, 1 or 2; never a traceback; on 2 one sentence (argparse's usage lines aside)."""
    assert "Traceback" not in err, err
    assert rc in (0, 1, 2), (rc, err)
    if rc == 2:
        lines = [ln.split("\r")[-1] for ln in err.splitlines()]      # a progress bar's \r
        lines = [ln for ln in lines if ln.strip() and not ln.startswith(("usage:", " "))]
        assert len(lines) == 1 and "error:" in lines[0], err


PLUGIN = (Path(__file__).parent / "authors" / "my_lambert.py").read_bytes()

#: (command, the slot the path goes in, suffix) -- each cheap when the path is good.
OUTPUT_SLOTS = (("render", "-o", ".exr"), ("compare", "--diff", ".png"),
                ("fit", "--json", ".json"), ("fit", "--report", ".txt"),
                ("validate", "--json", ".json"), ("validate", "--report", ".html"),
                ("check", "--json", ".json"), ("check", "--out-dir", ""))
INPUT_SLOTS = (("render", "scene", ".xml"), ("compare", "A", ".exr"),
               ("validate", "--plugin", ".py"), ("check", "--plugin", ".py"),
               ("fit", "--plugin", ".py"))


def _argv(command: str, slot: str, path: str, tiny: Path, image: Path) -> list[str]:
    if command == "render":
        return (["render", path, "-o", str(tiny.with_name("o.exr"))] if slot == "scene"
                else ["render", str(tiny), "-o", path])
    if command == "compare":
        return (["compare", path, str(image)] if slot == "A"
                else ["compare", str(image), str(image), "--diff", path])
    if command == "fit":
        return ["fit", "diffuse", "--model", "lambert", "--maxiter", "1", slot, path]
    if command == "validate":
        return ["validate", "diffuse", "--no-sweep", "--quick", "--only", "finite", slot, path]
    # check: a --lambert nobody registers keeps a good path from running the whole table
    return ["check", "--lambert", "nobody_registers_this", "--no-progress", slot, path]


def _path_case(tmp_path_factory, tiny, slot, kind) -> None:
    command, flag, suffix = slot
    base = tmp_path_factory.mktemp("paths")
    image = base / "image.exr"
    exr.write(image, np.full((4, 4, 3), 0.5, np.float32))
    content = {".xml": TINY.encode(), ".exr": image.read_bytes(), ".py": PLUGIN}.get(suffix) \
        if (command, flag, suffix) in INPUT_SLOTS else None
    path = make_path(base, kind, suffix, content)
    try:
        rc, err = run(_argv(command, flag, path, tiny, image))
    finally:
        unlock(base)
    check_any_outcome(rc, err)


@settings(FAST, max_examples=12)
@given(slot=st.sampled_from(OUTPUT_SLOTS + INPUT_SLOTS), kind=st.sampled_from(PATH_KINDS))
def test_paths(tmp_path_factory, tiny, variant_llvm_rgb, slot, kind):
    _path_case(tmp_path_factory, tiny, slot, kind)


@pytest.mark.slow
@settings(LONG, max_examples=300)
@given(slot=st.sampled_from(OUTPUT_SLOTS + INPUT_SLOTS), kind=st.sampled_from(PATH_KINDS))
def test_paths_long(tmp_path_factory, tiny, variant_llvm_rgb, slot, kind):
    _path_case(tmp_path_factory, tiny, slot, kind)


@pytest.mark.parametrize("slot", OUTPUT_SLOTS + INPUT_SLOTS, ids=lambda s: f"{s[0]}{s[1]}")
@pytest.mark.parametrize("kind", ["missing_parent", "folder", "dangling_symlink",
                                  "parent_is_file"])
def test_paths_every_slot(tmp_path_factory, tiny, variant_llvm_rgb, slot, kind):
    """The kinds most likely to break, in every slot (not left to the search's draw)."""
    _path_case(tmp_path_factory, tiny, slot, kind)


def test_dangling_link_refused_before_the_render(tmp_path, tiny, variant_llvm_rgb):
    """Found by test_paths: -o a link to a missing folder rendered, then failed to write."""
    link = tmp_path / "out.exr"
    link.symlink_to(tmp_path / "gone" / "out.exr")
    rc, err = run(["render", str(tiny), "-o", str(link)])
    assert rc == 2 and "symbolic link" in err and "rendering" not in err, err


def test_name_too_long_is_one_sentence(tmp_path, tiny, variant_llvm_rgb):
    """Found by test_paths: an OSError naming the path was a traceback."""
    rc, err = run(["render", str(tiny), "-o", str(tmp_path / ("x" * 300 + ".exr"))])
    check_any_outcome(rc, err)
    assert rc == 2 and "File name too long" in err


# --- outputs never harm what is there --------------------------------------------------------

#: What an output path may name that must be refused, and what is written through.
HARM_KINDS = (*SPECIAL_KINDS, "link_to_fifo", "link_to_device", "the_input", "hardlink_to_input",
              "link_to_input", "empty", "trailing_slash", "link_to_file")
#: Output slots (command, option, suffix) and, for "the input", what their input is.
HARM_SLOTS = OUTPUT_SLOTS + (("compare-models", "-o", ""), ("bench", "--out", ""),
                             ("bench", "--markdown", ".md"), ("bench", "--cache", ""))
FOLDER_SLOTS = {("check", "--out-dir"), ("compare-models", "-o"), ("bench", "--out"),
                ("bench", "--cache")}


def _harm_argv(command, flag, path, tiny, image, plugin) -> list[str]:
    if command == "render":
        return ["render", str(tiny), "--plugin", str(plugin), "-o", path]
    if command == "compare":
        return ["compare", str(image), str(image), "--diff", path]
    if command == "fit":
        return ["fit", "diffuse", "--model", "lambert", "--maxiter", "1", "--plugin",
                str(plugin), flag, path]
    if command == "validate":
        return ["validate", "diffuse", "--no-sweep", "--quick", "--only", "finite",
                "--plugin", str(plugin), flag, path]
    if command == "check":
        return ["check", "--lambert", "nobody_registers_this", "--no-progress", "--plugin",
                str(plugin), flag, path]
    if command == "compare-models":
        return ["compare-models", str(tiny), "-o", path]
    return ["bench", "--quick", "--out", str(tiny.parent / "b"), "--quick-run", str(plugin),
            flag, path]                # bench: its input is the run.json of a quick run


def _the_input(command, tiny, image, plugin) -> Path:
    return {"render": tiny, "compare": image, "compare-models": tiny}.get(command, plugin)


def _harm_case(tmp_path_factory, tiny, slot, kind) -> None:
    command, flag, suffix = slot
    folder_slot = (command, flag) in FOLDER_SLOTS
    if kind in ("the_input", "hardlink_to_input", "link_to_input") and folder_slot:
        kind = "fifo"                  # a file that is an input cannot be a folder of results
    if kind == "trailing_slash" and folder_slot:
        kind = "empty"                 # a folder's name may end in '/'
    if command in ("compare-models", "bench") and kind == "link_to_file":
        kind = "link_to_fifo"          # their work is minutes long: refused kinds only
    base = tmp_path_factory.mktemp("harm")
    image = base / "image.exr"
    exr.write(image, np.full((4, 4, 3), 0.5, np.float32))
    plugin = base / "mine.py"
    plugin.write_bytes(PLUGIN)
    source = _the_input(command, tiny, image, plugin)
    before = source.read_bytes()
    path = base / f"out{suffix}"
    kept = None                        # the file type left at path (or at the link's target)
    if kind in SPECIAL_KINDS:
        kept = (path, make_special(path, kind))
    elif kind in ("link_to_fifo", "link_to_device"):
        target = base / "special"
        kept = (target, make_special(target, "fifo" if kind == "link_to_fifo" or
                                     os.geteuid() != 0 else "char_device"))
        path.symlink_to(target)
    elif kind == "the_input":
        path = source
    elif kind == "hardlink_to_input":
        os.link(source, path)
    elif kind == "link_to_input":
        path.symlink_to(source)
    elif kind == "link_to_file":
        (base / "real").write_bytes(b"old")
        path.symlink_to(base / "real")
    argv = _harm_argv(command, flag, {"empty": "", "trailing_slash": f"{path}/"}.get(kind,
                                                                                   str(path)),
                      tiny, image, plugin)
    rc, err = run(argv)
    assert source.read_bytes() == before, (slot, kind, "an input was overwritten")
    if kept is not None:
        assert stat.S_IFMT(os.lstat(kept[0]).st_mode) == kept[1], (slot, kind, err)
    if kind.startswith("link_to"):
        assert path.is_symlink(), (slot, kind)
    if kind == "link_to_file":
        check_any_outcome(rc, err)
        assert (base / "real").is_file()
        return
    check_any_outcome(rc, err)
    assert rc == 2, (slot, kind, rc, err)


@settings(FAST, max_examples=40)
@given(slot=st.sampled_from(HARM_SLOTS), kind=st.sampled_from(HARM_KINDS))
def test_outputs_never_harm_what_is_there(tmp_path_factory, tiny, variant_llvm_rgb, slot, kind):
    _harm_case(tmp_path_factory, tiny, slot, kind)


@pytest.mark.slow
@settings(LONG, max_examples=300)
@given(slot=st.sampled_from(HARM_SLOTS), kind=st.sampled_from(HARM_KINDS))
def test_outputs_never_harm_what_is_there_long(tmp_path_factory, tiny, variant_llvm_rgb, slot,
                                               kind):
    _harm_case(tmp_path_factory, tiny, slot, kind)
