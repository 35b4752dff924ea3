"""phonglab.fit.render_fit: a known phong recovered from its own render by differentiable rendering.

Tolerance (from the render noise): the fitted x̂ = (t, s, ln p) differs from the truth by the
target's pixel noise propagated through the least-squares fit, covariance
(JᵀJ)⁻¹Jᵀ diag(σ_T²) J (JᵀJ)⁻¹ (J by forward-mode AD through prb, σ_T² measured from
independent renders), plus the optimizer's own noise, the batch-means standard error of its
averaged iterates; both independent, so each parameter is accepted within
z · √(sd_T² + se_opt²), z = z_critical(ALPHA, 3) (Šidák over the three parameters).
"""

from __future__ import annotations

import numpy as np

from phonglab.stats import ALPHA, z_critical

TRUTH = (0.3, 0.4, 30.0)
START = (0.45, 0.05, 8.0)
RES, SPP, TARGET_SPP = 32, 16, 512


def test_recovers_a_known_phong_from_its_render(variant_llvm_rgb):
    from phonglab.fit import render_fit as rf
    scene = rf.sphere_scene(rf.phong_dict(*TRUTH), RES)
    target = rf.render(scene, TARGET_SPP, seed=10 ** 6)
    fit = rf.fit_image(target, START, res=RES, spp=SPP, iterations=160, average=50)
    assert fit.losses[-1] < 0.5 * fit.losses[0]
    lo, hi = np.array(rf.PHONG.bounds).T
    assert all(lo[k] <= v <= hi[k] for h in fit.history for k, v in enumerate(rf.PHONG.variables(h)))
    assert all(h[0] + h[1] <= 1.0 + 1e-6 for h in fit.history)
    x_true = rf.PHONG.variables(TRUTH)
    J = rf.jacobian(scene, x_true, 64)
    var_target = rf.pixel_variance(scene, 64, renders=8) * 64 / TARGET_SPP
    sd = np.sqrt(np.diag(rf.parameter_covariance(J, var_target)))
    tol = z_critical(ALPHA, 3) * np.sqrt(sd ** 2 + fit.batch_se ** 2)
    assert np.all(np.abs(fit.x - x_true) <= tol), (fit.fitted, fit.x - x_true, tol)
    # The start is far outside the tolerance: the test measures recovery, not the start.
    assert np.all(np.abs(rf.PHONG.variables(START) - x_true) > 5 * tol)
