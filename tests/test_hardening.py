"""Bad input found by a hostile but fair user: each case ends in one sentence with the fix and
exit code 2, before any rendering, and nothing on disk is lost or left stale.

Each test names the defect it pins (they failed before the fix):
* a stale ``.stderr.exr`` from an earlier render was kept and trusted by ``compare``;
* ``--max-depth`` on a scene without a ``$max_depth`` default swapped its integrator for ``path``;
* output problems (read-only file or folder, a parent that is a file, a PNG path that is a
  folder) were found after the render, as tracebacks;
* a scene with no sensor, a film of 0 pixels or one too large for memory raised Dr.Jit
  errors (or crashed); problems that are not markup were reported as "malformed XML";
* the other commands' inputs: a folder given as the scene was "not found"; ``check --json``,
  ``bench --out/--markdown``, ``compare-models -o`` and ``fit --report DIR/`` were checked
  after the work, or not at all (tracebacks, raw ``[Errno 2]``, a file named like a folder);
  an output that was a symbolic link was replaced by a regular file; ``--max-seconds -1``
  ran the pilot first; ``doctor`` said "using" a DRJIT_LIBLLVM_PATH that is no libLLVM.
"""

from __future__ import annotations

import importlib.util
import json
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from phonglab import cli, planner, stats
from phonglab.engine import exr
from phonglab.engine.render import render_scene
from phonglab.engine.scenes import load_scene
from phonglab.errors import PlanError, SceneError

FILM = ('<sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" '
        'target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm">'
        '<integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>')
WHITTED_NO_DEPTH_DEFAULT = f"""<scene version="3.0.0">
  <integrator type="whitted"><string name="units" value="graphics"/></integrator>
  {FILM}
  <shape type="sphere"><bsdf type="phong"/></shape>
  <emitter type="point"><point name="position" value="0, 2, 3"/><rgb name="intensity" value="5"/></emitter>
</scene>"""


def _write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def _fails_in_one_sentence(capsys, argv: list[str], *patterns: str) -> str:
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.split("\r")[-1].strip()   # after the progress bar, if any
    assert err.startswith("phonglab: error: ") and "\n" not in err, err
    assert "Traceback" not in err and "malformed XML" not in err, err
    for p in patterns:
        assert p in err, (p, err)
    return err


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


# --- --max-depth keeps the scene's integrator ---------------------------------------------------

def test_max_depth_applies_to_the_scenes_own_integrator(tmp_path, capsys):
    scene = _write(tmp_path, "w.xml", WHITTED_NO_DEPTH_DEFAULT)
    out = tmp_path / "w.exr"
    assert cli.main(["render", str(scene), "--spp", "1", "--max-depth", "3", "-o", str(out)]) == 0
    meta = exr.read(out)[1]
    assert meta["max_depth"] == 3 and "Whitted" in meta["integrator"], meta


def test_max_depth_is_refused_for_an_integrator_without_one(tmp_path, capsys):
    scene = _write(tmp_path, "d.xml", WHITTED_NO_DEPTH_DEFAULT.replace(
        '<integrator type="whitted"><string name="units" value="graphics"/></integrator>',
        '<integrator type="direct"/>'))
    _fails_in_one_sentence(capsys, ["render", str(scene), "--max-depth", "3", "-o",
                                    str(tmp_path / "d.exr")], "'direct' integrator", "max_depth")
    assert not (tmp_path / "d.exr").exists()


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


# --- scenes that cannot be rendered, and errors named for what went wrong ----------------------

def test_a_scene_without_a_sensor_is_one_sentence(tmp_path, capsys):
    scene = _write(tmp_path, "s.xml", '<scene version="3.0.0"><shape type="sphere"/>'
                                      '<emitter type="constant"/></scene>')
    _fails_in_one_sentence(capsys, ["render", str(scene), "-o", str(tmp_path / "s.exr")],
                           "no <sensor>")


@pytest.mark.parametrize("res, words", [(0, "0 x 0 pixels"), (20000, "GiB of memory")])
def test_impossible_films_are_refused_before_allocation(variant_llvm_rgb, res, words):
    scene = load_scene("gray_direct", res=res)
    with pytest.raises(SceneError, match=words):
        render_scene(scene, 1)


