r"""The catalogue of Mitsuba 3.9.1's built-in BSDFs (and phonglab's own) that ``phonglab validate
--all-builtins`` checks.

:func:`cases` lists every BSDF plugin of Mitsuba 3.9.1 (``src/bsdfs/*.cpp`` at tag v3.9.1,
commit 478e193a183c) that can be built standalone, each at two or more parameter settings, plus
phonglab's ``lambert`` and ``phong``.  A :class:`Case` holds a ``mi.load_dict`` spec, the variant
it needs (polarized plugins need a ``*_polarized`` variant) and the rows that are KNOWN to fail
with their documented cause (from :mod:`.findings`: the Mitsuba source line and one sentence);
:func:`catalogue` is the BSDF kind's conformance table.
A KNOWN row is still reported; it only does not make the run fail.  :data:`LEFT_OUT` names the
3.9.1 plugins that are not in the catalogue and why.

Specs are plain dicts except for textures: a bitmap texture takes a ``mi.Bitmap`` (which exists
in every variant) built from a numpy array, so the same spec loads in any variant.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ... import runtime
from ..conformance import Catalogue, ValidatorIssue, known_causes, known_of
from . import findings

POLARIZED = "llvm_ad_spectral_polarized"
SPECTRAL = "llvm_ad_spectral"


@dataclass(frozen=True)
class Case:
    """One BSDF at one parameter setting."""

    label: str                       #: unique, e.g. ``roughplastic/beckmann-a0.25``
    spec: dict[str, Any]             #: the ``mi.load_dict`` dictionary
    variant: str | None = None       #: None: phonglab's default (``llvm_ad_rgb``)
    #: topic -> the documented causes (``Known``, each "src/.../file.cpp:LINE: why" with its
    #: signature) of rows known to fail in Mitsuba 3.9.1
    known: dict[str, tuple] = field(default_factory=dict)
    #: every lobe is a Dirac delta (no density to histogram): directions and energy only
    delta: bool = False
    note: str = ""                   #: what the setting exercises, for the table

    @property
    def plugin(self) -> str:
        """The plugin type at the top of the spec."""
        return self.spec["type"]

    def resolved_variant(self) -> str:
        """The variant the case runs in."""
        return self.variant or runtime.default_variant()

    def meta(self) -> dict:
        """What the case adds to its report's meta (its note, whether every lobe is a delta)."""
        return {"note": self.note, "delta": self.delta}


def load(case: Case):
    """``mi.load_dict(case.spec)`` in the case's variant (set, phonglab plugins registered)."""
    from ... import registration
    registration.register(case.resolved_variant())
    import mitsuba as mi
    return mi.load_dict(case.spec)


# ----------------------------------------------------------------------------- textures
def bump_texture(res: int = 32) -> dict:
    """A smooth height field h(u, v) = 0.5 + 0.5 sin(2πu) cos(2πv) as a raw bitmap texture."""
    import mitsuba as mi
    t = (np.arange(res) + 0.5) / res
    h = 0.5 + 0.5 * np.sin(2 * np.pi * t)[None, :] * np.cos(2 * np.pi * t)[:, None]
    return {"type": "bitmap", "bitmap": mi.Bitmap(h.astype(np.float32)[..., None]), "raw": True}


def normal_texture(normal=(0.3, 0.2, 1.0)) -> dict:
    """A constant tangent-space normal (normalised), encoded (n + 1) / 2 in a raw bitmap."""
    import mitsuba as mi
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    img = np.tile(((n + 1.0) / 2.0).astype(np.float32), (4, 4, 1))
    return {"type": "bitmap", "bitmap": mi.Bitmap(img), "raw": True}


def _rgb(*v) -> dict:
    return {"type": "rgb", "value": list(v)}


def _smooth_and_diffuse() -> list[Case]:
    return [
        Case("diffuse/0.5", {"type": "diffuse", "reflectance": 0.5}, note="grey"),
        Case("diffuse/rgb", {"type": "diffuse", "reflectance": _rgb(0.2, 0.5, 0.9)},
             note="coloured"),
        Case("diffuse/white", {"type": "diffuse", "reflectance": 1.0},
             note="albedo exactly 1"),
        Case("diffuse/black", {"type": "diffuse", "reflectance": 0.0},
             note="black: albedo 0"),
        Case("plastic/default", {"type": "plastic"}, note="delta coat + diffuse base"),
        Case("plastic/nonlinear-ior1.9", {"type": "plastic", "int_ior": 1.9, "nonlinear": True,
                                          "diffuse_reflectance": _rgb(0.8, 0.3, 0.1)},
             note="nonlinear, high IOR"),
        Case("conductor/mirror", {"type": "conductor"}, delta=True, note="perfect mirror"),
        Case("conductor/Au", {"type": "conductor", "material": "Au"}, delta=True,
             note="gold (complex IOR)"),
        Case("dielectric/1.5", {"type": "dielectric"}, delta=True, note="glass"),
        Case("dielectric/inverted", {"type": "dielectric", "int_ior": 1.0, "ext_ior": 1.5},
             delta=True, note="eta < 1"),
        Case("thindielectric/1.5", {"type": "thindielectric"}, delta=True, note="thin glass"),
        Case("thindielectric/1.9", {"type": "thindielectric", "int_ior": 1.9}, delta=True,
             note="high IOR"),
    ]


