r"""The emitter under test, placed where it can be sampled, and the reference points it is
probed from.

Mitsuba needs more than the emitter object (Mitsuba 3.9.1 sources, commit 478e193a):

* an ``area`` emitter samples through its shape (src/emitters/area.cpp, ``sample_direction``:
  ``m_shape->sample_direction``; without one it returns zeros in JIT variants).  An emitter
  loaded without a shape is attached to one (:data:`DEFAULT_SHAPE`, or the ``shape`` the
  caller gives, e.g. ``--set shape.type=sphere``) by loading the shape with the emitter object
  inside it; rays are traced in a scene holding that shape alone (a mesh intersects rays only
  through a scene's acceleration structure);
* environment and directional emitters take their bounding sphere from the scene in
  ``set_scene`` (constant.cpp, envmap.cpp, directional.cpp: radius r_scene(1 + RayEpsilon),
  RayEpsilon = 1500·2⁻²⁴): they are loaded into a tiny scene (a unit sphere at the origin, so
  r_scene = √3) and the radius their ``sample_ray`` weights use is that one.  Mitsuba 3.9.1 never
  calls a Python emitter's ``set_scene``: for a Python plugin the radius is unknown and the
  rows that need it say so;
* a delta-position light (point, spot) has a position: found as ``ds.p`` of one sample.

Reference points (:class:`RefGroup`, one point per lane): for a surface emitter outside its
shape (at 3 and 1.5 bounding radii), on both sides of a one-sided flat shape (rectangle, disk),
and for a closed shape (sphere, cube) on its surface as a ray from inside computes it (float32
intersection points, where a renderer's next-event estimation starts) and inside it (the
centre and an off-centre point); for an environment emitter the scene centre and points inside
its bounding sphere; for a delta-position light points at distances 0.5, 1 and 2 over random
directions (for a spot, half of them inside a cone of 1.3× its cutoff angle about its axis); for
a directional light points inside and outside the scene's bounding sphere.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import drjit as dr
import mitsuba as mi
import numpy as np

from ... import dispatch, probe
from ..directions import basis
from ..inputs import ValidateError
from .config import rng

#: The shape an area emitter loaded alone is attached to (Mitsuba's default rectangle, 2 × 2).
DEFAULT_SHAPE = {"type": "rectangle"}
#: Shapes that enclose a volume (reference points inside them make sense).
CLOSED = ("Sphere", "Cube")
#: Shapes emitting from one side only whose other side is probed too.
FLAT = ("Rectangle", "Disk")
#: math::RayEpsilon of float variants: 1500 · 2⁻²⁴ (include/mitsuba/core/math.h).
RAY_EPSILON = 1500 * 2.0 ** -24

#: The query methods ``mi.Emitter``'s trampoline forwards to a Python emitter (``PyEmitter``,
#: src/render/python/emitter_v.cpp:21-61 at v3.9.1), called through the binding by :func:`view`.
METHODS = ("sample_ray", "sample_direction", "pdf_direction", "eval_direction",
           "sample_position", "pdf_position", "eval", "sample_wavelengths")


def view(emitter) -> dispatch.Dispatched:
    """The emitter as Mitsuba's integrators call it (:func:`phonglab.dispatch.view`)."""
    return dispatch.view(emitter, mi.Emitter, METHODS)


@dataclass
class RefGroup:
    """Reference points of one kind: ``where`` ∈ outside/front/behind/on/inside/near, ``p``
    (n, 3) one point per lane; ``chi2``: whether the χ² topic tests from ``p[0]``."""

    label: str
    where: str
    p: np.ndarray
    chi2: bool = True


