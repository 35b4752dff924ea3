"""Mitsuba 3.9.1 sunsky: the sun's pdf_direction does not integrate to 1 (float32 cone test).

include/mitsuba/render/sunsky.h (tag v3.9.1): compute_pdfs gives the sun the uniform-cone
density 1/(2π(1 − cos θ_sun)) (lines 929-932) on the directions hit_sun accepts,
dot(sun, normalize(to_world⁻¹ d)) ≥ cos θ_sun in float32 (line 946).  The sun's half aperture
is 0.268 deg: 1 − cos θ_sun = 1.09e-5 is 183 float32 steps, so the rounding of the dot product
moves the accepted cone's edge by a step or so, i.e. its solid angle by ~0.5 %, in a direction
that depends on where the sun stands; sample_sun draws from the exact cone.  With the sky off
(sky_scale = 0) the sun is the whole density, and ∫ pdf_direction dω over a cap twice the
sun's radius reads 1.0052 ± 0.0005 at the default place (Tokyo, 2010-07-10 15:00): the χ²
test of sample_direction against pdf_direction rejects it at 10⁶ samples.

Run: python tests/repro/sunsky_sun_pdf_normalization.py  -> exit 1 while the behaviour is present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
scene = mi.load_dict({"type": "scene", "sun": {"type": "sunsky", "sky_scale": 0.0},
                      "ball": {"type": "sphere", "radius": 0.01}})
emitter = scene.emitters()[0]
sun = np.array(mi.traverse(emitter)["sun_direction"], np.float64).ravel()
sun /= np.linalg.norm(sun)
cap_cos = np.cos(2 * np.radians(0.5358 / 2))            # a cap twice the sun's radius
t1 = np.cross(sun, [1.0, 0.0, 0.0] if abs(sun[0]) < 0.9 else [0.0, 1.0, 0.0])
t1 /= np.linalg.norm(t1)
t2 = np.cross(sun, t1)
rng = np.random.default_rng(0)
estimates = []
for _ in range(8):                     # uniform directions on the cap, float64 -> float32
    n = 1 << 20
    c = 1.0 - rng.random(n) * (1.0 - cap_cos)
    s, phi = np.sqrt(1.0 - c * c), 2.0 * np.pi * rng.random(n)
    d = (s * np.cos(phi))[:, None] * t1 + (s * np.sin(phi))[:, None] * t2 + c[:, None] * sun
    ds = dr.zeros(mi.DirectionSample3f, n)
    ds.d = mi.Vector3f(d.T.astype(np.float32))
    pdf = np.array(emitter.pdf_direction(dr.zeros(mi.Interaction3f, n), ds), np.float64)
    estimates.append(pdf.mean() * 2.0 * np.pi * (1.0 - cap_cos))
mean, err = np.mean(estimates), np.std(estimates, ddof=1) / np.sqrt(len(estimates))
print(f"∫ pdf_direction dω of the sun alone (sky_scale 0): {mean:.4f} ± {err:.4f} (must be 1)")
present = abs(mean - 1.0) > 5.0 * err
print("behaviour present: the sun's pdf is not normalized" if present
      else "changed: the sun's pdf integrates to 1")
sys.exit(1 if present else 0)
