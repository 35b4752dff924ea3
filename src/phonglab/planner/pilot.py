r"""The planner's pilot: short renders that measure the depth bias, the noise and the time.

With ``P`` passes of ``s`` samples each (pass k of every depth uses the seed
:func:`phonglab.engine.render.pass_seed` (seed, k), so the passes of two depths follow the same paths
up to the shallower depth), ``full_k`` the pass images at full depth and ``depth_k`` those at
depth d, ``D_k = full_k − depth_k`` and per pixel and channel:

* weights      w ≈ 1/(r² + ε), from a second full-depth pilot with other seeds (:func:`_weights`);
* depth bias   b(d)² = mean[((mean_k D_k)² − var_k(D_k)/P) · w]  (:func:`depth_bias2`); at the
  depths of the first ladder stage the second pilot measures it again (its own D_k, the first
  pilot's weights) and :meth:`Pilot.measure` pools the two by samples.  A pixel's term is 0
  unless two of its passes found the omitted bounces (with one, (mean_k D)² and var_k(D)/P
  cancel), so where they are rare the estimate of a small pilot is mostly 0 with a rare large
  value: nb_sphere_row at 512×128 has b(4) = 0.0021 (pilots of 64 spp, two seeds), and its
  default pilot (4 passes of 1 spp) measured 3e-6 to 0.003 over ten seeds, six under the
  budget 0.00125 (the plan chose depth 4 and missed E by 6 %); pooled with the second pilot
  (16 spp, stratified) seeds 1-6 gave 0.0015 to 0.0029, every one over it;
* noise        σ² = s · var_k(pass_k), the variance of one sample; a render of N samples per
  pixel has the relative noise n(N)² = mean[σ² · w]/N (:attr:`DepthSample.noise_per_sample`
  is n(1));
* time         T(spp) = a + b·spp, fitted to timed renders (:func:`_time_model`).

**One render for many depths.**  In RGB and mono variants (emitters not hidden) the depth
images come from :mod:`.ladder`: one full-depth path per sample whose prefix sums are the
images ``path`` renders at each depth of a stage of :data:`LADDER_STAGES` (sample for sample,
tested), so a stage costs one render and one JIT kernel instead of one per depth, and the gap
the bisection searches is rendered at once (:meth:`Pilot.prefetch`).  Measured side by side
(128², pilot of 16 spp, kernels compiled, pilot and time model): glass_slab (10 depths) 0.60 s
in 4 renders against 0.88 s in 12 on a quiet machine (3.1 s against 6.6 s at load average
~5); gray_direct (2 depths) 0.22 s against 0.27 s (1.4 s against 1.9 s loaded).
Other variants keep one ``path`` render per depth.

The package docstring (:mod:`phonglab.planner`) derives each of them and gives the sources.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..engine import render
from ..engine.metrics import REL_EPS
from ..engine.scenes import SceneInfo, path_integrator
from . import ladder

#: ε of the relative error E = √mean((x − r)²/(r² + ε)) (phonglab.engine.metrics.relative_rmse).
EPS = REL_EPS
#: The depth bias may use at most this fraction of the target error (b(d) <= BIAS_FRACTION · E).
BIAS_FRACTION = 0.25
#: Candidate depths, searched in order, then bisected between the last failing and first passing.
DEPTH_LADDER = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64)
#: The depth ladder's renders (:mod:`.ladder`): a stage is rendered when the search reaches it
#: (each AOV costs film splats per sample, so a shallow scene should not pay for deep depths).
LADDER_STAGES = ((1, 2, 3, 4), (6, 8, 12, 16), (24, 32, 48, 64))
#: Pilot: total samples per pixel, split into this many passes of equal size (same seeds per depth).
PILOT_SPP = 64
PILOT_PASSES = 4
#: The later ladder stages keep the pilot within this fraction of the render's predicted samples
#: (:meth:`Pilot.limit`).
PILOT_FRACTION = 0.25
#: Films of more pixels than this get a pilot of the same number of samples per image
#: (PILOT_SPP · PILOT_PIXELS), at least MIN_PILOT_SPP per pixel: the pilot's statistics are
#: means over the image (bias b(d), noise n(1)), as precise with fewer samples per pixel over
#: more pixels, and a pilot of 64 spp at 256² cost as much as the render it plans.
PILOT_PIXELS = 64 * 64
MIN_PILOT_SPP = 4
#: The stratified pilot render (weights and the sampler's gain) is made of passes of this many
#: samples per pixel (at least 2 passes): the gain it measures is that of such passes, and a
#: planned stratified render's passes hold at least as many.
STRATIFIED_PASS_SPP = 8


def pilot_size(pixels: int, passes: int = PILOT_PASSES) -> tuple[int, int]:
    """(samples per pixel, passes) of the default pilot of a film of ``pixels``: the samples of
    PILOT_SPP over PILOT_PIXELS pixels, between MIN_PILOT_SPP and PILOT_SPP per pixel, in at
    most ``passes`` passes (fewer when there are fewer samples; spp a multiple of them)."""
    spp = PILOT_SPP * PILOT_PIXELS / max(pixels, 1)
    spp = max(MIN_PILOT_SPP, min(PILOT_SPP, int(spp)))
    passes = max(2, min(passes, spp))
    return spp // passes * passes, passes
#: Time per sample of multijitter over ``independent`` at the pass counts
#: :func:`.choice.stratified_layout` uses (:data:`.choice.CHEAP_PASS_SPP`; every count it is
#: asked for is a kernel of its own, so it is not timed apart): measured 1.06-1.11x on
#: gray_direct, gray_room, cornell_phong and glass_slab, 1.24x on nb_sphere_row (128²,
#: max_depth 8, 256-1024 spp, medians of 3); 1.05-1.08x at 8, 16 and 64 spp.  The time model,
#: rendered with multijitter where the plan may stratify, divides its time per sample by this
#: to price ``independent``.
STRATIFIED_COST = 1.15
#: The time model renders 1 spp and enough spp for TIME_SAMPLES samples (at least 2): its fit
#: a + b·spp needs two sizes, not many samples (4 spp at 128², 2 at 256² and beyond, where
#: 4 spp cost deep rgb scenes ~0.2 s of the pilot).
TIME_SPP = 1
TIME_SAMPLES = 4 * 128 * 128
#: Seed of the pilot relative to the render's (pass k uses render.pass_seed(seed, k)): a plan
#: for a render of seed S pilots with S + PILOT_SEED (:attr:`.planning.PlanOptions.pilot_seed`).
#: The pilot renders with seeds seed, seed + 1 (second pilot), seed + 2, ... (later ladder
#: stages, at most 3) and seed + TIME_SEED, ... (time model).
PILOT_SEED = 1
TIME_SEED = 7
#: The pilot's renders use seeds PILOT_SEED to PILOT_SEED + PILOT_SEEDS (relative to its own).
PILOT_SEEDS = TIME_SEED + 7


@dataclass
class DepthSample:
    """Pilot statistics at one max_depth."""

    depth: int
    bias: float            #: b(d): relative RMS of the omitted (deeper) contribution
    energy_omitted: float  #: Σ(full − depth) / Σ full over the image: energy of deeper bounces
    noise_per_sample: float  #: √mean(σ²/(r² + ε)): relative noise of a 1-spp image


def depth_bias2(diff: np.ndarray, weight: np.ndarray) -> float:
    """b² = mean[((mean_k D_k)² − var_k(D_k)/P) · w] from the (P, H, W, C) pass differences
    D_k = full_k − depth_k of P >= 2 independent passes (unbiased for mean[(E D)² · w])."""
    mean = diff.mean(axis=0)
    se2 = diff.var(axis=0, ddof=1) / diff.shape[0]
    return float(np.mean((mean * mean - se2) * weight))


def _weights(passes_img: np.ndarray) -> np.ndarray:
    r"""Per-value weights ≈ 1/(r² + ε) of the relative MSE, from P pass images of an estimate of r.

    With r̂ the pass mean, se² its squared standard error (``var_k/P``), q = r² + ε and
    f(r) = 1/q, the delta method (second-order Taylor expansion about r, E[r̂ − r] = 0) gives
    E[f(r̂)] ≈ f(r) + ½ f''(r)·se², with f''(r) = (6r² − 2ε)/q³, so
    E[1/(r̂² + ε)] ≈ (1 + (3r² − ε)·se²/q²)/q.  Dividing 1/(r̂² + ε) by that factor (evaluated
    at r̂) removes the second-order bias a noisy r̂ adds: without it dark, noisy pixels
    (r² < ε/3, where f is concave) would weigh too little and bright, noisy ones too much.
    The factor is kept >= 1/2 (it falls below 1/2 only where se² > ε/2 at r ≈ 0): there the
    expansion no longer holds and the uncorrected weight is the safer estimate.
    """
    r2 = passes_img.mean(axis=0) ** 2
    se2 = passes_img.var(axis=0, ddof=1) / passes_img.shape[0]
    q = r2 + EPS
    return 1.0 / q / np.maximum(1.0 + (3.0 * r2 - EPS) * se2 / (q * q), 0.5)


def stratification_gain(indep: np.ndarray, indep_spp: int, indep_weights: np.ndarray,
                        strat: np.ndarray, strat_spp: int, strat_weights: np.ndarray) -> float:
    r"""How many times fewer samples a stratified sampler needs than the independent one.

    ``indep`` and ``strat`` are (P, H, W, C) pass images of ``indep_spp`` and ``strat_spp``
    samples per pass.  For i.i.d. samples ``s · var_k(pass_k)`` is the variance of one sample
    whatever s is; for stratified ones it is the variance an image of s samples per pixel has,
    times s, which falls as strata refine.  The gain is the ratio of the two relative
    variances, ``mean(s_i var_i · w) / mean(s_s var_s · w)``, each weighted by the *other*
    render's weights (:func:`_weights`), so that no variance is weighted by a mean drawn from
    the same samples.  It holds for passes of ``strat_spp`` samples; passes of more samples
    gain at least as much (jittered strata only refine: Owen, "Monte Carlo and quasi-Monte
    Carlo for statistics", 2009; Pharr, Jakob & Humphreys, PBR 4th ed., §8.5), so using it
    for a longer render errs towards more samples.
    """
    v_indep = float(np.mean(indep.var(axis=0, ddof=1) * indep_spp * indep_weights))
    v_strat = float(np.mean(strat.var(axis=0, ddof=1) * strat_spp * strat_weights))
    if v_strat <= 0.0:
        return 1.0 if v_indep <= 0.0 else math.inf
    return v_indep / v_strat


def _time_model(scene, integrator, seed: int, spp_small: int = TIME_SPP, repeats: int = 3,
                sensor=0) -> tuple[tuple[float, float], list[render.RenderResult]]:
    """((a, b) of T(spp) = a + b·spp, the renders timed) from alternating one-pass renders of
    spp_small and spp_big = max(2·spp_small, ⌈TIME_SAMPLES / pixels⌉) samples per pixel.

    Each render goes through :func:`phonglab.engine.render.render_scene`, the loop the planned render
    runs, and its ``pass_seconds[0]`` (``mi.render``, evaluation and the copy to numpy) is the
    time.  Medians of ``repeats`` renders each, render i with seed ``seed + i`` (their images
    are samples of the scene like any other: :meth:`Pilot.reusable`); the kernel must already
    be compiled.
    """
    w, h = (int(v) for v in scene.sensors()[0].film().size())
    spp_big = max(2 * spp_small, -(-TIME_SAMPLES // (w * h)))
    t_small, t_big, renders = [], [], []
    for k in range(repeats):
        for spp, bucket in ((spp_small, t_small), (spp_big, t_big)):
            timed = render.render_scene(scene, spp, seed=seed + len(renders), sensor=sensor,
                                        integrator=integrator, keep_passes=True)
            bucket.append(timed.pass_seconds[0])
            renders.append(timed)
    ts, tb = float(np.median(t_small)), float(np.median(t_big))
    b = (tb - ts) / (spp_big - spp_small)
    if b <= 0:  # timing noise swamped the difference: charge everything per sample
        return (0.0, tb / spp_big), renders
    return (max(ts - b * spp_small, 0.0), b), renders


def merged(passes_img: np.ndarray, pass_spp: list[int]) -> render.RenderResult:
    """The (P, H, W, C) pass images of ``pass_spp`` samples each as one render
    (:class:`phonglab.engine.render.PassMerge`: its image and standard error)."""
    merge = render.PassMerge(int(sum(pass_spp)), len(pass_spp))
    for img, n in zip(passes_img, pass_spp):
        merge.add(img, int(n))
    return merge.result(0.0, [])


class Pilot:
    """The pilot renders of one loaded scene, and the statistics drawn from them.

    Construction renders the two full-depth pilots (the reference of the depth bias and, with
    other seeds, the weights); :meth:`measure` renders a depth on first use and caches it.
    """

    def __init__(self, scene, info: SceneInfo, spp: int = PILOT_SPP,
                 passes: int = PILOT_PASSES, seed: int = PILOT_SEED, stratified=None):
        self.scene, self.info, self.passes, self.seed = scene, info, passes, seed
        self.spp_per_pass = spp // passes
        #: one-render depth ladder (:mod:`.ladder`) where it applies, else one render per depth
        self.one_kernel = ladder.applies(info)
        self.renders = 0  #: pilot renders made (each spp samples per pixel)
        self.first_seconds = 0.0  #: wall time of the first (full-depth) pilot render
        #: depth -> (full-depth passes of the ladder render that held it, its passes at that
        #: depth, that render's seed, its samples per pass)
        self.ladder_images: dict[int, tuple[np.ndarray, np.ndarray, int, int]] = {}
        #: samples per pixel of a later ladder stage (:meth:`limit`)
        self.stage_spp = spp
        #: histogram of the vertices the ladder's full-depth paths found (:func:`.ladder.work`)
        self.lengths = np.zeros(ladder.LENGTH_BINS)
        #: (failing, passing, value) when :meth:`search_depth` left a gap unsearched
        self.gap_skipped: tuple[int, int, float] | None = None
        self.stratified = stratified
        #: seed of the next ladder render beyond the first two (each later stage draws new
        #: samples: :meth:`prefetch`)
        self.next_seed = seed + 2
        if self.one_kernel:
            self.full, depth_images = self._render_ladder(LADDER_STAGES[0])
            self.ladder_images = {d: (self.full, imgs, seed, self.spp_per_pass)
                                  for d, imgs in depth_images.items()}
        else:
            self.full = self._render(-1, seed)
        # The weights come from an independent full-depth pilot (other seeds): taken from
        # `full` itself they would shrink exactly where a rare bright sample inflates the
        # variance (a caustic firefly raises both), and the noise would be underestimated.
        # (From the first ladder stage's kernel where the ladder applies: no second compile.)
        # With a stratified sensor it is that sampler's render, in passes of
        # STRATIFIED_PASS_SPP: it also measures the sampler's gain (:func:`stratification_gain`)
        # at no extra cost.
        size: dict = {}
        if stratified is not None:
            spp = max(self.spp, 2 * STRATIFIED_PASS_SPP)
            size = {"spp": spp, "passes": spp // STRATIFIED_PASS_SPP, "sensor": stratified}
        second, second_depths = (self._render_ladder(LADDER_STAGES[0], seed + 1, **size)
                                 if self.one_kernel else (self._render(-1, seed + 1, **size), {}))
        self.weight = _weights(second)
        # Its depth images (the ladder's first stage) estimate the depth bias again, with
        # other samples, weighted by the first pilot's weights (:meth:`measure`).
        self.second, self.second_depths = second, second_depths
        self.second_spp = size.get("spp", self.spp)
        self.second_weight = _weights(self.full)
        #: n(1)² of the scene's sampler over that of the stratified one at its pass size
        #: (1 without a stratified sensor): the factor fewer samples it needs (full depth)
        self.gain = 1.0
        self.stratified_pass_spp = 0
        if stratified is not None:
            self.stratified_pass_spp = render.pass_spps(self.scene, size["spp"], size["passes"],
                                                        stratified)[0]
            self.gain = stratification_gain(self.full, self.spp_per_pass, self.weight,
                                            second, self.stratified_pass_spp,
                                            self.second_weight)
        self.samples: dict[int, DepthSample] = {}
        self.compiled: set[int] = set()  #: finite depths whose kernel the pilot compiled
        #: per depth: (H, W) channel mean of σ²·w, the relative variance of one sample per pixel
        self.variance_maps: dict[int, np.ndarray] = {}
        self.time_models: dict[int, tuple[float, float]] = {}
        #: per depth: its pass images and their seed (the first pilot's, or a later ladder
        #: stage's), those of the second pilot (kept for :meth:`reusable`), and the time
        #: model's renders (with the render that compiled its kernel)
        self.depth_passes: dict[int, tuple[np.ndarray, int]] = {}
        self.second_depth_passes: dict[int, np.ndarray] = {}
        self.timed: dict[int, list[render.RenderResult]] = {}

    @property
    def spp(self) -> int:
        """Samples per pixel of each pilot render (passes × samples per pass)."""
        return self.spp_per_pass * self.passes

    def _pilot_render(self, integrator, seed: int, spp: int | None = None,
                      passes: int | None = None, sensor=0) -> np.ndarray:
        """The pass images of one pilot render (the pilot's spp and passes unless given);
        :attr:`first_seconds` keeps the first one's wall time."""
        self.renders += 1
        done = render.render_scene(self.scene, spp or self.spp, seed=seed,
                                   passes=passes or self.passes, sensor=sensor,
                                   integrator=integrator, keep_passes=True)
        if self.renders == 1:
            self.first_seconds = done.seconds
        return done.passes

    def _render(self, depth: int, seed: int, **size) -> np.ndarray:
        """The pass images of a ``path`` render at ``depth`` (``size``: :meth:`_pilot_render`)."""
        return self._pilot_render(path_integrator(depth, self.info), seed, **size)

    def _render_ladder(self, depths, seed: int | None = None,
                       **size) -> tuple[np.ndarray, dict[int, np.ndarray]]:
        """One ``DepthLadder`` (:func:`.ladder.ladder_class`) render (the pilot's seed unless given): its
        full-depth pass images and those of every depth in ``depths`` (the same samples, so
        ``full − depth`` is what two renders with the same seeds would give)."""
        integrator = ladder.ladder(depths, self.info)
        imgs = self._pilot_render(integrator, self.seed if seed is None else seed, **size)
        self.lengths += np.array(integrator.lengths, dtype=np.float64)
        return ladder.split(imgs, depths)

    def unrendered(self, depths) -> list[int]:
        """The finite depths of ``depths`` neither measured nor held by a ladder render."""
        return [d for d in depths if d > 0 and d not in self.samples
                and d not in self.ladder_images]

    def prefetch(self, depths) -> None:
        """Render the depths not yet measured in one ladder render (one-kernel pilots only),
        with a seed of its own: its D_k = full_k − depth_k are formed from its own full-depth
        paths, and its depth images are samples no other pilot render holds
        (:meth:`reusable`)."""
        missing = self.unrendered(depths)
        if self.one_kernel and missing:
            full, images = self._render_ladder(missing, self.next_seed, spp=self.stage_spp)
            per_pass = self.stage_spp // self.passes
            self.ladder_images.update({d: (full, imgs, self.next_seed, per_pass)
                                       for d, imgs in images.items()})
            self.next_seed += 1

    def variance_map(self, passes_img: np.ndarray, per_pass: int | None = None) -> np.ndarray:
        """(H, W) mean over channels of σ² · w, σ² = s · var_k(pass_k) the variance of one
        sample: the relative variance a pixel's sample carries (what adaptive sampling
        allocates by)."""
        sigma2 = passes_img.var(axis=0, ddof=1) * (per_pass or self.spp_per_pass)
        return (sigma2 * self.weight).mean(axis=-1)

    def noise_per_sample(self, passes_img: np.ndarray) -> float:
        """n(1) = √mean(σ² · w), σ² = s · var_k(pass_k) the variance of one sample."""
        return math.sqrt(float(np.mean(self.variance_map(passes_img))))

    def measure_model(self, integrator) -> tuple[float, np.ndarray, tuple[float, float]]:
        """(n(1), variance map, (a, b) of T = a + b·spp) of another integrator of the scene
        (the planner's cheaper exact models), rendered like the depth pilots."""
        imgs = self._pilot_render(integrator, self.seed)
        vmap = self.variance_map(imgs)
        return (math.sqrt(float(np.mean(vmap))), vmap,
                _time_model(self.scene, integrator, self.seed + TIME_SEED)[0])

    def measure(self, d: int) -> DepthSample:
        """The :class:`DepthSample` of max_depth d (-1: full depth, no bias), rendered once."""
        if d not in self.samples:
            if d == -1:
                self.samples[d] = DepthSample(-1, 0.0, 0.0, self.noise_per_sample(self.full))
                self.variance_maps[d] = self.variance_map(self.full)
            else:
                if self.one_kernel and d not in self.ladder_images:
                    self.prefetch(next((st for st in LADDER_STAGES if d in st), (d,)))
                full, seed, per_pass = self.full, self.seed, self.spp_per_pass
                if d in self.ladder_images:
                    full, imgs, seed, per_pass = self.ladder_images.pop(d)
                else:   # a path render with the first pilot's seeds
                    imgs = self._render(d, self.seed)
                    self.compiled.add(d)
                self.depth_passes[d] = (imgs, seed, per_pass)
                diff = full - imgs
                bias2 = depth_bias2(diff, self.weight)
                if d in self.second_depths:  # the second pilot's estimate, pooled by samples
                    self.second_depth_passes[d] = self.second_depths.pop(d)
                    bias2_second = depth_bias2(self.second - self.second_depth_passes[d],
                                               self.second_weight)
                    bias2 = ((self.spp * bias2 + self.second_spp * bias2_second)
                             / (self.spp + self.second_spp))
                energy = float(diff.mean(axis=0).sum()) / (float(full.mean(axis=0).sum()) or 1.0)
                self.variance_maps[d] = self.variance_map(imgs, per_pass)
                self.samples[d] = DepthSample(d, math.sqrt(max(bias2, 0.0)),
                                              energy if abs(energy) > 1e-9 else 0.0,
                                              math.sqrt(float(np.mean(self.variance_maps[d]))))
        return self.samples[d]

    def gap_value(self, failing: int, passing: int, target_error: float) -> float:
        """At most how many times its own cost a ladder render of the depths between
        ``failing`` and ``passing`` can save on the planned render (one-kernel pilots).

        With W(d) the mean ray casts per sample at depth d (:func:`.ladder.work`, from the
        lengths of the pilot's full-depth paths) and N = n(1)²/(E² − b²) the uniform spp at
        ``passing``, a depth in the gap saves at most N·(W(passing) − W(failing + 1)) casts
        per pixel, and the gap's render costs spp·W(−1) (the pilot's spp, full depth).  Both
        err towards searching: the ladder costs more per cast than ``path`` (its AOVs), and
        a stratified or adaptive render takes fewer than N samples.
        """
        s = self.measure(passing)
        budget2 = target_error ** 2 - s.bias ** 2
        if budget2 <= 0 or not self.lengths.any():
            return math.inf
        n = s.noise_per_sample ** 2 / budget2
        saved = ladder.work(self.lengths, passing) - ladder.work(self.lengths, failing + 1)
        # the gap's render is priced at the pilot's full size, whatever :meth:`limit` gave
        # the stages: a render's launches and passes cost as much as its samples on a cheap
        # scene (gray_room at 128² chose depth 5 over 6 with a 4-spp gap render and took
        # 0.05 s longer in all)
        return saved * n / (ladder.work(self.lengths, -1) * self.spp)

    def limit(self, target_error: float) -> None:
        r"""Size the later ladder stages so that the pilot's renders stay within
        :data:`PILOT_FRACTION` of the samples the render is predicted to need.

        With n(1) the first pilot's relative noise at full depth, the render needs about
        N = n(1)²/E² samples per pixel; the first two pilot renders hold ``spp + second_spp``
        of them, and each later stage gets what is left of PILOT_FRACTION · N, between one
        sample per pass and the first pilot's spp.  A cheap scene (gray_room at 128²: N ≈ 95,
        the first two renders 32) thus searches deeper stages with 4 spp (65 536 samples of
        the image: its b(d) is an image mean), and an expensive one with the pilot's full
        size.  Their samples are not lost either way (:meth:`reusable`).
        """
        n = self.measure(-1).noise_per_sample ** 2 / target_error ** 2
        left = PILOT_FRACTION * n - (self.spp + self.second_spp)
        per_pass = int(min(self.spp_per_pass, max(1, left // self.passes)))
        self.stage_spp = per_pass * self.passes

    def search_depth(self, allowed: float, cap: int = DEPTH_LADDER[-1],
                     target_error: float | None = None) -> tuple[int, int]:
        """(depth, failing): the smallest depth with b(d) <= ``allowed``, and the deepest one
        measured that fails (0 when depth 1 passes).

        The ladder :data:`DEPTH_LADDER` (depths <= ``cap``) is climbed until a depth passes,
        then the gap to the last failing one is bisected (b is non-increasing in d).  When no
        depth up to ``cap`` passes, ``depth`` is -1 (unbounded).  Given ``target_error``, a
        gap that needs a render of its own is searched only when that render can pay for
        itself (:meth:`gap_value` >= 1); otherwise ``depth`` is the passing ladder depth and
        :attr:`gap_skipped` says why (Russian roulette leaves few paths that deep: glass_slab
        and cornell_phong cost the same at depth 9 to 16, measured).
        """
        if target_error is not None:
            self.limit(target_error)
        failing, passing = 0, None
        for d in (d for d in DEPTH_LADDER if d <= cap):
            if self.measure(d).bias <= allowed:
                passing = d
                break
            failing = d
        if passing is None:
            self.measure(-1)
            return -1, failing
        if (self.one_kernel and target_error is not None
                and self.unrendered(range(failing + 1, passing))):
            value = self.gap_value(failing, passing, target_error)
            if value < 1.0:
                self.gap_skipped = (failing, passing, value)
                return passing, failing
        self.prefetch(range(failing + 1, passing))
        while passing - failing > 1:
            mid = (passing + failing) // 2
            if self.measure(mid).bias <= allowed:
                passing = mid
            else:
                failing = mid
        return passing, failing

    def time_model(self, depth: int) -> tuple[float, float]:
        """(a, b) of T(spp) = a + b·spp at ``depth``, steady state (the kernel compiled first);
        measured once per depth (steps 4 and 5 both ask)."""
        if depth not in self.time_models:
            integrator = path_integrator(depth, self.info)
            # with the stratified sensor where the plan may stratify: the renders are then
            # worth that sampler's samples to the planned render (:meth:`reusable`), and the
            # time per sample of ``independent`` is theirs over STRATIFIED_COST
            sensor = self.stratified if self.stratified is not None else 0
            timed = []
            if depth not in self.compiled:  # compile the kernel before timing
                timed.append(render.render_scene(self.scene, 1, seed=self.seed + TIME_SEED,
                                                 sensor=sensor, integrator=integrator,
                                                 keep_passes=True))
            (a, b), renders = _time_model(self.scene, integrator, self.seed + TIME_SEED + 1,
                                          sensor=sensor)
            self.time_models[depth] = (a, b / STRATIFIED_COST if sensor else b)
            self.timed[depth] = timed + renders
        return self.time_models[depth]

    def reusable(self, depth: int) -> list[tuple[render.RenderResult, np.ndarray]]:
        r"""The pilot's renders that are samples of the planned render's image at ``depth``,
        one per independent seed, for :func:`phonglab.engine.render.combine_renders`, each with
        weights ≈ 1/(r² + ε) from other samples than its own (the second pilot's for every
        render but the second pilot, the first pilot's for it) to measure its precision by.

        * the first pilot's seeds: its images at ``depth`` (the ladder's, or a ``path``
          render's), else its full-depth images, and the images at ``depth`` of a later
          ladder stage (seeds of its own);
        * the second pilot (other seeds; stratified when the plan may stratify): its images
          at ``depth`` when its ladder stage held it, else its full-depth images;
        * the time model's renders at ``depth`` (and the render that compiled its kernel), one
          pass each, as one render of unequal passes.

        A full-depth image has the expectation of the unbounded image, which exceeds the one
        at ``depth`` by the deeper bounces' energy D >= 0 (radiance is never negative), so a
        combination that includes one has a depth bias (1 − λ)·D, λ its weight: at most the
        plan's b(d), and the error the plan reports stays an upper bound.  Every render here
        has two passes or more (a standard error), and none shares a seed with the render
        planned after it when the pilot's seed differs from the render's
        (:func:`.planning.plan`; ``phonglab render`` uses the render's seed + 1).
        """
        groups = []
        imgs, seed, per_pass = self.depth_passes.get(depth, (None, None, 0))
        full = [(self.full, self.spp_per_pass)]
        for passes_img, n in (full if imgs is None else [(imgs, per_pass)] if seed == self.seed
                              else full + [(imgs, per_pass)]):
            groups.append((merged(passes_img, [n] * len(passes_img)), self.weight))
        second = self.second_depth_passes.get(depth, self.second)
        per = self.stratified_pass_spp or self.second_spp // len(second)
        groups.append((merged(second, [per] * len(second)), self.second_weight))
        # the time model's renders, one group per size (passes of one size: with a stratified
        # sampler a pass's variance is not that of its samples over its count)
        timed = self.timed.get(depth, [])
        for size in sorted({int(t.pass_spp[0]) for t in timed}):
            same = [t for t in timed if int(t.pass_spp[0]) == size]
            if len(same) >= 2:
                imgs = np.concatenate([t.passes for t in same])
                groups.append((merged(imgs, [size] * len(same)), self.weight))
        return groups

    def depths(self) -> list[DepthSample]:
        """Every depth measured, finite ones in order, then -1."""
        return [self.samples[d] for d in sorted(self.samples, key=lambda d: (d == -1, d))]
