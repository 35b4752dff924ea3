"""The ``whitted`` integrator: construction, the seed's formula by hand, path equivalence, Snell.

Cheapest first: parameters and errors → graphics units against a hand computation of
the seed's complete equation (float64 numpy) → radiance units against Mitsuba's ``path``
on identical rays (deterministic: equal to float precision) → rendered images
(identical camera rays per seed: equal; two lights: path picks one at random, so they
agree within the Monte Carlo error, per-pixel z-test at ALPHA with Šidák over pixels) →
refraction through a glass slab (Snell's law, TIR) → glass and gold in front of an
emissive backdrop, whitted's deterministic ray tree against path's random choice.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from scipy import stats

from phonglab.engine.scenes import SCENES_DIR as SCENES, load_scene, scene_defaults
from phonglab.stats import ALPHA, sidak
from phonglab.physics import optics
from phonglab.engine.render import render_scene

# ----------------------------------------------------------------------------- helpers

KD = [0.5, 0.3, 0.2]
KS = [0.3, 0.25, 0.2]
P = 10.0
LIGHT = np.array([1.0, 0.5, 2.0])
I_LIGHT = np.array([4.0, 5.0, 6.0])
I_AMB = np.array([0.1, 0.2, 0.3])
K_AMB = np.array([0.2, 0.4, 0.6])
ABC = (1.0, 0.3, 0.05)


def plane_scene(occluder: bool = False, **integrator):
    """The plane z = 0 (phong k_d=KD, k_s=KS, p=P, id "mat") under one point light at LIGHT."""
    d = {"type": "scene",
         "integrator": {"type": "whitted", **integrator},
         "plane": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([10, 10, 1]),
                   "bsdf": {"type": "phong", "id": "mat",
                            "diffuse_reflectance": {"type": "rgb", "value": KD},
                            "specular_reflectance": {"type": "rgb", "value": KS},
                            "exponent": P}},
         "light": {"type": "point", "position": LIGHT.tolist(),
                   "intensity": {"type": "rgb", "value": I_LIGHT.tolist()}}}
    if occluder:
        # A small ball on the segment from the surface point (0, 0, 0) to the light.
        d["ball"] = {"type": "sphere", "center": (0.5 * LIGHT).tolist(), "radius": 0.1,
                     "bsdf": {"type": "lambert"}}
    return mi.load_dict(d)


def trace(scene, integrator, origins, directions, seed=0):
    """integrator.sample on the given rays with a freshly seeded sampler: (n, 3) numpy."""
    n = len(origins)
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed, n)
    ray = mi.Ray3f(mi.Point3f(*(mi.Float(c) for c in np.asarray(origins, np.float32).T)),
                   mi.Vector3f(*(mi.Float(c) for c in np.asarray(directions, np.float32).T)))
    value, _, _ = integrator.sample(scene, sampler, ray, None, True)
    return np.array(value, dtype=np.float64).T      # Dr.Jit arrays are (channels, n)


def seed_formula(points, eye, shadowed=None, ambient=True, k_amb=K_AMB):
    """The seed's complete equation in float64, phong plane z = 0 (N = +Z), one light."""
    n = np.array([0.0, 0.0, 1.0])
    out = []
    for i, p in enumerate(points):
        v = eye[i] - p
        v /= np.linalg.norm(v)
        to_l = LIGHT - p
        r = np.linalg.norm(to_l)
        l_dir = to_l / r
        refl = 2.0 * np.dot(n, v) * n - v                      # R = 2 (N·V) N − V
        ln, lr = np.dot(l_dir, n), np.dot(l_dir, refl)
        att = ABC[0] + ABC[1] * r + ABC[2] * r * r
        direct = I_LIGHT / att * (np.array(KD) * max(ln, 0.0) + np.array(KS) * max(lr, 0.0) ** P)
        if shadowed is not None and shadowed[i]:
            direct = 0.0 * direct
        out.append((k_amb * I_AMB if ambient else 0.0) + direct)
    return np.array(out)


def camera_rays(points, view):
    """Rays from points + 3·view towards the points (view: unit vector away from the plane)."""
    view = np.asarray(view, np.float64) / np.linalg.norm(view)
    eye = np.asarray(points) + 3.0 * view
    return eye, np.tile(-view, (len(points), 1))


