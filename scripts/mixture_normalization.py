"""An independent ∫pdf dω_o of tests/authors/narrow_broad_mixture.py, to judge the
``normalization`` topic's quadrature against.

(a) float64: the plugin's pdf formula is normalized lobe by lobe, so
    ∫pdf64 = (1 − w_s)·1 + w_s·P_s(θ_i), P_s = Pr[2(ω_i·h)h − ω_i above the horizon] for
    h ~ D(h) = (p + 1)/(2π) cos^p θ_h, counted over N float64 half-vector samples (binomial σ,
    × w_s);
(b) the plugin's own float32 pdf: ∫pdf32 = ∫pdf64 + E_q[(pdf32 − pdf64)/q], q the float64
    mixture density with lobe weights ½/½ (its support holds every direction where pdf > 0),
    pdf64 evaluated at the same float32 directions; the mean over batches and its standard
    error.  Measured (k_d = 0.5, k_s = 1e-4, p = 2000, cos θ_i = 0.15, 0.05, 0.01, 1e-4):
    ∫pdf64 = 0.99999992, 0.99997369, 0.99991774, 0.99990017, ∫pdf32 within 6e-8 of it.

    python scripts/mixture_normalization.py KD KS EXPONENT COS_THETA_I [COS_THETA_I ...]
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

import phonglab

PLUGIN = Path(__file__).resolve().parents[1] / "tests" / "authors" / "narrow_broad_mixture.py"


def main(argv: list[str]) -> None:
    phonglab.register("llvm_ad_rgb")
    import mitsuba as mi
    from phonglab import probe
    from phonglab.validate.bsdf import lanes

    exec(compile(PLUGIN.read_text(), str(PLUGIN), "exec"), {"__name__": "narrow_broad"})
    kd, ks, p = float(argv[0]), float(argv[1]), float(argv[2])
    w = ks / (kd + ks)
    bsdf = mi.load_dict({"type": "narrow_broad_mixture", "diffuse_reflectance": kd,
                         "specular_reflectance": ks, "exponent": p})

    def pdf64(wi, wo, w_s):
        s = wi + wo
        n = np.linalg.norm(s, axis=1)
        d = (p + 1) / (2 * np.pi) * np.maximum(s[:, 2] / n, 0) ** p
        ok = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        return np.where(ok, (1 - w_s) * wo[:, 2] / np.pi + w_s * d / (2 * n), 0.0)

    def halfvectors(n, rng):
        cos_h = rng.random(n) ** (1 / (p + 1))
        sin_h, phi = np.sqrt(1 - cos_h * cos_h), 2 * np.pi * rng.random(n)
        return np.column_stack([sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h])

    def draw(wi, n, rng):
        h = halfvectors(n, rng)
        glossy = 2 * np.sum(wi * h, 1)[:, None] * h - wi
        u, v = rng.random(n), 2 * np.pi * rng.random(n)
        r = np.sqrt(u)
        diffuse = np.column_stack([r * np.cos(v), r * np.sin(v), np.sqrt(1 - u)])
        return np.where((rng.random(n) < 0.5)[:, None], glossy, diffuse)

    rng = np.random.default_rng(12345)
    n, batches = 1 << 20, 8
    for c in map(float, argv[3:]):
        for phi in (0.0, 2.1):
            wi = lanes.exact(probe.direction(math.acos(c), phi))
            wis = np.repeat(wi[None], n, 0)
            frac = []
            for _ in range(batches):
                h = halfvectors(n, rng)
                frac.append(np.mean((2 * np.sum(wis * h, 1) * h[:, 2] - wis[:, 2]) > 0))
            p_s = float(np.mean(frac))
            q64 = (1 - w) + w * p_s
            se64 = w * math.sqrt(p_s * (1 - p_s) / (n * batches))
            diffs = []
            for _ in range(batches):
                wo = draw(wis, n, rng)
                q = pdf64(wis, wo, 0.5)
                ok = q > 0
                wo32 = wo[ok].astype(np.float32).astype(np.float64)
                unit = wo32 / np.linalg.norm(wo32, axis=1, keepdims=True)
                diff = probe.pdf(bsdf, wi, wo32) - pdf64(wis[ok], unit, w)
                diffs.append(np.sum(diff / q[ok]) / n)
            diffs = np.array(diffs)
            se32 = math.hypot(se64, diffs.std(ddof=1) / math.sqrt(batches))
            print(f"w_s = {w:.4e}, p = {p:g}, cos θ_i = {c:g}, φ_i = {phi}: "
                  f"∫pdf64 = {q64:.8f} ± {se64:.0e}; ∫pdf32 = {q64 + diffs.mean():.8f} ± "
                  f"{se32:.0e} ({n * batches} samples each)", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
