r"""Mitsuba 3.9.1's built-in emitters as validation cases, and the findings that explain
their failing rows (matched by signature, :mod:`.signatures`).

Finding ``sphere_emitter_inside`` (src/shapes/sphere.cpp at 478e193a, ``sample_direction``
lines 256-259 and ``pdf_direction`` lines 330-336): sample_direction treats a reference point
as outside when |p − c|² > (r(1 ∓ RayEpsilon))² (− without, + with flip_normals) and then
samples the cone of directions to the sphere (pdf 1/(2π(1 − cos θ_max))), else it samples by
area (pdf = dist²/(A |cos θ'|)); pdf_direction treats it as outside when r/|p − c| <
1 − 2⁻²⁴.  The two thresholds differ by ~RayEpsilon = 8.9e-5 relative, and points on the
sphere as a float32 ray intersection computes them fall between them: there ds.pdf ≠
pdf_direction(ds) (with flip_normals, as in a camera inside an emitting sphere, area pdf
against the cone's ≈ 1/2π; without, the cone's against the area pdf of a sample at
distance ≈ 0), and the MIS weights of next-event estimation and BSDF sampling do not sum to
one: +0.25 % of Le per bounce in ``phonglab check``'s enclosure (docs/checks.md).
Reproducer: tests/repro/sphere_emitter_inside.py.

Finding ``projector-eval-direction-unmasked`` (src/emitters/projector.cpp:272-295):
eval_direction lacks the frustum mask of sample_direction (line 212), so a reference point
behind the projector gets a negative intensity (reproducer
tests/repro/projector_eval_direction_unmasked.py).

Findings ``sunsky-sun-rim-pdf`` and ``sunsky-sun-rim-weight``
(include/mitsuba/render/sunsky.h:430, 946): sample_direction counts every sun sample as a sun
hit while pdf_direction and eval test dot(sun, d) ≥ cos θ_sun in float32, which samples on
the cone's rim fail by 1-3 steps of 2⁻²⁴: ds.pdf and the weight carry the sun there,
pdf_direction and eval_direction the sky alone (145 of 65536 samples at latitude 0, 20 of
timed_sunsky's; reproducer tests/repro/sunsky_sun_rim_pdf.py).  The validator's tolerances
never absorb these lanes (emitter/identities.sun_rim): the findings explain them.

:data:`CATALOGUE` is the emitter conformance table (docs/conformance-emitters.md, ``make
conformance``): :func:`catalogue_cases` (every 3.9.1 emitter that loads standalone),
:data:`FINDINGS`, :data:`LEFT_OUT`; :func:`cases` is the older label -> (spec, shape, known)
view of the first eleven the tests use.
"""

from __future__ import annotations

from ..conformance import Catalogue, Finding, KindCase, ValidatorIssue, with_known
from .signatures import InvalidSample, NegativeOnly, SphereSurfaceBand, SunConeRim

_SPHERES = ("area (sphere)", "area (sphere, flip_normals)")
_SPHERE_CAUSE = (
    "sample_direction treats a reference point as inside the sphere when |p − c|² ≤ "
    "(r(1 ∓ RayEpsilon))² (lines 256-259) and samples by area there, pdf_direction when "
    "r/|p − c| ≥ 1 − 2^-24 (lines 330-336) and returns the cone's pdf otherwise: at points on "
    "the sphere as a float32 ray from inside computes them (where next-event estimation "
    "starts) ds.pdf ≠ pdf_direction(ds), and the MIS weights of emitter and BSDF sampling no "
    "longer sum to one: +0.25 % of Le per bounce in `phonglab check`'s sphere enclosure "
    "(docs/checks.md)")
_SPHERE_MEASURED = ("2515 of 16384 float32 points on the sphere (15.4 %) have ds.pdf ≠ "
                    "pdf_direction(ds), e.g. ds.pdf 0.265819 against pdf_direction 0.159233 "
                    "(1/2π, the cone's; flip_normals)")