POINTS = np.array([[0.0, 0.0, 0.0], [0.3, -0.4, 0.0], [1.2, 0.9, 0.0], [-2.0, 1.5, 0.0],
                   [1.6, 1.0, 0.0]])
VIEW = [-0.3, -0.2, 1.0]   # oblique, so that L·R differs from L·N


# ----------------------------------------------------------------------------- construction

def test_loads_with_documented_defaults(variant_llvm_rgb):
    w = mi.load_dict({"type": "whitted"})
    assert (w.units, w.max_depth, w.shadows) == ("graphics", 5, True)
    params = w.parameters()
    assert (params["attenuation_constant"], params["attenuation_linear"],
            params["attenuation_quadratic"]) == (1.0, 0.0, 0.0)
    assert "attenuation_linear" in mi.traverse(w)
    assert w.class_name() == "Whitted" and "max_depth=5" in w.to_string()


@pytest.mark.parametrize("props, message", [
    ({"units": "physics"}, "'units' must be"),
    ({"max_depth": 0}, "'max_depth' must lie in"),
    ({"max_depth": -1}, "'max_depth' must lie in"),
    ({"attenuation_constant": 0.0}, "not all 0"),
    ({"attenuation_linear": -1.0}, "must be >= 0"),
    ({"units": "radiance", "attenuation_quadratic": 1.0}, "graphics' only"),
], ids=["units", "depth0", "depth-1", "abc0", "negative", "radiance-attenuation"])
def test_bad_parameters_are_explained(variant_llvm_rgb, props, message):
    with pytest.raises(Exception, match=message):
        mi.load_dict({"type": "whitted", **props})


def test_unknown_ambient_reflectance_id_is_explained(variant_llvm_rgb):
    scene = plane_scene()
    w = mi.load_dict({"type": "whitted", "ambient_reflectance_nope": 0.3})
    with pytest.raises(Exception, match="names no BSDF"):
        trace(scene, w, [[0, 0, 1]], [[0, 0, -1]])


# ----------------------------------------------------------------------------- graphics units

def graphics(**extra):
    return dict(units="graphics", ambient={"type": "rgb", "value": I_AMB.tolist()},
                attenuation_constant=ABC[0], attenuation_linear=ABC[1],
                attenuation_quadratic=ABC[2], max_depth=2, **extra)


def test_graphics_units_match_the_seeds_formula_by_hand(variant_llvm_rgb):
    """I = k_amb I_amb + I/(a + b r + c r²) (k_d (L·N) + k_s (L·R)^p), k_amb given per BSDF id."""
    scene = plane_scene(**graphics(ambient_reflectance_mat={"type": "rgb",
                                                              "value": K_AMB.tolist()}))
    eye, d = camera_rays(POINTS, VIEW)
    got = trace(scene, scene.integrator(), eye, d)
    want = seed_formula(POINTS, eye)
    # Float32 kernel against float64 by hand: a few ulps of the largest term.
    np.testing.assert_allclose(got, want, rtol=2e-5, atol=1e-6)
    # The last point sees the highlight's edge, the first none: both lobes are exercised.
    assert np.ptp(want[:, 0]) > 0.1


def test_ambient_reflectance_defaults_to_diffuse(variant_llvm_rgb):
    scene = plane_scene(**graphics())
    eye, d = camera_rays(POINTS, VIEW)
    got = trace(scene, scene.integrator(), eye, d)
    np.testing.assert_allclose(got, seed_formula(POINTS, eye, k_amb=np.array(KD)),
                               rtol=2e-5, atol=1e-6)


@pytest.mark.parametrize("shadows", [True, False])
def test_shadows_only_visible_lights(variant_llvm_rgb, shadows):
    """shadows=true: the occluded point keeps only its ambient term; false: OpenGL, all lights."""
    scene = plane_scene(occluder=True, **graphics(shadows=shadows))
    pts = POINTS[:2]                 # (0,0,0) is behind the ball, (0.3,−0.4,0) is not
    eye, d = camera_rays(pts, [0.0, -1.0, 1.0])
    got = trace(scene, scene.integrator(), eye, d)
    want = seed_formula(pts, eye, shadowed=[shadows, False], k_amb=np.array(KD))
    np.testing.assert_allclose(got, want, rtol=2e-5, atol=1e-6)


