"""phonglab.probe, the numpy <-> Dr.Jit bridge, against closed forms and Mitsuba's conventions.

Tolerances: inputs and results pass through float32 (relative rounding 6e-8 per operation),
so values computed by a handful of float32 operations agree with the float64 reference
to ~1e-6 relative; ``FLOAT32`` below allows that with a small margin.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import phonglab
from phonglab import probe

#: rtol for a few float32 operations against a float64 reference (~1e-6 relative, 2x margin)
FLOAT32 = 2e-6
RHO = 0.5
LAMBERTIAN = ["diffuse", "lambert"]   # Mitsuba's built-in and phonglab's plugin, same parameter


def _variant(name: str):
    """Set ``name`` (registering phonglab's plugins) and return the mitsuba module."""
    phonglab.register(name)
    import mitsuba as mi

    return mi


def _polarized_variant() -> str:
    import mitsuba as mi

    for name in ("llvm_ad_spectral_polarized", "llvm_ad_mono_polarized"):
        if name in mi.variants():
            return name
    pytest.skip("no LLVM polarized variant in this Mitsuba build")


def _lambertian(mi, kind: str):
    return mi.load_dict({"type": kind, "reflectance": {"type": "rgb", "value": RHO}})


def _random_dirs(n: int, seed: int, upper: bool = True) -> np.ndarray:
    """Uniform unit vectors, rounded to float32 (what the BSDF sees) and renormalized."""
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    if upper:
        v[:, 2] = np.abs(v[:, 2])
    return v.astype(np.float32).astype(np.float64)


def _check_lambertian_closed_form(mi, bsdf, n: int, channels: int):
    """eval = ρ/π cos θ_o, pdf = cos θ_o/π above the horizon, 0 below; sample weight = ρ."""
    wi, wo = _random_dirs(n, 1), _random_dirs(n, 2)
    cos_o = wo[:, 2]
    value = probe.eval(bsdf, wi, wo)
    assert value.shape == (n, channels)
    np.testing.assert_allclose(value, np.repeat((RHO / math.pi * cos_o)[:, None], channels, 1),
                               rtol=FLOAT32, atol=0)
    p = probe.pdf(bsdf, wi, wo)
    assert p.shape == (n,)
    np.testing.assert_allclose(p, cos_o / math.pi, rtol=FLOAT32, atol=0)
    below = wo * np.array([1.0, 1.0, -1.0])           # the same directions under the surface
    assert np.all(probe.eval(bsdf, wi, below) == 0.0)
    assert np.all(probe.pdf(bsdf, wi, below) == 0.0)
    assert np.all(probe.eval(bsdf, below, wo) == 0.0)  # one-sided: a viewer below sees nothing
    s = probe.sample(bsdf, wi, 0.5, np.random.default_rng(3).random((n, 2)))
    # cos θ_o / π over cos θ_o / π cancels: the weight is ρ up to float32 rounding.
    np.testing.assert_allclose(s.weight, RHO, rtol=FLOAT32)
    np.testing.assert_allclose(s.pdf, s.wo[:, 2] / math.pi, rtol=FLOAT32, atol=1e-7)


# ----------------------------------------------------------------------------- numpy helpers
def test_direction_shapes_and_unit_norm():
    assert probe.direction(0.3).shape == (3,)
    np.testing.assert_array_equal(probe.direction(0.0), [0.0, 0.0, 1.0])
    theta = np.linspace(0.0, math.pi, 7)
    d = probe.direction(theta, 0.4)
    assert d.shape == (7, 3)
    assert probe.direction(0.3, np.linspace(0, 6, 5)).shape == (5, 3)   # φ broadcasts too
    assert probe.direction(theta[:, None], np.zeros(4)).shape == (7, 4, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, rtol=1e-15)  # float64
    np.testing.assert_allclose(d[:, 2], np.cos(theta), rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.arctan2(d[1:-1, 1], d[1:-1, 0]), 0.4, rtol=1e-14)


def test_interaction_fields_and_shapes():
    mi = _variant("llvm_ad_spectral")
    wi = _random_dirs(5, 0)
    si = probe.interaction(wi)
    np.testing.assert_allclose(probe.to_numpy(si.wi), wi, rtol=1e-7)   # exactly float32 wi
    np.testing.assert_array_equal(probe.to_numpy(si.n, 5), np.tile([0.0, 0.0, 1.0], (5, 1)))
    np.testing.assert_array_equal(probe.to_numpy(si.sh_frame.s, 5)[0], [1.0, 0.0, 0.0])
    np.testing.assert_array_equal(probe.to_numpy(si.uv, 5), np.full((5, 2), 0.5))
    lam = probe.to_numpy(si.wavelengths, 5)
    assert lam.shape == (5, 4)
    np.testing.assert_allclose(lam, np.tile(probe.default_wavelengths(), (5, 1)), rtol=1e-7)
    assert np.all((lam > mi.MI_CIE_MIN) & (lam < mi.MI_CIE_MAX))
    assert probe.to_numpy(probe.interaction(wi[0], n=3).wi).shape == (3, 3)
    with pytest.raises(ValueError):
        probe.interaction(wi, n=4)


def test_broadcasting_and_shape_errors():
    mi = _variant("llvm_ad_rgb")
    bsdf = _lambertian(mi, "diffuse")
    wo = _random_dirs(6, 4)
    one_wi = probe.eval(bsdf, wo[0], wo)
    per_lane = probe.eval(bsdf, np.tile(wo[0], (6, 1)), wo)
    np.testing.assert_array_equal(one_wi, per_lane)
    assert probe.eval(bsdf, wo, wo[0]).shape == (6, 3)
    assert probe.pdf(bsdf, wo[0], wo[1]).shape == (1,)
    with pytest.raises(ValueError):
        probe.eval(bsdf, wo[:4], wo)
    with pytest.raises(ValueError):
        probe.eval(bsdf, wo[0], wo[:, :2])


# ----------------------------------------------------------------------------- Lambertian
@pytest.mark.parametrize("kind", LAMBERTIAN)
def test_lambertian_eval_pdf_sample_llvm_rgb(kind):
    mi = _variant("llvm_ad_rgb")
    bsdf = _lambertian(mi, kind)
    _check_lambertian_closed_form(mi, bsdf, 2000, 3)
    wi, wo = _random_dirs(500, 5), _random_dirs(500, 6, upper=False)
    value, p = probe.eval_pdf(bsdf, wi, wo)
    # eval_pdf is the same arithmetic as eval and pdf: equal to float32 rounding.
    np.testing.assert_allclose(value, probe.eval(bsdf, wi, wo), rtol=FLOAT32, atol=0)
    np.testing.assert_allclose(p, probe.pdf(bsdf, wi, wo), rtol=FLOAT32, atol=0)
    # The sample's weight and pdf agree with eval and pdf at the sampled direction.
    s = probe.sample_random(bsdf, wi[0], 2000, seed=7)
    e, q = probe.eval_pdf(bsdf, wi[0], s.wo)
    assert np.all(q > 0)
    np.testing.assert_allclose(s.weight, e / q[:, None], rtol=4 * FLOAT32)   # ratio of two
    np.testing.assert_allclose(s.pdf, q, rtol=FLOAT32)
    np.testing.assert_allclose(np.linalg.norm(s.wo, axis=1), 1.0, rtol=FLOAT32)
    assert np.all(s.eta == 1.0)
    assert np.all(s.sampled_type == int(mi.BSDFFlags.DiffuseReflection))
    assert np.all(s.sampled_component == 0)


@pytest.mark.parametrize("kind", LAMBERTIAN)
@pytest.mark.parametrize("variant, n, channels", [
    ("scalar_rgb", 16, 3),         # scalar: the probe loops over lanes, keep n small
    ("llvm_ad_mono", 500, 1),
    ("llvm_ad_spectral", 500, 4),  # one column per wavelength of default_wavelengths()
    ("polarized", 500, None),      # the unpolarized intensity of the Mueller matrix
])
def test_lambertian_closed_form_in_other_variants(kind, variant, n, channels):
    if variant == "polarized":
        _variant("llvm_ad_rgb")
        variant = _polarized_variant()
        channels = 4 if "spectral" in variant else 1
    mi = _variant(variant)
    _check_lambertian_closed_form(mi, _lambertian(mi, kind), n, channels)


# ----------------------------------------------------------------------------- Phong
PHONG = {"type": "phong", "diffuse_reflectance": {"type": "rgb", "value": 0.3},
         "specular_reflectance": {"type": "rgb", "value": 0.5}, "exponent": 20.0}


def test_phong_sample_matches_eval_over_pdf():
    mi = _variant("llvm_ad_rgb")
    bsdf = mi.load_dict(PHONG)
    wi = probe.direction(0.6, 0.3)
    s = probe.sample_random(bsdf, wi, 4000, seed=11)
    e, p = probe.eval_pdf(bsdf, wi, s.wo)
    valid = s.pdf > 0
    assert valid.mean() > 0.9                         # few samples fall below the horizon
    # weight = eval / pdf of the whole mixture, per sample (a ratio of float32 values).
    np.testing.assert_allclose(s.weight[valid], e[valid] / p[valid, None], rtol=4 * FLOAT32)
    np.testing.assert_allclose(s.pdf[valid], p[valid], rtol=FLOAT32)
    assert np.all(s.weight[~valid] == 0.0)
    assert set(np.unique(s.sampled_component)) == {0, 1}   # both lobes, by sample1


@pytest.mark.parametrize("component", [0, 1])
def test_phong_component_context(component):
    mi = _variant("llvm_ad_rgb")
    bsdf = mi.load_dict(PHONG)
    s = probe.sample_random(bsdf, probe.direction(0.4), 500, seed=component,
                            ctx=probe.context(component=component))
    assert np.all(s.sampled_component == component)
    lobe = int(bsdf.flags(component)) & int(mi.BSDFFlags.All)   # lobe bits, no FrontSide
    assert np.all(s.sampled_type == lobe)
    # type_mask selects the same lobe by its flags.
    t = probe.sample_random(bsdf, probe.direction(0.4), 500, seed=component,
                            ctx=probe.context(type_mask=lobe))
    assert np.all(t.sampled_component == component)


# ----------------------------------------------------------------------------- dielectric
def test_dielectric_snell_eta_and_total_internal_reflection():
    mi = _variant("llvm_ad_rgb")
    # ext_ior=1 explicitly: Mitsuba's default exterior is air (1.000277), eta would be 1.4996.
    eta = 1.5
    bsdf = mi.load_dict({"type": "dielectric", "int_ior": eta, "ext_ior": 1.0})
    phi = 0.7
    # sample1 = 0.99999 > Fresnel reflectance: transmission wherever it is possible.
    theta = np.radians([0.0, 10.0, 30.0, 60.0, 80.0])
    s = probe.sample(bsdf, probe.direction(theta, phi), 0.99999, (0.5, 0.5))
    assert np.all(s.sampled_type == int(mi.BSDFFlags.DeltaTransmission))
    assert np.all(s.wo[:, 2] < 0)
    sin_t = np.hypot(s.wo[:, 0], s.wo[:, 1])
    np.testing.assert_allclose(sin_t, np.sin(theta) / eta, rtol=0, atol=1e-6)   # float32
    # The transmitted ray continues across the normal: opposite azimuth.
    np.testing.assert_allclose(np.arctan2(s.wo[1:, 1], s.wo[1:, 0]), phi - math.pi, atol=1e-5)
    # eta is the relative IOR of the crossing, η_transmitted / η_incident.
    np.testing.assert_allclose(s.eta, eta, rtol=1e-7)
    # Radiance mode: the weight carries 1/η² (radiance compresses into the denser medium).
    np.testing.assert_allclose(s.weight, 1.0 / eta**2, rtol=FLOAT32)

    # From inside (wi below the surface): transmission below the critical angle...
    inside = -probe.direction(np.radians([10.0, 30.0]), phi)
    t = probe.sample(bsdf, inside, 0.99999, (0.5, 0.5))
    assert np.all(t.sampled_type == int(mi.BSDFFlags.DeltaTransmission))
    np.testing.assert_allclose(np.hypot(t.wo[:, 0], t.wo[:, 1]),
                               eta * np.sin(np.radians([10.0, 30.0])), atol=1e-6)
    np.testing.assert_allclose(t.eta, 1.0 / eta, rtol=1e-7)
    # ...and pure (total internal) reflection beyond it, asin(1/1.5) = 41.8°.
    beyond = -probe.direction(np.radians([45.0, 60.0, 85.0]), phi)
    r = probe.sample(bsdf, beyond, 0.99999, (0.5, 0.5))
    assert np.all(r.sampled_type == int(mi.BSDFFlags.DeltaReflection))
    np.testing.assert_allclose(r.wo, beyond * np.array([-1.0, -1.0, 1.0]), atol=1e-6)
    np.testing.assert_array_equal(r.eta, 1.0)
    np.testing.assert_array_equal(r.pdf, 1.0)           # F = 1: reflection is certain
    np.testing.assert_allclose(r.weight, 1.0, rtol=FLOAT32)


# ----------------------------------------------------------------------------- sample_random
def test_sample_random_is_reproducible_and_broadcasts_wi():
    mi = _variant("llvm_ad_rgb")
    bsdf = mi.load_dict(PHONG)
    wi = probe.direction(0.5, 1.0)
    a = probe.sample_random(bsdf, wi, 300, seed=5)
    b = probe.sample_random(bsdf, wi, 300, seed=5)
    c = probe.sample_random(bsdf, np.tile(wi, (300, 1)), 300, seed=5)
    fields = ["wo", "weight", "pdf", "eta", "sampled_type", "sampled_component"]
    for f in fields:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
        np.testing.assert_array_equal(getattr(a, f), getattr(c, f))
    assert a.n == 300 and a.wo.shape == (300, 3) and a.weight.shape == (300, 3)
    assert a.sampled_type.dtype == np.int64 and a.sampled_component.dtype == np.int64
    assert not np.array_equal(a.wo, probe.sample_random(bsdf, wi, 300, seed=6).wo)
    # The documented draw order: u1 = rng.random(n) first, then u2 = rng.random((n, 2)).
    rng = np.random.default_rng(5)
    u1 = rng.random(300)
    d = probe.sample(bsdf, wi, u1, rng.random((300, 2)))
    np.testing.assert_array_equal(a.wo, d.wo)


def test_sample_in_scalar_variant_matches_llvm():
    # Same float32 inputs, same formulas: equal up to float32 rounding (FMA contraction
    # in the JIT kernel).
    rows = {}
    for name in ("llvm_ad_rgb", "scalar_rgb"):
        mi = _variant(name)
        bsdf = mi.load_dict(PHONG)
        rows[name] = probe.sample_random(bsdf, probe.direction(0.5), 12, seed=2)
    lv, sc = rows["llvm_ad_rgb"], rows["scalar_rgb"]
    np.testing.assert_array_equal(lv.sampled_component, sc.sampled_component)
    np.testing.assert_allclose(lv.wo, sc.wo, rtol=0, atol=1e-6)
    np.testing.assert_allclose(lv.weight, sc.weight, rtol=1e-5)


def test_a_return_of_another_width_is_refused_before_numpy_copies_it(variant_llvm_rgb):
    """A Python eval returning 2 lanes for N queried is one sentence, before the copy (broadcast
    against N lanes downstream, it can grow a validate run past 20 GB)."""
    import drjit as dr
    import mitsuba as mi

    class Wide(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.m_flags = mi.BSDFFlags.DiffuseReflection
            self.m_components = [self.m_flags]

        def eval(self, ctx, si, wo, active):
            return mi.Float(0.1, 0.2)

    b = Wide(mi.Properties())
    wo = probe.direction(np.linspace(0.1, 1.2, 1000), 0.3)
    with pytest.raises(ValueError, match="returned 2 lanes where 1000 were queried"):
        probe.eval(b, probe.direction(0.3), wo)
    assert dr.width(mi.Float(0.1, 0.2)) == 2


def test_a_query_over_the_memory_budget_is_one_sentence_before_the_kernel_runs(
        variant_llvm_rgb, monkeypatch):
    import mitsuba as mi
    b = mi.load_dict({"type": "diffuse"})
    wo = probe.direction(np.linspace(0.1, 1.2, 1000), 0.3)
    assert probe.eval(b, probe.direction(0.3), wo).shape == (1000, 3)
    # 1000 lanes x 3 channels x 4 bytes x 4 (float32 + float64 copies) = 48000 bytes
    monkeypatch.setattr(probe, "QUERY_BUDGET", 40_000)
    with pytest.raises(MemoryError, match="one probe query of 1000 lanes would need about .* "
                                          "budget for one query"):
        probe.eval(b, probe.direction(0.3), wo)