def _rough() -> list[Case]:
    plastic = {"specular_reflectance": 0.7, "diffuse_reflectance": 0.1}
    return [
        Case("roughplastic/beckmann-a0.1", {"type": "roughplastic"}, note="defaults"),
        Case("roughplastic/beckmann-a0.25", {"type": "roughplastic", "alpha": 0.25, **plastic},
             note="Mitsuba's own chi2 test setting"),
        Case("roughplastic/ggx-a0.25", {"type": "roughplastic", "distribution": "ggx",
                                        "alpha": 0.25, **plastic}, note="GGX"),
        Case("roughplastic/ggx-a0.5-nonlinear",
             {"type": "roughplastic", "distribution": "ggx", "alpha": 0.5, "nonlinear": True,
              "diffuse_reflectance": _rgb(0.7, 0.4, 0.2)}, note="rough, nonlinear"),
        Case("roughplastic/black", {"type": "roughplastic", "diffuse_reflectance": 0.0,
                                    "specular_reflectance": 0.0},
             note="black: both reflectances 0"),
        Case("roughconductor/beckmann-a0.2", {"type": "roughconductor",
                                              "distribution": "beckmann", "alpha": 0.2},
             note="Beckmann, perfect conductor"),
        Case("roughconductor/ggx-a0.3-Cu", {"type": "roughconductor", "distribution": "ggx",
                                            "alpha": 0.3, "material": "Cu"}, note="GGX, copper"),
        Case("roughconductor/ggx-aniso", {"type": "roughconductor", "distribution": "ggx",
                                          "alpha_u": 0.05, "alpha_v": 0.4, "material": "Al"},
             note="anisotropic"),
        Case("roughconductor/ggx-a0.01-Au", {"type": "roughconductor", "distribution": "ggx",
                                             "alpha": 0.01, "material": "Au"},
             note="narrow lobe"),
        Case("roughconductor/beckmann-novisible",
             {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.4,
              "sample_visible": False}, note="full-distribution sampling"),
        Case("roughdielectric/beckmann-a0.1", {"type": "roughdielectric"}, note="defaults"),
        Case("roughdielectric/ggx-a0.3", {"type": "roughdielectric", "distribution": "ggx",
                                          "alpha": 0.3}, note="GGX"),
        Case("roughdielectric/ggx-aniso-inverted",
             {"type": "roughdielectric", "distribution": "ggx", "alpha_u": 0.1, "alpha_v": 0.3,
              "int_ior": 1.0, "ext_ior": 1.33}, note="anisotropic, eta < 1"),
    ]


def _principled() -> list[Case]:
    return [
        Case("principled/default", {"type": "principled"}, note="defaults"),
        Case("principled/all-lobes",
             {"type": "principled", "base_color": _rgb(0.8, 0.5, 0.3), "metallic": 0.3,
              "roughness": 0.4, "anisotropic": 0.5, "spec_trans": 0.4, "sheen": 0.5,
              "clearcoat": 0.6, "clearcoat_gloss": 0.5, "specular": 0.6}, note="every lobe on"),
        Case("principled/metal", {"type": "principled", "metallic": 1.0, "roughness": 0.2},
             note="metallic"),
        Case("principledthin/default", {"type": "principledthin"}, note="defaults"),
        Case("principledthin/all-lobes",
             {"type": "principledthin", "base_color": _rgb(0.6, 0.7, 0.3), "roughness": 0.4,
              "anisotropic": 0.3, "spec_trans": 0.3, "diff_trans": 0.4, "sheen": 0.4,
              "flatness": 0.5, "eta": 1.4}, note="every lobe on"),
    ]


