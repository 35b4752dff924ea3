"""phonglab validate: the API, the report (JSON schema, table, HTML), --set parsing, the CLI's
exit codes and checks of bad input, the pytest helper, and the batch job for --all-builtins."""

from __future__ import annotations

import json
import pickle
import re
from pathlib import Path

import numpy as np
import pytest

from phonglab.cli import main
from phonglab.settings import ParameterError, parse_sets
from phonglab.testing import assert_bsdf_valid
from phonglab.validate import validate_bsdf
from phonglab.validate.bsdf.topics import TOPICS, Row
from phonglab.validate.gradient import unconverged
from phonglab.validate.inputs import ValidateError
from phonglab.validate.kind import topic_page, topic_url
from phonglab.verdict import STATUSES, Report

DEFECTS = Path(__file__).parent / "defects"
ROW_FIELDS = {"topic", "name", "measured", "expected", "stderr", "tolerance", "status", "reason",
              "details", "doc"}


def _check_schema(d: dict) -> None:
    assert set(d) == {"meta", "results"}
    assert d["results"]
    for r in d["results"]:
        # a sweep's row also names its parameter point; nothing else differs
        assert set(r) == ROW_FIELDS | ({"point"} if "point" in r else set())
        assert isinstance(r.get("point", {}), dict)
        assert r["topic"] in TOPICS and r["status"] in STATUSES
        assert isinstance(r["details"], dict) and isinstance(r["reason"], str)
    json.dumps(d, allow_nan=False)            # strictly valid JSON (no NaN/Inf)


# ----------------------------------------------------------------------------- inputs
def test_parse_sets():
    assert parse_sets(["alpha=0.25", "distribution=ggx", "sample_visible=false", "n=3",
                       "reflectance=0.2,0.3,0.4", "nested.type=diffuse",
                       "nested.reflectance=0.7"]) == {
        "alpha": 0.25, "distribution": "ggx", "sample_visible": False, "n": 3,
        "reflectance": {"type": "rgb", "value": [0.2, 0.3, 0.4]},
        "nested": {"type": "diffuse", "reflectance": 0.7}}


@pytest.mark.parametrize("bad", ["alpha", "=1", "alpha=", "a..b=1", "x=nan", "c=1,inf,2"])
def test_parse_sets_refuses(bad):
    with pytest.raises(ParameterError):
        parse_sets([bad])


def test_parse_sets_refuses_value_and_nested():
    with pytest.raises(ParameterError):
        parse_sets(["nested=1", "nested.type=diffuse"])


def test_row_refuses_unknown_topic_and_status():
    with pytest.raises(ValueError):
        Row("speed", "x", 1.0, 1.0, None, 0.0, "pass", "")
    with pytest.raises(ValueError):
        Row("cost", "x", 1.0, 1.0, None, 0.0, "ok", "")


# ----------------------------------------------------------------------------- API
def test_report_round_trip_and_table(variant_llvm_rgb):
    report = validate_bsdf("lambert", quick=True, topics=["finite", "energy", "gradient"])
    assert report.passed and not report.failing
    assert {r.topic for r in report.rows} == {"finite", "energy", "gradient"}
    d = json.loads(report.to_json())
    _check_schema(d)
    again = Report.from_dict(d)
    assert [r.name for r in again.rows] == [r.name for r in report.rows]
    text = report.table()
    assert "energy" in text and "directional albedo" in text
    energy = next(r for r in report.rows if r.topic == "energy")
    assert energy.measured == pytest.approx(0.5, abs=1e-4)          # lambert ρ = 0.5
    assert {"theta_deg", "albedo", "band", "lobes"} <= set(energy.details)


def test_spec_forms_dict_xml_and_loaded(variant_llvm_rgb, tmp_path):
    import mitsuba as mi
    xml = tmp_path / "b.xml"
    xml.write_text('<bsdf version="3.0.0" type="diffuse"><rgb name="reflectance" '
                   'value="0.2, 0.4, 0.6"/></bsdf>')
    for spec in ({"type": "diffuse", "reflectance": 0.3}, str(xml),
                 mi.load_dict({"type": "diffuse"})):
        report = validate_bsdf(spec, quick=True, topics=["energy"])
        assert report.passed, report.table()
    params = validate_bsdf("diffuse", params={"reflectance": 0.25}, quick=True, topics=["energy"])
    assert params.rows[0].measured == pytest.approx(0.25, abs=1e-4)