def test_graphics_spot_and_directional_lights(variant_llvm_rgb):
    """Spot: I_i times its falloff (1 inside beam_width, 0 past cutoff_angle), attenuated;
    directional: I_i = its irradiance E, no attenuation (OpenGL), L = −direction."""
    pts = np.array([[0.0, 0.0, 0.0], [0.3, -0.2, 0.0], [6.0, 0.0, 0.0]])
    eye, d = camera_rays(pts, VIEW)
    spot = {"type": "spot", "cutoff_angle": 30.0, "beam_width": 20.0,
            "intensity": {"type": "rgb", "value": I_LIGHT.tolist()},
            "to_world": mi.ScalarTransform4f().look_at(origin=LIGHT.tolist(), target=[0, 0, 0],
                                                       up=[0, 0, 1])}
    integrator = mi.load_dict({"type": "whitted", **graphics()})
    plane = {"type": "scene",
             "plane": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([10, 10, 1]),
                       "bsdf": {"type": "phong",
                                "diffuse_reflectance": {"type": "rgb", "value": KD},
                                "specular_reflectance": {"type": "rgb", "value": KS},
                                "exponent": P}}}
    got = trace(mi.load_dict({**plane, "light": spot}), integrator, eye, d)
    want = seed_formula(pts, eye, k_amb=np.array(KD))
    ambient_only = np.array(KD) * I_AMB
    # (0,0,0) and (0.3,−0.2,0) lie inside the beam (≤ 7° off its axis), (6,0,0) past the cutoff.
    np.testing.assert_allclose(got[:2], want[:2], rtol=2e-5, atol=1e-6)
    np.testing.assert_allclose(got[2], ambient_only, rtol=1e-6)

    E = np.array([0.7, 0.8, 0.9])
    w = np.array([0.3, 0.1, -1.0]) / np.linalg.norm([0.3, 0.1, -1.0])
    sun = {"type": "directional", "direction": w.tolist(),
           "irradiance": {"type": "rgb", "value": E.tolist()}}
    got = trace(mi.load_dict({**plane, "light": sun}), integrator, eye, d)
    n = np.array([0.0, 0.0, 1.0])
    for i, p in enumerate(pts):
        v = (eye[i] - p) / np.linalg.norm(eye[i] - p)
        refl = 2 * v @ n * n - v
        want = np.array(KD) * I_AMB + E * (np.array(KD) * (-w @ n) + np.array(KS)
                                           * max(-w @ refl, 0.0) ** P)
        np.testing.assert_allclose(got[i], want, rtol=2e-5, atol=1e-6)


# ----------------------------------------------------------------------------- radiance units

def sphere_scene(light: str, integrator: dict, res: int = 24, rfilter: str = "box"):
    """A phong ball on a lambert floor, a two-sided lambert card, and the given lights."""
    lights = {
        "point": {"type": "point", "position": [1.0, 2.0, 3.0],
                  "intensity": {"type": "rgb", "value": [5.0, 4.0, 3.0]}},
        "spot": {"type": "spot", "cutoff_angle": 25.0, "beam_width": 15.0,
                 "to_world": mi.ScalarTransform4f().look_at(origin=[-1.0, 1.5, 3.0],
                                                            target=[0, 0, 0], up=[0, 1, 0]),
                 "intensity": {"type": "rgb", "value": [20.0, 20.0, 20.0]}},
    }
    d = {"type": "scene", "integrator": integrator,
         "ball": {"type": "sphere", "radius": 0.8,
                  "bsdf": {"type": "phong", "exponent": 20.0,
                           "diffuse_reflectance": {"type": "rgb", "value": [0.6, 0.2, 0.1]},
                           "specular_reflectance": {"type": "rgb", "value": [0.3, 0.3, 0.3]}}},
         "floor": {"type": "rectangle", "bsdf": {"type": "lambert"},
                   "to_world": mi.ScalarTransform4f().translate([0, 0, -0.8]).scale(4.0)},
         "card": {"type": "rectangle", "bsdf": {"type": "twosided", "b": {"type": "diffuse"}},
                  "to_world": mi.ScalarTransform4f().translate([1.5, 0, 0]).rotate([0, 1, 0], 70)
                  .scale(0.6)},
         "sensor": {"type": "perspective", "fov": 50.0,
                    "to_world": mi.ScalarTransform4f().look_at(origin=[0, -4, 3], target=[0, 0, 0],
                                                               up=[0, 0, 1]),
                    "film": {"type": "hdrfilm", "width": res, "height": res,
                             "rfilter": {"type": rfilter}}}}
    for name in light.split("+"):
        d[name] = lights[name]
    return mi.load_dict(d)