def _wrappers() -> list[Case]:
    rough_metal = {"type": "roughconductor", "distribution": "ggx", "alpha": 0.2}
    return [
        Case("blendbsdf/diffuse+roughconductor",
             {"type": "blendbsdf", "weight": 0.3,
              "bsdf_0": {"type": "diffuse"}, "bsdf_1": rough_metal},
             note="two different lobes (PR#1681 class)"),
        Case("blendbsdf/roughconductor+roughdielectric",
             {"type": "blendbsdf", "weight": 0.6,
              "bsdf_0": {"type": "roughconductor", "alpha": 0.3},
              "bsdf_1": {"type": "roughdielectric", "alpha": 0.2}},
             note="reflection + transmission"),
        Case("twosided/diffuse", {"type": "twosided", "bsdf": {"type": "diffuse"}},
             note="one BSDF both sides"),
        Case("twosided/diffuse|roughconductor",
             {"type": "twosided", "bsdf_0": {"type": "diffuse"}, "bsdf_1": rough_metal},
             note="different front and back"),
        Case("bumpmap/diffuse", {"type": "bumpmap", "arbitrary": bump_texture(), "scale": 0.5,
                                 "bsdf": {"type": "diffuse"}}, note="sinusoidal height"),
        Case("bumpmap/roughconductor", {"type": "bumpmap", "arbitrary": bump_texture(),
                                        "scale": 0.2, "bsdf": rough_metal},
             note="sinusoidal height"),
        Case("normalmap/diffuse", {"type": "normalmap", "normalmap": normal_texture(),
                                   "bsdf": {"type": "diffuse"}}, note="tilted normal"),
        Case("normalmap/roughconductor", {"type": "normalmap",
                                          "normalmap": normal_texture((-0.4, 0.1, 1.0)),
                                          "bsdf": rough_metal}, note="tilted normal"),
        Case("mask/diffuse-0.5", {"type": "mask", "opacity": 0.5, "bsdf": {"type": "diffuse"}},
             note="half transparent"),
        Case("mask/roughconductor-0.8", {"type": "mask", "opacity": 0.8, "bsdf": rough_metal},
             note="mostly opaque"),
    ]


def _hair_spectral_polarized() -> list[Case]:
    return [
        Case("hair/default", {"type": "hair"}, note="defaults (eumelanin 1.3)"),
        Case("hair/blond-rough", {"type": "hair", "eumelanin": 0.3, "pheomelanin": 0.2,
                                  "longitudinal_roughness": 0.5, "azimuthal_roughness": 0.6,
                                  "scale_tilt": 3.0}, note="light, rough"),
        Case("conductor/Au-spectral", {"type": "conductor", "material": "Au"}, SPECTRAL,
             delta=True, note="spectral IOR"),
        Case("roughconductor/ggx-Cu-spectral", {"type": "roughconductor", "distribution": "ggx",
                                                "alpha": 0.3, "material": "Cu"}, SPECTRAL,
             note="spectral IOR"),
        Case("polarizer/0deg", {"type": "polarizer"}, POLARIZED, delta=True,
             note="linear polarizer"),
        Case("polarizer/45deg-0.5", {"type": "polarizer", "theta": 45.0,
                                     "transmittance": 0.5}, POLARIZED, delta=True,
             note="rotated, grey"),
        Case("retarder/quarter", {"type": "retarder", "theta": 30.0, "delta": 90.0}, POLARIZED,
             delta=True, note="quarter-wave plate"),
        Case("retarder/half", {"type": "retarder", "delta": 180.0}, POLARIZED, delta=True,
             note="half-wave plate"),
        Case("circular/right", {"type": "circular"}, POLARIZED, delta=True,
             note="right circular polarizer"),
        Case("circular/left", {"type": "circular", "left_handed": True}, POLARIZED, delta=True,
             note="left circular polarizer"),
        Case("pplastic/default", {"type": "pplastic"}, POLARIZED, note="defaults"),
        Case("pplastic/rough-ggx", {"type": "pplastic", "alpha": 0.3, "distribution": "ggx",
                                    "diffuse_reflectance": _rgb(0.3, 0.5, 0.2)}, POLARIZED,
             note="rough GGX"),
        Case("roughconductor/polarized", {"type": "roughconductor", "alpha": 0.3}, POLARIZED,
             note="Fresnel as Mueller matrix"),
        Case("conductor/polarized", {"type": "conductor", "material": "Au"}, POLARIZED,
             delta=True, note="gold mirror, Fresnel as Mueller matrix"),
        Case("dielectric/polarized", {"type": "dielectric", "int_ior": 1.5}, POLARIZED,
             delta=True, note="glass, Fresnel reflection and refraction as Mueller matrices"),
        Case("roughdielectric/polarized", {"type": "roughdielectric", "alpha": 0.3}, POLARIZED,
             note="a depolarizer in 3.9.1 (roughdielectric.cpp:117)"),
        Case("thindielectric/polarized", {"type": "thindielectric"}, POLARIZED, delta=True,
             note="a depolarizer in 3.9.1 (thindielectric.cpp:98)"),
        Case("diffuse/polarized", {"type": "diffuse", "reflectance": 0.5}, POLARIZED,
             note="control: a depolarizer"),
    ]