def test_bad_input_is_one_sentence(variant_llvm_rgb, tmp_path):
    with pytest.raises(ValidateError, match="cannot load BSDF 'nosuch'"):
        validate_bsdf("nosuch", quick=True)
    with pytest.raises(ValidateError, match="unknown topic"):
        validate_bsdf("diffuse", topics=["speed"])
    with pytest.raises(ValidateError, match="does not exist"):
        validate_bsdf("diffuse", plugins=[tmp_path / "none.py"])
    broken = tmp_path / "broken.py"
    broken.write_text("raise RuntimeError('oops')\n")
    with pytest.raises(ValidateError, match="failed: RuntimeError: oops"):
        validate_bsdf("diffuse", plugins=[broken])


def test_runner_is_kind_independent(variant_llvm_rgb):
    """core.run takes any Kind: its topics table in order, a raising topic is one failing row,
    KNOWN applies, m comes from the kind and the meta names the kind's plugin."""
    from phonglab import stats
    from phonglab.settings import Loaded
    from phonglab.validate import core

    def boom():
        raise RuntimeError("no such lane")

    def runners(plugin, opts, topics, m):
        return {"cost": lambda: [Row("cost", "c", 1.0, 1.0, None, None, "pass", "")],
                "finite": boom}
    kind = core.Kind(name="toy", word="toy", plural="toys", class_name="Object", register="register_toy",
                     topics=("finite", "cost"), options=lambda quick, seed, topics: None,
                     statistical_tests=lambda plugin, opts, topics: 3, runners=runners)
    report = core.run(kind, Loaded(object(), "toy-1", None), topics=("finite", "cost"),
                      known={"finite": "documented"})
    assert [r.topic for r in report.rows] == ["finite", "cost"]
    assert report.rows[0].status == "KNOWN" and "raised RuntimeError: no such lane" in \
        report.rows[0].reason
    assert report.meta["toy"] == "toy-1" and report.meta["statistical_tests"] == 3
    assert report.meta["alpha"] == stats.ALPHA == 0.01


def test_known_turns_a_fail_into_known_with_the_same_tolerance(variant_llvm_rgb):
    plugin = [DEFECTS / "energy_gain.py"]
    plain = validate_bsdf("defect_energy_gain", plugins=plugin, quick=True, topics=["energy"])
    known = validate_bsdf("defect_energy_gain", plugins=plugin, quick=True, topics=["energy"],
                          known={"energy": "documented: eval.cpp:12 omits 1/pi"})
    assert not plain.passed and known.passed
    (a,), (b,) = plain.rows, known.rows
    assert (a.status, b.status) == ("fail", "KNOWN")
    assert b.tolerance == a.tolerance and b.reason.startswith("documented: eval.cpp:12")


def test_assert_bsdf_valid(variant_llvm_rgb):
    assert assert_bsdf_valid("lambert", quick=True, topics=["weight"]).passed
    with pytest.raises(AssertionError) as info:
        # the given point alone: its sweep would also (rightly) fail energy at the probed
        # reflectance 10, which this plugin accepts (test_validate_sweep covers sweeps)
        assert_bsdf_valid("defect_weight_noise", plugins=[DEFECTS / "weight_noise.py"],
                          quick=True, topics=["weight", "energy"], sweep=False)
    msg = str(info.value)
    assert "weight = eval/pdf per sample" in msg and "fail" in msg
    assert "directional albedo" not in msg                   # only the failing rows


# ----------------------------------------------------------------------------- CLI
def test_cli_pass_json_and_html(variant_llvm_rgb, tmp_path, capsys):
    out_json, out_html = tmp_path / "r.json", tmp_path / "sub" / "r.html"
    rc = main(["validate", "lambert", "--quick", "--json", str(out_json),
               "--report", str(out_html)])
    text = capsys.readouterr().out
    assert rc == 0 and "lambert: PASSED" in text and "status" in text
    _check_schema(json.loads(out_json.read_text()))
    page = out_html.read_text()
    assert page.startswith("<!DOCTYPE html>") and "data:image/png;base64," in page
    # self-contained: no external resource of any kind; its only links are the topics' pages
    links = re.findall(r'<a href="([^"]*)">', page)
    assert set(links) <= {topic_url(topic_page("bsdf", t)) for t in TOPICS}
    rest = re.sub(r'<a href="[^"]*">', "", page)
    assert not re.search(r"(src|href)\s*=\s*[\"'](?!data:)", rest)
    assert "http://" not in rest and "https://" not in rest


