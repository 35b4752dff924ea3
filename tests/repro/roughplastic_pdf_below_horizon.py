"""Mitsuba 3.9.1 roughplastic: pdf() is non-zero for wo below the horizon in vectorized variants.

src/bsdfs/roughplastic.cpp:391 computes ``active &= cos_theta_i > 0 && cos_theta_o > 0`` but
pdf() ends with ``return result;`` (line 422) and eval_pdf() with ``return {value & active, pdf}``
(line 501): the pdf is never masked by ``active``.  The early ``if (dr::none_or<false>(active))
return 0`` (line 393) only helps when EVERY lane is inactive, i.e. in scalar variants.  So in
llvm_/cuda_ variants a direction wo below the horizon gets the specular density
D(H) G1(wi, H) / (4 cos theta_i) whenever H = normalize(wi + wo) is above it, although
sample() never returns such a wo (it zeroes the weight); mi.chi2 then sees a pdf that integrates to more
than 1 and rejects (the "alpha = 0.25 fails chi2 at 45 degrees" finding).  roughconductor.cpp
ends its pdf() with ``return dr::select(active, result, 0.f)``.  The same unmasked return
gives pdf = NaN at exactly grazing incidence (cos_theta_i = 0: the specular term divides by
4 cos_theta_i, line 414) when another lane of the call is active.

Run: python tests/repro/roughplastic_pdf_below_horizon.py  -> exit 1 while the bug is present.
"""
import math
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import mitsuba as mi

SPEC = {"type": "roughplastic", "alpha": 0.25, "specular_reflectance": 0.7,
        "diffuse_reflectance": 0.1}
s, c = math.sin(math.radians(45)), math.cos(math.radians(45))
WO = [(0.6, 0.0, 0.8), (-0.993884, 0.0, -0.110432)]    # lane 0 above, lane 1 BELOW the horizon


def pdfs(variant):
    mi.set_variant(variant)
    bsdf = mi.load_dict(SPEC)
    out = []
    for wo in WO:
        si = mi.SurfaceInteraction3f()
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        si.wi = mi.Vector3f(s, 0, c)
        if variant.startswith("llvm"):       # the two directions as lanes of ONE call
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f([s, s], [0, 0], [c, c])
            si.sh_frame = mi.Frame3f(mi.Vector3f([0, 0], [0, 0], [1, 1]))
            wo_lanes = mi.Vector3f(*[[w[k] for w in WO] for k in range(3)])
            return list(bsdf.pdf(mi.BSDFContext(), si, wo_lanes)), \
                list(bsdf.eval_pdf(mi.BSDFContext(), si, wo_lanes)[1])
        out.append(float(bsdf.pdf(mi.BSDFContext(), si, mi.Vector3f(*wo))))
    return out, None


def grazing_pdf():
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f([1.0, s], [0, 0], [0.0, c])          # lane 0 exactly grazing
    si.sh_frame = mi.Frame3f(mi.Vector3f([0, 0], [0, 0], [1, 1]))
    wo = mi.Vector3f([0.6, 0.6], [0, 0], [0.8, 0.8])
    return float(mi.load_dict(SPEC).pdf(mi.BSDFContext(), si, wo)[0])


scalar, _ = pdfs("scalar_rgb")
vector, vector_eval_pdf = pdfs("llvm_ad_rgb")
print(f"pdf(wo below horizon): scalar_rgb {scalar[1]:.6g}, llvm_ad_rgb pdf {vector[1]:.6g}, "
      f"eval_pdf {vector_eval_pdf[1]:.6g} (expected 0)")
graze = grazing_pdf()
print(f"pdf at cos_theta_i = 0: {graze} (expected 0)")
sys.exit(1 if vector[1] != 0 or vector_eval_pdf[1] != 0 or math.isnan(graze) else 0)
