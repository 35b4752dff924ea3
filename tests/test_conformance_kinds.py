"""The emitter and integrator conformance tables (phonglab.validate.registry.catalogue):
catalogues load, every 3.9.1 plugin is covered or left out, findings name their cases and
reproducers, the markdown renders from a small JSON, and the validator fixes the tables led
to.  Default tier: no validation runs here (``make conformance`` runs the tables)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from phonglab.validate import conformance, markdown, registry
from phonglab.verdict import Report, Row

REPO_ROOT = Path(__file__).resolve().parents[1]

#: src/emitters/*.cpp and src/integrators/*.cpp + src/python/python/ad/integrators/*.py at
#: tag v3.9.1 (timed_sunsky included; prb_basic, volprim_rf_basic are Python integrators)
MITSUBA = {
    "emitter": {"area", "constant", "directional", "directionalarea", "envmap", "point",
                "projector", "spot", "sunsky", "timed_sunsky"},
    "integrator": {"aov", "depth", "direct", "moment", "path", "ptracer", "stokes", "volpath",
                   "volpathmis", "direct_projective", "prb", "prb_basic", "prb_projective",
                   "prbvolpath", "volprim_rf_basic"},
}
SOURCE_LINE = re.compile(r"^(src|include|plugins)/[\w/]+\.(cpp|h|py):\d+$")


@pytest.fixture(params=["emitter", "integrator"])
def cat(request, variant_llvm_rgb):
    return registry.catalogue(request.param)


def test_catalogue_loads_and_covers_3_9_1(cat):
    cases = cat.cases()
    labels = [c.label for c in cases]
    assert len(labels) == len(set(labels))
    assert MITSUBA[cat.kind.name] <= {c.plugin for c in cases} | set(cat.left_out)
    for c in cases:
        assert c.skip or c.plugin not in cat.left_out, c.label
        assert cat.find(c.label).label == c.label


def test_findings_name_cases_source_lines_and_reproducers(cat):
    labels = {c.label for c in cat.cases()}
    for f in cat.findings:
        assert set(f.labels) <= labels, f.key
        assert f.topic in cat.kind.topics and f.rows, f.key
        assert SOURCE_LINE.match(f.source), f.source
        assert (REPO_ROOT / f.reproducer).is_file(), f.reproducer
    for v in cat.validator_issues:
        assert set(v.labels) <= labels and v.topic in cat.kind.topics, v.key
    known = {c.label: c.known for c in cat.cases() if c.known}
    for f in cat.findings:                  # each finding reaches its cases as a signature
        for label in f.labels:
            assert f.key in {k.key for k in known[label][f.topic]}


def test_volpathmis_signatures_hold_exactly_where_roulette_meets_a_counted_hit(variant_llvm_rgb):
    """volpathmis.cpp: roulette runs at depth > rr_depth (line 238), an emitter hit counts at
    depth < max_depth (line 244): the bias needs rr_depth <= D - 2, and each signature holds
    there and nowhere else; a point that leaves rr_depth unset has its default, 5."""
    import types

    import mitsuba as mi

    from phonglab.validate.integrator import ranges

    found = {f.key: f for f in registry.catalogue("integrator").findings}
    for key, depth in (("volpathmis-roulette-mis", 64), ("volpathmis-roulette-mis-shallow", 3),
                       ("volpathmis-roulette-mis-agreement", 5)):
        k = found[key].known()
        assert all(k.holds_at({"rr_depth": rr}) for rr in range(1, depth - 1)), key
        assert not any(k.holds_at({"rr_depth": rr}) for rr in (depth - 1, depth, 1000)), key
    target = types.SimpleNamespace(spec={"type": "volpathmis"},
                                   integrator=mi.load_dict({"type": "volpathmis"}))
    assert ranges.values(target) == {"rr_depth": 5.0}
    target.spec = {"type": "direct", "emitter_samples": 4}
    target.integrator = mi.load_dict(target.spec)
    assert ranges.values(target) == {"emitter_samples": 4.0, "bsdf_samples": 1.0}


def test_sun_rim_lanes_are_the_findings_never_a_tolerance(variant_llvm_rgb):
    """sunsky.h:430 counts a sun sample as a sun hit untested, 946 tests it: on the cone's rim
    the same ds.d is sun to one, sky to the other.  No sensitivity allowance absorbs those
    lanes; the findings explain them, timed_sunsky's too (its sun read back from its own
    sample_direction, bit for bit sunsky's where both are known)."""
    import drjit as dr
    import mitsuba as mi
    import numpy as np

    from phonglab.validate import batch
    from phonglab.validate.emitter import setup

    sky = mi.load_dict({"type": "sunsky", "latitude": 0.0})
    _, sun, cos_half = setup.sun_cone(sky)
    read = setup._sampled_sun(sky, cos_half)
    assert np.array_equal(np.array(dr.ravel(sun)), np.array(dr.ravel(read)))
    assert setup.sun_cone(mi.load_dict({"type": "timed_sunsky"})) is not None
    d = batch.run_case("timed_sunsky", {"kind": "emitter", "seed": 0, "quick": False,
                                        "topics": ["weight", "pdf"]})
    rows = {r["name"]: r for r in d["results"]}
    for name, key in (("weight x ds.pdf = eval_direction(ds)", "sunsky-sun-rim-weight"),
                      ("weight x ds.pdf = eval at the traced point", "sunsky-sun-rim-weight"),
                      ("ds.pdf = pdf_direction(ds)", "sunsky-sun-rim-pdf")):
        assert rows[name]["status"] == "KNOWN", name
        assert rows[name]["details"]["known_by"] == [key]
        assert rows[name]["measured"] > 2 * rows[name]["tolerance"]   # absorbed: 0.999 of 1


