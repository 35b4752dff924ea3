"""Mitsuba 3.9.1 sggx: sample() draws from the wrong distribution unless wi is an axis.

include/mitsuba/render/microflake.h (commit 478e193a) lines 83-88, ``sggx_sample``:
``Matrix3f m(sh_frame.s, sh_frame.t, sh_frame.n); m = dr::transpose(m);
s2 = m * s_mat * dr::transpose(m)``.  Dr.Jit's Matrix takes rows, so after the transpose the
columns of m are (s, t, n) and s2 = Rᵀ S R, R the rotation to the local frame, where Heitz et
al.'s visible-normal sampling needs S in that frame, R S Rᵀ.  The two agree when R is a
permutation (wi on an axis: mitsuba's own chi2 test, src/phase/tests/test_sggx.py, samples at
wi = (0, 0, 1) only) and differ otherwise: eval_pdf (sggx.cpp:116, from sggx_pdf, no frame)
is right, the sampled directions are not distributed by it, and a volumetric path tracer's
phase sampling of an anisotropic sggx medium is biased (its weight assumes eval_pdf's density).
Reported upstream as mitsuba3 issue #1728 (open): "erasing the transpose [line 84] solves
this".

Check: the mean scattered direction E[wo] of 2^20 samples against ∫ wo pdf dω (a 2M-point
Fibonacci sphere), at an oblique wi; exit 1 while they differ by more than 6 standard errors.
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
S = np.array([0.15, 1.0, 0.8, 0.0, 0.0, 0.0], np.float32)        # Sxx Syy Szz Sxy Sxz Syz
phase = mi.load_dict({"type": "sggx", "S": {"type": "gridvolume",
                                            "data": mi.TensorXf(S, (1, 1, 1, 6))}})
wi = np.array([0.48, -0.36, 0.8])
ctx = mi.PhaseFunctionContext(None)


def interaction(n):
    mei = dr.zeros(mi.MediumInteraction3f, n)
    mei.wi = mi.Vector3f(*map(float, wi))
    mei.sh_frame = mi.Frame3f(mei.wi)
    return mei


n = 1 << 20
u = np.random.default_rng(1).random((n, 2)).astype(np.float32)
wo, _, _ = phase.sample(ctx, interaction(n), mi.Float(u[:, 0]),
                        mi.Point2f(mi.Float(u[:, 0]), mi.Float(u[:, 1])))
wo = np.stack([np.array(c, dtype=np.float64) for c in wo], axis=1)
mean, se = wo.mean(axis=0), wo.std(axis=0) / np.sqrt(n)

m = 2_000_000                                                     # Fibonacci sphere
i = np.arange(m) + 0.5
z = 1 - 2 * i / m
r = np.sqrt(1 - z * z)
phi = np.pi * (3 - np.sqrt(5)) * i
d = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
_, pdf = phase.eval_pdf(ctx, interaction(m), mi.Vector3f(*(mi.Float(d[:, k]) for k in range(3))))
pdf = np.array(pdf, dtype=np.float64)
total = pdf.mean() * 4 * np.pi
expect = (d * pdf[:, None]).mean(axis=0) * 4 * np.pi
z_score = np.abs(mean - expect) / se
print(f"wi = {wi}: ∫pdf = {total:.5f}; E[wo] sampled {np.round(mean, 4)} vs ∫ wo pdf "
      f"{np.round(expect, 4)}: {np.round(z_score, 1)} standard errors")
sys.exit(1 if z_score.max() > 6 else 0)
