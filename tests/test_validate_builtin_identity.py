"""A built-in's documented findings follow it wherever it appears: matched by what is
loaded (its C++ class and what it was loaded from), not by how it was named, so a type name, a
dict, an XML file and a scene's material get the same verdict; a wrapper's row that fails
because of a built-in child's finding reads KNOWN, inherited from that child, only when the
child judged alone shows it as much.

So ``phonglab validate material.xml`` (a Beckmann roughconductor at alpha 0.3) reads its
``normalization`` (0.9973 against 1) and ``gradient`` (eta.value) rows KNOWN by the findings
that make ``phonglab validate roughconductor --set alpha=0.3`` pass; a Python wrapper that
only tints such a child has the same two rows KNOWN, inherited, not blamed on the wrapper;
and a scene's material is validated as itself.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from phonglab.cli import main
from phonglab.validate import validate_bsdf

HERE = Path(__file__).parent
WRAPPER = HERE / "authors" / "tinted_wrapper.py"
#: The topics where a Beckmann roughconductor at its default material has findings.
TOPICS = ["--only", "normalization", "--only", "gradient"]

METAL_XML = ('<bsdf type="roughconductor" version="3.0.0">'
             '<float name="alpha" value="0.3"/></bsdf>')
SCENE = """<scene version="3.0.0">
    <default name="a" value="0.3"/>
    <bsdf type="roughconductor" id="metal"><float name="alpha" value="$a"/></bsdf>
    <shape type="rectangle"><ref id="metal"/></shape>
    <shape type="sphere">
        <bsdf type="twosided" id="shell">
            <bsdf type="plastic" id="white_plastic">
                <float name="int_ior" value="2.5"/>
                <float name="diffuse_reflectance" value="1"/>
                <float name="specular_reflectance" value="1"/>
            </bsdf>
        </bsdf>
    </shape>
</scene>
"""


def _rows(tmp_path, *args) -> tuple[int, list[dict]]:
    """(exit status, JSON rows) of ``phonglab validate ARGS --quick`` in llvm_ad_rgb (named:
    a run in this process keeps the variant an earlier test set)."""
    out = tmp_path / "r.json"
    out.unlink(missing_ok=True)
    rc = main(["validate", *map(str, args), "--quick", "--variant", "llvm_ad_rgb", "--json",
               str(out)])
    return rc, json.loads(out.read_text())["results"] if out.exists() else []


def _verdict(rows) -> list[tuple]:
    """What a verdict is made of: each row's topic, name, status and the findings by name."""
    return [(r["topic"], r["name"], r["status"], tuple(r["details"].get("known_by", ())))
            for r in rows]


def test_an_xml_builtin_gets_the_same_verdict_as_by_its_type_name(tmp_path):
    xml = tmp_path / "metal.xml"
    xml.write_text(METAL_XML)
    rc_name, by_name = _rows(tmp_path, "roughconductor", "--set", "alpha=0.3", "--no-sweep",
                             *TOPICS)
    rc_xml, by_xml = _rows(tmp_path, xml, *TOPICS)
    assert rc_name == rc_xml == 0
    assert _verdict(by_xml) == _verdict(by_name)
    known = {k for r in by_xml for k in r["details"].get("known_by", ())}
    assert known == {"beckmann-pdf-normalization", "conductor-eta0-gradient"}
    rc, raw = _rows(tmp_path, xml, *TOPICS, "--no-known")
    assert rc == 1 and {r["status"] for r in raw} >= {"fail"}


def test_a_dict_builtin_gets_the_same_verdict_as_by_its_type_name(variant_llvm_rgb):
    common = dict(quick=True, topics=["normalization", "gradient"], known="builtin")
    by_dict = validate_bsdf({"type": "roughconductor", "alpha": 0.3}, **common)
    by_name = validate_bsdf("roughconductor", params={"alpha": 0.3}, **common)
    verdict = [(r.topic, r.name, r.status, tuple(r.details.get("known_by", ())))
               for r in by_dict.rows]
    assert verdict == [(r.topic, r.name, r.status, tuple(r.details.get("known_by", ())))
                       for r in by_name.rows]
    assert by_dict.passed and by_dict.meta["builtin"]["type"] == "roughconductor"
    assert sum(r.status == "KNOWN" for r in by_dict.rows) == 2


def test_a_finding_holds_where_the_loaded_parameters_say(variant_llvm_rgb, tmp_path):
    """``given=`` settings are read from what loaded (a GGX lobe in the file gets no Beckmann
    finding), ``at=`` conditions from the parameters the XML gives (plastic's F_dr fit at
    int_ior in [2, 3])."""
    import mitsuba as mi

    from phonglab.validate import builtin, registry
    kind = registry.by_name("bsdf")

    def keys(xml_text, topic):
        xml = tmp_path / "b.xml"
        xml.write_text(xml_text)
        ident = builtin.identify(kind, mi.load_file(str(xml)), {"file": str(xml)})
        return ident, {k.key for k in builtin.findings(kind, ident).get(topic, ())}
    ident, norm = keys(METAL_XML, "normalization")
    assert ident.type == "roughconductor" and ident.params["alpha"] == 0.3
    assert ident.params["distribution"] == "beckmann" and "beckmann-pdf-normalization" in norm
    _, norm = keys(METAL_XML.replace("/></bsdf>", '/><string name="distribution" '
                                                  'value="ggx"/></bsdf>'), "normalization")
    assert "beckmann-pdf-normalization" not in norm
    ident, _ = keys('<bsdf type="plastic" version="3.0.0"><float name="int_ior" value="2.5"/>'
                    '</bsdf>', "energy")
    assert ident.numbers()["int_ior"] == 2.5
    assert builtin.identify(kind, mi.load_dict({"type": "lambert"})) is None   # a Python plugin