_SUN_RIM_LABELS = ("sunsky", "sunsky (equator)", "timed_sunsky")
_SUN_RIM_CAUSE = (
    "sample_direction decides whether its direction hits the sun by another test than "
    "pdf_direction (line 451) and eval (lines 319-321), which apply hit_sun, dot(sun, "
    "normalize(to_world⁻¹ d)) ≥ cos θ_sun (line 946), in float32: `sun_hit = !pick_sky || "
    "hit_sun(sun_angles, sample_dir)` (line 430) counts every direction drawn from the sun's "
    "cone as a hit untested, and tests a sky sample on the unnormalized sample_dir.  The "
    "sun's half aperture is 0.268 deg (1 − cos θ_sun = 1.09e-5, 183 float32 steps below 1): "
    "a direction sample_sun draws at the cone's rim (warp::square_to_uniform_cone at the "
    "disk's edge then Frame3f::to_world, line 903) can round 1-3 steps outside the test, and "
    "a sky sample's two tests differ by up to a few steps, so within ~4 steps of the rim the "
    "same ds.d is sun to sample_direction and sky to pdf_direction and eval (or, for a sky "
    "sample, the reverse): there ds.pdf and the weight carry the sun, pdf_direction and eval "
    "the sky's alone.  Which samples do depends on the sun's direction and the reference "
    "point (none of 65536 from the origin at the default place, Tokyo, though the table's "
    "other reference points meet one there).  A render's next-event estimation counts the "
    "sun along those directions, BSDF sampling (and MIS weights from pdf_direction) does "
    "not.  timed_sunsky shares the code (its sun at the validator's time 0 is read back from "
    "its own sample_direction, emitter/setup.sun_cone).  The fix is one test for both: "
    "hit_sun on normalize(to_world⁻¹ d) for every sample")
_SUN_RIM_MEASURED = (
    "sunsky at latitude 0 (2010-07-10 15:00): 145 of the 40095 sun samples of 65536 from the "
    "origin have ds.pdf 8959.3 against pdf_direction 0.102..0.103, each 1 or 2 float32 steps "
    "outside the cone by hit_sun's test (weight x ds.pdf (20970.4, 16957.9, 12044.2) against "
    "eval_direction (0.2025, 0.2236, 0.2402) on the first); latitude -20: 230 (1-3 steps), "
    "10: 3, Tokyo (default): 0; timed_sunsky (default): 20 of 23545")

