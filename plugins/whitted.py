r"""Whitted-style integrator (``whitted``): the seed lecture's complete lighting equation.

.. list-table::

   * - units
     - |string|
     - ``graphics`` (default): the seed's formula literally. ``radiance``: the same light
       transport in physical units, f_r · I/r² · cos θ through the BSDF's own ``eval``.
   * - ambient
     - |spectrum| or |texture|
     - Ambient "intensity" I_amb (default 0), in [0, 1e30] (float32 headroom).
   * - ambient_reflectance_<bsdf id>
     - |spectrum| or |texture|
     - Ambient reflectance k_amb in [0, 1] of the BSDF with that ``id`` (any number of
       these); a BSDF without one uses its diffuse reflectance (the seed's default).
       An id that names no BSDF of the scene is an error at the first render.
   * - attenuation_constant, attenuation_linear, attenuation_quadratic
     - |float|
     - OpenGL attenuation a, b, c >= 0 of 1/(a + b r + c r²) (defaults 1, 0, 0: no
       attenuation), finite float32 numbers, not denormal, not all 0.  The denominator
       is floored at ``ATTENUATION_FLOOR`` = 1e-6 (the factor is at most 10^6), so a
       light at r -> 0 or a tiny a stays finite.  ``graphics`` units only: ``radiance``
       units have the physical 1/r².
   * - shadows
     - |bool|
     - true (default): only lights visible from the point count (the ray-tracing case);
       false: every light counts (the OpenGL/z-buffer case).
   * - max_depth
     - |int|
     - Longest path in segments, Mitsuba's convention (default 5, a whole number in 1..10):
       1 = emission seen directly, 2 = local illumination at the first hit, each further
       level one more reflected or transmitted ray.
   * - hide_emitters
     - |bool|
     - Hide directly visible emitters (default false), as in ``path``.

Math, as the code computes it, at a hit with view direction V = si.wi (local shading
frame, N = +Z), for every point, spot or directional emitter i (light direction L_i,
distance r_i), Zorin's "complete equation" plus Whitted's recursive rays::

    graphics:  I = L_e + k_amb I_amb + Σ_i vis_i · I_i / (a + b r_i + c r_i²)
                                 · (k_diff max(0, L_i·N) + k_spec max(0, L_i·R)^p) · [L_i·N > 0]
               R = 2 (N·V) N − V
    radiance:  I = L_e + k_amb I_amb + Σ_i vis_i · f_r(V, L_i) cos θ_i · I_i / r_i²
    both:        + w_R · I(reflected ray) + w_T · I(transmitted ray)      (delta BSDFs only)

* I_i is what ``emitter.sample_direction`` returns times r² (the light's ``intensity``
  times a spot light's angular falloff); for directional lights I_i is their irradiance,
  r = ∞ and the attenuation is 1 (as in OpenGL).  Area and environment emitters do not
  light surfaces in this model: they are seen (L_e) directly or through reflected and
  transmitted rays; the ambient term stands in for their (and all indirect) light.
* graphics: for ``phong`` BSDFs (any BSDF with ``specular_reflectance`` and ``exponent``)
  k_diff = diffuse_reflectance, k_spec = specular_reflectance, p = exponent; for every
  other BSDF k_diff = ``eval_diffuse_reflectance`` (lambert/diffuse: reflectance) and
  k_spec = 0.  No π, no (p+2)/(2π), no cos θ on the specular term.  Surfaces are lit on
  their front side (back side too for two-sided BSDFs, by flipping N towards V).
* radiance: ``bsdf.eval_pdf`` (f_r cos θ_i) times ``spec`` = I_i/r_i² (times falloff), for
  any BSDF; with point lights only, shadows on and max_depth=2 this is term for term what
  Mitsuba's ``path`` computes (its emitter sample of a delta light is deterministic and
  its MIS weight is 1).  k_amb = eval_diffuse_reflectance by default, as above: for a
  Lambertian under uniform unoccluded radiance I_amb the reflected radiance is exactly
  ρ I_amb.
* vis_i = 1 when ``shadows`` is false, else 1 where the shadow ray
  ``si.spawn_ray_to(ds.p)`` is unoccluded.
* Reflected and transmitted rays are traced where the BSDF has a DeltaReflection or
  DeltaTransmission component (smooth ``conductor``, ``dielectric``, ``thindielectric``,
  ``plastic``'s coating).  Directions come from the seed's formulas (``_optics.reflect``,
  ``_optics.refract`` with η = n1/n2 = 1/bs.eta); weights w_R, w_T are the BSDF's own
  sample weights with only that component enabled (Fresnel F and (1 − F)/η'² for a
  dielectric in radiance transport, the conductor's Fresnel term) in both units, as the
  seed does not define them.  Past the critical angle the seed's square root is imaginary:
  no transmitted ray is traced and the reflection weight is F = 1.  The tree is
  deterministic (both rays, not a random choice as in ``path``), so it costs up to
  2^(max_depth−1) intersections per camera ray in a glass scene.

References: D. Zorin, *Lighting* (lecture notes, 2005); B. T. Phong, CACM 18(6), 1975;
T. Whitted, "An improved illumination model for shaded display", CACM 23(6), 1980;
OpenGL 2.1 specification §2.14.1 (lighting equation, attenuation).
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from . import _common, _optics
from ._common import MaterialError
from .phong import phong_lobe

UNITS = ("graphics", "radiance")
MAX_DEPTH_LIMIT = 10  #: the ray tree doubles per level in glass: cap the traced kernel
AMBIENT_PREFIX = "ambient_reflectance_"
#: Least denominator a + b r + c r² of the attenuation (its factor is at most 1e6).
ATTENUATION_FLOOR = 1e-6
#: OpenGL attenuation coefficients a, b, c of 1/(a + b r + c r²) and their defaults.
ATTENUATION = {"attenuation_constant": 1.0, "attenuation_linear": 0.0,
               "attenuation_quadratic": 0.0}


def _check_max_depth(value) -> int:
    """max_depth as an int in 1..MAX_DEPTH_LIMIT, or :class:`MaterialError`."""
    try:
        depth = float(value)
    except (TypeError, ValueError):
        depth = math.nan
    if not (math.isfinite(depth) and depth == int(depth) and 1 <= depth <= MAX_DEPTH_LIMIT):
        raise MaterialError(
            f"whitted: 'max_depth' must lie in 1..{MAX_DEPTH_LIMIT} (a whole number of path "
            f"segments, 2 = local illumination at the first hit), got {value!r}; the ray tree "
            f"is unrolled, so unbounded depth (-1) is not available.")
    return int(depth)


def _check_attenuation(name: str, value) -> float:
    return _common.check_number("whitted", name, value, "a coefficient of 1/(a + b r + c r²)",
                                "use a=1, b=c=0 for no attenuation")


def _is_point_like(emitter) -> bool:
    return mi.has_flag(emitter.flags(), mi.EmitterFlags.DeltaPosition)


def _is_directional(emitter) -> bool:
    return mi.has_flag(emitter.flags(), mi.EmitterFlags.DeltaDirection)


def _jit() -> bool:
    return dr.is_jit_v(mi.Float)


def _same_bsdf(ptr, bsdf):
    """Mask of the lanes whose BSDF is ``bsdf`` (scalar variants: the same Python object,
    which nanobind returns for one C++ BSDF while a reference to it is alive)."""
    if _jit():
        return ptr == mi.BSDFPtr(bsdf)
    return mi.Bool(ptr is bsdf)


def delta_lights(scene) -> list:
    """The scene's point, spot and directional emitters (those this model sums over)."""
    return [e for e in scene.emitters() if _is_point_like(e) or _is_directional(e)]