RADIANCE = {"type": "whitted", "units": "radiance", "max_depth": 2}
PATH2 = {"type": "path", "max_depth": 2}


@pytest.mark.parametrize("light", ["point", "spot"])
def test_radiance_units_equal_path_on_identical_rays(variant_llvm_rgb, light):
    """One delta light: path's emitter sample is deterministic and its MIS weight 1, so
    L = L_e + f_r cos θ · I/r² (· spot falloff) is the same computation in both."""
    scene = sphere_scene(light, RADIANCE)
    sensor = scene.sensors()[0]
    res = 24
    u, v = np.meshgrid((np.arange(res) + 0.5) / res, (np.arange(res) + 0.5) / res)
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(mi.Float(u.ravel()), mi.Float(v.ravel())),
                               mi.Point2f(0.5, 0.5))
    sampler = mi.load_dict({"type": "independent"})
    out = {}
    for name, integ in (("whitted", scene.integrator()), ("path", mi.load_dict(PATH2))):
        sampler.seed(7, res * res)
        out[name] = np.array(integ.sample(scene, sampler, mi.Ray3f(ray), None, True)[0]).T
    assert np.count_nonzero(out["path"].max(axis=1) > 0) > res * res // 5   # lit pixels exist
    np.testing.assert_allclose(out["whitted"], out["path"], rtol=1e-6, atol=1e-7)


def test_rendered_images_equal_path_with_one_light(variant_llvm_rgb):
    """Same seed → same camera rays per sample (they come first from the sampler): the
    pixel means agree to float precision, antialiasing included."""
    images = []
    for integ in (RADIANCE, PATH2):
        images.append(render_scene(sphere_scene("point", integ, rfilter="gaussian"), spp=4,
                                   seed=3).image)
    assert images[1].max() > 0.05
    np.testing.assert_allclose(images[0], images[1], rtol=1e-5, atol=1e-6)


def paired_t_test(scene_a, scene_b, spp, passes, seed, what):
    """Paired per-pixel t-test of E[a] = E[b] at ALPHA, Šidák over the pixels.

    Pass k renders both scenes with seed ``seed + k``: the camera rays are the sampler's
    first dimensions, so they are identical in a and b, and the per-pass difference
    d_k = a_k − b_k carries only what differs (path's random choices).  t = mean(d) /
    (std(d)/√passes) has a Student t distribution with passes − 1 degrees of freedom.
    The same test on the image mean catches small global errors.  Pixels where d never
    varies must agree to float precision.
    """
    diffs = []
    for k in range(passes):
        a = np.array(mi.render(scene_a, spp=spp, seed=seed + k), np.float64)
        b = np.array(mi.render(scene_b, spp=spp, seed=seed + k), np.float64)
        diffs.append(a - b)
    diffs = np.array(diffs)
    mean = diffs.mean(axis=0)
    se = diffs.std(axis=0, ddof=1) / np.sqrt(passes)
    noisy = se > 1e-7
    assert noisy.sum() > 20, f"{what}: too few pixels where path varies to test anything"
    # Two families at level sidak(ALPHA, 2) each: the image mean (one test, much more power
    # against a global error) and the pixels (Šidák over them).
    level = sidak(ALPHA, 2)
    per_pass = diffs.mean(axis=(1, 2, 3))
    t_all = abs(per_pass.mean()) / (per_pass.std(ddof=1) / np.sqrt(passes))
    t_crit_all = stats.t.isf(level / 2, passes - 1)
    assert t_all <= t_crit_all, (f"{what}: the image means differ by {per_pass.mean():.4g} "
                                 f"({t_all:.2f} > t_crit {t_crit_all:.2f})")
    t_crit = stats.t.isf(sidak(level, int(noisy.sum())) / 2, passes - 1)
    t = np.where(noisy, np.abs(mean) / np.where(noisy, se, 1.0), 0.0)
    worst = np.unravel_index(np.argmax(t), t.shape)
    if t[worst] > t_crit:
        np.save(f"/tmp/{what.split()[0]}_paired_diffs.npy", diffs)
    assert t[worst] <= t_crit, (f"{what}: pixel {worst} differs by {mean[worst]:.4g} ± "
                                f"{se[worst]:.2g} ({t[worst]:.2f} > t_crit {t_crit:.2f})")
    np.testing.assert_allclose(mean[~noisy], 0.0, atol=1e-5)
    return t[worst], t_crit