#: Every Mitsuba 3.9.1 behaviour behind a failing row of the emitter table.
FINDINGS: tuple[Finding, ...] = (
    Finding("sphere_emitter_inside", "pdf", _SPHERES, "src/shapes/sphere.cpp:256",
            _SPHERE_CAUSE, _SPHERE_MEASURED, "ds.pdf = pdf_direction(ds) on every lane",
            "tests/repro/sphere_emitter_inside.py",
            excerpt="Float radius_adj = m_radius.value() * (m_flip_normals ?",
            rows=("ds.pdf = pdf_direction(ds)",),
            region=SphereSurfaceBand()),
    Finding("mesh-vertex-normal-solid-angle", "chi2", ("area (obj mesh, vertex normals)",),
            "src/render/mesh.cpp:907",
            "Mesh::sample_position sets ps.n to the interpolated vertex normal (lines 907-913) "
            "and Shape::sample_direction / pdf_direction convert the area density to solid "
            "angle with |d·ps.n| (src/render/shape.cpp:106-108, 118-121; a BSDF hit's record "
            "takes si.sh_frame.n, include/mitsuba/render/records.h:77), while the Jacobian of "
            "the map from the surface to directions has the triangle's geometric normal: "
            "ds.pdf = pdf_direction is not the density of the sampled directions (off by "
            "|cos_geo|/|cos_shading|, unbounded near the silhouette) and emitter sampling "
            "of such a light is biased, by an amount and sign that depend on the scene: in the "
            "reproducer's scene (the octahedron light 2 above a diffuse plane, seen from "
            "(0, -6, 6)) path (MIS) renders the plane -4.3 % (5.5 standard errors) against "
            "prb_basic (BSDF sampling only).  The table's χ² row integrates pdf_direction over "
            "the visible surface to 1.057 and 0.650 from its two reference points (default "
            "sizes; 1.158 and 0.740 on --quick's lattice: the integrand |cos_geo|/|cos_shading| "
            "is unbounded at the silhouette), where the fraction of samples that reach it is "
            "0.319 and 0.347 (11.8 % and 4.0 % more go to hidden points).  Reported upstream as "
            "mitsuba3 issue #1952 (open)",
            "ds.pdf / (dist²/(A |cos_geo|)) over 6169 visible samples: min 0.438, max 21316, "
            "mean 6.429; image mean: path 0.02224 ± 0.00006, prb_basic 0.02322 ± 0.00017 "
            "(-4.25 %)",
            "∫ pdf_direction dω over the directions that reach the light = the fraction of "
            "samples that do (flat triangles: 0.375 and 0.500, the chi2 passes)",
            "tests/repro/mesh_vertex_normal_emitter_pdf.py",
            excerpt="ps.n = dr::fmadd(n0, (1.f - b.x() - b.y()),",
            rows=("direction sampling matches pdf_direction (min p-value)",)),
    Finding("sunsky-sun-pdf-normalization", "chi2", ("sunsky", "timed_sunsky"),
            "include/mitsuba/render/sunsky.h:946",
            "compute_pdfs gives the sun the uniform-cone density 1/(2π(1 − cos θ_sun)) (lines "
            "929-932) on the directions hit_sun accepts, dot(sun, normalize(to_world⁻¹ d)) ≥ "
            "cos θ_sun in float32 (line 946); 1 − cos θ_sun = 1.09e-5 is 183 float32 steps, so "
            "the rounding of the dot product moves the accepted cone's edge by about a step, "
            "its solid angle by ~0.5 %, in a direction that depends on where the sun stands, "
            "while sample_sun draws from the exact cone (line 903): the sun's pdf_direction "
            "does not integrate to 1.  The χ² test sees it where the sun holds (nearly) all "
            "the samples, with the sky off; with the sky on (61 % sun) the excess stays "
            "under its Poisson error at 10⁶ samples (the table's bins at sky_scale 0: ∫ "
            "pdf_direction 1.0037 from the scene centre, χ² p = 5e-7 at 10⁶ samples)",
            "∫ pdf_direction dω of the sun alone (sky_scale 0, default place): 1.0052 ± 0.0005 "
            "(8 x 2^20 float32 directions on a cap twice the sun's radius)",
            "1", "tests/repro/sunsky_sun_pdf_normalization.py",
            excerpt="return dr::dot(sun_dir, local_wo) >= dr::cos(m_sun_half_aperture);",
            rows=("direction sampling matches pdf_direction (min p-value)",),
            at=(("sky_scale", (0.0, 1e-3)),)),
    Finding("timed_sunsky-negative-rgb", "finite", ("timed_sunsky",),
            "include/mitsuba/render/sunsky.h:655",
            "the sky's Hosek-Wilkie fit eval_sky (lines 642-655: c1 c2 R, no clamp) has a "
            "negative blue channel within ~0.07 deg of the horizon, which nothing documents; "
            "the sun's RGB (lines 580-581) is negative in blue too while the sun disc is under "
            "~1 deg high, where timed_sunsky's default day puts it part of the time -- that "
            "part is documented (src/emitters/timed_sunsky.cpp:171-176: the sun's radiance is "
            "ill-represented in linear sRGB, negative values are left un-clamped).  A render "
            "gets negative blue light from a low sun (an RGB film keeps it)",
            "eval within 1 deg of the horizon: 55 of 4096 directions have a negative channel, "
            "the lowest -0.0008935, the highest at 0.073 deg elevation; sample_direction: 1474 "
            "of 4096 weights (36 %) have a negative channel",
            "radiance >= 0", "tests/repro/timed_sunsky_negative_rgb.py",
            excerpt="return c1 * c2 * sky_radiance;",
            rows=("sample_direction: ds.pdf, ds.d, weight", "eval_direction at the sampled ds",
                  "eval along rays from the reference points", "sample_ray: weight, ray"),
            region=NegativeOnly()),
    Finding("projector-eval-direction-unmasked", "finite", ("projector",),
            "src/emitters/projector.cpp:272",
            "eval_direction (lines 272-295) evaluates the texture at ds.uv and divides by "
            "it_local.z² (−n·d) without the frustum test `uv in [0, 1]², it_local.z > 0` that "
            "sample_direction applies (line 212): behind the projector it returns a negative "
            "intensity (±inf on its plane).  No render pays: Mitsuba's integrators evaluate an "
            "emitter direction only where ds.pdf != 0 (path.cpp:248-255, prb.py, "
            "prb_projective.py, direct_projective.py)",
            "eval_direction = -3.219 at (0.1, 0.2, -1) behind the default projector, where "
            "sample_direction returns pdf 0 and weight 0",
            "eval_direction = 0 (no light) outside the frustum",
            "tests/repro/projector_eval_direction_unmasked.py",
            excerpt="Spectrum eval_direction(const Interaction3f &it,",
            rows=("eval_direction at the sampled ds",), region=InvalidSample()),
    Finding("sunsky-sun-rim-pdf", "pdf", _SUN_RIM_LABELS, "include/mitsuba/render/sunsky.h:430",
            _SUN_RIM_CAUSE, _SUN_RIM_MEASURED,
            "ds.pdf = pdf_direction(ds) on every lane (one test of the sun's cone for both)",
            "tests/repro/sunsky_sun_rim_pdf.py",
            excerpt="Float sun_hit = !pick_sky || hit_sun(sun_angles, sample_dir);",
            rows=("ds.pdf = pdf_direction(ds)",),
            region=SunConeRim()),
    Finding("sunsky-sun-rim-weight", "weight", _SUN_RIM_LABELS,
            "include/mitsuba/render/sunsky.h:430",
            "the same sun samples (finding sunsky-sun-rim-pdf): sample_direction's weight "
            "carries the sun's radiance (eval with that sun_hit, line 436) while eval and "
            "eval_direction (through eval, lines 319-321) re-test hit_sun (line 946) and "
            "return the sky's alone",
            "weight·ds.pdf = sky + sun radiance against eval_direction = sky only on the lanes "
            "of sunsky-sun-rim-pdf (rel_diff ≈ 1, 1024 times 2^-10)",
            "weight·ds.pdf = eval_direction(ds) = eval along ds.d",
            "tests/repro/sunsky_sun_rim_pdf.py",
            excerpt="Float sun_hit = !pick_sky || hit_sun(sun_angles, sample_dir);",
            rows=("weight x ds.pdf = eval_direction(ds)",
                  "weight x ds.pdf = eval at the traced point"),
            region=SunConeRim()),
)

