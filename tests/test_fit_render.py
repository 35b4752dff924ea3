"""phonglab.fit.render_fit: a known phong recovered from its own render by differentiable rendering.

Tolerance (from the render noise): after Adam and the Gauss–Newton polish, the fitted
x̂ = (t, s, ln p) differs from the truth, to first order, by the least-squares response to
the target's pixel noise and to the last polish render's noise, independent, with covariance
(JᵀJ)⁻¹ Jᵀ (C_T + C_P) J (JᵀJ)⁻¹ (J by forward-mode AD through prb; C the per-pixel RGB noise
covariance, measured from independent renders at 64 spp and scaled by 64/spp).  Each parameter
is accepted within z · sd, z = z_critical(ALPHA, 3) (Šidák over the three parameters).
"""

from __future__ import annotations

import numpy as np

from phonglab.stats import ALPHA, z_critical

TRUTH = (0.3, 0.4, 30.0)
START = (0.2, 0.02, 5.0)
RES, SPP, TARGET_SPP, POLISH_SPP, NOISE_SPP = 32, 16, 512, 256, 64


def test_recovers_a_known_phong_from_its_render(variant_llvm_rgb):
    from phonglab.fit import render_fit as rf
    scene = rf.sphere_scene(rf.phong_dict(*TRUTH), RES)
    target = rf.render(scene, TARGET_SPP, seed=10 ** 6)
    fit = rf.fit_image(target, START, res=RES, spp=SPP, polish_spp=POLISH_SPP)
    assert fit.losses[-1] < 0.5 * fit.losses[0]
    lo, hi = np.array(rf.PHONG.bounds).T
    assert all(lo[k] <= v <= hi[k] for h in fit.history for k, v in enumerate(rf.PHONG.variables(h)))
    assert all(h[0] + h[1] <= 1.0 + 1e-6 for h in fit.history)
    assert np.all(np.isfinite(fit.history)) and np.all(np.isfinite(fit.losses))
    assert np.all(lo <= fit.x) and np.all(fit.x <= hi)
    x_true = rf.PHONG.variables(TRUTH)
    J = rf.jacobian(scene, x_true, NOISE_SPP)
    noise = rf.pixel_covariance(scene, NOISE_SPP, renders=8)
    cov = rf.parameter_covariance(J, noise * (NOISE_SPP / TARGET_SPP + NOISE_SPP / POLISH_SPP))
    tol = z_critical(ALPHA, 3) * np.sqrt(np.diag(cov))
    assert np.all(np.abs(fit.x - x_true) <= tol), (fit.fitted, fit.x - x_true, tol)
    # The start is far outside the tolerance: the test measures recovery, not the start.
    assert np.all(np.abs(rf.PHONG.variables(START) - x_true) > 5 * tol)
