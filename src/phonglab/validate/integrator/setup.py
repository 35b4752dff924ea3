r"""The integrator under test as the validator holds it: how it is rebuilt at a scene's path
depth, and what kind of estimator it is.

A type name or a dict spec is reloaded per scene with ``max_depth`` set to the scene's depth
(Mitsuba's convention, src/integrators/path.cpp: ``max_depth`` D counts path vertices, D = 1
is the emission seen directly, D = 2 adds direct illumination at the first hit; each further
level one more bounce).  Whether it has that parameter is found by loading it with one:
Mitsuba refuses an unreferenced property, C++ and Python plugins alike.  An integrator that
accepts ``max_depth`` but keeps its own (``direct_projective`` sets 2 whatever it is given,
src/python/python/ad/integrators/direct_projective.py:96-98) is read back
(:func:`phonglab.engine.render.max_depth_of`, or a Python integrator's ``max_depth`` attribute) and
held at the depth it keeps.  Without the parameter the depth is the one the integrator is
known to compute: :data:`FIXED_DEPTHS` for Mitsuba's built-ins (``direct``: emission plus
direct illumination, the depth-2 model), a Python plugin's class attribute ``FIXED_DEPTH``;
otherwise it is *measured* (``depth == "measured"``): the closed emitting enclosure rendered
at two albedos (:func:`phonglab.validate.integrator.analytic.measure_depth`) identifies the
depth, or none -- a value that matches no integer depth, itself a failing ``bias`` row --
and every scene is then judged at the measured depth as at a declared one.  An XML file or a
loaded object cannot be rebuilt and is likewise run as it is (its depth read back, else
measured).

Kinds of estimator: an integrator that returns AOVs beside its radiance (``aov_names()`` not
empty, a Python ``sample()`` returning ``(L, valid, [depth])``, Mitsuba's ``moment``, ``aov``
with a nested integrator) has its radiance judged on every topic -- rendered through
:func:`radiance_only`, which calls it as Mitsuba's render loop does and drops the AOVs -- and
its AOV channels on ``finite`` alone (finite; they may be negative); an integrator whose image
has no radiance at all (``aov`` without a nested integrator: its image has exactly its AOV
channels; ``depth``) is checked for finite output only; a splatting (adjoint, light-tracing)
integrator (``mi.AdjointIntegrator``: ``ptracer``) cannot connect a pinhole camera through a
delta BSDF, so scenes seen through glass do not apply; an AD integrator
(``mi.ad.integrators.common.ADIntegrator``: ``prb``, ``direct_projective`` ...) in an AD
variant has the ``gradient`` topic.
"""

from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import mitsuba as mi

from ... import dispatch
from ...engine.render import max_depth_of
from ...settings import Loaded

#: Built-ins without ``max_depth`` and the depth their estimator computes.
FIXED_DEPTHS = {"direct": 2}
#: Built-ins whose image is not radiance although ``aov_names()`` is empty (``depth`` returns
#: the distance to the first hit in every channel, src/integrators/depth.cpp): as an AOV
#: integrator, finite output only.
NOT_RADIANCE = ("DepthIntegrator",)
#: How to declare the depth an integrator without ``max_depth`` computes (skip reasons quote it).
DECLARE = ("To declare it, give the integrator class the attribute FIXED_DEPTH (path vertices, "
           "1 = emission seen, 2 = plus direct illumination), e.g. "
           "`class MyDirect(mi.SamplingIntegrator): FIXED_DEPTH = 2`")
#: The depth a spec is probed with to learn whether it takes and keeps ``max_depth``.
PROBE_DEPTH = 3


@dataclass
class Target:
    """The integrator under test (:func:`build`)."""

    label: str
    spec: dict | None            #: its ``mi.load_dict`` spec; None: not rebuildable
    integrator: object           #: as loaded
    depth: str                   #: "settable", "fixed" or "measured"
    #: the depth it computes when ``depth == "fixed"``, or the measured one (None before the
    #: measurement, or when it matched no integer depth)
    fixed_depth: int | None
    depth_note: str              #: why (the table's skip reasons quote it)
    aov: bool                    #: its image has no radiance (AOV channels alone): finite only
    splatting: bool
    ad: bool
    #: the depth measurement (:class:`~.analytic.DepthFit`) once made (``depth == "measured"``)
    measurement: object = None
    #: its AOV names when it returns them beside radiance (the radiance topics drop them)
    aovs: tuple[str, ...] = ()

    @property
    def judged(self):
        """The integrator as loaded, as the radiance topics render it (:func:`radiance_only`
        when it returns AOVs beside its radiance)."""
        return radiance_only(self.integrator) if self.aovs else self.integrator

    def make(self, max_depth: int | None = None, whole: bool = False):
        """The integrator at ``max_depth`` (settable), else as it is; its radiance alone
        unless ``whole`` (the image with its AOV channels)."""
        if self.depth != "settable" or max_depth is None:
            integ = self.integrator
        else:
            integ = mi.load_dict({**self.spec, "max_depth": int(max_depth)})
        return integ if whole or not self.aovs else radiance_only(integ)

    def at_depth(self, depth: int | None, whole: bool = False) -> tuple[object | None, str]:
        """(integrator, "") for a scene needing path depth ``depth`` (None: any depth >= 2),
        or (None, why it does not apply); ``whole`` as in :meth:`make`."""
        if depth is None:
            if self.own_depth is not None and self.own_depth < 2:
                return None, f"the scene needs depth >= 2; {self.depth_note}"
            return self.make(4, whole), ""
        if self.depth == "settable":
            try:
                return self.make(depth, whole), ""
            except Exception as exc:     # it takes max_depth but refuses this one (whitted: <= 10)
                why = str(exc).strip().splitlines()[-1][:200] if str(exc).strip() else repr(exc)
                return None, f"it refuses max_depth {depth}: {why}"
        if self.depth in ("fixed", "measured") and self.fixed_depth == depth:
            return self.make(None, whole), ""
        return None, f"the scene's value holds at max_depth {depth}; {self.depth_note}"

    @property
    def own_depth(self) -> int | None:
        """The depth it computes when it cannot be set (declared, kept or measured)."""
        return self.fixed_depth if self.depth in ("fixed", "measured") else None


