"""Mitsuba 3.9.1 homogeneous: with a microflake phase function whose S varies in space, the
majorant is σ_t at the origin, not along the ray.

src/media/homogeneous.cpp (commit 478e193a) lines 153-157 and 164: ``get_majorant`` returns
``eval_sigmat(mi)``, σ_t times the phase function's ``projected_area(mi)``, which SGGX
evaluates with its S at mi.p (src/phase/sggx.cpp:125); ``Medium::sample_interaction`` queries
the majorant before it sets p (src/render/medium.cpp:47-62), so p = (0, 0, 0) whatever the ray.
``get_scattering_coefficients`` (167-176) evaluates the same product at the collision's p and
returns σ_n = 0: σ_t + σ_n ≠ majorant wherever S differs from S at the origin, while
``m_is_homogeneous`` (line 138) tells the integrators σ_t is the majorant.  Distances are then
drawn at the origin's rate and every collision taken as real.

Run: python tests/repro/homogeneous_microflake_majorant_at_origin.py  -> exit 1 while the
behaviour is present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
S = np.zeros((4, 4, 4, 6), np.float32)           # flakes facing z at x = 0, facing x at x = 1
for i in range(4):
    f = i / 3
    S[:, :, i, 0], S[:, :, i, 1], S[:, :, i, 2] = 0.1 + 0.9 * f, 0.1, 1.0 - 0.9 * f
medium = mi.load_dict({"type": "homogeneous", "sigma_t": 2.0,
                       "phase": {"type": "sggx", "S": {"type": "gridvolume",
                                                       "data": mi.TensorXf(S)}}})
ray = mi.Ray3f(mi.Point3f(1.0, 0.5, -1.0), mi.Vector3f(0.0, 0.0, 1.0))
mei = medium.sample_interaction(ray, mi.Float(0.5), mi.UInt32(0), mi.Bool(True))
maj = float(np.array(mei.combined_extinction)[0, 0])
st, sn = float(np.array(mei.sigma_t)[0, 0]), float(np.array(mei.sigma_n)[0, 0])
print(f"at p = {np.array(mei.p).ravel().round(3).tolist()}: sigma_t {st:.4f} + sigma_n {sn:.4f} "
      f"against the majorant {maj:.4f} sample_interaction drew the distance with")
sys.exit(1 if abs(st + sn - maj) > 1e-3 * maj else 0)