def _phonglab() -> list[Case]:
    return [
        Case("lambert/0.5", {"type": "lambert"}, note="phonglab"),
        Case("lambert/rgb", {"type": "lambert", "reflectance": _rgb(0.9, 0.4, 0.1)},
             note="phonglab, coloured"),
        Case("phong/default", {"type": "phong"}, note="phonglab, p = 30"),
        Case("phong/glossy", {"type": "phong", "diffuse_reflectance": 0.2,
                              "specular_reflectance": 0.7, "exponent": 200.0},
             note="phonglab, p = 200"),
        Case("phong/narrow", {"type": "phong", "diffuse_reflectance": 0.0,
                              "specular_reflectance": 0.8, "exponent": 1e4},
             note="phonglab, p = 10^4"),
    ]


def cases() -> list[Case]:
    """Every case of the conformance table, Mitsuba's built-ins first, phonglab's own last."""
    out = (_smooth_and_diffuse() + _rough() + _principled() + _wrappers()
           + _hair_spectral_polarized() + _phonglab())
    known = known_causes(findings.FINDINGS)
    return [Case(c.label, c.spec, c.variant, {**c.known, **known.get(c.label, {})}, c.delta,
                 c.note) for c in out]


#: Mitsuba 3.9.1's microfacet distribution when none is given (include/mitsuba/render/
#: microfacet.h:104, src/bsdfs/roughconductor.cpp:183).
DEFAULT_DISTRIBUTION = "beckmann"


def known_for_plugin(plugin: str, given: dict | None = None) -> dict[str, tuple]:
    """topic -> every documented cause of the cases of ``plugin`` (a type name), for that
    plugin validated away from the table's points (a sweep): each cause still holds only
    inside its own signature, so a failure outside all of them stays a fail.  With ``given``
    (the parameters a user set), a finding whose cause lives in a load-time setting
    (:attr:`~phonglab.validate.conformance.Finding.given`, e.g. the Beckmann pdf's
    normalization defect in ``distribution = beckmann``, the default when not given) counts
    only where that setting agrees: it says nothing about a GGX lobe, so a GGX failure of that
    row stays a fail; a cause elsewhere (the conductor Fresnel term's derivative at eta = 0)
    holds for every distribution."""
    out = known_of(cases(), plugin)
    if given is None:
        return out
    settings = {"distribution": DEFAULT_DISTRIBUTION, **given}
    needs = {f.key: f.given for f in findings.FINDINGS}

    def holds(cause) -> bool:
        return all(str(settings.get(name, "")).lower() == value.lower()
                   for name, value in needs.get(getattr(cause, "key", ""), ()))

    kept = {topic: tuple(c for c in causes if holds(c)) for topic, causes in out.items()}
    return {topic: causes for topic, causes in kept.items() if causes}


def catalogue() -> Catalogue:
    """The BSDF kind's table: :func:`cases`, :data:`~.findings.FINDINGS` and the validator's
    issues, each looked up at call time (a test patches them)."""
    return Catalogue(lambda: cases(), "phonglab.validate.bsdf.builtins.cases()",
                     findings.FINDINGS, "phonglab.validate.bsdf.findings.FINDINGS",
                     VALIDATOR_ISSUES, LEFT_OUT,
                     tests="tests/test_builtins_catalog.py",
                     case_text="one BSDF at one parameter setting",
                     # through the sweep at default sizes its 63 cases take over an hour on
                     # 2 cores: run at --quick (scripts/conformance.py --sweep --quick)
                     sweep=False)


#: Rows of the BSDF table that fail because of the validator while its fix is open (the
#: fixed ones are told in docs/validator-fixes.md).
VALIDATOR_ISSUES: tuple[ValidatorIssue, ...] = ()

#: Mitsuba 3.9.1 BSDF plugins (src/bsdfs/*.cpp) that are not in :func:`cases`, and why.
LEFT_OUT: dict[str, str] = {
    "measured": "needs a measured data file (RGL .bsdf, `filename`), none ships with Mitsuba",
    "measured_polarized": "needs a measured pBSDF data file (`filename`), none ships with "
                          "Mitsuba",
    "null": "has no lobe (BSDFFlags.Null only: rays pass straight through); eval, pdf and "
            "sample are identically zero by design, so no topic has anything to check",
}
