"""The parts of the BSDF kind (:data:`phonglab.validate.bsdf.KIND`): its statistical tests, its
runners, its sweep's parameters and its built-ins' findings (the kind-independent runner
:mod:`phonglab.validate.core` and sweep :mod:`phonglab.validate.sweep` do the rest;
:func:`phonglab.validate.validate_bsdf` is the validator).

The statistical tests of a BSDF are the χ² cells and the normalization cells (unless every lobe
is a delta), when it has a delta lobe the energy cells whose albedo is a mean of sample
weights, and when it has a Null lobe the eval_null_transmission cells (a mean Null-sample
weight); the other topics are identities at float32 round-off, or informational (``cost``).
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from ... import probe
from . import lanes, ranges
from ..returns import checked, defines
from .config import options
from .contract import eval_diffuse_reflectance, eval_null_transmission, has_null
from .cost import cost
from .energy import energy
from .gradient import gradient
from .identify import children, identify   # noqa: F401 (the kind's parts)
from .identities import component, eval_pdf, finite, weight_and_pdf
from .normalization import normalization
from . import intensity as intensity_topic
from .polarization import mueller, mueller_identities, mueller_reciprocity
from .reciprocity import reciprocity
from .sampling import chi2


def statistical_tests(bsdf, opts, topics) -> int:
    """m: the number of statistical tests the run makes (χ² and normalization cells, energy
    cells with delta lobes, eval_null_transmission cells with a Null lobe)."""
    m = 0
    if "chi2" in topics and not lanes.delta_only(bsdf):
        m += len(opts.cells(opts.chi2_cos, opts.chi2_phi))
    if "normalization" in topics and not lanes.delta_only(bsdf):
        m += len(opts.cells(opts.energy_cos))
    if "energy" in topics and lanes.bsdf_has(bsdf, int(mi.BSDFFlags.Delta) |
                                             int(mi.BSDFFlags.Delta1D)):
        m += len(opts.energy_cos)
    if "eval_null_transmission" in topics and has_null(bsdf):
        m += len(opts.cells())
    return max(m, 1)


def runners(bsdf, opts, topics, m: int) -> dict:
    """topic -> the function that makes its rows (``weight`` makes the ``pdf`` rows too when
    both run: they share the samples)."""
    return {
        "finite": lambda: finite(bsdf, opts),
        "eval_pdf": lambda: eval_pdf(bsdf, opts),
        "weight": lambda: weight_and_pdf(bsdf, opts, {"weight", "pdf"} & set(topics)),
        "pdf": lambda: [] if "weight" in topics else weight_and_pdf(bsdf, opts, {"pdf"}),
        "chi2": lambda: chi2(bsdf, opts, m),
        "normalization": lambda: normalization(bsdf, opts, m),
        "energy": lambda: energy(bsdf, opts, m),
        "reciprocity": lambda: reciprocity(bsdf, opts),
        "component": lambda: component(bsdf, opts),
        "eval_null_transmission": lambda: eval_null_transmission(bsdf, opts, m),
        "eval_diffuse_reflectance": lambda: eval_diffuse_reflectance(bsdf, opts),
        "mueller": lambda: mueller(bsdf, opts),
        "intensity": lambda: intensity_topic.intensity(bsdf, opts),
        "mueller_identities": lambda: mueller_identities(bsdf, opts),
        "mueller_reciprocity": lambda: mueller_reciprocity(bsdf, opts),
        "gradient": lambda: gradient(bsdf, opts),
        "cost": lambda: cost(bsdf, opts),
    }


def returns(plugin, name: str = "BSDF") -> None:
    """A Python BSDF's ``sample``, ``eval``, ``pdf`` and ``eval_pdf`` (those its class defines)
    return what Mitsuba casts to (BSDFSample3f, Spectrum), Spectrum, Float, (Spectrum, Float)
    (:mod:`phonglab.validate.returns`)."""
    if not isinstance(plugin, mi.BSDF) or mi.is_polarized:
        return          # Mueller matrices: the polarized topics read them
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.t = mi.Float(1.0)
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wi = dr.normalize(mi.Vector3f(0.3, 0.2, 0.9))
    si.uv = mi.Point2f(0.5, 0.5)
    ctx, wo = mi.BSDFContext(), dr.normalize(mi.Vector3f(-0.2, 0.1, 0.9))
    active = mi.Bool(True)
    for method, args, expects in (
            ("sample", (ctx, si, mi.Float(0.5), mi.Point2f(0.3, 0.6), active),
             "a tuple (bs: mi.BSDFSample3f, weight: mi.Spectrum), e.g. return bs, weight"),
            ("eval", (ctx, si, wo, active), "one mi.Spectrum or number (the BSDF times cos θ_o)"),
            ("pdf", (ctx, si, wo, active), "one mi.Float or number"),
            ("eval_pdf", (ctx, si, wo, active),
             "a tuple (value: mi.Spectrum, pdf: mi.Float), e.g. return value, pdf")):
        if defines(plugin, method):
            checked(probe.view(plugin), "BSDF", name, method, args, expects)


def in_scene(scene) -> list:
    """The BSDFs a loaded scene holds at its top: its shapes' materials (``shape.bsdf()``)."""
    return [bsdf for bsdf in (shape.bsdf() for shape in scene.shapes()) if bsdf is not None]


#: The sweep's parameters and the values a documented cause's ``at`` is held against.
parameters = ranges.parameters
domain = ranges.domain
values = ranges.traversed
#: What a run keeps across its points: the unpolarized reference process of ``intensity``.
session = intensity_topic.session


def known_for(name: str, params: dict | None) -> dict:
    """The conformance table's findings of the Mitsuba built-in BSDF ``name``, for the
    microfacet distribution of ``params`` (:func:`phonglab.validate.bsdf.builtins.known_for_plugin`)."""
    from .builtins import known_for_plugin   # the catalogue and its findings: only when asked
    return known_for_plugin(name, params or {})


def catalogue():
    """The BSDF conformance table (:mod:`.builtins`)."""
    from .builtins import catalogue as table
    return table()