def test_rendered_images_agree_within_noise_with_two_lights(variant_llvm_rgb):
    """Two lights: path samples one of them (weight 2 when chosen), whitted sums both; the
    expectations are equal, path's per-pixel variance is the emitter choice.  Power: with
    these counts a 3 % change of the spot light's intensity in whitted alone (an image-mean
    shift of 1.3 %) was detected at t = 4.2 > 3.0 (measured once, 2026-11-21)."""
    paired_t_test(sphere_scene("point+spot", RADIANCE), sphere_scene("point+spot", PATH2),
                  spp=16, passes=32, seed=5, what="whitted(radiance) vs path, two lights")


# ----------------------------------------------------------------------------- refraction

def slab_scene():
    """A glass slab (n = 1.5 in air) 0.5 thick, top face at z = 0."""
    return mi.load_dict({"type": "scene",
                         "slab": {"type": "cube", "bsdf": {"type": "dielectric",
                                                           "int_ior": 1.5, "ext_ior": 1.0},
                                  "to_world": mi.ScalarTransform4f().translate([0, 0, -0.25])
                                  .scale([20.0, 20.0, 0.25])}})


def _children(scene, origins, directions):
    # Imported here: the plugin module subclasses the current variant's mi.SamplingIntegrator,
    # so it can only be imported once a variant is set.
    from phonglab.plugins.whitted import delta_child

    ray = mi.Ray3f(mi.Point3f(*(mi.Float(c) for c in np.asarray(origins, np.float32).T)),
                   mi.Vector3f(*(mi.Float(c) for c in np.asarray(directions, np.float32).T)))
    si = scene.ray_intersect(ray)
    bsdf = si.bsdf(ray)
    out = {}
    for name, kind in (("R", mi.BSDFFlags.DeltaReflection), ("T", mi.BSDFFlags.DeltaTransmission)):
        child, weight, ok = delta_child(si, bsdf, kind, si.is_valid())
        out[name] = (np.array(child.d, np.float64).T, np.array(weight, np.float64).T,
                     np.array(ok, bool))
    n_world = np.array(si.sh_frame.n, np.float64).T
    return out, n_world


ANGLES = np.array([0.0, 20.0, 40.0, 60.0, 80.0])


def _rays_at(angles_deg, z0, down=True):
    th = np.radians(angles_deg)
    d = np.stack([np.sin(th), np.zeros_like(th), -np.cos(th) if down else np.cos(th)], axis=1)
    o = np.stack([np.zeros_like(th), np.zeros_like(th), np.full_like(th, z0)], axis=1)
    return o, d


