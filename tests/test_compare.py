"""``phonglab compare``: no NaN, no tautology, the output rules of render (phonglab.engine.compare)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from phonglab import cli
from phonglab.engine import exr

from helpers import fails_in_one_sentence as _fails_in_one_sentence


# --- compare: no NaN, no tautology, the output rules of render ----------------------------------

def test_compare_of_identical_images_says_why_the_test_is_undefined(tmp_path, capsys):
    """Two black images (or any two equal ones) have SE = 0: the test is undefined, and says
    why (z and p are not printed as nan, nor --json written with a bare NaN, invalid JSON)."""
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
    """The same file compared with itself is no evidence (not 'same expected image, p = 1')."""
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
