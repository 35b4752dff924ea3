"""phonglab.bench.adaptive_oracle's pure parts: sizes, the reference rule, the quiet-machine
wait, the account of a missed row and the BENCHMARKS.md section (on a small made-up record;
nothing here renders or times)."""

from __future__ import annotations

import json
from types import SimpleNamespace

import pytest

from phonglab.bench import adaptive_oracle as ao


def test_sizes_scale_each_direction():
    assert ao.scaled_params({"res": 128}, 4) == {"res": 512}
    assert ao.scaled_params({"width": 512, "height": 128, "spp": 8}, 2) == \
        {"width": 1024, "height": 256, "spp": 8}
    assert ao.size_label({"res": 256}) == "256²"
    assert ao.size_label({"width": 2048, "height": 512}) == "2048×512"


def test_reference_spp_rule():
    # noise 0.001 at 4096 spp, E = 0.01: E/4 needs 4096 (0.001/0.0025)² = 655 -> 768
    assert ao.reference_spp(0.001, 4096, 0.01) == 768
    # a noisy scene is capped at the bench's 4096, a clean one floored at one step
    assert ao.reference_spp(0.005, 4096, 0.01) == 4096
    assert ao.reference_spp(1e-6, 4096, 0.01) == ao.REFERENCE_STEP
    # the predicted noise at the chosen spp is within the share (where not capped)
    n = ao.reference_spp(0.002, 4096, 0.02)
    assert 0.002 * (4096 / n) ** 0.5 <= 0.25 * 0.02 < 0.002 * (4096 / (n - 256)) ** 0.5


def test_wait_for_quiet_waits_by_steps_and_gives_up():
    loads = iter([3.0, 2.0, 1.0])
    slept = []
    seen = ao.wait_for_quiet(1.5, step=60, most=600, log=lambda m: None,
                             load=lambda: (next(loads), 1.0, 1.0), sleep=slept.append)
    assert slept == [60, 60] and seen["waited_s"] == 120 and seen["quiet"]
    seen = ao.wait_for_quiet(1.5, step=60, most=120, log=lambda m: None,
                             load=lambda: (4.0, 1.0, 1.0), sleep=slept.append)
    assert seen["waited_s"] == 120 and not seen["quiet"] and seen["load"] == [4.0, 1.0, 1.0]


def _row(scene, scale, **kw):
    row = {"scene": scene, "scale": scale, "params": {"res": 32 * scale}, "target": 0.02,
           "oracle": 4.0, "oracle_time": 2.0, "equal_samples": 3.2, "share_time": 0.512,
           "achieved": {"median": 1.024, "min": 0.9, "max": 1.1, "n": 3}, "met": False,
           "factors": {"wavefront": 1.0, "placement": 1.25, "passes": 2.0, "host": 1.25},
           "total": 3.125, "reference_spp": 4096, "reference_noise_e": 0.26,
           "medians": {"seconds": 0.5, "pair_seconds": 0.16, "spp": 100.0, "passes": 4}}
    return {**row, **kw}


def test_account_names_the_fewest_terms_that_reach_the_target():
    # terms: allocation 0.8, path cost 4/(2·1.25) = 1.6, wavefront 1, passes 0.5, host 0.8
    text = ao.account(_row("gray_direct", 1))
    assert text.startswith("0.51 of the time oracle (the terms multiply to 0.51): held back "
                           "by passes ×0.50; without it 1.02.")
    # a share the passes alone cannot lift names the next term too
    text = ao.account(_row("gray_direct", 1, share_time=0.36, achieved={"median": 0.72}))
    assert "by passes ×0.50, allocation ×0.80; without them 0.90." in text and "spread" in text
    # passes below 1: the one-pass trace is no floor, path cost and passes are one term
    row = _row("nb_sphere_row", 1, factors={"wavefront": 1.0, "placement": 2.5, "passes": 0.8,
                                            "host": 1.0}, share_time=0.4)
    assert set(ao.share_terms(row)) == {"allocation", "path cost and passes (split unresolved)",
                                        "wavefront", "host"}
    assert ao.share_terms(row)["path cost and passes (split unresolved)"] == pytest.approx(1.0)
    assert ao.account(_row("gray_direct", 1, met=True)) is None
    assert ao.account(_row("gray_direct", 1, met=None)) is None


def test_account_of_the_furnace_overhead():
    row = _row("check_furnace_enclosure", 1, oracle=1.0, oracle_time=1.0,
               achieved={"median": 1 / 1.2, "min": 0.8, "max": 0.9, "n": 3},
               factors={"wavefront": 1.0, "placement": 0.98, "passes": 1.1, "host": 1.05})
    assert ao.account(row) == ("cost 1.20x uniform (the factors multiply to 1.13x): held back "
                               "by passes ×1.10, host ×1.05; without them 1.04x.")


