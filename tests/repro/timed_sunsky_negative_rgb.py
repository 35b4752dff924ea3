"""Mitsuba 3.9.1 timed_sunsky in an RGB variant: negative radiance near the horizon.

include/mitsuba/render/sunsky.h:642-655 (commit 478e193a): the sky's Hosek-Wilkie fit eval_sky
returns c1 c2 R without a clamp, and its blue channel goes below zero within ~0.07 deg of the
horizon -- a bug: nothing documents it.  The sun's RGB (sunsky.h:580-581) is negative in blue
too while the sun disc is under ~1 deg high, where timed_sunsky's default day puts it part of
the time: 36 % of its direction samples are sun samples with weights like (0.73, 0.20, -0.011)
(radiance (3819, 1032, -58)).  That part is documented: src/emitters/timed_sunsky.cpp:171-176
(sunsky.cpp says the same), "the sun's radiance is ill-represented by the linear sRGB color
space ... it can happen that it contains negative pixel values ... These results are left
un-clamped".

Run: python tests/repro/timed_sunsky_negative_rgb.py  -> exit 1 while the behaviour is present.
"""
import math
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
scene = mi.load_dict({"type": "scene", "sky": {"type": "timed_sunsky"},
                      "s": {"type": "sphere"}})
sky = scene.emitters()[0]
n = 4096
elev = np.radians(np.linspace(0.01, 1.0, 64))             # 0.01 .. 1 deg above the horizon
phi = np.linspace(0.0, 2 * math.pi, n // 64, endpoint=False)
E, P = np.meshgrid(elev, phi)
d = np.stack([np.cos(E) * np.cos(P), np.cos(E) * np.sin(P), np.sin(E)], -1).reshape(-1, 3)
si = dr.zeros(mi.SurfaceInteraction3f, len(d))
si.wi = mi.Vector3f(*(mi.Float(np.ascontiguousarray(-d[:, k], np.float32)) for k in range(3)))
L = np.array(sky.eval(si)).T
neg = (L < 0).any(axis=1)
print(f"eval within 1 deg of the horizon: {neg.sum()} of {len(d)} directions have a negative "
      f"channel, the lowest {L.min():.4g}; highest elevation with one "
      f"{np.degrees(np.arcsin(d[neg, 2].max())) if neg.any() else float('nan'):.3f} deg")
it = dr.zeros(mi.Interaction3f, n)
u = np.random.default_rng(0).random((n, 2)).astype(np.float32)
ds, w = sky.sample_direction(it, mi.Point2f(mi.Float(u[:, 0]), mi.Float(u[:, 1])))
W = np.array(w).T
print(f"sample_direction: {(W < 0).any(axis=1).sum()} of {n} weights with a negative channel")
present = bool(neg.any())
print("behaviour present: negative RGB radiance" if present else "changed: no negative value")
sys.exit(1 if present else 0)
