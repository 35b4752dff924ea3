"""Mitsuba 3.9.1 sggx: eval_pdf is NaN in the exact forward direction wo = -wi.

src/phase/sggx.cpp (commit 478e193a) line 116: ``sggx_pdf(dr::normalize(wo + mi.wi), s)``;
at wo = -wi the half vector is the zero vector and normalize() gives NaN, which the value and
the pdf carry (a microflake model scatters forward only through flakes seen edge-on, whose
half vector is undefined: the limit is finite).  sample() itself returns wo = -wi (reflect
about a flake normal perpendicular to wi) at its corner sample values along axis-aligned wi,
so eval_pdf at a sampled direction can be NaN; a light-sampled direction straight through
the scattering point hits it too.

Run: python tests/repro/sggx_eval_forward_nan.py  -> exit 1 while the behaviour is present.
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
S = np.array([0.15, 1.0, 0.8, 0.0, 0.0, 0.0], np.float32)
phase = mi.load_dict({"type": "sggx", "S": {"type": "gridvolume",
                                            "data": mi.TensorXf(S, (1, 1, 1, 6))}})
mei = dr.zeros(mi.MediumInteraction3f, 1)
mei.wi = mi.Vector3f(1.0, 0.0, 0.0)
mei.sh_frame = mi.Frame3f(mei.wi)
value, pdf = phase.eval_pdf(mi.PhaseFunctionContext(None), mei, mi.Vector3f(-1.0, 0.0, 0.0))
v = float(np.array(pdf)[0])
print(f"eval_pdf at wo = -wi = (-1, 0, 0): pdf = {v}")
sys.exit(0 if np.isfinite(v) else 1)
