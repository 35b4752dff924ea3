"""The kind registry (phonglab.validate.registry): one KINDS sequence that every face iterates,
detection from what a plugin is (never by trying each kind), a --plugin file run once, and a
file that would shadow a name Mitsuba or phonglab already has refused before any work."""

from __future__ import annotations

from pathlib import Path

import pytest

from phonglab.cli import main
from phonglab.registration import PLUGINS
from phonglab.validate import registry
from phonglab.validate.inputs import ValidateError

HERE = Path(__file__).parent
DEFECTS = HERE / "defects"

SHADOWS_DIFFUSE = '''import mitsuba as mi


class Mine(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)


mi.register_bsdf("diffuse", lambda props: Mine(props))
'''

COUNTS_ITS_RUNS = '''import mitsuba as mi
from pathlib import Path

counter = Path(__file__).with_suffix(".runs")
counter.write_text(str(int(counter.read_text()) + 1 if counter.exists() else 1))
'''


def test_every_face_iterates_the_one_kinds_sequence():
    """The CLI's topics, the package face, the pytest helpers and the conformance tables are
    made from KINDS: a kind is listed once."""
    import phonglab.testing as testing
    import phonglab.validate as face

    names = [k.name for k in registry.KINDS]
    assert len(set(names)) == len(names) and names[:3] == ["bsdf", "emitter", "integrator"]
    for k in registry.KINDS:
        assert callable(getattr(face, k.function)) and k.function in face.__all__
        assert callable(getattr(testing, k.assert_helper)) and k.assert_helper in testing.__all__
        assert k.module().__name__ == f"phonglab.validate.{k.name}.kind" and k.tag and k.object_type
    assert registry.names() == tuple(names)
    for k in registry.KINDS:
        assert registry.catalogue(k.name).kind is k
    assert set(registry.every_topic()) == {t for k in registry.KINDS for t in k.topics}
    for _, _, name in PLUGINS:      # registration.py registers them with mi.register_<kind>
        assert registry.by_name(name).register == f"mi.register_{name}"


def test_importing_the_registry_imports_no_mitsuba():
    import subprocess
    import sys
    code = ("import sys, phonglab.validate.registry, phonglab.testing; "
            "sys.exit(1 if 'mitsuba' in sys.modules else 0)")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


@pytest.mark.parametrize("spec, kind", [
    ("diffuse", "bsdf"), ("lambert", "bsdf"), ("point", "emitter"), ("path", "integrator"),
    ("whitted", "integrator"), ({"type": "roughplastic", "alpha": 0.2}, "bsdf"),
])
def test_detect_names_the_kind_from_what_the_plugin_is(variant_llvm_rgb, spec, kind):
    assert registry.detect(spec).name == kind


def test_detect_reads_an_xml_files_root_element(variant_llvm_rgb, tmp_path):
    bsdf = tmp_path / "b.xml"
    bsdf.write_text('<?xml version="1.0"?>\n<!-- a comment -->\n<bsdf version="3.0.0" '
                    'type="diffuse"/>\n')
    assert registry.detect(str(bsdf)).name == "bsdf"
    scene = tmp_path / "s.xml"
    scene.write_text('<scene version="3.0.0"><bsdf type="diffuse"/></scene>')
    with pytest.raises(ValidateError, match=r"holds a <scene>; validate takes an XML file "
                                            r"holding one <bsdf> or <emitter>"):
        registry.detect(str(scene))


def test_detect_refuses_another_kind_of_plugin_in_one_sentence(variant_llvm_rgb):
    with pytest.raises(ValidateError, match="'sphere' is a Mitsuba Shape plugin; validate takes "
                                            "a BSDF, an emitter"):
        registry.detect("sphere")
    with pytest.raises(ValidateError, match="unknown plugin type 'nosuch'"):
        registry.detect("nosuch")


@pytest.mark.parametrize("name", ["diffuse", "lambert"])
def test_a_plugin_file_shadowing_a_name_is_refused_before_work(variant_llvm_rgb, tmp_path, capsys,
                                                               name):
    """mine.py registering 'diffuse' (Mitsuba's built-in) or 'lambert' (phonglab's plugin) is
    exit 2 naming the collision, not a validation of the plugin it shadows."""
    plugin = tmp_path / "mine.py"
    plugin.write_text(SHADOWS_DIFFUSE.replace('"diffuse"', f'"{name}"'))
    assert main(["validate", name, "--quick", "--plugin", str(plugin)]) == 2
    err = capsys.readouterr().err
    owner = "Mitsuba" if name == "diffuse" else "phonglab"
    assert (f"registers '{name}', a name {owner} already has" in err and "my_" + name in err
            and "Traceback" not in err and len(err.strip().splitlines()) == 1), err


def test_a_plugin_file_runs_once_per_validation(variant_llvm_rgb, tmp_path):
    """The CLI runs a --plugin file once, not once per kind it tries."""
    plugin = tmp_path / "light.py"
    plugin.write_text(COUNTS_ITS_RUNS + (HERE / "defects_emitter" / "point_control.py").read_text())
    assert main(["validate", "defect_point_control", "--quick", "--only", "finite",
                 "--plugin", str(plugin)]) == 0
    assert plugin.with_suffix(".runs").read_text() == "1"


def test_a_file_registering_several_plugins_says_which_it_validates(variant_llvm_rgb, tmp_path,
                                                                   capsys):
    plugin = tmp_path / "two.py"
    plugin.write_text((DEFECTS / "energy_gain.py").read_text() + "\n"
                      + (DEFECTS / "nonreciprocal.py").read_text())
    main(["validate", "defect_energy_gain", "--quick", "--no-sweep", "--only", "finite",
          "--plugin", str(plugin)])
    out = capsys.readouterr().out
    assert "validated the BSDF 'defect_energy_gain'; the plugin files also registered" in out