@dataclass
class Setup:
    """One emitter ready to be probed, with what the topics need to know of its geometry."""

    emitter: object
    kind: str                           #: "position", "direction", "surface" or "infinite"
    python: bool                        #: a Python plugin (mi.register_emitter)
    shape: object = None
    shape_name: str = ""
    flipped: bool = False
    scene: object = None                #: an environment's scene, or the shape's alone
    center: np.ndarray = field(default_factory=lambda: np.zeros(3))
    radius: float = 1.0                 #: the shape's or scene's bounding radius
    bsphere_radius: float | None = None  #: the radius Mitsuba's set_scene gives the emitter
    axis: np.ndarray | None = None      #: a spot's axis (to_world · +z)
    cutoff_deg: float | None = None
    #: Mitsuba's sunsky: (to_world⁻¹, the local sun direction, cos of the sun's half aperture),
    #: float32 as sunsky.h's hit_sun takes them (:func:`sun_cone`)
    sun: tuple | None = None

    @property
    def delta(self) -> bool:
        return self.kind in ("position", "direction")

    @property
    def calls(self):
        """The emitter as Mitsuba's integrators call it (:mod:`phonglab.dispatch`: ``active``
        passed, returns cast by the trampoline); a stand-in that is no ``mi.Emitter`` as it is."""
        if isinstance(self.emitter, mi.Emitter):
            return view(self.emitter)
        return self.emitter

    @property
    def sphere(self) -> tuple[np.ndarray, float] | None:
        """(centre, radius) when the shape is a sphere (its bbox is centre ± r)."""
        if self.shape_name != "Sphere":
            return None
        return self.center, self.radius / math.sqrt(3.0)


def kind_of(emitter) -> str:
    flags = int(emitter.flags())
    if flags & int(mi.EmitterFlags.DeltaPosition):
        return "position"
    if flags & int(mi.EmitterFlags.DeltaDirection):
        return "direction"
    if flags & int(mi.EmitterFlags.Infinite):
        return "infinite"
    if flags & int(mi.EmitterFlags.Surface):
        return "surface"
    raise ValidateError(f"the emitter's flags {flags} name none of DeltaPosition, "
                        f"DeltaDirection, Infinite, Surface; set m_flags in its constructor")


def build(emitter, shape_spec: dict | None = None) -> Setup:
    """The :class:`Setup` of a loaded emitter (attached to a shape or placed in a scene)."""
    if not dr.is_jit_v(mi.Float):
        raise ValidateError(f"the emitter validator runs in a JIT variant (llvm_ad_rgb, "
                            f"cuda_ad_rgb, ...), not {mi.variant()}; pass --variant llvm_ad_rgb")
    kind = kind_of(emitter)
    python = type(emitter) is not mi.Emitter
    if shape_spec is not None and kind != "surface":
        raise ValidateError("--set shape.* attaches a surface emitter to a shape; this emitter "
                            "is not a surface emitter, drop the shape")
    setup = Setup(emitter, kind, python)
    if kind == "surface":
        _attach(setup, shape_spec)
    elif kind in ("infinite", "direction"):
        setup.scene = mi.load_dict({"type": "scene", "emitter": emitter,
                                    "shape": {"type": "sphere"}})
        bs = setup.scene.bbox().bounding_sphere()
        setup.center, setup.radius = np.array(bs.center, np.float64).ravel(), float(bs.radius)
        if not python:
            setup.bsphere_radius = max(RAY_EPSILON, setup.radius * (1.0 + RAY_EPSILON))
            setup.sun = sun_cone(emitter)
    else:
        _locate(setup)
    return setup


def sun_cone(emitter) -> tuple | None:
    """(to_world⁻¹, sun direction, cos θ_sun) of Mitsuba's ``sunsky`` or ``timed_sunsky``
    (None for any other emitter), in float32 as include/mitsuba/render/sunsky.h (v3.9.1) tests
    a direction against the sun: ``hit_sun`` (line 946) is dot(sph_to_dir(sun_angles),
    normalize(to_world⁻¹ d)) ≥ cos(m_sun_half_aperture), m_sun_half_aperture =
    deg_to_rad(sun_aperture / 2) (sunsky.h:205; the aperture read back from the plugin's
    description).  sunsky's sun_angles = dir_to_sph(to_world⁻¹ sun_direction)
    (src/emitters/sunsky.cpp:257); timed_sunsky's move with the time (timed_sunsky.cpp:321-336)
    and no parameter exposes them: its sun at the validator's time 0 is read back from
    sample_direction (:func:`_sampled_sun`)."""
    name = emitter.class_name()
    if name not in ("SunskyEmitter", "TimedSunskyEmitter"):
        return None
    params = mi.traverse(emitter)
    if "to_world" not in params.keys():
        return None
    found = re.search(r"Sun aperture = ([0-9.eE+-]+)", str(emitter))
    aperture = float(found.group(1)) if found else 0.5358
    inv = params["to_world"].inverse()
    cos_half = dr.cos(dr.deg2rad(mi.Float(0.5) * mi.Float(aperture)))
    if name == "TimedSunskyEmitter":
        sun = _sampled_sun(emitter, cos_half)
        return None if sun is None else (inv, inv @ sun, cos_half)
    if "sun_direction" not in params.keys():
        return None
    angles = mi.dir_to_sph(inv @ params["sun_direction"])
    return inv, mi.sph_to_dir(angles.x, angles.y), cos_half


