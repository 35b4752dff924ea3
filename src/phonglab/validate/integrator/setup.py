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

Kinds of estimator: an AOV integrator (``aov_names()`` not empty: it returns channels that are
not radiance) is checked for finite output only; a splatting (adjoint, light-tracing)
integrator (``mi.AdjointIntegrator``: ``ptracer``) cannot connect a pinhole camera through a
delta BSDF, so scenes seen through glass do not apply; an AD integrator
(``mi.ad.integrators.common.ADIntegrator``: ``prb``, ``direct_projective`` ...) in an AD
variant has the ``gradient`` topic.
"""

from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import mitsuba as mi

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
    aov: bool
    splatting: bool
    ad: bool
    #: the depth measurement (:class:`~.analytic.DepthFit`) once made (``depth == "measured"``)
    measurement: object = None

    def make(self, max_depth: int | None = None):
        """The integrator at ``max_depth`` (settable), else as it is."""
        if self.depth != "settable" or max_depth is None:
            return self.integrator
        return mi.load_dict({**self.spec, "max_depth": int(max_depth)})

    def at_depth(self, depth: int | None) -> tuple[object | None, str]:
        """(integrator, "") for a scene needing path depth ``depth`` (None: any depth >= 2),
        or (None, why it does not apply)."""
        if depth is None:
            if self.own_depth is not None and self.own_depth < 2:
                return None, f"the scene needs depth >= 2; {self.depth_note}"
            return self.make(4), ""
        if self.depth == "settable":
            try:
                return self.make(depth), ""
            except Exception as exc:     # it takes max_depth but refuses this one (whitted: <= 10)
                why = str(exc).strip().splitlines()[-1][:200] if str(exc).strip() else repr(exc)
                return None, f"it refuses max_depth {depth}: {why}"
        if self.depth in ("fixed", "measured") and self.fixed_depth == depth:
            return self.integrator, ""
        return None, f"the scene's value holds at max_depth {depth}; {self.depth_note}"

    @property
    def own_depth(self) -> int | None:
        """The depth it computes when it cannot be set (declared, kept or measured)."""
        return self.fixed_depth if self.depth in ("fixed", "measured") else None


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
    aov = bool(list(integ.aov_names())) or integ.class_name() in NOT_RADIANCE
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
    return Target(loaded.label, d, integ, depth, fixed, note, aov, splatting, ad)

