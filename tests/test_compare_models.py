"""``compare_models``: the difference statistics by hand, then one tiny end-to-end run and the CLI."""

from __future__ import annotations

import numpy as np
import pytest

from phonglab import cli

from phonglab.engine import exr
from phonglab.engine.compare_models import compare_models, format_table, pair_stats
from phonglab.errors import PhonglabError


def test_pair_stats_by_hand():
    b = np.ones((2, 3, 3))
    a = 2.0 * b
    a[1, 2] = [2.0, 2.0, 5.0]
    st = pair_stats(a, b, "a", "b")
    # |a − b| = 1 everywhere except one channel where it is 4: mean (17 + 4)/18.
    assert st.mean_abs == pytest.approx(21 / 18)
    assert st.max_abs == 4.0 and st.where_max == (1, 2)
    assert st.relative == pytest.approx(21 / 18)
    # s = Σab / Σa² = (17·2 + 5) / (17·4 + 25)
    assert st.scale == pytest.approx(39 / 93)
    assert "a − b" in format_table([st])
    with pytest.raises(PhonglabError, match="shapes"):
        pair_stats(a, b[:1])


def test_compare_models_end_to_end(variant_llvm_rgb, tmp_path):
    """Tiny exponent series at max_depth 2: radiance and path see the same direct light, so
    with equal spp and seed (identical camera rays) they agree to float precision."""
    c = compare_models("exponent_series", tmp_path, spp=2, path_spp=2, max_depth=2,
                       params={"width": 48, "height": 16})
    np.testing.assert_allclose(c.images["radiance"], c.images["path"], rtol=1e-5, atol=1e-6)
    g_r = next(s for s in c.stats if (s.a, s.b) == ("graphics", "radiance"))
    assert g_r.relative > 10          # graphics units: no 1/(π r²) at r ≈ 6
    for name in ("graphics", "radiance", "path"):
        image, meta = exr.read(tmp_path / f"{name}.exr")
        assert image.shape == (16, 48, 3) and meta["model"] == name
        assert (tmp_path / f"{name}.png").is_file()
    assert (tmp_path / "figure.png").stat().st_size > 1000
    assert (tmp_path / "diff_graphics_path.png").is_file()
    assert "graphics − path" in (tmp_path / "table.txt").read_text()


def test_cli_reports_bad_input(variant_llvm_rgb, tmp_path, capsys):
    assert cli.main(["compare-models", "no_such_scene", "-o", str(tmp_path)]) == 2
    assert "scene file not found" in capsys.readouterr().err
    assert cli.main(["compare-models", "exponent_series", "-D", "colour=red",
                     "-o", str(tmp_path)]) == 2
    assert "no parameter 'colour'" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:   # argparse refuses it, as any malformed option
        cli.main(["compare-models", "exponent_series", "-D", "width", "-o", str(tmp_path)])
    assert exit_.value.code == 2 and "NAME=VALUE" in capsys.readouterr().err