def _sampled_sun(emitter, cos_half) -> mi.Vector3f | None:
    """The world direction of the sun's centre as the emitter's sample_direction draws it at
    time 0 (sunsky.h:405-411: sample.x ≥ the sky's sampling weight w picks the sun, whose
    sample ((x − w)/(1 − w), y) warp::square_to_uniform_cone maps to the cone's axis at
    (0.5, 0.5), and Frame3f(sph_to_dir(sun_angles)).to_world gives that axis back exactly,
    line 902).  A sample x draws the sun when its directions at y = 0.25 and 0.75 and the
    one at x = 1 − 2⁻²⁴ all lie within the sun's cone of each other (a sky sample moves far
    with y); w is the least such float32 x, found by bisection on the float32 values (w is
    within 4e-5 of 1 for timed_sunsky's low sun at turbidity 10).  None when no sample reaches
    the sun."""
    cos2 = math.cos(2.2 * math.acos(float(np.ravel(cos_half)[0])))   # twice the cone, and some

    def draw(x: np.ndarray, y: float):
        it = dr.zeros(mi.Interaction3f, len(x))
        ds, _ = emitter.sample_direction(it, point2(np.stack([x, np.full_like(x, y)], 1)))
        return ds, probe.to_numpy(ds.d, len(x)).astype(np.float64)

    top = draw(np.array([1 - 2.0 ** -24], np.float32), 0.5)[1][0]
    if not np.all(np.isfinite(top)) or np.linalg.norm(top) == 0:
        return None

    def sun(x: np.ndarray) -> np.ndarray:
        a, b = draw(x, 0.25)[1], draw(x, 0.75)[1]
        return ((np.sum(a * b, 1) >= cos2) & (a @ top >= cos2) & (b @ top >= cos2))

    # bisection on the float32 bit patterns (ordered like the values for x >= 0)
    lo, hi = np.float32(0).view(np.int32), np.float32(1 - 2.0 ** -24).view(np.int32)
    if not sun(np.array([hi], np.int32).view(np.float32))[0]:
        return None
    if sun(np.array([lo], np.int32).view(np.float32))[0]:
        hi = lo
    while hi - lo > 1:                                # sun(hi), not sun(lo)
        mid = lo + (hi - lo) // 2
        if sun(np.array([mid], np.int32).view(np.float32))[0]:
            hi = mid
        else:
            lo = mid
    w = np.array([hi], np.int32).view(np.float32)[0]
    one, half = np.float32(1), np.float32(0.5)
    centre = np.float32(w + half * (one - w))
    up, down = [centre], [centre]
    for _ in range(8):
        up.append(np.nextafter(up[-1], np.float32(2)))
        down.append(np.nextafter(down[-1], np.float32(-1)))
    tries = np.array(down[::-1] + up[1:], np.float32)
    remapped = (tries - w) / (one - w)               # float32, as sunsky.h:411 divides
    x = tries[int(np.argmin(np.abs(remapped.astype(np.float64) - 0.5)))]
    ds, d = draw(np.array([x], np.float32), 0.5)
    # the check that x draws the centre of a cone of the sun's aperture: (x, 0) and
    # (x, 1 − 2⁻²⁴) land on its rim on either side (a sky sample near the zenith, where y
    # moves nothing, passes the test above when no sample draws the sun: sun_scale 0)
    rim = np.concatenate([draw(np.array([x], np.float32), y)[1] for y in (0.0, 1 - 2.0 ** -24)])
    one_minus = 1.0 - float(np.ravel(cos_half)[0])
    ok = (np.all(np.abs((1.0 - rim @ d[0]) / one_minus - 1.0) < 0.05)
          and abs((1.0 - rim[0] @ rim[1]) / (4.0 * one_minus) - 1.0) < 0.1)
    return ds.d if ok else None


def sun_rim_ulps(sun: tuple, d: np.ndarray) -> np.ndarray:
    """Per direction d (N, 3): dot(sun, normalize(to_world⁻¹ d)) − cos θ_sun in float32, in
    steps of 2⁻²⁴ (the float32 spacing just below 1): ≥ 0 inside the sun's cone by sunsky.h's
    own test, < 0 outside."""
    inv, sun_dir, cos_half = sun
    local = dr.normalize(inv @ probe.to_vectors(d))
    return probe.to_numpy(dr.dot(sun_dir, local) - cos_half, len(d)) / 2.0 ** -24