def test_refraction_into_the_slab_follows_snell(variant_llvm_rgb):
    """Air → glass: n1 sin θ1 = n2 sin θ2, T in the plane of V and N, weights F and 1 − F
    (times 1/η'² = (1/1.5)² for radiance entering the denser medium)."""
    o, d = _rays_at(ANGLES, 1.0)
    ch, n = _children(slab_scene(), o, d)
    t, w_t, ok_t = ch["T"]
    r, w_r, ok_r = ch["R"]
    assert ok_t.all() and ok_r.all()
    v = -d
    np.testing.assert_allclose(optics.snell_residual(v, t, n, 1.0, 1.5), 0.0, atol=2e-6)
    # Coplanar with V and N: T · (V × N) = 0 (V × N = 0 at normal incidence, trivially).
    np.testing.assert_allclose(np.einsum("ij,ij->i", t, np.cross(v, n)), 0.0, atol=1e-6)
    np.testing.assert_allclose(r, optics.reflect(v, n), atol=1e-6)
    F, _ = optics.fresnel_dielectric(np.cos(np.radians(ANGLES)), 1.0 / 1.5)
    np.testing.assert_allclose(w_r[:, 0], F, rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(w_t[:, 0], (1.0 - F) / 1.5 ** 2, rtol=1e-4, atol=1e-6)


def test_beyond_the_critical_angle_only_the_reflected_ray_is_traced(variant_llvm_rgb):
    """Glass → air from inside the slab: θ_c = asin(1/1.5) = 41.81°; below it T exists with
    n2 sin θ = n1 sin θ', above it only R with weight F = 1."""
    angles = np.array([10.0, 30.0, 41.0, 42.5, 60.0, 80.0])
    o, d = _rays_at(angles, -0.25, down=True)              # from the slab's middle downwards
    ch, n = _children(slab_scene(), o, d)
    t, w_t, ok_t = ch["T"]
    r, w_r, ok_r = ch["R"]
    critical = np.degrees(optics.critical_angle(1.5))
    assert 41.0 < critical < 42.5
    below = angles < critical
    assert (ok_t == below).all() and ok_r.all()
    np.testing.assert_allclose(optics.snell_residual(-d[below], t[below], n[below], 1.5, 1.0), 0.0,
                               atol=2e-6)
    assert (w_t[~below] == 0).all()
    np.testing.assert_allclose(w_r[~below], 1.0, rtol=1e-6)
    np.testing.assert_allclose(r[~below], optics.reflect(-d[~below], n[~below]), atol=1e-6)


def backdrop_scene(integrator):
    """Glass and gold balls in front of an emissive checkerboard, constant sky 0.2: every
    light path is delta vertices + emission, the case where path's random choice of
    reflection or refraction has the same expectation as whitted's ray tree."""
    checker = {"type": "checkerboard", "to_uv": mi.ScalarTransform4f().scale([6, 6, 1]),
               "color0": {"type": "rgb", "value": [0.2, 0.5, 1.0]},
               "color1": {"type": "rgb", "value": [1.0, 0.3, 0.1]}}
    return mi.load_dict({
        "type": "scene", "integrator": integrator,
        "glass": {"type": "sphere", "center": [-0.6, 0, 0], "radius": 0.5,
                  "bsdf": {"type": "dielectric"}},
        "gold": {"type": "sphere", "center": [0.6, 0, 0], "radius": 0.5,
                 "bsdf": {"type": "conductor", "material": "Au"}},
        "wall": {"type": "rectangle", "emitter": {"type": "area", "radiance": checker},
                 "to_world": mi.ScalarTransform4f().translate([0, 0, -1]).scale(3.0)},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.2, 0.2, 0.2]}},
        "sensor": {"type": "perspective", "fov": 30.0,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 24, "height": 16,
                            "rfilter": {"type": "box"}}}})


def test_glass_and_metal_ray_tree_equals_path_in_expectation(variant_llvm_rgb):
    """max_depth = 3 (entry and exit refraction reach the backdrop): E[path] = whitted."""
    integ = {"type": "whitted", "units": "radiance", "max_depth": 3}
    paired_t_test(backdrop_scene(integ), backdrop_scene({"type": "path", "max_depth": 3}),
                  spp=16, passes=16, seed=11, what="whitted(radiance) vs path, glass + gold")


# ----------------------------------------------------------------------------- scenes

@pytest.mark.parametrize("name", ["exponent_series", "metal_vs_plastic", "attenuation_demo",
                                  "glass_sphere"])
def test_scenes_render_with_whitted_and_path(variant_llvm_rgb, name):
    """Each new scene loads with its whitted integrator (and path where it declares one)."""
    small = {"width": 24, "height": 16, "spp": 1}
    kinds = ["whitted", "path"] if "integrator" in scene_defaults(SCENES / f"{name}.xml") \
        else ["whitted"]
    for kind in kinds:
        extra = {"integrator": kind} if kind == "path" else {}
        scene = load_scene(name, **small, **extra)
        image = np.array(mi.render(scene))
        assert image.shape == (16, 24, 3) and np.isfinite(image).all() and image.max() > 0


