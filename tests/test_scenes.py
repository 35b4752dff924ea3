"""Every scene phonglab ships (src/phonglab/scenes_xml/) loads, renders finite and non-black, and documents itself.

A scene's header comment must say what it shows and what to expect (STYLE §6), and each one
must declare the sample count as a `<default name="spp">` so that tests and charts can vary it.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from phonglab.engine.render import render_scene
from phonglab.engine.scenes import SCENES_DIR, load_scene

SCENES = sorted(SCENES_DIR.glob("*.xml"))


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_scene_header_and_spp_default(path):
    text = path.read_text()
    header = re.match(r"\s*<!--(.*?)-->", text, re.S)
    assert header, f"{path.name} has no header comment"
    assert len(header.group(1).split()) >= 20, f"{path.name}: the header should derive what to expect"
    assert re.search(r'<default\s+name="spp"', text), f'{path.name} lacks <default name="spp" .../>'


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_scene_loads_and_renders(path, variant_llvm_rgb):
    scene = load_scene(path, variant_llvm_rgb, spp=1)
    size = scene.sensors()[0].film().size()
    # A one-pixel meter (irradiancemeter) needs many rays to find a small source.
    spp = 1 if size[0] * size[1] > 4 else 4096
    image = render_scene(scene, spp=spp).image
    assert np.all(np.isfinite(image)), f"{path.name} rendered NaN/Inf"
    assert image.max() > 0, f"{path.name} rendered black"