def test_the_class_map_names_every_builtin_of_the_table(variant_llvm_rgb):
    """Every case of the conformance table that loads in the default variant is identified as
    its own plugin type from the loaded object alone."""
    import mitsuba as mi

    from phonglab.validate.bsdf.builtins import cases
    from phonglab.validate.bsdf.identify import builtin_type
    seen = set()
    for case in cases():
        if case.variant is not None or case.plugin in seen:
            continue
        seen.add(case.plugin)
        obj = mi.load_dict(case.spec)
        expected = None if case.plugin in ("lambert", "phong") else case.plugin
        assert builtin_type(obj) == expected, case.label
    assert len(seen) >= 15


def test_a_wrapper_names_its_childs_finding_on_every_row_it_inherits(tmp_path, capsys):
    args = ["tinted_wrapper", "--plugin", WRAPPER, "--no-sweep"]
    rc_raw, raw = _rows(tmp_path, *args, "--no-known")
    failing = {(r["topic"], r["name"]) for r in raw if r["status"] == "fail"}
    assert rc_raw == 1 and failing == {("normalization", "∫ pdf dω_o = P(sample counted)"),
                                       ("gradient", "nested.eta.value")}
    capsys.readouterr()
    rc, rows = _rows(tmp_path, *args)
    out = capsys.readouterr().out
    assert rc == 0
    inherited = {(r["topic"], r["name"]): r for r in rows if "inherited" in r["details"]}
    assert set(inherited) == failing                  # every row it inherits, and no other
    for r in inherited.values():
        assert r["status"] == "KNOWN"
        assert r["reason"].startswith("inherited from the child roughconductor (nested): "
                                      "finding ")
        assert r["details"]["inherited"]["child"] == "roughconductor"
    assert {k for r in inherited.values() for k in r["details"]["inherited"]["findings"]} == {
        "beckmann-pdf-normalization", "conductor-eta0-gradient"}
    assert "PASSED (2 rows inherited from the child roughconductor (nested), KNOWN)" in out


def test_a_wrappers_own_error_is_never_inherited(tmp_path, capsys):
    """The same wrapper reporting half its child's pdf fails normalization at 0.5, not the
    child's 0.9973: the row stays a fail and says the child alone is closer."""
    rc, rows = _rows(tmp_path, "tinted_wrapper", "--plugin", WRAPPER, "--no-sweep",
                     "--set", "pdf_scale=0.5", "--only", "normalization")
    (row,) = rows
    assert rc == 1 and row["status"] == "fail"
    assert row["details"]["not_inherited"][0]["child"] == "roughconductor"
    assert "farther than the child" in row["reason"] and "this plugin's own" in row["reason"]
    assert "FAILED (1 rows)" in capsys.readouterr().out


def test_a_builtin_inside_a_scene_by_its_id(tmp_path, capsys):
    scene = tmp_path / "scene.xml"
    scene.write_text(SCENE)
    rc_name, by_name = _rows(tmp_path, "roughconductor", "--set", "alpha=0.3", "--no-sweep",
                             *TOPICS)
    rc, rows = _rows(tmp_path, scene, "--bsdf", "metal", *TOPICS)
    assert rc == rc_name == 0 and _verdict(rows) == _verdict(by_name)
    assert "metal (roughconductor) in scene.xml: PASSED" in capsys.readouterr().out
    # at= from the scene's element (int_ior 2.5): the white plastic's energy gain is KNOWN,
    # and inherited by the two-sided shell around it
    rc, rows = _rows(tmp_path, scene, "--bsdf", "white_plastic", "--only", "energy")
    assert rc == 0 and rows[0]["details"]["known_by"] == ["plastic-fdr-fit-energy"]
    rc, rows = _rows(tmp_path, scene, "--bsdf", "shell", "--only", "energy")
    assert rc == 0 and rows[0]["details"]["inherited"]["child"] == "plastic"


@pytest.mark.parametrize("args, message", [
    (["--bsdf", "nope"], "no BSDF with id 'nope' on its shapes; its BSDFs with an id: metal, "
                         "shell, white_plastic"),
    ([], "is a scene; name the material to validate with --bsdf ID"),
    (["--bsdf", "metal", "--set", "alpha=0.1"], "--set cannot change a scene's material"),
])
def test_a_scene_material_given_wrongly_is_one_sentence(tmp_path, capsys, args, message):
    scene = tmp_path / "scene.xml"
    scene.write_text(SCENE)
    assert main(["validate", str(scene), "--quick", *args]) == 2
    assert message in capsys.readouterr().err