def test_report_section_renders_a_small_record(tmp_path):
    assert ao.report_section(SimpleNamespace(out=tmp_path)) == []
    rows = [_row("gray_direct", 1), _row("gray_direct", 2, met=True, share_time=0.85),
            _row("glass_slab", 1, share_time=0.7996), _row("glass_slab", 2, share_time=0.7946),
            _row("check_furnace_enclosure", 1, oracle=1.0, oracle_time=1.0, met=True,
                 achieved={"median": 1.0, "min": 0.97, "max": 1.02, "n": 3}),
            _row("check_furnace_enclosure", 2, oracle=1.0, oracle_time=1.0,
                 achieved={"median": 1 / 1.2, "min": 0.8, "max": 0.9, "n": 3},
                 factors={"wavefront": 1.0, "placement": 1.0, "passes": 1.1, "host": 1.05})]
    meta = {"date": "2026-12-06", "seeds": 3, "cores": 2, "load_start": [0.4, 1, 1],
            "load_end": [1.2, 1, 1], "timed_seconds": 600.0, "prepare_seconds_all": 120.0}
    (tmp_path / ao.JSON_NAME).write_text(json.dumps({"meta": meta, "rows": rows}))
    text = "\n".join(ao.report_section(SimpleNamespace(out=tmp_path)))
    assert "(32², 64²; the furnace 32², 64²)" in text and "10.0 min" in text
    assert "load average 0.4 at its start, 1.2 at its end" in text and "Note" not in text
    meta["load_start"] = [2.5, 1, 1]
    (tmp_path / ao.JSON_NAME).write_text(json.dumps({"meta": meta, "rows": rows}))
    noted = "\n".join(ao.report_section(SimpleNamespace(out=tmp_path)))
    assert "**Note:** other processes" in noted
    assert ("| gray_direct | 0.02 | 2.00x | 1.02x [0.90–1.10] | 0.51 | **not met** | 2.00x | "
            "1.02x [0.90–1.10] | 0.85 | **met** |") in text
    assert ("| check_furnace_enclosure | 0.02 | 1.00x | 1.00x [0.97–1.02] | cost 1.00x | **met** "
            "| 1.00x | 0.83x [0.80–0.90] | cost 1.20x | **not met** |") in text
    assert ("| gray_direct | 64² | 0.500 | 0.160 | 100 | 4 | 3.20x | 1.00 | 1.25 | 2.00 | 1.25 "
            "| 3.12 |") in text
    assert "Median over the scenes, 32² → 64²: wavefront 1.00 → 1.00; placement" in text
    assert "| gray_direct | 4096 spp, 0.26 E | 4096 spp, 0.26 E |" in text
    assert "Targets met: 32² 1 of 3, 64² 1 of 3." in text
    # a share that 2 decimals would round onto the target shows 3
    assert ("| glass_slab | 0.02 | 2.00x | 1.02x [0.90–1.10] | 0.800 | **not met** | 2.00x | "
            "1.02x [0.90–1.10] | 0.79 | **not met** |") in text
    assert "* gray_direct 32²: 0.51 of the time oracle" in text
    assert "* check_furnace_enclosure 64²: cost 1.20x uniform" in text
    assert "gray_direct 64²:" not in text


@pytest.mark.parametrize("scale", [1, 2, 4])
def test_every_oracle_scene_scales(scale):
    from phonglab.bench.config import Config
    for name, (_, params) in Config().adaptive_oracle_scenes.items():
        p = ao.scaled_params(params, scale)
        assert ao.size_label(p) in (f"{128 * scale}²", f"{512 * scale}×{128 * scale}",
                                    f"{32 * scale}²")


def test_cost_factors_multiply_to_the_total():
    from phonglab.bench.adaptive_sweeps import cost_factors
    rows = [{"seconds": 1.2 * k, "trace_seconds": 1.0 * k, "pair_seconds": 0.5 * k,
             "one_pass_seconds": 0.8 * k, "one_pass_uniform_seconds": 0.4 * k,
             "spp": 100.0, "passes": 4} for k in (1.0, 1.1, 0.9)]
    c = cost_factors(rows)
    assert c["factors"] == pytest.approx({"wavefront": 0.8, "placement": 2.0, "passes": 1.25,
                                          "host": 1.2})
    assert c["total"] == pytest.approx(2.4) == pytest.approx(
        0.8 * 2.0 * 1.25 * 1.2)
    assert c["medians"]["seconds"] == pytest.approx(1.2)