@pytest.mark.parametrize("body, params, words", [
    ('<bsdf type="phong"><float name="exponent" value="shiny"/></bsdf>', {},
     "'shiny' is not a valid floating point value"),
    ('<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" '
     'value="missing.png"/></texture></bsdf>', {}, "cannot open the file 'missing.png'"),
    ('<bsdf type="diffuse"/>', {"spp": "-3"}, "sample_count = -3"),
    ('<bsdf type="diffuse"/>', {"unused": "1"}, "does not use the parameter(s) unused=1"),
])
def test_load_errors_are_named_for_what_went_wrong(tmp_path, variant_llvm_rgb, body, params, words):
    film = FILM.replace('<film', '<sampler type="independent"><integer name="sample_count" '
                                 'value="$spp"/></sampler><film')
    scene = _write(tmp_path, "e.xml", f'<scene version="3.0.0"><default name="spp" value="4"/>'
                                      f'{film}<shape type="sphere">{body}</shape></scene>')
    with pytest.raises(SceneError) as info:
        load_scene(scene, **params)
    msg = str(info.value)
    assert words in msg and "malformed XML" not in msg and "\n" not in msg, msg


def test_a_plugin_value_error_is_passed_through(tmp_path, capsys):
    scene = _write(tmp_path, "w.xml", WHITTED_NO_DEPTH_DEFAULT.replace(
        '<string name="units" value="graphics"/>',
        '<float name="attenuation_constant" value="-1"/>'))
    _fails_in_one_sentence(capsys, ["render", str(scene), "-o", str(tmp_path / "w.exr")],
                           "whitted: 'attenuation_constant' must be >= 0")


def test_malformed_xml_is_still_called_so(tmp_path, capsys):
    scene = _write(tmp_path, "m.xml", '<scene version="3.0.0"><shape type="sphere"></scene>')
    assert cli.main(["render", str(scene), "-o", str(tmp_path / "m.exr")]) == 2
    assert "malformed XML" in capsys.readouterr().err


def test_the_render_id_ties_image_and_stderr(tmp_path):
    out = tmp_path / "x.exr"
    assert cli.main(["render", "gray_direct", "--spp", "16", "-o", str(out)]) == 0
    image_id = exr.read(out)[1]["render_id"]
    assert exr.read(exr.stderr_path(out))[1]["render_id"] == image_id
    assert np.isfinite(exr.read_image(out)).all()


# --- absurd plans are refused before anything renders ------------------------------------------

def test_an_absurd_target_is_refused_by_plan_and_render(tmp_path, capsys):
    _fails_in_one_sentence(capsys, ["plan", "gray_direct", "--target-error", "1e-9", "--set",
                                    "res=16"], "more than a render takes")
    out = tmp_path / "x.exr"
    _fails_in_one_sentence(capsys, ["render", "gray_direct", "--target-error", "1e-9", "-o",
                                    str(out)], "more than a render takes")
    assert not out.exists()


def test_a_plan_over_the_time_limit_is_refused_unless_allowed(capsys):
    argv = ["plan", "gray_direct", "--target-error", "0.01", "--set", "res=16"]
    _fails_in_one_sentence(capsys, argv + ["--max-seconds", "1e-6"], "over the limit",
                           "--max-seconds")
    assert cli.main(argv + ["--max-seconds", "inf"]) == 0


def test_a_plugin_error_during_the_render_is_the_plugins_sentence(tmp_path, capsys):
    """whitted refuses an unknown ambient_reflectance_<id> at render time; Dr.Jit wraps that in
    its custom-operation RuntimeError, which render_scene unwraps."""
    scene = _write(tmp_path, "w.xml", WHITTED_NO_DEPTH_DEFAULT.replace(
        '<string name="units" value="graphics"/>',
        '<rgb name="ambient_reflectance_nope" value="0.3"/>'))
    _fails_in_one_sentence(capsys, ["render", str(scene), "-o", str(tmp_path / "w.exr")],
                           "ambient_reflectance_nope")


def test_a_planned_render_checks_its_outputs_before_the_pilot(tmp_path, capsys, monkeypatch):
    def no_pilot(*args, **kwargs):
        raise AssertionError("the plan was made although the output cannot be written")

    monkeypatch.setattr(planner, "plan", no_pilot)
    (tmp_path / "x.png").mkdir()
    _fails_in_one_sentence(capsys, ["render", "gray_direct", "--target-error", "0.05", "-o",
                                    str(tmp_path / "x.exr")], "is a folder")