SPHERE_INSIDE = FINDINGS[0].known()

#: A 4 x 8 RGB environment (a sky-like gradient with one bright texel), written by
#: :func:`envmap_file` for the envmap case.
ENVMAP_SIZE = (4, 8)


def envmap_array():
    """The environment of the envmap case: (h, w, 3) float32 (numpy, fixed values)."""
    import numpy as np

    h, w = ENVMAP_SIZE
    y = (np.arange(h) + 0.5) / h
    img = np.zeros((h, w, 3), np.float32)
    img[...] = (0.2 + 0.8 * (1.0 - y))[:, None, None] * np.array([0.6, 0.8, 1.0], np.float32)
    img[1, 5] = [8.0, 7.0, 5.0]
    return img


def envmap_file(path) -> str:
    """Write :func:`envmap_array` as an EXR environment map to ``path``; its path."""
    import mitsuba as mi

    mi.Bitmap(envmap_array()).write(str(path))
    return str(path)


#: An octahedron (|x| + |y| + |z| = 1) as Wavefront OBJ, faces wound outwards.
OCTAHEDRON_OBJ = """v 1 0 0
v -1 0 0
v 0 1 0
v 0 -1 0
v 0 0 1
v 0 0 -1
f 1 3 5
f 1 6 3
f 1 5 4
f 1 4 6
f 2 5 3
f 2 3 6
f 2 4 5
f 2 6 4
"""


def mesh_file() -> str:
    """:data:`OCTAHEDRON_OBJ` written once into phonglab's temporary folder (Mitsuba's
    ``obj`` plugin reads a file; no mesh ships with Mitsuba or phonglab); its path."""
    import tempfile
    from pathlib import Path

    path = Path(tempfile.gettempdir()) / "phonglab-conformance" / "octahedron.obj"
    if not path.is_file() or path.read_text() != OCTAHEDRON_OBJ:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{id(path)}.tmp")
        tmp.write_text(OCTAHEDRON_OBJ)
        tmp.replace(path)
    return str(path)


def cases(envmap_path=None) -> dict[str, tuple[dict, dict | None, dict]]:
    """label -> (emitter spec, shape spec or None, known) for Mitsuba's built-in emitters."""
    known_sphere = {"pdf": [FINDINGS[0].known()], "chi2": [FINDINGS[1].known()]}
    out = {
        "point": ({"type": "point", "position": [0.2, -0.1, 0.5], "intensity": 3.0}, None, {}),
        "spot": ({"type": "spot", "cutoff_angle": 25.0, "beam_width": 15.0, "intensity": 2.0,
                  "to_world": _look_at()}, None, {}),
        "directional": ({"type": "directional", "direction": [0.3, -0.2, -1.0],
                         "irradiance": 2.0}, None, {}),
        "area (rectangle)": ({"type": "area", "radiance": 2.0}, {"type": "rectangle"}, {}),
        "area (disk)": ({"type": "area", "radiance": 2.0}, {"type": "disk"}, {}),
        "area (cube)": ({"type": "area", "radiance": 2.0}, {"type": "cube"}, {}),
        "area (cylinder)": ({"type": "area", "radiance": 2.0}, {"type": "cylinder"}, {}),
        "area (sphere)": ({"type": "area", "radiance": 2.0}, {"type": "sphere"}, known_sphere),
        "area (sphere, flip_normals)": ({"type": "area", "radiance": 2.0},
                                        {"type": "sphere", "flip_normals": True}, known_sphere),
        "constant": ({"type": "constant", "radiance": 1.5}, None, {}),
    }
    if envmap_path is not None:
        out["envmap"] = ({"type": "envmap", "filename": str(envmap_path)}, None, {})
    return out