def test_whitted_and_sphere_findings_are_in_the_tables(variant_llvm_rgb):
    emitters = {c.label: c for c in registry.catalogue("emitter").cases()}
    keys = {k.key for k in emitters["area (sphere, flip_normals)"].known["pdf"]}
    assert keys == {"sphere_emitter_inside"}
    integrators = {c.label: c for c in registry.catalogue("integrator").cases()}
    assert integrators["whitted/radiance"].spec == {"type": "whitted", "units": "radiance"}
    assert "plane under a point light" not in {
        n for k in integrators["whitted/radiance"].known["bias"] for n in k.rows}


def _report(label, kind, rows):
    return Report({"case": label, kind: label, "variant": "llvm_ad_rgb", "note": "n"},
                  rows).to_dict()


def test_markdown_renders_emitter_and_integrator_json():
    emitter = registry.catalogue("emitter")
    reports = [
        _report("area (sphere)", "emitter",
                [Row("finite", "x", 0.0, 0.0, None, 0.0, "pass", ""),
                 Row("pdf", "ds.pdf = pdf_direction(ds)", 0.6, 0.0, None, 1e-3, "KNOWN", "why"),
                 Row("power", "p", 1.5, 1.0, 0.1, 0.3, "fail", "why")]),
        _report("directionalarea", "emitter",
                [Row("finite", "the case loads and runs", None, None, None, None, "skipped",
                     "no model")]),
    ]
    data = {"meta": {"options": {"kind": "emitter", "quick": False, "seed": 0},
                     "seconds": 7.5}, "reports": reports}
    md = markdown.render_markdown(data)
    assert md.startswith("# Conformance of Mitsuba 3.9.1's built-in emitters")
    assert "`docs/conformance-emitters.json`" in md and "validate_emitter" in md
    row = next(line for line in md.splitlines() if line.startswith("| `area (sphere)`"))
    cells = [c.strip() for c in row.strip("|").split("|")][3:]
    assert dict(zip(emitter.kind.topics, cells)) == {
        "finite": "pass", "weight": "", "pdf": "KNOWN", "chi2": "", "power": "**fail**",
        "gradient": "", "cost": ""}
    assert "src/shapes/sphere.cpp#L256" in md and "tests/repro/sphere_emitter_inside.py" in md
    assert "**Unexplained fail** (power)" in md
    assert "1 pass, 1 fail, 1 KNOWN, 1 skipped rows, 7.5 s" in md
    for name in emitter.left_out:
        assert f"* `{name}`:" in md

    integ = registry.catalogue("integrator")
    data = {"meta": {"options": {"kind": "integrator", "quick": True, "seed": 0}},
            "reports": [_report("whitted/radiance", "integrator",
                                [Row("bias", "enclosure ρ=0.5 D=2", 2.0, 3.0, 0.01, 0.05,
                                     "KNOWN", "model")])]}
    md = markdown.render_markdown(data, integ)
    assert "built-in integrators" in md and "--quick" in md
    assert "(../plugins/whitted.py#L49)" in md        # phonglab's own source, linked relatively


def test_kind_options_reach_the_runner(variant_llvm_rgb):
    # a skipped case is one skipped row, without running a validator
    from phonglab.validate import batch

    d = batch.run_case("directionalarea", {"kind": "emitter", "seed": 0, "quick": True})
    assert [r["status"] for r in d["results"]] == ["skipped"]
    assert d["meta"]["case"] == "directionalarea" and "delta" not in d["meta"]


def test_refused_depth_is_a_skipped_scene_and_depth_is_not_radiance(variant_llvm_rgb):
    from phonglab.validate import loading, registry
    kind = registry.by_name("integrator")

    whitted = loading.prepare(kind, {"type": "whitted", "units": "radiance"}).plugin
    assert whitted.depth == "settable"
    integ, why = whitted.at_depth(64)            # whitted takes max_depth in 1..10
    assert integ is None and "refuses max_depth 64" in why
    assert whitted.at_depth(2)[0] is not None
    assert loading.prepare(kind, "depth").plugin.aov


def test_mesh_cost_baseline(variant_llvm_rgb):
    from phonglab.validate.emitter import builtins as eb
    from phonglab.validate.emitter.cost import baseline
    from phonglab.validate import loading, registry

    setup = loading.prepare(registry.by_name("emitter"), {"type": "area"},
                         params={"shape": {"type": "obj", "filename": eb.mesh_file()}}).plugin
    _, name, _ = baseline(setup)
    assert name == "area on a cube"


def _reproducers():
    from phonglab.validate.emitter.builtins import FINDINGS as E
    from phonglab.validate.integrator.builtins import FINDINGS as I
    return sorted({f.reproducer for f in E + I})


@pytest.mark.slow
@pytest.mark.parametrize("script", _reproducers())
def test_reproducer_shows_its_finding(script, tmp_path):
    """Each tests/repro script of the two tables exits 1 while its behaviour is present."""
    import subprocess
    import sys

    from phonglab import runtime
    runtime.configure()
    import mitsuba as mi
    if mi.__version__ != conformance.MITSUBA_VERSION:
        pytest.skip(f"the findings are pinned to Mitsuba {conformance.MITSUBA_VERSION}")
    done = subprocess.run([sys.executable, str(REPO_ROOT / script)], capture_output=True,
                          text=True, timeout=300, cwd=tmp_path)
    assert done.returncode == 1, done.stdout + done.stderr