def _attach(setup: Setup, shape_spec) -> None:
    shape = setup.emitter.get_shape()
    if shape is None:
        spec = dict(shape_spec or DEFAULT_SHAPE)
        try:
            shape = mi.load_dict({**spec, "emitter": setup.emitter})
        except Exception as exc:
            raise ValidateError(f"cannot attach the emitter to the shape {spec!r} "
                                f"({str(exc).splitlines()[-1][:200]}); give a shape type such "
                                f"as rectangle, disk, sphere or cube") from exc
    elif shape_spec is not None:
        raise ValidateError("the emitter is already attached to a shape; drop --set shape.*")
    setup.shape, setup.shape_name = shape, shape.class_name()
    # a scene of the shape alone: meshes (cube, obj, ply) intersect rays only through one
    setup.scene = mi.load_dict({"type": "scene", "shape": shape})
    setup.flipped = bool(shape.has_flipped_normals())
    bbox = shape.bbox()
    lo, hi = np.array(bbox.min, np.float64).ravel(), np.array(bbox.max, np.float64).ravel()
    setup.center, setup.radius = 0.5 * (lo + hi), float(0.5 * np.linalg.norm(hi - lo))


def _locate(setup: Setup) -> None:
    it = dr.zeros(mi.Interaction3f, 1)
    it.p = mi.Point3f(3.0, 5.0, 7.0)
    ds, _ = setup.calls.sample_direction(it, mi.Point2f(0.5, 0.5))
    setup.center = probe.to_numpy(ds.p, 1)[0]
    params = mi.traverse(setup.emitter)
    if "to_world" in params.keys() and "cutoff_angle" in params.keys():
        m = np.array(params["to_world"].matrix, np.float64).reshape(4, 4)
        axis = m[:3, :3] @ np.array([0.0, 0.0, 1.0])
        setup.axis = axis / np.linalg.norm(axis)
        setup.cutoff_deg = float(np.ravel(params["cutoff_angle"])[0])


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def sphere_dirs(r: np.random.Generator, n: int) -> np.ndarray:
    z = 2.0 * r.random(n) - 1.0
    phi = 2.0 * np.pi * r.random(n)
    s = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)


def cone_dirs(r: np.random.Generator, n: int, axis: np.ndarray, cos_max: float) -> np.ndarray:
    """n directions uniform in the cone of half-angle acos(cos_max) about ``axis``."""
    z = 1.0 - r.random(n) * (1.0 - cos_max)
    phi = 2.0 * np.pi * r.random(n)
    s = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    local = np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)
    return local @ basis(axis)