def scene_bsdfs(scene) -> list:
    """The distinct BSDFs of the scene's shapes, in shape order."""
    out = []
    for shape in scene.shapes():
        bsdf = shape.bsdf()
        if bsdf is not None and not any(bsdf is b for b in out):
            out.append(bsdf)
    return out


def delta_child(si, bsdf, kind, active):
    """The reflected or transmitted ray of a delta BSDF component at si.

    Args:
        si: surface interaction of the hit.
        bsdf: ``si.bsdf()``.
        kind: ``mi.BSDFFlags.DeltaReflection`` or ``mi.BSDFFlags.DeltaTransmission``.
        active: lanes to consider.

    Returns:
        (ray, weight, valid): the world-space ray spawned at si in the seed's direction
        (R = 2 (N·V) N − V, or T from :func:`_optics.refract` with η = n1/n2), the BSDF's
        sample weight with only ``kind`` enabled, and where the ray exists (the BSDF has
        that component, its weight is non-zero and, for T, there is no total internal
        reflection).
    """
    ctx = mi.BSDFContext()
    ctx.type_mask = int(kind)
    has = active & mi.has_flag(bsdf.flags(), kind)
    bs, weight = bsdf.sample(ctx, si, 0.5, mi.Point2f(0.5, 0.5), has)
    wi = si.wi
    # The normal on V's side: the seed's formulas assume V·N >= 0.
    n = mi.Vector3f(0.0, 0.0, dr.select(wi.z >= 0.0, 1.0, -1.0))
    if kind == mi.BSDFFlags.DeltaReflection:
        d_local = _optics.reflect(wi, n)
        ok = has & (bs.pdf > 0.0)
    else:
        # Mitsuba's bs.eta is the relative index across (n2/n1); the seed's η is n1/n2.
        eta = dr.rcp(dr.select(bs.eta > 0.0, bs.eta, 1.0))
        d_local, exists = _optics.refract(wi, n, eta)
        ok = has & (bs.pdf > 0.0) & exists
    ok &= dr.any(weight != 0.0)
    ray = si.spawn_ray(si.to_world(dr.normalize(d_local)))
    return ray, dr.select(ok, weight, 0.0), ok