# --- compare: no NaN, no tautology, the output rules of render ----------------------------------

def test_compare_of_identical_images_says_why_the_test_is_undefined(tmp_path, capsys):
    """Two black images (or any two equal ones) have SE = 0: z and p used to print as nan
    and --json wrote a bare NaN (invalid JSON)."""
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    for p in (a, b):
        exr.write(p, np.zeros((4, 6, 3), np.float32))
    assert cli.main(["compare", str(a), str(b), "--json"]) == 0
    data = json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(c))
    assert data["z"] is None and data["p_value"] is None
    assert "zero standard error" in data["undefined"]
    assert cli.main(["compare", str(a), str(b)]) == 0
    out = capsys.readouterr().out
    assert "nan" not in out.lower() and "undefined: the mean difference has zero" in out, out


def test_compare_of_a_render_with_itself_is_not_evidence(tmp_path, capsys):
    """The same file compared with itself used to report 'same expected image, p = 1'."""
    a = tmp_path / "a.exr"
    assert cli.main(["render", "gray_direct", "--spp", "16", "-o", str(a)]) == 0
    copy = tmp_path / "copy.exr"
    copy.write_bytes(a.read_bytes())
    copy_stderr = exr.stderr_path(copy)
    copy_stderr.write_bytes(exr.stderr_path(a).read_bytes())
    capsys.readouterr()
    for other, needle in ((a, "the same file"), (copy, "one render")):
        assert cli.main(["compare", str(a), str(other), "--json"]) == 0
        data = json.loads(capsys.readouterr().out)
        assert data["p_value"] is None and needle in data["undefined"], data


def test_compare_diff_follows_the_output_rules(tmp_path, capsys):
    """--diff wrote over a read-only PNG and into a read-only folder."""
    a = tmp_path / "a.exr"
    exr.write(a, np.random.default_rng(0).random((4, 6, 3)).astype(np.float32))
    b = tmp_path / "b.exr"
    exr.write(b, np.random.default_rng(1).random((4, 6, 3)).astype(np.float32))
    png = tmp_path / "d.png"
    png.write_bytes(b"keep")
    png.chmod(0o444)
    _fails_in_one_sentence(capsys, ["compare", str(a), str(b), "--diff", str(png)], "read-only")
    assert png.read_bytes() == b"keep"
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        _fails_in_one_sentence(capsys, ["compare", str(a), str(b), "--diff",
                                        str(folder / "d.png")], "read-only")
        assert list(folder.iterdir()) == []
    finally:
        folder.chmod(0o755)


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
    """On a full disk OpenEXR's failed close went unnoticed: the old image was replaced by a
    0-byte file and `render` said nothing (exit 0)."""
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


# --- Ctrl-C anywhere: exit 130, one line, the previous files intact -----------------------------

INTERRUPT_MESSAGE = "phonglab: interrupted; files already written are complete."