def test_cli_fail_with_plugin_and_chi2_figure(variant_llvm_rgb, tmp_path, capsys):
    out_html = tmp_path / "r.html"
    rc = main(["validate", "defect_pdf_mismatch", "--plugin", str(DEFECTS / "pdf_mismatch.py"),
               "--quick", "--only", "chi2", "--only", "energy", "--report", str(out_html),
               "--no-sweep"])
    assert rc == 1 and "FAILED" in capsys.readouterr().out
    assert "Failing χ² cells" in out_html.read_text()


@pytest.mark.parametrize("argv, message", [
    (["validate", "nosuch"], "unknown plugin type 'nosuch'"),
    (["validate", "diffuse", "--set", "reflectance"], "is not NAME=VALUE"),
    (["validate", "diffuse", "--only", "speed"], "unknown topic 'speed'"),
    (["validate", "x", "--plugin", "no/such/file.py"], "does not exist"),
    (["validate", "missing.xml"], "does not exist"),
    (["validate"], "name the plugin to validate"),
    (["validate", "diffuse", "--report", "out.txt"], "must end in .html"),
    (["validate", "diffuse", "--set", "alpha=0.2", "--all-builtins"], "takes no plugin"),
])
def test_cli_bad_input_exit_2(variant_llvm_rgb, capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_cli_all_builtins_with_a_small_catalogue(variant_llvm_rgb, tmp_path, capsys, monkeypatch):
    from phonglab.validate import batch
    from phonglab.validate.bsdf import builtins
    small = [builtins.Case("diffuse/test", {"type": "diffuse"}),
             builtins.Case("conductor/test", {"type": "conductor"}, delta=True)]
    monkeypatch.setattr(builtins, "cases", lambda: small)
    out = tmp_path / "all.json"
    rc = main(["validate", "--all-builtins", "--quick", "--only", "finite", "--only", "energy",
               "--json", str(out)])
    assert rc == 0, capsys.readouterr().out
    data = json.loads(out.read_text())
    assert [r["meta"]["case"] for r in data["reports"]] == ["diffuse/test", "conductor/test"]
    for r in data["reports"]:
        _check_schema(r)
    # The job function is picklable and takes a label (for a process pool or Dask).
    job = pickle.loads(pickle.dumps(batch.run_case))
    d = job("conductor/test", {"quick": True, "topics": ["energy"]})
    assert d["meta"]["case"] == "conductor/test" and d["results"][0]["status"] == "pass"


def test_bench_report_validate_section(tmp_path):
    from types import SimpleNamespace

    from phonglab.bench.validate_report import validate_section
    assert validate_section(SimpleNamespace(out=tmp_path)) == []
    (tmp_path / "validate.json").write_text(json.dumps([
        {"plugin": "diffuse", "variant": "llvm_ad_rgb", "kind": "bsdf", "repeats": 3,
         "exit_codes": [0], "points": 4, "targets": [20.0, 5.0],
         "profile_default": {"chi2": 2.5, "finite": 0.1, "normalization": 3.0, "weight": 0.2},
         "profile_quick": {"chi2": 2.5, "finite": 0.1, "normalization": 3.0, "weight": 0.2},
         "default_seconds": [5.0, 6.0, 7.0], "quick_seconds": [2.0, 5.5, 11.0]},
        {"plugin": "hg", "variant": "llvm_ad_rgb", "kind": "phase", "repeats": 3,
         "exit_codes": [0], "points": 3, "targets": None, "profile_default": {"chi2": 1.0},
         "profile_quick": {"gradient": 0.7},
         "default_seconds": [5.0, 6.0, 7.0], "quick_seconds": [2.0, 2.5, 3.0]}]))
    text = "\n".join(validate_section(SimpleNamespace(out=tmp_path)))
    # the median against each target (5.5 s --quick misses 5 s), the largest topics in order
    assert ("| diffuse | bsdf | 4 | 6.0 [5.0, 7.0] | **met** | 5.5 [2.0, 11.0] | **not met** | "
            "normalization 3.0, chi2 2.5, weight 0.2 | normalization 3.0, chi2 2.5, weight 0.2 |") in text
    assert "| hg | phase | 3 | 6.0 [5.0, 7.0] | — | 2.5 [2.0, 3.0] | — | chi2 1.0 | gradient 0.7 |" in text
    assert "1 plugins miss a target; in each missed run two topics take 95%–95%" in text
    assert ("- diffuse, 4 points: --quick 5.5 s > 5 s: normalization 3.0 s + chi2 2.5 s"
            " (95% of the profile)") in text
    assert "Before and after" not in text
    assert "Timed " not in text               # one run: no dates to tell apart
    # a default run on 2 processes whose two largest topics alone, shared out, exceed 20 s
    rows = json.loads((tmp_path / "validate.json").read_text())
    slow = {**rows[0], "plugin": "slowbsdf", "default_seconds": [40.0], "quick_seconds": [1.0],
            "where": {"workers": 2},
            "profile_default": {"normalization": 30.0, "chi2": 20.0, "weight": 1.0}}
    (tmp_path / "validate.json").write_text(json.dumps(rows + [slow]))
    text = "\n".join(validate_section(SimpleNamespace(out=tmp_path)))
    assert ("- slowbsdf, 4 points: default 40.0 s > 20 s: normalization 30.0 s + chi2 20.0 s "
            "(98% of the profile; 25.0 s alone on 2 processes, above the target)") in text
    (tmp_path / "validate.json").write_text(json.dumps(rows))
    rows = json.loads((tmp_path / "validate.json").read_text())
    rows[1]["measured"] = "2026-12-07 08:02 UTC at abc1234"      # hg timed again later
    (tmp_path / "validate.json").write_text(json.dumps(rows))
    text = "\n".join(validate_section(SimpleNamespace(out=tmp_path)))
    assert ("Timed in an earlier run (before the script recorded when): diffuse; "
            "2026-12-07 08:02 UTC at abc1234: hg.") in text
    (tmp_path / "validate-before.json").write_text(json.dumps({"commit": "abc1234", "rows": [
        {"plugin": "diffuse", "default_seconds": [10.0, 12.0], "quick_seconds": [4.0, 6.0]}]}))
    text = "\n".join(validate_section(SimpleNamespace(out=tmp_path)))
    assert "at commit abc1234" in text
    assert "| diffuse | 11.0 → 6.0 | 0.55 | 5.0 → 5.5 | 1.10 |" in text
    # one plugin timed in two variants: each row against its own variant's
    rows = json.loads((tmp_path / "validate.json").read_text())
    rows.append({**rows[0], "variant": "llvm_ad_mono_polarized",
                 "default_seconds": [30.0], "quick_seconds": [3.0]})
    (tmp_path / "validate.json").write_text(json.dumps(rows))
    (tmp_path / "validate-before.json").write_text(json.dumps({"commit": "abc1234", "rows": [
        {"plugin": "diffuse", "variant": "llvm_ad_rgb", "default_seconds": [12.0],
         "quick_seconds": [5.0]},
        {"plugin": "diffuse", "variant": "llvm_ad_mono_polarized", "default_seconds": [40.0],
         "quick_seconds": [4.0]}]}))
    text = "\n".join(validate_section(SimpleNamespace(out=tmp_path)))
    assert "| diffuse | 12.0 → 6.0 | 0.50 | 5.0 → 5.5 | 1.10 |" in text
    assert "| diffuse (llvm_ad_mono_polarized) | 40.0 → 30.0 | 0.75 | 4.0 → 3.0 | 0.75 |" in text


def test_lobe_quadrature_centre_anywhere():
    import math

    import numpy as np

    from phonglab.physics.quadrature import lobe_quadrature
    for theta in (0.0, 0.6, 1.5707):
        for azimuth, symmetric in ((math.pi, True), (1.0, False), (4.0, False)):
            wo, w = lobe_quadrature(theta, 0.05, 12, azimuth=azimuth, symmetric=symmetric)
            assert np.sum(w) == pytest.approx(2 * math.pi, rel=1e-12)
            assert np.sum(w * wo[:, 2]) == pytest.approx(math.pi, rel=1e-12)
            assert wo[:, 2].min() >= 0.0


def test_a_topic_that_raises_is_one_failing_row(variant_llvm_rgb, tmp_path):
    plugin = tmp_path / "raising.py"
    plugin.write_text((DEFECTS / "energy_gain.py").read_text()
                      .replace("defect_energy_gain", "raises_in_eval_pdf")
                      .replace("value = self.reflectance * mi.Frame3f.cos_theta(wo)",
                               "value = self.reflectance * dr.inv_pi * mi.Frame3f.cos_theta(wo)")
                      .replace("        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)",
                               "        raise RuntimeError('eval_pdf is not implemented')"))
    report = validate_bsdf("raises_in_eval_pdf", plugins=[plugin], quick=True,
                           topics=["finite", "eval_pdf", "energy", "weight"])
    failing = {r.topic: r for r in report.failing}
    assert set(failing) == {"finite", "eval_pdf"}
    assert "raised RuntimeError" in failing["eval_pdf"].reason
    assert "traceback" in failing["eval_pdf"].details
    assert {r.topic for r in report.rows if r.status == "pass"} == {"energy", "weight"}


EXITS = "import sys\nsys.exit(0)\n"
REGISTERS_NOTHING = "import mitsuba as mi\n\nclass Nothing(mi.BSDF):\n    pass\n"
REGISTERS_AN_EMITTER = ("import mitsuba as mi\n\nclass Lamp(mi.Emitter):\n"
                        "    def __init__(self, props):\n        mi.Emitter.__init__(self, props)\n\n"
                        "mi.register_emitter('my_lamp', lambda props: Lamp(props))\n")


@pytest.mark.parametrize("text, needle", [
    (EXITS, "called sys.exit(0) while it was loaded"),
    (REGISTERS_NOTHING, "registered nothing; validating a BSDF needs a file that calls "
                        "mi.register_bsdf"),
    (REGISTERS_AN_EMITTER, "registered the emitter 'my_lamp'"),
], ids=["sys.exit(0)", "nothing", "an emitter"])
def test_a_plugin_file_that_registers_no_bsdf_is_bad_input(variant_llvm_rgb, tmp_path, capsys,
                                                           text, needle):
    """A --plugin file that called sys.exit(0) made `validate` exit 0 ('all pass') without
    validating anything; one that registered nothing or another kind left 'cannot load'."""
    plugin = tmp_path / "p.py"
    plugin.write_text(text)
    assert main(["validate", "diffuse", "--quick", "--plugin", str(plugin)]) == 2
    err = capsys.readouterr().err
    assert needle in err and "Traceback" not in err and len(err.strip().splitlines()) == 1, err


def test_a_plugin_file_that_registers_another_name_says_which(variant_llvm_rgb, tmp_path, capsys):
    plugin = tmp_path / "p.py"
    plugin.write_text((DEFECTS / "energy_gain.py").read_text())
    assert main(["validate", "my_bsdf", "--quick", "--plugin", str(plugin)]) == 2
    err = capsys.readouterr().err
    assert "cannot load BSDF 'my_bsdf'" in err and "registered 'defect_energy_gain'" in err, err


def test_all_builtins_keeps_each_case_and_resumes(variant_llvm_rgb, tmp_path, capsys,
                                                  monkeypatch):
    """Ctrl-C during --all-builtins keeps every finished case: each is kept as it finishes
    (not only in the JSON written at the end), and a rerun runs only the rest."""
    from phonglab.validate import batch
    from phonglab.validate.bsdf import builtins

    small = [builtins.Case("diffuse/test", {"type": "diffuse"}),
             builtins.Case("roughconductor/test", {"type": "roughconductor"}),
             builtins.Case("conductor/test", {"type": "conductor"}, delta=True)]
    monkeypatch.setattr(builtins, "cases", lambda: small)
    ran = []
    real = batch.run_case

    def interrupted_after_two(case, options=None):
        if len(ran) == 2:
            raise KeyboardInterrupt
        ran.append(case.label)
        return real(case, options)

    monkeypatch.setattr(batch, "run_case", interrupted_after_two)
    out = tmp_path / "all.json"
    argv = ["validate", "--all-builtins", "--quick", "--only", "finite", "--json", str(out)]
    assert main(argv) == 130
    log = Path(str(out) + ".partial.jsonl")
    assert not out.exists() and len(log.read_text().splitlines()) == 3   # options + 2 cases
    ran.clear()
    monkeypatch.setattr(batch, "run_case", lambda case, options=None:
                        ran.append(case.label) or real(case, options))
    assert main(argv) == 0
    assert "resuming: 2 cases already done" in capsys.readouterr().out
    assert ran == ["conductor/test"] and not log.exists()
    data = json.loads(out.read_text())
    assert [r["meta"]["case"] for r in data["reports"]] == [c.label for c in small]
    # Other options start afresh.
    monkeypatch.setattr(batch, "run_case", interrupted_after_two)
    ran.clear()
    assert main(argv[:-2] + ["--seed", "1", "--json", str(out)]) == 130
    assert len(log.read_text().splitlines()) == 3 and '"seed": 1' in log.read_text()


@pytest.mark.parametrize("seed", [-1, 1.5, True])
def test_a_bad_seed_is_bad_input_not_failing_topics(variant_llvm_rgb, seed):
    """validate_bsdf(seed=-1) reported seven failing topics (numpy refused the seed inside
    each); the CLI refuses it at the option (tests/test_render_inputs.py)."""
    with pytest.raises(ValidateError, match="the seed must be a whole number >= 0"):
        validate_bsdf("diffuse", seed=seed, quick=True, topics=["finite"])


@pytest.mark.parametrize("spec, params", [
    ("diffuse", {"reflectance": 0.0}), ("lambert", {"reflectance": 0.0}),
    ("phong", {"diffuse_reflectance": 0.0, "specular_reflectance": 0.0}),
    ("roughconductor", {"specular_reflectance": 0.0, "alpha": 0.3}),
], ids=["diffuse", "lambert", "phong", "roughconductor"])
def test_a_black_bsdf_passes_on_what_is_defined(variant_llvm_rgb, spec, params):
    """A black BSDF (every weight 0) passes χ²: its directions are histogrammed as drawn (a
    histogram of non-zero weights alone would be empty against ∫pdf = 1), and its weight/pdf
    rows say it is black (not 'nothing to compare for a purely delta BSDF')."""
    report = validate_bsdf(spec, params=params, quick=True,
                           topics=["finite", "weight", "pdf", "chi2"])
    assert report.passed, report.table(report.failing)
    (chi2,) = [r for r in report.rows if r.topic == "chi2"]
    assert chi2.status == "pass" and all(c.get("black") for c in chi2.details["cells"])
    for r in report.rows:
        if r.topic in ("weight", "pdf"):
            assert r.status == "skipped" and "a black BSDF" in r.reason and "delta" not in \
                r.reason.split(":")[-1], r.reason


def test_weights_of_zero_where_eval_is_not_fail_the_weight_topic(variant_llvm_rgb, tmp_path):
    """The black-BSDF handling must not excuse a sampler whose weights are all 0 while eval is
    not: those lanes are compared (weight 0 against eval/pdf = ρ), and χ² keeps failing on
    the empty histogram."""
    plugin = tmp_path / "zero_weight.py"
    plugin.write_text((DEFECTS / "weight_noise.py").read_text()
                      .replace("value * 2.0 * sample1", "value * 0.0")
                      .replace("defect_weight_noise", "defect_zero_weight"))
    report = validate_bsdf("defect_zero_weight", plugins=[plugin], quick=True,
                           topics=["weight", "chi2"])
    assert {r.topic for r in report.failing} == {"weight", "chi2"}, report.table()


def test_a_failing_row_shows_its_worst_lane_in_plain_numbers(variant_llvm_rgb):
    """Beyond 'measured 1023, tolerance 1', which tells an author nothing to act on, the table
    and the assert_bsdf_valid message give the worst lane's wi, wo and both sides."""
    with pytest.raises(AssertionError) as info:
        assert_bsdf_valid("defect_weight_noise", plugins=[DEFECTS / "weight_noise.py"],
                          quick=True, topics=["weight"])
    line = [ln for ln in str(info.value).splitlines() if "worst lane:" in ln]
    assert line and "wi = (" in line[0] and "weight = " in line[0], str(info.value)
    assert "eval_over_pdf = 0.5" in line[0] and "held to a relative tolerance of" in line[0]


def test_the_html_report_shows_the_worst_lane(variant_llvm_rgb, tmp_path):
    from phonglab.validate import html

    report = validate_bsdf("defect_weight_noise", plugins=[DEFECTS / "weight_noise.py"],
                           quick=True, topics=["weight"])
    page = html.write(report, tmp_path / "r.html").read_text()
    assert "worst lane: wi = (" in page and "eval_over_pdf = 0.5" in page


def test_a_builtin_named_by_its_type_carries_its_documented_findings(capsys):
    """`phonglab validate roughconductor` exits 0 though the Beckmann pdf's normalization fails
    (a documented Mitsuba 3.9.1 finding, microfacet.h): the conformance table's causes of the
    plugin apply by default, each only inside its signature; --no-known shows the raw fail."""
    args = ["validate", "roughconductor", "--quick", "--no-sweep", "--only", "normalization"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "KNOWN" in out and "--no-known reports them as fails" in out
    assert main(args + ["--no-known"]) == 1
    assert "KNOWN rows" not in capsys.readouterr().out


def test_a_builtins_findings_follow_its_microfacet_distribution():
    """The Beckmann normalization finding explains a Beckmann lobe (Mitsuba's default), never a
    GGX one: there a normalization fail stays a fail.  A cause outside the distribution (the
    conductor Fresnel term's derivative at eta = 0, fresnel.h) holds for GGX too, though the
    table shows it on Beckmann cases only (it made every GGX roughconductor sweep fail its
    eta gradient); a plugin without a distribution keeps its findings whatever is given."""
    from phonglab.validate.bsdf.builtins import known_for_plugin

    def keys(given, plugin="roughconductor", topic="normalization"):
        return {getattr(c, "key", "") for c in known_for_plugin(plugin, given).get(topic, ())}
    assert "beckmann-pdf-normalization" in keys({})
    assert "beckmann-pdf-normalization" in keys({"distribution": "beckmann"})
    assert "beckmann-pdf-normalization" not in keys({"distribution": "ggx"})
    assert "conductor-eta0-gradient" in keys({"distribution": "ggx"}, topic="gradient")
    assert keys({"distribution": "ggx"}, "plastic", "energy") == keys(None, "plastic", "energy") != set()


def test_a_gradient_skip_of_the_checks_own_making_does_not_blame_the_plugin(variant_llvm_rgb):
    """Conductor's eval is 0 (a delta lobe), so the eval-based gradient has no dependence to
    follow: the skip says it is the check's limit (not "the BSDF refused the update") -- and
    AD that lost a dependence eval has still fails."""
    report = validate_bsdf("conductor", topics=["gradient"])
    rows = [r for r in report.rows if r.status == "skipped"]
    assert rows and all("refused" not in r.reason for r in rows)
    assert any("a limit of the check, not a defect of the BSDF" in r.reason for r in rows)


def test_ad_that_loses_a_dependence_eval_has_fails(variant_llvm_rgb, tmp_path):
    plugin = tmp_path / "detached.py"
    plugin.write_text((DEFECTS / "sweep" / "plain_lambert.py").read_text().replace(
        "value = self.GAIN * self.kd *", "value = self.GAIN * dr.detach(self.kd) *"))
    report = validate_bsdf("author_lambert", plugins=[plugin], topics=["gradient"])
    (row,) = [r for r in report.rows if r.name == "kd"]
    assert row.status == "fail" and "AD lost a dependence eval has" in row.reason


def test_a_lane_judges_ad_only_where_its_own_quotients_converge(variant_llvm_rgb):
    """pplastic at int_ior 1 (η = 0.99972, the default-size sweep's corner): lanes just above
    the critical cosine 0.0235 have ∂eval/∂η ~ 1/√(cos² θ − cos² θ_c), AD 138 against
    quotients D(h) 0.31 and D(h/2) 0.78 (the step crosses the total-reflection edge). Judged
    against 1 % of max(|D(h/2)|, |AD|), they were kept and the row read 408 against 3.4 (a
    fail); judged from the quotients alone they are left out, and the kept lanes agree."""
    assert unconverged(np.array([0.31]), np.array([0.78]), np.zeros(1))[0]
    assert not unconverged(np.array([0.780]), np.array([0.781]), np.zeros(1))[0]
    report = validate_bsdf({"type": "pplastic", "int_ior": 1.0}, topics=["gradient"])
    (row,) = [r for r in report.rows if r.name == "eta.value"]
    assert row.status == "pass", row.reason
    assert row.details["jump_lanes"] > 0 and abs(row.measured) < 10