class Whitted(mi.SamplingIntegrator):
    """The seed's local lighting model plus Whitted's reflected and transmitted rays."""

    def __init__(self, props: mi.Properties):
        mi.SamplingIntegrator.__init__(self, props)
        self.units = str(props.get("units", "graphics"))
        if self.units not in UNITS:
            raise MaterialError(f"whitted: 'units' must be 'graphics' or 'radiance', got "
                                f"{self.units!r}.")
        self.max_depth = _check_max_depth(props.get("max_depth", 5))
        self.shadows = bool(props.get("shadows", True))
        self.hide_emitters = bool(props.get("hide_emitters", False))
        (self.ambient,) = _common.load_textures("whitted", props, [("ambient", 0.0)],
                                                unbounded=True)
        for name, default in ATTENUATION.items():
            setattr(self, name, mi.Float(_check_attenuation(name, props.get(name, default))))
        self._check_attenuation_sum()
        self.ambient_reflectance = {}
        for key in props.keys():
            if key.startswith(AMBIENT_PREFIX):
                (texture,) = _common.load_textures("whitted", props, [(key, 0.0)])
                self.ambient_reflectance[key[len(AMBIENT_PREFIX):]] = texture
        self._make_opaque()
        self._accepted = _common.snapshot(self._members())

    def traverse(self, callback):
        callback.put("ambient", self.ambient, mi.ParamFlags.NonDifferentiable)
        for name in ATTENUATION:
            callback.put(name, getattr(self, name), mi.ParamFlags.NonDifferentiable)

    def _members(self) -> dict:
        """The traversed members, whose values an update writes in place."""
        return {"ambient": self.ambient, **{name: getattr(self, name) for name in ATTENUATION}}

    def parameters_changed(self, keys=None):
        """Re-validate after ``params.update()``; a refused value is replaced by the last
        accepted one (here and in the caller's parameter map) before the error propagates."""
        def validate():
            for name in ATTENUATION:
                _check_attenuation(name, _common.scalar_of(getattr(self, name)))
            self._check_attenuation_sum()
            if not mi.is_spectral:   # spectral textures hold up-sampled spectra
                _common.check_textures("whitted", {"ambient": self.ambient},
                                       upper=_common.INTENSITY_MAX)

        self._accepted = _common.commit(self._members(), self._accepted, validate,
                                        self._make_opaque)

    def _make_opaque(self):
        # Opaque: a sweep of a, b, c through mi.traverse never recompiles the kernel.
        for name in ATTENUATION:
            dr.make_opaque(getattr(self, name))

    def _check_attenuation_sum(self):
        abc = [_common.scalar_of(getattr(self, name)) for name in ATTENUATION]
        if sum(abc) <= 0.0:
            raise MaterialError(
                f"whitted: attenuation a, b, c ('attenuation_constant', 'attenuation_linear', "
                f"'attenuation_quadratic') must be >= 0 and not all 0 (1/(a + b r + c r²)), "
                f"got {abc}; use a=1, b=c=0 for none.")
        if self.units == "radiance" and abc != list(ATTENUATION.values()):
            raise MaterialError(
                f"whitted: attenuation_* applies to units='graphics' only, got {abc}; radiance "
                f"units already have the physical 1/r², so leave a=1, b=c=0 there.")

    def parameters(self) -> dict:
        """This integrator's settings as a ``mi.load_dict`` dictionary (uniform textures only)."""
        out = {"type": "whitted", "units": self.units, "max_depth": self.max_depth,
               "shadows": self.shadows, "hide_emitters": self.hide_emitters,
               **{name: float(np.asarray(getattr(self, name)).ravel()[0])
                  for name in ATTENUATION}}
        return out

    # ------------------------------------------------------------------ rendering
    def sample(self, scene, sampler, ray, medium=None, active=True):
        materials = scene_bsdfs(scene)
        ids = {b.id() for b in materials}
        unknown = sorted(set(self.ambient_reflectance) - ids)
        if unknown:
            known = ", ".join(repr(i) for i in sorted(i for i in ids if i)) or "none"
            raise MaterialError(
                f"whitted: '{AMBIENT_PREFIX}{unknown[0]}' names no BSDF of the scene (the ids "
                f"of its BSDFs: {known}); use the id of a <bsdf id=...> that a shape uses.")
        flags = 0
        for b in materials:
            flags |= int(b.flags())
        kinds = [k for k in (mi.BSDFFlags.DeltaReflection, mi.BSDFFlags.DeltaTransmission)
                 if flags & int(k)]
        env = scene.environment() is not None and not self.hide_emitters
        L, hit = self._trace(scene, materials, delta_lights(scene), kinds, mi.Ray3f(ray), 1,
                             mi.Bool(active))
        return L, hit | mi.Bool(env), []

    def _trace(self, scene, materials, lights, kinds, ray, depth, active):
        """Radiance along ``ray``, the depth-th segment of the path (camera ray: 1)."""
        si = scene.ray_intersect(ray, mi.RayFlags.All, depth == 1, active)
        show = active if not (depth == 1 and self.hide_emitters) else mi.Bool(False)
        emitter = si.emitter(scene, show)
        if _jit():
            L = dr.select(show, emitter.eval(si, show), 0.0)
        else:  # scalar variants: a missing emitter or BSDF is None, not a masked lane
            L = emitter.eval(si, show) if (emitter is not None and show) else mi.Spectrum(0.0)
        hit = active & si.is_valid()
        if depth + 1 > self.max_depth or (not _jit() and not hit):
            return L, hit
        bsdf = si.bsdf(ray)
        L += self._local(scene, materials, lights, si, bsdf, hit)
        for kind in kinds:
            child, weight, ok = delta_child(si, bsdf, kind, hit)
            L_child, _ = self._trace(scene, materials, lights, kinds, child, depth + 1, ok)
            L += dr.select(ok, weight * L_child, 0.0)
        return L, hit

    def _material(self, materials, si, bsdf, active):
        """(k_amb, k_diff, k_spec, p) per lane: phong's own parameters where the BSDF is one."""
        k_diff = bsdf.eval_diffuse_reflectance(si, active)
        k_spec = dr.zeros(mi.Spectrum)
        p = mi.Float(0.0)
        k_amb = mi.Spectrum(k_diff)
        ptr = si.bsdf()
        for b in materials:
            is_phong = hasattr(b, "specular_reflectance") and hasattr(b, "exponent")
            amb = self.ambient_reflectance.get(b.id())
            if not is_phong and amb is None:
                continue
            mine = active & _same_bsdf(ptr, b)
            if is_phong and self.units == "graphics":
                k_spec = dr.select(mine, b.specular_reflectance.eval(si, mine), k_spec)
                p = dr.select(mine, b.exponent, p)
            if amb is not None:
                k_amb = dr.select(mine, amb.eval(si, mine), k_amb)
        return k_amb, k_diff, k_spec, p

    def _local(self, scene, materials, lights, si, bsdf, active):
        """Ambient plus the direct terms of every point/spot/directional light at si."""
        k_amb, k_diff, k_spec, p = self._material(materials, si, bsdf, active)
        L = dr.select(active, k_amb * self.ambient.eval(si, active), 0.0)
        ctx = mi.BSDFContext()
        wi = si.wi
        if self.units == "graphics":
            # Two-sided BSDFs are lit from the side V is on: flip N (i.e. z) towards V.
            flip = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.BackSide) & (wi.z < 0.0)
            wi = mi.Vector3f(wi.x, wi.y, dr.select(flip, -wi.z, wi.z))
            R = _optics.reflect(wi, mi.Vector3f(0.0, 0.0, 1.0))
        for emitter in lights:
            # Delta lights ignore the sample: ds and spec are deterministic.
            ds, spec = emitter.sample_direction(si, mi.Point2f(0.5, 0.5), active)
            lit = active & (ds.pdf != 0.0)
            if self.shadows:
                occluded = scene.ray_test(si.spawn_ray_to(ds.p), lit)
                lit = lit & (~occluded if _jit() else not occluded)   # ~True is -2 in Python
            wo = si.to_local(ds.d)
            if self.units == "radiance":
                value, _ = bsdf.eval_pdf(ctx, si, wo, lit)
                L += dr.select(lit, value * spec, 0.0)
                continue
            wo = mi.Vector3f(wo.x, wo.y, dr.select(flip, -wo.z, wo.z))
            cos_n = wo.z                      # L·N
            cos_r = dr.dot(wo, R)             # L·R
            if _is_point_like(emitter):
                r = ds.dist
                intensity = spec * (r * r)    # I_i (times the spot falloff)
                # Floored: a light closer than the coefficients allow (a + b r + c r² -> 0)
                # stays finite instead of overflowing float32 to Inf (and Inf·0 to NaN).
                attenuation = dr.maximum(self.attenuation_constant + self.attenuation_linear * r
                                         + self.attenuation_quadratic * r * r,
                                         ATTENUATION_FLOOR)
            else:
                intensity, attenuation = spec, mi.Float(1.0)
            front = lit & (wi.z > 0.0) & (cos_n > 0.0)
            value = intensity / attenuation * (k_diff * cos_n + k_spec * phong_lobe(cos_r, p))
            L += dr.select(front, value, 0.0)
        return L

    def class_name(self):
        # The trampoline would answer "SamplingIntegrator" (provenance metadata reads this).
        return "Whitted"

    def to_string(self):
        return (f"Whitted[units={self.units!r}, max_depth={self.max_depth}, "
                f"shadows={self.shadows}]")


PLUGIN_CLASS = Whitted