def radiance_channels() -> int:
    """How many leading channels of a rendered image are radiance (1 in mono variants, else 3:
    spectral images are developed to RGB)."""
    return 1 if mi.is_monochromatic else 3


#: The query method ``mi.SamplingIntegrator``'s binding calls through the trampoline
#: (``PySamplingIntegrator::sample``, src/render/python/integrator_v.cpp:98-113 at v3.9.1), as
#: ``SamplingIntegrator::render`` calls it (:func:`radiance_only`).
METHODS = ("sample",)


def view(integrator) -> dispatch.Dispatched:
    """The integrator as ``SamplingIntegrator::render`` calls it
    (:func:`phonglab.dispatch.view`)."""
    return dispatch.view(integrator, mi.SamplingIntegrator, METHODS)


_RADIANCE_ONLY: dict = {}


def radiance_only(integrator):
    """``integrator`` as a sampling integrator without AOVs: its ``sample`` called through
    Mitsuba's dispatch (:func:`phonglab.dispatch.view`, as ``SamplingIntegrator::render``
    calls it) and its radiance and validity returned, the AOVs dropped."""
    variant = mi.variant()
    if variant not in _RADIANCE_ONLY:
        class RadianceOnly(mi.SamplingIntegrator):
            def __init__(self, inner):
                mi.SamplingIntegrator.__init__(self, mi.Properties())
                self.inner = view(inner)

            def sample(self, scene, sampler, ray, medium, active):
                spectrum, valid, _ = self.inner.sample(scene, sampler, ray, medium, active)
                return spectrum, valid, []

            def aov_names(self):
                return []

            def to_string(self):
                return f"RadianceOnly[{self.inner.plugin}]"

        _RADIANCE_ONLY[variant] = RadianceOnly
    return _RADIANCE_ONLY[variant](integrator)


def _image_channels(integ) -> int:
    """The channels of ``integ``'s image: one 1-spp render of a 2 × 2 film."""
    scene = mi.load_dict({"type": "scene", "shape": {"type": "sphere"},
                          "light": {"type": "constant"},
                          "sensor": {"type": "perspective", "film": {
                              "type": "hdrfilm", "width": 2, "height": 2},
                              "to_world": mi.ScalarTransform4f().look_at(
                                  [0, 0, -4], [0, 0, 0], [0, 1, 0])}})
    return int(mi.render(scene, integrator=integ, spp=1).shape[-1])


def _returns_radiance(integ, names: list) -> bool:
    """Whether ``integ``'s image has radiance channels: not one of :data:`NOT_RADIANCE`, and,
    when it has AOVs, an image with more channels than its AOV names (Mitsuba's ``aov``
    without a nested integrator develops its AOV channels alone)."""
    if integ.class_name() in NOT_RADIANCE:
        return False
    if not names or not isinstance(integ, mi.SamplingIntegrator):
        return True
    try:
        return _image_channels(integ) != len(names)
    except Exception:           # the topics render it again and report its error
        return True

def _kept_depth(integrator) -> int | None:
    own = getattr(integrator, "max_depth", None)
    if isinstance(own, int):
        return own
    return max_depth_of(integrator)


def build(loaded: Loaded, spec, params: dict | None) -> Target:
    """The :class:`Target` of a loaded integrator; ``spec``/``params`` as the user gave them."""
    integ = loaded.plugin
    d = None
    if isinstance(spec, str) and not spec.endswith(".xml"):
        d = {"type": spec, **(params or {})}
    elif isinstance(spec, dict):
        d = {**spec, **(params or {})}
    names = list(integ.aov_names())
    radiance = _returns_radiance(integ, names)
    aov = not radiance
    aovs = tuple(names) if radiance else ()
    splatting = isinstance(integ, mi.AdjointIntegrator)
    ad = dr.is_diff_v(mi.Float) and isinstance(integ, mi.ad.integrators.common.ADIntegrator)
    depth, fixed, note = "measured", None, ""
    if d is None:
        note = "an XML file or a loaded object cannot be rebuilt at another max_depth"
        kept = max_depth_of(integ)
        if kept is not None:
            depth, fixed = "fixed", kept
            note += f"; it was built with max_depth {kept}"
        else:
            note += f"; its depth is measured. {DECLARE}"
    else:
        try:
            probe = mi.load_dict({**d, "max_depth": PROBE_DEPTH})
        except Exception:
            probe = None
        if probe is not None:
            kept = _kept_depth(probe)
            if kept is None or kept == PROBE_DEPTH:
                depth, note = "settable", "max_depth is set per scene"
            else:
                depth, fixed = "fixed", kept
                note = (f"it takes max_depth but keeps {kept} (given {PROBE_DEPTH}): held to the "
                        f"depth-{kept} model")
        else:
            fixed = FIXED_DEPTHS.get(d["type"], getattr(type(integ), "FIXED_DEPTH", None))
            if fixed is not None:
                depth = "fixed"
                note = f"it has no max_depth and computes the depth-{fixed} model"
            else:
                note = f"it has no max_depth and declares no FIXED_DEPTH: its depth is measured. {DECLARE}"
    return Target(loaded.label, d, integ, depth, fixed, note, aov, splatting, ad,
                  aovs=aovs)

