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
"""

from __future__ import annotations

import contextlib
import io
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from phonglab import cli

from phonglab.engine import exr

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