def test_radiance_units_equal_path_in_every_variant(any_variant):
    """The path equivalence (one point light, max_depth 2) in mono, spectral and scalar too,
    and the graphics formula by hand in scalar_rgb (Python BSDFs are slow there: few rays)."""
    scene = sphere_scene("point", RADIANCE)
    assert scene.integrator().parameters()["attenuation_constant"] == 1.0
    path = mi.load_dict(PATH2)
    sensor = scene.sensors()[0]
    uv = [(0.5, 0.5), (0.2, 0.5), (0.8, 0.6), (0.5, 0.35), (0.7, 0.45)]
    # JIT variants: one batch of rays; scalar: one ray at a time.
    batches = [uv] if dr.is_jit_v(mi.Float) else [[p] for p in uv]
    values = {0: [], 1: []}
    for batch in batches:
        u, v = (np.array(c, np.float32) for c in zip(*batch))
        pos = mi.Point2f(mi.Float(u), mi.Float(v)) if dr.is_jit_v(mi.Float) else \
            mi.Point2f(float(u[0]), float(v[0]))
        for k, integ in enumerate((scene.integrator(), path)):
            sampler = mi.load_dict({"type": "independent"})
            sampler.seed(1, len(batch))
            ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
            values[k].append(np.array(integ.sample(scene, sampler, ray, None, True)[0],
                                      np.float64).reshape(-1, len(batch)).T)
    got, want = np.concatenate(values[0]), np.concatenate(values[1])
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-7)
    assert np.count_nonzero(want.max(axis=1) > 0) >= 3
    if any_variant == "scalar_rgb":
        scene = plane_scene(**graphics())
        eye, d = camera_rays(POINTS[:2], VIEW)
        sampler = mi.load_dict({"type": "independent"})
        got = []
        for o, dd in zip(eye, d):
            sampler.seed(0, 1)
            ray = mi.Ray3f(mi.Point3f(*o), mi.Vector3f(*dd))
            got.append(np.array(scene.integrator().sample(scene, sampler, ray, None, True)[0]))
        np.testing.assert_allclose(np.array(got), seed_formula(POINTS[:2], eye,
                                                               k_amb=np.array(KD)),
                                   rtol=2e-5, atol=1e-6)


def test_attenuation_demo_header(variant_llvm_rgb):
    """The values attenuation_demo.xml's header derives, at each sphere's nearest point."""
    light, eye, radius = np.array([-0.8, 1.8, 1.5]), np.array([3.0, 2.4, 6.0]), 0.3
    centres = np.array([[0.4 + i, 0.0, 0.0] for i in range(7)])
    to_light = light - centres
    r = np.linalg.norm(to_light, axis=1) - radius
    nearest = centres + radius * 0.999 * to_light / np.linalg.norm(to_light, axis=1)[:, None]
    d = nearest - eye
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    cases = {(): 5 * 0.35 * np.ones(7), (("a", 0), ("c", 1)): 5 * 0.35 / r ** 2,
             (("b", 0.5),): 5 * 0.35 / (1 + 0.5 * r), (("units", "radiance"),):
             5 * 0.35 / (np.pi * r ** 2)}
    for params, want in cases.items():
        scene = load_scene("attenuation_demo", **dict(params))
        got = trace(scene, scene.integrator(), np.tile(eye, (7, 1)), d)[:, 0]
        # The 0.999 inset and (L·R)^20 of a far-off highlight: 0.5 % at most.
        np.testing.assert_allclose(got, want, rtol=5e-3, err_msg=str(params))
    np.testing.assert_allclose((r[-1] / r[0]) ** 2, 9.72, rtol=1e-3)


def _jit_kernels(scene, integrator) -> list[tuple]:
    """(hash, cache hit) of the JIT kernels one render launches."""
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()
    render_scene(scene, 4, seed=3, integrator=integrator)
    return [(k.get("hash"), bool(k.get("cache_hit", 0))) for k in dr.kernel_history()
            if str(k.get("type", "")).endswith("JIT")]


@pytest.mark.parametrize("name", [pytest.param("exponent_series", marks=pytest.mark.slow),  # ~8 s
                                  "attenuation_demo"])
def test_graphics_and_radiance_units_launch_the_same_kernels_without_recompiling(variant_llvm_rgb, name):
    """Graphics units cost what radiance units cost in kernels: per render the same number of
    JIT launches, and a second render (another seed) reuses every kernel of the first (the
    per-material loop of graphics units is traced, not compiled, again).  The time ratio
    itself is a benchmark (bench.render_sweeps.sweep_whitted_units), not a unit test."""
    scene = load_scene(name, "llvm_ad_rgb", width=32, height=16)
    settings = scene.integrator().parameters()
    kernels = {}
    for units in ("graphics", "radiance"):
        integrator = mi.load_dict(dict(settings, units=units))
        first = _jit_kernels(scene, integrator)
        second = _jit_kernels(scene, integrator)
        assert [h for h, _ in second] == [h for h, _ in first], f"{units}: recompiled"
        assert all(hit for _, hit in second), f"{units}: {second}"
        kernels[units] = len(first)
    assert kernels["graphics"] == kernels["radiance"], kernels
