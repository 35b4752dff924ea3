"""phonglab.settings: the one NAME=VALUE grammar and the one plugin loader."""

from __future__ import annotations

import pytest

from phonglab.settings import ParameterError, PluginError, load_plugin, parse_sets, parse_value, split


@pytest.mark.parametrize("text, value", [
    ("0.25", 0.25), ("1", 1), ("-2", -2), ("1e-3", 1e-3), ("True", True), (" false ", False),
    ("ggx", "ggx"), ("0.2, 0.3,0.4", {"type": "rgb", "value": [0.2, 0.3, 0.4]}),
    ("a,b", "a,b"), ("1,", "1,"), ("file.exr", "file.exr"),
])
def test_value_grammar(text, value):
    got = parse_value(text)
    assert got == value and type(got) is type(value)


@pytest.mark.parametrize("text, message", [
    ("1,2", "has 2 numbers; give one number or three"),
    ("1,2,3,4", "has 4 numbers"),
    ("nan", "is not finite"),
    ("0.1,inf,0.2", "non-finite component"),
])
def test_value_refusals_are_one_sentence(text, message):
    with pytest.raises(ParameterError, match=message):
        parse_value(text)


def test_malformed_setting_names_both_the_form_and_the_fix():
    for bad in ("alpha", "=1", "alpha=", "a-b=1"):
        with pytest.raises(ParameterError) as info:
            parse_sets([bad])
        text = str(info.value)
        assert "--set expects NAME=VALUE" in text and "is not NAME=VALUE" in text
        assert "--set alpha=0.2" in text


def test_later_setting_wins_and_nested_keys():
    assert parse_sets(["alpha=0.1", "alpha=0.2", "bsdf.type=diffuse"]) == {
        "alpha": 0.2, "bsdf": {"type": "diffuse"}}


def test_integer_ior_is_read_as_a_float_that_mitsuba_loads(variant_llvm_rgb):
    import mitsuba as mi
    # include/mitsuba/render/ior.h:79-94: an integer int_ior is read as a material name
    sets = parse_sets(["int_ior=3", "bsdf.ext_ior=1", "max_depth=3"])
    assert sets == {"int_ior": 3.0, "bsdf": {"ext_ior": 1.0}, "max_depth": 3}
    assert isinstance(sets["int_ior"], float) and isinstance(sets["max_depth"], int)
    loaded = load_plugin("dielectric", {"int_ior": sets["int_ior"]}, kind=mi.BSDF, word="BSDF")
    assert "eta = 2.999" in str(loaded.plugin)   # 3 / air's 1.000277


def test_split_keeps_text():
    assert split("res=256") == ("res", "256")
    assert split("title=a=b") == ("title", "a=b")
    assert split("res=") == ("res", "")
    assert split("res") is None and split("=3") is None


def test_scene_param_uses_the_same_split():
    import argparse

    from phonglab.cli.options import scene_param
    assert scene_param("res=16") == ("res", "16")
    with pytest.raises(argparse.ArgumentTypeError, match="expected NAME=VALUE"):
        scene_param("res")


def test_load_plugin_forms(variant_llvm_rgb, tmp_path):
    import mitsuba as mi
    hint = "check it"
    loaded = load_plugin("roughconductor", {"alpha": 1}, kind=mi.BSDF, word="BSDF", hint=hint)
    assert loaded.label == "roughconductor" and loaded.spec == {"type": "roughconductor",
                                                                "alpha": 1}
    assert float(mi.traverse(loaded.plugin)["alpha.value"][0]) == 1.0   # an int is a float
    xml = tmp_path / "b.xml"
    xml.write_text('<bsdf version="3.0.0" type="diffuse"/>')
    assert load_plugin(str(xml), kind=mi.BSDF, word="BSDF").spec == {"file": str(xml)}
    again = load_plugin(loaded.plugin, kind=mi.BSDF, word="BSDF")
    assert again.plugin is loaded.plugin and again.spec is None
    with pytest.raises(PluginError, match=r"cannot load BSDF 'nosuch' \(.*not found\); check it"):
        load_plugin("nosuch", kind=mi.BSDF, word="BSDF", hint=hint)
    with pytest.raises(PluginError, match="is a .*, not a BSDF plugin"):
        load_plugin("independent", kind=mi.BSDF, word="BSDF")
    with pytest.raises(PluginError, match="cannot be set on an already loaded BSDF"):
        load_plugin(loaded.plugin, {"alpha": 0.1}, kind=mi.BSDF, word="BSDF")
    with pytest.raises(PluginError, match="does not exist"):
        load_plugin(str(tmp_path / "none.xml"), kind=mi.BSDF, word="BSDF")


def test_a_constant_textures_value_key_sets_the_parameter_itself():
    """``reflectance.value=0.5,0.5,0.5`` (mi.traverse's key of a constant texture) sets the
    texture itself, not {"reflectance": {"value": {"type": "rgb", ...}}}, which Mitsuba
    refuses ("missing 'type' attribute")."""
    from phonglab.settings import parse_sets
    assert parse_sets(["diffuse_reflectance.value=0.5,0.5,0.5", "roughness.value=0.2"]) == {
        "diffuse_reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}, "roughness": 0.2}
    assert parse_sets(["r.type=bitmap", "r.value=0.3"]) == {"r": {"type": "bitmap", "value": 0.3}}


def test_a_bitmap_without_a_file_is_one_sentence_not_a_crash(variant_llvm_rgb):
    """Mitsuba 3.9.1 segfaults loading {"type": "bitmap"} (exit 139, no message)."""
    import mitsuba as mi
    with pytest.raises(PluginError, match="the bitmap texture diffuse_reflectance has no filename"):
        load_plugin("roughplastic", {"diffuse_reflectance": {"type": "bitmap"}}, kind=mi.BSDF,
                    word="BSDF")