@pytest.mark.slow
@pytest.mark.parametrize("delay", [0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7, 0.9, 1.5])
def test_ctrl_c_at_any_point_of_a_render_is_one_line(tmp_path, delay):
    """SIGINT at points from start-up to mid-render.  Not inside the first ~0.1 s (0.08 s on
    a quiet machine, so the first point is twice that): there the interpreter is still
    importing the console script's `phonglab.cli`, before any phonglab code can catch it,
    and Python prints its own traceback.  During the variant's set-up it used to surface as `SystemError: <built-in function __import__> returned a result with an
    exception set` (exit 1, ~60 lines); inside a plugin's constructor as 'could not load the
    scene: KeyboardInterrupt' (exit 2); during the subcommand imports as a traceback, or an
    abort (exit -6) when the error handler then imported Dr.Jit or when the interpreter
    finalised a half-imported Dr.Jit ("PyThreadState_Get ... finalizing")."""
    out = tmp_path / "x.exr"
    assert cli.main(["render", "gray_direct", "--spp", "4", "-o", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    exe = Path(sys.executable).with_name("phonglab")
    proc = subprocess.Popen([str(exe), "render", "cornell_phong", "--spp", "256", "-o", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    time.sleep(delay)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    lines = [ln.strip() for ln in err.replace("\r", "\n").splitlines() if ln.strip()
             and not ln.strip().startswith("rendering")]
    if proc.returncode == 0:                 # it finished first: a complete new set
        assert exr.read(out)[1]["scene"].endswith("cornell_phong.xml")
        return
    assert proc.returncode == 130 and lines == [INTERRUPT_MESSAGE], (proc.returncode, err[-2000:])
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def _load_repro(name: str):
    spec = importlib.util.spec_from_file_location(name, Path(__file__).parent / "repro" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


CTRL_C_INSIDE_A_RENDER = _load_repro("sigint_handler_logs").FIRE_DURING_RENDER + """
import sys
# As in the console script, no thread exists before cli.main routes SIGINT: Dr.Jit's own
# threads, started by this import, must not take it either.
signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
import mitsuba as mi
signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
from phonglab import cli
real = mi.render
def render(*args, **kwargs):            # Ctrl-C while Mitsuba's own C handler is installed
    if not getattr(render, "fired", False):
        render.fired = True
        fire_during_render()
    integrator = kwargs.get("integrator") or args[0].integrator()
    try:
        return real(*args, **kwargs)
    finally:                            # Mitsuba's handler cancels the integrator it guards
        print("cancelled by Mitsuba's handler:", integrator.should_stop(), flush=True)
mi.render = render
sys.exit(cli.main(["render", "cornell_phong", "--spp", "256", "-o", sys.argv[1]]))
"""


def test_ctrl_c_inside_a_render_never_runs_mitsubas_signal_handler(tmp_path):
    """Mitsuba 3.9.1 installs a C SIGINT handler for each render that logs ("Received interrupt
    signal, winding down..") from inside the handler (integrator_v.cpp:30-49): not
    async-signal-safe, it hung `phonglab render` for good in CI (the slow Ctrl-C test at
    0.5 s), and a Ctrl-C in the instant before it stores the previous handler kills the
    process with SIG_DFL.  phonglab takes SIGINT on a thread of its own
    (runtime.interrupts_routed): Mitsuba's handler never runs, the command says one line and
    exits 130.  Without the routing the handler runs and cancels the integrator (checked)."""
    out = tmp_path / "x.exr"
    proc = subprocess.run([sys.executable, "-c", CTRL_C_INSIDE_A_RENDER, str(out)],
                          capture_output=True, text=True, timeout=120,
                          start_new_session=True)
    both = proc.stdout + proc.stderr
    assert "cancelled by Mitsuba's handler: False" in proc.stdout, both[-2000:]
    assert "cancelled by Mitsuba's handler: True" not in proc.stdout, both[-2000:]
    lines = [ln.strip() for ln in proc.stderr.replace("\r", "\n").splitlines()
             if ln.strip() and not ln.strip().startswith("rendering")]
    assert proc.returncode == 130 and lines == [INTERRUPT_MESSAGE], (proc.returncode, both[-2000:])
    assert not out.exists()


@pytest.mark.slow
def test_the_sigint_reproducer_shows_mitsubas_handler():
    """tests/repro/sigint_handler_logs.py exits 1 while Mitsuba 3.9.1's render handler runs
    Log from signal context (the reason for runtime.interrupts_routed)."""
    script = Path(__file__).parent / "repro" / "sigint_handler_logs.py"
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 1, done.stdout + done.stderr


def test_routing_restores_the_signal_mask_and_handler():
    """After a command, in-process callers (notebooks, pytest) get Ctrl-C as before."""
    before = signal.pthread_sigmask(signal.SIG_BLOCK, set())
    assert cli.main(["doctor"]) in (0, 1)
    assert signal.pthread_sigmask(signal.SIG_BLOCK, set()) == before
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(1)


# --- seeds: Mitsuba's 32-bit range, refused outside it before any work -------------------------

@pytest.mark.parametrize("command", [["render", "gray_direct"], ["check", "--only", "snell"],
                                     ["validate", "diffuse", "--quick"],
                                     ["compare-models", "gray_direct"]])
@pytest.mark.parametrize("bad", ["-1", str(1 << 32), "1e3"])
def test_a_seed_outside_32_bits_is_refused_before_any_work(command, bad, capsys):
    """-1 and 2³² − 1 used to render the same image (pass seeds are taken mod 2³²) while the
    headers recorded different seeds; `validate --seed -1` reported seven failing topics."""
    with pytest.raises(SystemExit) as info:
        cli.main([*command, "--seed", bad])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "argument --seed: the seed must" in err and "Traceback" not in err, err


def test_distinct_seeds_give_distinct_first_pass_seeds():
    """pass_seed(s, 0) = s·1_000_003 mod 2³² is a bijection of 0..2³² − 1 (the factor is odd):
    no two accepted seeds share their first pass."""
    from phonglab.engine.render import pass_seed

    seeds = np.random.default_rng(5).integers(0, 1 << 32, 200_000, dtype=np.uint64)
    seeds = np.unique(np.concatenate([seeds, [0, 1, (1 << 32) - 1]]))
    mapped = {pass_seed(int(s), 0) for s in seeds}
    assert len(mapped) == len(seeds) and all(0 <= m < 1 << 32 for m in mapped)


# --- what real scenes carry: film formats, AOV and particle-tracing integrators ----------------

CONTENT = """<scene version="3.0.0">
  {integrator}
  <sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0"
    up="0, 1, 0"/></transform><film type="hdrfilm"><integer name="width" value="12"/>
    <integer name="height" value="10"/><string name="pixel_format" value="{fmt}"/></film></sensor>
  <shape type="sphere"><bsdf type="diffuse"/></shape>
  <emitter type="point"><point name="position" value="0, 2, 3"/><rgb name="intensity" value="5"/>
  </emitter>
</scene>"""
PATH = '<integrator type="path"/>'
AOV = '<integrator type="aov"><string name="aovs" value="nn:sh_normal"/></integrator>'
AOV_NESTED = ('<integrator type="aov"><string name="aovs" value="dd:depth"/>'
              '<integrator type="path" name="p"/></integrator>')
PTRACER = '<integrator type="ptracer"/>'


def _content(tmp_path, integrator=PATH, fmt="rgb", name="s.xml") -> Path:
    return _write(tmp_path, name, CONTENT.format(integrator=integrator, fmt=fmt))


@pytest.mark.parametrize("fmt, names", [("xyz", ["X", "Y", "Z"]), ("luminance_alpha", ["Y", "A"]),
                                        ("xyza", ["X", "Y", "Z", "A"])])
def test_a_film_of_another_pixel_format_keeps_its_channel_names(variant_llvm_rgb, tmp_path, capsys,
                                                                fmt, names):
    """An xyz or luminance_alpha film was written as if it were RGB (channels R, G, B)."""
    import OpenEXR

    out = tmp_path / "x.exr"
    assert cli.main(["render", str(_content(tmp_path, fmt=fmt)), "--spp", "16", "-o",
                     str(out)]) == 0
    for path in (out, exr.stderr_path(out)):
        with OpenEXR.File(str(path)) as f:
            assert sorted(f.channels()) == sorted(names), path
        image, meta = exr.read(path)
        assert meta["channels"] == names and image.shape == (10, 12, len(names))
    rgb = tmp_path / "rgb.exr"
    assert cli.main(["render", str(_content(tmp_path, name="r.xml")), "--spp", "4", "-o",
                     str(rgb)]) == 0
    if len(names) == 3:                    # same shape, other quantities: not comparable
        capsys.readouterr()
        _fails_in_one_sentence(capsys, ["compare", str(out), str(rgb)], "holds channels X, Y, Z")


@pytest.mark.parametrize("fmt", ["rgb", "rgba", "luminance"])
def test_the_usual_films_are_written_as_before(variant_llvm_rgb, tmp_path, fmt):
    out = tmp_path / "x.exr"
    assert cli.main(["render", str(_content(tmp_path, fmt=fmt)), "--spp", "4", "-o",
                     str(out)]) == 0
    image, meta = exr.read(out)
    assert "channels" not in meta and image.shape == {"rgb": (10, 12, 3), "rgba": (10, 12, 4),
                                                      "luminance": (10, 12)}[fmt]


ADAPTIVE = ["--adaptive", "--target-error", "0.1"]


@pytest.mark.parametrize("integrator, route, needle", [
    (AOV, [], "arbitrary output variables (nn.X, nn.Y, nn.Z)"),
    (AOV_NESTED, [], "arbitrary output variables (p.R, p.G, p.B, p.A, ...)"),
    (AOV, ADAPTIVE, "arbitrary output variables"),
    (PTRACER, ADAPTIVE, "not sampled per pixel"),
], ids=["aov", "aov-nested", "aov-adaptive", "ptracer-adaptive"])
def test_integrators_phonglab_cannot_sample_are_one_sentence(tmp_path, capsys, integrator,
                                                             route, needle):
    """An aov integrator was written as RGBA (its 4 AOV channels), and --adaptive reported
    'error 0, meets the target' on it; --adaptive on ptracer raised a nanobind TypeError."""
    out = tmp_path / "x.exr"
    _fails_in_one_sentence(capsys, ["render", str(_content(tmp_path, integrator)), "-o", str(out),
                                    *(route or ["--spp", "4"])], needle)
    assert not out.exists()


def test_a_particle_tracer_renders_uniformly(variant_llvm_rgb, tmp_path):
    out = tmp_path / "x.exr"
    assert cli.main(["render", str(_content(tmp_path, PTRACER)), "--spp", "16", "-o",
                     str(out)]) == 0
    assert exr.read(out)[0].shape == (10, 12, 3)


@pytest.mark.parametrize("fmt", ["xyz", "luminance", "rgba"])
def test_adaptive_refuses_a_film_it_would_write_as_rgb(variant_llvm_rgb, tmp_path, capsys, fmt):
    """A luminance film rendered adaptively came out as three channels named R, G, B."""
    _fails_in_one_sentence(capsys, ["render", str(_content(tmp_path, fmt=fmt)), *ADAPTIVE,
                                    "-o", str(tmp_path / "x.exr")],
                           "adaptive sampling writes R, G, B", "pixel_format")


def test_a_wide_film_has_a_bounded_spp_preview(tmp_path):
    """A 4096 x 4 film made a 262144-pixel-wide spp map preview (the preview adds a title,
    a colour bar and labels below the map: 70 pixels, and at least 320 wide)."""
    from PIL import Image

    from phonglab.engine.adaptive import SPP_PNG_MAX_SIDE, write_spp_map_png

    for shape in [(4, 4096), (4096, 4), (3, 9000), (16, 16)]:
        path = write_spp_map_png(tmp_path / "m.png", np.full(shape, 4))
        assert max(Image.open(path).size) <= SPP_PNG_MAX_SIDE + 70, shape


# --- one render, one file set: the spp map is a member --------------------------------------------

def test_a_uniform_render_removes_the_spp_map_of_an_earlier_adaptive_one(tmp_path, capsys):
    """The spp map was written after the set and never removed: a later uniform render left
    an old x.spp.exr / x.spp.png beside its new image."""
    out = tmp_path / "x.exr"
    assert cli.main(["render", "gray_direct", "--adaptive", "--target-error", "0.2",
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
    assert cli.main(["render", "gray_direct", "--adaptive", "--target-error", "0.2",
                     "-D", "res=16", "-o", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def broken(spp):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(adaptive, "spp_map_image", broken)
    capsys.readouterr()
    _fails_in_one_sentence(capsys, ["render", "gray_direct", "--adaptive", "--target-error",
                                    "0.2", "-D", "res=16", "--seed", "4", "-o", str(out)],
                           "No space left on device")
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


CROP = ('<integer name="crop_offset_x" value="4"/><integer name="crop_offset_y" value="2"/>'
        '<integer name="crop_width" value="6"/><integer name="crop_height" value="5"/>'
        '<rfilter type="box"/>')


def _region_pass_means(result, region=(slice(None), slice(None))) -> np.ndarray:
    return result.passes[:, region[0], region[1]].mean(axis=(1, 2))


def test_a_crop_window_renders_its_part_of_the_film(variant_llvm_rgb, tmp_path):
    """A film's crop window (offset 4, 2; 6 x 5 of 12 x 10): the uniform and the adaptive
    render are the crop's size and see, in expectation, what the full film sees there.
    Two-sample t-tests of the region's mean, per channel (8 passes against 8 passes, and 6
    adaptive seeds against the full film's passes), Šidák over the 6 tests."""
    from phonglab.engine import adaptive, scenes
    from phonglab.engine.render import render_scene

    text = CONTENT.format(integrator=PATH, fmt="rgb").replace(
        '<string name="pixel_format" value="rgb"/>', '<string name="pixel_format" value="rgb"/>'
        + CROP)
    crop = scenes.load_scene(_write(tmp_path, "crop.xml", text))
    full_box = scenes.load_scene(_write(tmp_path, "box.xml", text.replace(CROP, '<rfilter '
                                                                          'type="box"/>')))
    region = (slice(2, 7), slice(4, 10))
    a = _region_pass_means(render_scene(full_box, 256, seed=1, passes=8, keep_passes=True),
                           region)
    b_result = render_scene(crop, 256, seed=2, passes=8, keep_passes=True)
    assert b_result.image.shape == (5, 6, 3)
    b = _region_pass_means(b_result)
    c = np.array([adaptive.render_adaptive(crop, 0.03, seed=s).image.mean(axis=(0, 1))
                  for s in range(6)])
    z = stats.t_critical(5, stats.ALPHA, 6)      # the smaller sample: 6 seeds, 5 dof
    for x in (b, c):
        se = np.sqrt(a.var(axis=0, ddof=1) / len(a) + x.var(axis=0, ddof=1) / len(x))
        t = np.abs(a.mean(axis=0) - x.mean(axis=0)) / se
        assert np.all(t <= z), (a.mean(axis=0), x.mean(axis=0), t)


# --- every input answered before the work: folders, outputs, links, limits, libLLVM -----------

TINY_SCENE = '<scene version="3.0.0"><shape type="sphere"/></scene>'


def _no_work(monkeypatch, target: str, name: str) -> None:
    """``target.name`` (the command's work) fails the test if it is reached."""
    def work(*args, **kwargs):
        raise AssertionError(f"{target}.{name} ran although an input was bad")

    monkeypatch.setattr(importlib.import_module(target), name, work)


@pytest.mark.parametrize("command", [["render"], ["plan"], ["compare-models"]])
def test_a_folder_given_as_the_scene_is_called_a_folder(tmp_path, capsys, command):
    """It was 'scene file not found' followed by the list of shipped scenes."""
    (tmp_path / "scenes").mkdir()
    (tmp_path / "scenes" / "a.xml").write_text(TINY_SCENE)
    err = _fails_in_one_sentence(capsys, [*command, str(tmp_path / "scenes")], "is a folder",
                                 str(tmp_path / "scenes" / "a.xml"))
    assert "not found" not in err


@pytest.mark.parametrize("argv, work, words", [
    # written after all the checks had run (and failed with the checks' results lost)
    (["check", "--only", "snell", "--json", "/proc/c.json"], ("phonglab.checks", "run_checks"),
     ["/proc", "read-only", "JSON file"]),
    (["check", "--only", "snell", "--json", "{tmp}/"], ("phonglab.checks", "run_checks"),
     ["ends in '/'", "names a folder"]),
    (["check", "--only", "snell", "--out-dir", "{tmp}/file"], ("phonglab.checks", "run_checks"),
     ["is a file, not a folder"]),
    # a FileExistsError traceback from mkdir
    (["bench", "--quick", "--out", "{tmp}/file"], ("phonglab.bench.run", "run_bench"),
     ["is a file, not a folder", "--out"]),
    # "[Errno 2] No such file or directory: '/proc/bench'"
    (["bench", "--quick", "--out", "/proc/bench"], ("phonglab.bench.run", "run_bench"),
     ["/proc", "read-only", "--out"]),
    (["bench", "--quick", "--out", "{tmp}/b", "--markdown", "/proc/b.md"],
     ("phonglab.bench.run", "run_bench"), ["/proc", "read-only", "--markdown"]),
    # silently ignored: the report then quoted no quick run
    (["bench", "--quick", "--out", "{tmp}/b", "--quick-run", "{tmp}"],
     ("phonglab.bench.run", "run_bench"), ["is a folder", "--quick-run"]),
    (["bench", "--quick", "--out", "{tmp}/b", "--quick-run", "{tmp}/none.json"],
     ("phonglab.bench.run", "run_bench"), ["does not exist", "--quick-run"]),
    # a FileExistsError traceback after the three renders
    (["compare-models", "gray_direct", "-o", "{tmp}/file"],
     ("phonglab.engine.compare_models", "compare_models"), ["is a file, not a folder", "-o"]),
    # wrote the report as a file named like the folder
    (["fit", "roughconductor", "--report", "{tmp}/rep/"], ("phonglab.fit.optimize", "fit"),
     ["ends in '/'", "--report"]),
    (["fit", "roughconductor", "--json", "/proc/f.json"], ("phonglab.fit.optimize", "fit"),
     ["/proc", "read-only", "--json"]),
], ids=["check-json-proc", "check-json-folder", "check-out-dir-file", "bench-out-file",
        "bench-out-proc", "bench-markdown-proc", "bench-quick-run-folder",
        "bench-quick-run-missing", "compare-models-out-file", "fit-report-folder",
        "fit-json-proc"])
def test_every_output_is_checked_before_the_work(tmp_path, capsys, monkeypatch, argv, work,
                                                 words):
    (tmp_path / "file").write_text("keep")
    _no_work(monkeypatch, *work)
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    err = _fails_in_one_sentence(capsys, argv, *words)
    assert "Errno" not in err, err
    assert (tmp_path / "file").read_text() == "keep"
    assert not (tmp_path / "rep").exists() and not (tmp_path / "b").exists()


def test_an_output_that_is_a_symlink_is_written_through_the_link(tmp_path, capsys):
    """The atomic rename replaced the link with a regular file, leaving its target stale."""
    (tmp_path / "real.json").write_text("{}")
    (tmp_path / "link.json").symlink_to("real.json")
    assert cli.main(["check", "--only", "snell", "--spp", "16", "--json",
                     str(tmp_path / "link.json")]) == 0
    assert (tmp_path / "link.json").is_symlink()
    assert json.loads((tmp_path / "real.json").read_text())["results"]
    (tmp_path / "link.exr").symlink_to("real.exr")          # dangling: made through it
    assert cli.main(["render", "gray_direct", "-D", "res=8", "--spp", "2", "-o",
                     str(tmp_path / "link.exr")]) == 0
    assert (tmp_path / "link.exr").is_symlink() and exr.read(tmp_path / "real.exr")[0].size
    capsys.readouterr()


def test_a_symlink_to_a_folder_is_a_folder_for_the_output_checks(tmp_path, capsys):
    (tmp_path / "d").mkdir()
    (tmp_path / "x.json").symlink_to("d")
    _fails_in_one_sentence(capsys, ["check", "--only", "snell", "--json",
                                    str(tmp_path / "x.json")], "is a folder")


@pytest.mark.parametrize("command", [["render", "gray_direct", "--target-error", "0.1"],
                                     ["plan", "gray_direct"]])
@pytest.mark.parametrize("bad", ["-1", "0", "nan"])
def test_a_time_limit_that_is_not_positive_is_refused_before_any_work(command, bad, capsys,
                                                                       monkeypatch):
    """`render --max-seconds -1` ran the pilot, then refused every plan as over the limit."""
    _no_work(monkeypatch, "phonglab.planner", "plan")
    _fails_in_one_sentence(capsys, [*command, "--max-seconds", bad],
                           "--max-seconds must be a positive number of seconds")


def test_the_planner_refuses_a_time_limit_that_is_not_positive():
    with pytest.raises(PlanError, match="positive number of seconds"):
        planner.plan("gray_direct", 0.1, max_seconds=-1)


@pytest.mark.parametrize("library, words", [
    ("text", "is not a shared library"),         # /etc/passwd: "using /etc/passwd", exit 0
    ("folder", "is a folder"),
    ("elf", "could not be loaded by Dr.Jit"),    # a real shared library that is not libLLVM
])
def test_doctor_fails_when_the_libllvm_path_is_not_a_libllvm(tmp_path, library, words):
    import _ctypes

    path = {"text": tmp_path / "passwd", "folder": tmp_path,
            "elf": Path(_ctypes.__file__)}[library]
    (tmp_path / "passwd").write_text("root:x:0:0:root:/root:/bin/bash\n")
    done = subprocess.run([sys.executable, "-m", "phonglab.cli", "doctor"], capture_output=True,
                          text=True, timeout=120,
                          env={**os.environ, "DRJIT_LIBLLVM_PATH": str(path)})
    assert done.returncode == 1, done.stdout
    line = next(l for l in done.stdout.splitlines() if l.startswith("libLLVM"))
    assert words in line and "using" not in line, line
    assert "variant : scalar_rgb" in done.stdout
