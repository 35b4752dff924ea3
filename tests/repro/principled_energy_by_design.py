"""Mitsuba 3.9.1 principled/principledthin: a white or smooth Disney BSDF reflects more than 1.

By design of the Disney model (not a bug): Burley's diffuse f_diff + f_retro
(src/bsdfs/principled.cpp:655, principledthin.cpp:539) raises the grazing response of a rough
surface, so at base_color 1 the diffuse lobe alone has albedo > 1; principled adds its
specular lobe on top without (1 - F) (principled.cpp:677-679), so at roughness 0.1 the sum
exceeds 1 at grazing incidence.  The albedo is a midpoint rule in half-vector space
(log-spaced tan theta_h; every reflection lobe here is centred on h = n).

Run: python tests/repro/principled_energy_by_design.py -> exit 1 while the albedo exceeds 1.
"""
import math
import sys

import numpy as np

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")


def albedo(spec, theta_deg, nu=1500, nphi=800):
    du = 10.0 / nu
    t = 10.0 ** (-6 + (np.arange(nu) + 0.5) * du)
    th, dth = np.arctan(t), math.log(10) * t / (1 + t * t) * du
    ph = (np.arange(nphi) + 0.5) * 2 * math.pi / nphi
    TH, PH = np.meshgrid(th, ph, indexing="ij")
    w = (np.sin(TH) * dth[:, None] * 2 * math.pi / nphi).ravel()
    h = np.stack([np.sin(TH) * np.cos(PH), np.sin(TH) * np.sin(PH), np.cos(TH)], -1).reshape(-1, 3)
    wi = np.array([math.sin(math.radians(theta_deg)), 0.0, math.cos(math.radians(theta_deg))])
    d = h @ wi
    wo = 2 * d[:, None] * h - wi
    ok = (d > 0) & (wo[:, 2] > 0)
    wo, w, d = wo[ok], w[ok], d[ok]
    n = len(wo)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wi = mi.Vector3f(*(float(x) for x in wi))
    ctx = mi.BSDFContext(mi.TransportMode.Importance)
    ev = np.array(mi.load_dict(spec).eval(ctx, si, mi.Vector3f(wo[:, 0], wo[:, 1], wo[:, 2])).x)
    return float(np.sum(w * 4 * d * ev))


if __name__ == "__main__":
    worst = 0.0
    for label, spec, theta in [("principledthin, base_color 1", {"type": "principledthin", "base_color": 1.0}, 72.54),
                               ("principled, base_color 1", {"type": "principled", "base_color": 1.0}, 87.13),
                               ("principled, roughness 0.1", {"type": "principled", "roughness": 0.1}, 89.99)]:
        a = albedo(spec, theta)
        worst = max(worst, a)
        print(f"{label}: albedo {a:.4f} at {theta} deg")
    sys.exit(1 if worst > 1.001 else 0)