def _look_at():
    import mitsuba as mi

    return mi.ScalarTransform4f().look_at(origin=[0.0, 0.0, 1.0], target=[0.3, 0.1, 0.0],
                                          up=[0.0, 1.0, 0.0])


_NOTES = {
    "point": "isotropic point light", "spot": "spot, 25 deg cutoff, 15 deg beam",
    "directional": "directional, oblique", "area (rectangle)": "one-sided rectangle",
    "area (disk)": "one-sided disk", "area (cube)": "closed mesh (cube)",
    "area (cylinder)": "open cylinder", "area (sphere)": "sphere, seen from outside and inside",
    "area (sphere, flip_normals)": "emitting inwards (a camera inside an emitting sphere)",
    "constant": "uniform environment",
}


def catalogue_cases() -> list[KindCase]:
    """Every case of the emitter conformance table, in table order (sets phonglab's default
    variant when none is active: the spot's transform needs one)."""
    from ... import registration
    registration.register()
    import mitsuba as mi

    out = [KindCase(label, spec, None, {}, _NOTES[label],
                    {"shape": shape} if shape is not None else {})
           for label, (spec, shape, _known) in cases().items()]
    obj = {"type": "obj", "filename": mesh_file()}
    out += [
        KindCase("area (obj mesh, face normals)", {"type": "area", "radiance": 2.0}, None, {},
                 "octahedron from an OBJ file, flat triangles",
                 {"shape": {**obj, "face_normals": True}}),
        KindCase("area (obj mesh, vertex normals)", {"type": "area", "radiance": 2.0}, None, {},
                 "the same octahedron with interpolated vertex normals (the OBJ default)",
                 {"shape": obj}),
        KindCase("envmap", {"type": "envmap", "bitmap": mi.Bitmap(envmap_array())}, None, {},
                 f"{ENVMAP_SIZE[0]} x {ENVMAP_SIZE[1]} bitmap, one bright texel"),
        KindCase("projector", {"type": "projector", "fov": 40.0,
                               "irradiance": {"type": "bitmap",
                                              "bitmap": mi.Bitmap(0.1 * envmap_array())}},
                 None, {}, "textured projector, 40 deg"),
        KindCase("sunsky", {"type": "sunsky"}, None, {},
                 "sun and sky at its default date and place (Tokyo, 2010-07-10 15:00)"),
        KindCase("sunsky (equator)", {"type": "sunsky", "latitude": 0.0}, None, {},
                 "the same date and time at latitude 0: sun samples on the sun cone's rim "
                 "round outside it (finding sunsky-sun-rim-pdf)"),
        KindCase("timed_sunsky", {"type": "timed_sunsky"}, None, {},
                 "sun and sky averaged over a day (defaults)"),
        KindCase("directionalarea", {"type": "directionalarea", "radiance": 2.0}, None, {},
                 "rectangle emitting along its normal only",
                 {"shape": {"type": "rectangle"}},
                 skip="loads (attached to a shape), but its flags are DeltaDirection | Surface "
                      "and the emitter validator has no model of a delta-direction surface "
                      "emitter yet (emitter/setup.kind_of takes it for a directional light and "
                      "refuses the shape): not validated"),
    ]
    return with_known(out, FINDINGS)


#: Mitsuba 3.9.1 emitter plugins (src/emitters/*.cpp) not validated by the table, and why.
LEFT_OUT: dict[str, str] = {
    "directionalarea": "in the table as a skipped row: the validator has no model of a "
                       "delta-direction surface emitter (DeltaDirection | Surface) yet",
}

#: Rows of the emitter table that fail because of the validator while its fix is open (the
#: fixed ones are told in docs/validator-fixes.md).
VALIDATOR_ISSUES: tuple[ValidatorIssue, ...] = ()

CATALOGUE = Catalogue(
    catalogue_cases, "phonglab.validate.emitter.builtins.catalogue_cases()", FINDINGS,
    "phonglab.validate.emitter.builtins.FINDINGS", VALIDATOR_ISSUES, LEFT_OUT,
    tests="tests/test_conformance_kinds.py", case_text="one emitter at one setting")