def ref_groups(setup: Setup, n: int, seed: int) -> list[RefGroup]:
    """The reference points of ``setup`` (see the module docstring), n lanes per group."""
    r = rng(seed, "refs")
    c, R = setup.center, setup.radius
    if setup.kind == "position":
        d = sphere_dirs(r, n)
        if setup.axis is not None:
            cos_max = math.cos(math.radians(min(89.0, 1.3 * setup.cutoff_deg)))
            d[: n // 2] = cone_dirs(r, n // 2, setup.axis, cos_max)
        return [RefGroup(f"at distance {k:g} from the light", "near", c + k * d, chi2=False)
                for k in (0.5, 1.0, 2.0)]
    if setup.kind == "direction":
        inside = c + R * 0.9 * np.cbrt(r.random((n, 1))) * sphere_dirs(r, n)
        return [RefGroup("inside the scene's bounding sphere", "inside", inside, chi2=False),
                RefGroup("outside the scene's bounding sphere", "outside",
                         c + 2.0 * R * sphere_dirs(r, n), chi2=False)]
    if setup.kind == "infinite":
        off = c + 0.5 * R * np.cbrt(r.random((n, 1))) * sphere_dirs(r, n)
        off[0] = c + 0.5 * R * unit(np.array([0.3, -0.5, 0.8]))
        return [RefGroup("the scene centre", "inside", np.tile(c, (n, 1))),
                RefGroup("inside the bounding sphere", "inside", off)]
    return _surface_refs(setup, n, r)


def _surface_refs(setup: Setup, n: int, r) -> list[RefGroup]:
    c, R, shape = setup.center, setup.radius, setup.shape
    groups = [RefGroup("outside, 3 bounding radii", "outside",
                       np.tile(c + 3.0 * R * unit(np.array([0.4, -0.3, 0.85])), (n, 1))),
              RefGroup("outside, 1.5 bounding radii", "outside",
                       np.tile(c + 1.5 * R * unit(np.array([-0.5, 0.6, 0.6])), (n, 1)))]
    if setup.shape_name in FLAT:
        ps = shape.sample_position(0.0, mi.Point2f(0.5, 0.5))
        nrm = probe.to_numpy(ps.n, 1)[0]
        t = unit(np.cross(nrm, [0.3, 0.5, 0.7]))
        off = unit(nrm + 0.4 * t)
        groups = [RefGroup("in front, 1.5 bounding radii", "front",
                           np.tile(c + 1.5 * R * off, (n, 1))),
                  RefGroup("in front, 0.3 bounding radii", "front",
                           np.tile(c + 0.3 * R * off, (n, 1))),
                  RefGroup("behind, 1.5 bounding radii", "behind",
                           np.tile(c - 1.5 * R * off, (n, 1)))]
    if setup.shape_name in CLOSED:
        d = sphere_dirs(r, n)
        d[0] = unit(np.array([0.2, 0.7, -0.4]))
        si = setup.scene.ray_intersect(mi.Ray3f(mi.Point3f(*map(float, c)),
                                                probe.to_vectors(d)))
        hit = probe.to_numpy(si.p, n)
        ok = np.array(si.is_valid(), bool).reshape(-1)
        hit[~ok] = hit[ok][0] if ok.any() else c
        inner = R / math.sqrt(3.0)
        groups += [RefGroup("on the surface, as a ray from inside hits it", "on", hit),
                   RefGroup("inside, the centre", "inside", np.tile(c, (n, 1))),
                   RefGroup("inside, off-centre", "inside",
                            np.tile(c + 0.4 * inner * unit(np.array([0.6, -0.2, 0.3])),
                                    (n, 1)))]
    return groups


def interaction(p: np.ndarray, wavelengths=None) -> mi.SurfaceInteraction3f:
    """An interaction of len(p) lanes at points p; in spectral variants ``wavelengths`` (nm,
    (n, C)), by default probe.default_wavelengths on every lane."""
    it = probe.interaction(np.array([0.0, 0.0, 1.0]), n=len(p), wavelengths=wavelengths)
    it.p = mi.Point3f(*(mi.Float(np.ascontiguousarray(p[:, k], np.float32)) for k in range(3)))
    return it


def wavelengths(n: int, r: np.random.Generator | None = None):
    """(the wavelengths of n lanes, the width they are uniform over).

    Spectral variants: with ``r``, uniform on [MI_CIE_MIN, MI_CIE_MAX] per lane and channel,
    and the width MI_CIE_MAX − MI_CIE_MIN (Mitsuba's sample_wavelengths weight L(λ)/p(λ) has
    the mean ∫ L(λ) dλ over that range: measured 592.8 for constant radiance 1.5, against
    470 · mean L(uniform λ) = 592.9); without ``r`` the fixed probe.default_wavelengths and 1.
    Other variants: (None, 1.0), the wavelengths being RGB channels.
    """
    if not mi.is_spectral:
        return None, 1.0
    k = dr.size_v(mi.UnpolarizedSpectrum)
    if r is None:
        return np.tile(probe.default_wavelengths(), (n, 1)), 1.0
    lo, hi = float(mi.MI_CIE_MIN), float(mi.MI_CIE_MAX)
    return lo + (hi - lo) * r.random((n, k)), hi - lo


def surface_interaction(n: int, lam=None) -> mi.SurfaceInteraction3f:
    """n zeroed lanes carrying the wavelengths ``lam`` ((n, C), spectral variants)."""
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    if mi.is_spectral:
        si.wavelengths = probe.interaction(np.array([0.0, 0.0, 1.0]), n=n,
                                           wavelengths=lam).wavelengths
    return si


def point2(u: np.ndarray) -> mi.Point2f:
    return mi.Point2f(mi.Float(np.ascontiguousarray(u[:, 0], np.float32)),
                      mi.Float(np.ascontiguousarray(u[:, 1], np.float32)))


def float_(x: np.ndarray) -> mi.Float:
    return mi.Float(np.ascontiguousarray(x, np.float32))

