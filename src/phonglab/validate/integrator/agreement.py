r"""The ``agreement`` topic: the integrator against Mitsuba's ``path`` on a scene without a
closed form (:func:`phonglab.validate.integrator.scenes.box`: diffuse walls, an area light,
a glossy ``roughplastic`` sphere), at the same max_depth.

Each side renders P passes of ``agreement_spp`` samples per pixel with its own seeds; the box
filter (radius ½) puts every sample in one pixel, so pixels, and blocks of
``agreement_block``² pixels, are independent.  Per block: the mean over its pixels and
channels in each pass, the mean of the P pass values and its standard error s/√P; Welch's
two-sample t-test (:func:`phonglab.stats.welch_pvalues`, Welch–Satterthwaite dof) of the two
sides.  Every block is one statistical test at the Šidák level of the plugin's m tests; the
row fails when the smallest p-value is below it.  ``path`` is the reference because it is
validated by ``bias`` itself (docs/validate.md).

Depth: 5 for an integrator that takes max_depth, its own for one held to a fixed depth
(``direct``: ``path`` at max_depth 2 computes the same expectation, emission plus direct
illumination with MIS); an integrator whose measured depth matched no integer depth or an AOV integrator is skipped.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ... import stats
from ...engine.render import render_scene
from . import scenes
from .config import seed
from .setup import Target
from ...verdict import NOT_APPLICABLE
from .topics import Row

#: The max_depth of the agreement scene for an integrator that takes one.
DEPTH = 5


def depth_of(target: Target) -> tuple[int | None, str]:
    """(the depth both sides render at, "") or (None, why the topic is skipped)."""
    if target.aov:
        return None, "an AOV integrator returns channels that are not radiance"
    if target.depth == "settable":
        return DEPTH, ""
    if target.own_depth is not None:
        return target.own_depth, ""
    return None, target.depth_note


def blocks(opts) -> int:
    """The number of block tests (one per block of the film)."""
    return (opts.agreement_res // opts.agreement_block) ** 2


def _block_means(res, b: int) -> np.ndarray:
    """(passes, blocks) block means of a render's passes."""
    p = np.asarray(res.passes, np.float64).mean(axis=-1)          # (P, H, W)
    n, h, w = p.shape
    return p[:, :h - h % b, :w - w % b].reshape(n, h // b, b, w // b, b).mean(axis=(2, 4)) \
        .reshape(n, -1)


def agreement(target: Target, opts, m: int) -> list[Row]:
    depth, why = depth_of(target)
    name = f"block means against path (max_depth {depth})" if depth else "block means against path"
    if depth is None:
        return [Row("agreement", name, None, None, None, None, "skipped", why,
                    {NOT_APPLICABLE: True} if target.aov else {})]
    integ = target.make(depth)
    ref = mi.load_dict({"type": "path", "max_depth": int(depth)})
    scene = mi.load_dict(scenes.box(opts.agreement_res))
    spp, p = opts.agreement_spp * opts.agreement_passes, opts.agreement_passes
    sides = [render_scene(scene, spp, seed=seed(opts.seed, "agreement", k), passes=p,
                          integrator=i, keep_passes=True) for k, i in enumerate((integ, ref))]
    b = opts.agreement_block
    (m1, s1), (m2, s2) = [(v.mean(axis=0), v.std(axis=0, ddof=1) / np.sqrt(len(v)))
                          for v in (_block_means(r, b) for r in sides)]
    pv, t = stats.welch_pvalues(m1, s1, m2, s2, p, p)
    level = stats.sidak(stats.ALPHA, m)
    worst = int(np.argmin(pv))
    ok = bool(np.all(np.isfinite(m1)) and pv[worst] >= level)
    return [Row("agreement", name, float(pv[worst]), level, None, None,
                "pass" if ok else "fail",
                f"Welch t-test of {len(pv)} blocks of {b}×{b} pixels, {p} passes × "
                f"{opts.agreement_spp} spp a side; smallest p-value against the Šidák level "
                f"(m = {m}); worst block {worst}: {m1[worst]:.5g} ± {s1[worst]:.2g} against "
                f"path {m2[worst]:.5g} ± {s2[worst]:.2g}",
                {"relation": ">=", "p_values": pv.tolist(), "t": t.tolist(),
                 "block_means": m1.tolist(), "path_block_means": m2.tolist(),
                 "max_depth": depth})]
