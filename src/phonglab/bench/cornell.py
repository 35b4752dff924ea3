r"""The Cornell-box set-ups the bench renders: materials swapped in, references, timed renders.

Every render comparison starts from ``phonglab/scenes_xml/cornell_phong.xml`` and swaps the
material of its two boxes (:func:`cornell_xml`) and of its walls (the scene's ``wall``
parameter).  A :class:`CornellSpec` names one such set-up; its reference image comes from
the one reference cache (:func:`phonglab.engine.references.reference`, with the scene's own
integrator, ``max_depth=None``): the spec's XML text is written once to
``<cache>/scenes/cornell-<hash of the text>.xml`` and that file, with the spec's
parameters, is what the cache keys on.

Look match of the built-ins (stated, not claimed equal BRDFs): ``diffuse`` / ``lambert``
boxes take ρ = k_d = 0.5; ``plastic`` takes diffuse_reflectance 0.5 and its default smooth
dielectric coating (IOR 1.49: a mirror highlight with Fresnel reflectance 4 % at normal
incidence instead of phong's k_s = 0.3 glossy lobe); ``roughplastic`` the same coating with
the Beckmann roughness matching the highlight width of phong's exponent
(:func:`phonglab.physics.roughness.beckmann_alpha`).
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from pathlib import Path

import drjit as dr
import mitsuba as mi

from .. import registration
from ..errors import PhonglabError
from ..engine.exr import atomic_path
from ..parallel import Runner
from ..physics.estimators import kernel_stats
from ..physics.roughness import beckmann_alpha
from ..engine.references import CACHE_DIR, Reference, reference
from ..engine.render import render_scene
from ..engine.scenes import scene_path
from .config import RATIO_RES, RENDER_RES

#: Box materials a render comparison can swap in (the walls take ``wall=``).
BOX_TYPES = ("phong", "lambert", "diffuse", "plastic", "roughplastic")
_GLOSSY_BLOCK = re.compile(r'<bsdf type="phong" id="glossy">.*?</bsdf>', re.S)


def _box_block(boxes: str, exponent: float) -> str | None:
    """The ``<bsdf id="glossy">`` element of ``boxes`` (None: keep the scene's phong)."""
    if boxes == "phong":
        return None
    if boxes in ("lambert", "diffuse"):
        return (f'<bsdf type="{boxes}" id="glossy"><rgb name="reflectance" value="0.5, 0.5, 0.5"/>'
                f'</bsdf>')
    if boxes == "plastic":
        return ('<bsdf type="plastic" id="glossy">'
                '<rgb name="diffuse_reflectance" value="0.5, 0.5, 0.5"/></bsdf>')
    return ('<bsdf type="roughplastic" id="glossy"><string name="distribution" value="beckmann"/>'
            f'<float name="alpha" value="{beckmann_alpha(exponent):.6f}"/>'
            '<rgb name="diffuse_reflectance" value="0.5, 0.5, 0.5"/></bsdf>')


def cornell_xml(boxes: str = "phong", exponent: float = 30.0, rfilter: str = "box") -> str:
    """The text of ``phonglab/scenes_xml/cornell_phong.xml`` with its two boxes made of ``boxes``.

    ``rfilter`` replaces the scene's Gaussian reconstruction filter (``"gaussian"`` keeps
    it).  The convergence measurements use ``box``: with a wider filter each pixel is a
    ratio estimator Σ w_k L_k / Σ w_k whose O(1/spp) bias and random weights make the
    RMSE fall faster than spp^−½ at low spp (measured slope −0.56 over 1–64 spp); with
    the box filter every sample lands in exactly one pixel with weight 1, so a pixel is
    a plain mean of its spp samples.  The materials are the module docstring's look match.
    """
    text = scene_path("cornell_phong").read_text()
    if boxes not in BOX_TYPES:
        raise PhonglabError(f"unknown box material {boxes!r}; use one of {', '.join(BOX_TYPES)}")
    block = _box_block(boxes, exponent)
    if rfilter != "gaussian":
        text, count = re.subn(r'<rfilter type="gaussian"\s*/>', f'<rfilter type="{rfilter}"/>', text)
        if count != 1:
            raise PhonglabError("phonglab/scenes_xml/cornell_phong.xml has no gaussian <rfilter>; "
                                "update phonglab.bench.cornell.cornell_xml")
    if block is not None:
        text, count = _GLOSSY_BLOCK.subn(block, text)
        if count != 1:
            raise PhonglabError("phonglab/scenes_xml/cornell_phong.xml has no "
                                "<bsdf type=\"phong\" id=\"glossy\"> block; update phonglab.bench")
    return text


@dataclass(frozen=True)
class CornellSpec:
    """A Cornell-box render set-up: materials, resolution, path depth."""

    walls: str = "lambert"
    boxes: str = "phong"
    res: int = RENDER_RES
    max_depth: int = 8
    exponent: float = 30.0
    rfilter: str = "box"

    @property
    def label(self) -> str:
        return (f"cornell {self.res}px walls={self.walls} boxes={self.boxes} depth={self.max_depth} "
                f"{self.rfilter} filter")

    def xml(self) -> str:
        return cornell_xml(self.boxes, self.exponent, self.rfilter)

    def params(self, xml: str | None = None) -> dict[str, str]:
        """The values of the scene's ``<default>`` entries this set-up sets."""
        params = dict(res=str(self.res), wall=self.walls, max_depth=str(self.max_depth))
        if '"$exponent"' in (xml if xml is not None else self.xml()):
            # Only phong boxes use it; Mitsuba rejects parameters the scene does not use.
            params["exponent"] = str(self.exponent)
        return params

    def load(self, variant: str | None = None):
        """The Mitsuba scene of this set-up (phonglab's plugins registered for ``variant``)."""
        registration.register(variant)
        try:
            xml = self.xml()
            return mi.load_string(xml, **self.params(xml))
        except Exception as exc:
            raise PhonglabError(f"cannot load the Cornell box ({self.label}): {exc}") from exc

    def scene_file(self, cache: str | Path | None = None) -> Path:
        """This set-up's XML text as a file under ``<cache>/scenes/``, named by its hash."""
        xml = self.xml()
        digest = hashlib.sha256(xml.encode()).hexdigest()[:16]
        path = Path(cache or CACHE_DIR) / "scenes" / f"cornell-{digest}.xml"
        if not path.is_file():
            path.parent.mkdir(parents=True, exist_ok=True)
            with atomic_path(path, ".xml") as tmp:
                Path(tmp).write_text(xml)
        return path

    def reference(self, spp: int, variant: str = "llvm_ad_rgb",
                  cache: str | Path | None = None, runner: Runner | None = None) -> Reference:
        """The cached reference of this set-up with at least ``spp`` samples (rendered if missing,
        its passes on ``runner``), with the scene's own integrator."""
        return reference(self.scene_file(cache), spp, self.params(), variant, max_depth=None,
                         cache_dir=cache, runner=runner)


def render_setups(res: int = RENDER_RES) -> dict[str, dict[str, tuple[CornellSpec, CornellSpec]]]:
    """Render comparisons: scene name → {method: (CornellSpec, the spec of its reference)}.

    ``lambert`` and ``diffuse`` share the ``diffuse`` reference, so a bias in either would
    show as an error floor.
    """
    diffuse_ref = CornellSpec(walls="diffuse", boxes="diffuse", res=res)
    return {
        "cornell-diffuse": {m: (CornellSpec(walls=m, boxes=m, res=res), diffuse_ref)
                            for m in ("lambert", "diffuse")},
        "cornell-glossy": {m: (CornellSpec(walls="diffuse", boxes=m, res=res),
                               CornellSpec(walls="diffuse", boxes=m, res=res))
                           for m in ("phong", "plastic", "roughplastic")},
    }


def ratio_spec(method: str, which: str) -> CornellSpec:
    """The render-time-ratio set-up: ``method`` on all surfaces, or on the boxes only."""
    if which == "all surfaces":
        return CornellSpec(walls=method, boxes=method, res=RATIO_RES)
    return CornellSpec(walls="diffuse", boxes=method, res=RATIO_RES)


def timed_render(scene, spp: int, seed: int) -> float:
    """Wall seconds of one render pass (image evaluated and copied to numpy)."""
    return render_scene(scene, spp, seed=seed).pass_seconds[0]


def render_jit(scene, spp: int, seed: int) -> tuple[float, float, int, int]:
    """(seconds, compile ms, kernels, cache hits) of one render (Dr.Jit kernel history on)."""
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()
    seconds = timed_render(scene, spp, seed)
    ms, kernels, hits = kernel_stats()
    return seconds, ms, kernels, hits
