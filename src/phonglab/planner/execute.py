r"""Executing a plan: :func:`render_plan` renders what :func:`.planning.plan` chose and reports
its error (:meth:`PlannedRender.describe` says what it did); the CLI (``phonglab render
--target-error E``) and the bench (:mod:`phonglab.bench.adaptive_sweeps`) both run plans
through it.

**The render** (:func:`sampling`, :func:`integrator`):

* uniform ``path`` (``plan.uses_wavefront`` false): :class:`phonglab.engine.render.UniformPasses`
  with :meth:`.Plan.render_kwargs` (the chosen sampler, spp and passes), the scene's own
  integrator at ``plan.max_depth``;
* anything else, another model or adaptive sampling: :class:`phonglab.engine.adaptive.AdaptiveSampling`
  with the model's integrator (:func:`.choice.model_dict`; the scene's own at
  ``plan.max_depth`` for ``path``) and the noise target √(E² − b²)
  (:attr:`.Plan.noise_target`, :func:`phonglab.engine.metrics.noise_target`); a uniform one traces
  ⌈``plan.render.spp``⌉ samples (at least 2: the error estimate needs a variance) in every pixel.

The scene is the one the pilot loaded and inspected (:attr:`.Plan.loaded`, :attr:`.Plan.info`;
:func:`phonglab.engine.render.open_scene_file`): Mitsuba loads it once per ``render``, not twice, and
a declared ``$max_depth`` is applied by rebuilding the scene's integrator with the plan's
depth, the integrator a reload would give.  Pass k has the seed
:func:`phonglab.engine.render.pass_seed` (seed, k) on either route.

**The error report** (:class:`ErrorReport`): E is the total relative error against a converged
reference, bias included (:mod:`phonglab.engine.metrics`, the one definition).  Achieved: against the
reference given, else the cached one of the planned scene and colour model
(:func:`phonglab.engine.references.cached`), when there is one, the reference's noise subtracted.
Estimated: √(n² + b²), n the render's relative noise (from its passes, uniform, weighed by the
pilot's weights ≈ 1/(r² + ε) rather than by the render's own image, whose fireflies would
weigh themselves down; the combination's 1/√Σ n_j/V_j when the render is combined with the
pilot's; from its samples, wavefront) and b the pilot's depth bias.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..engine import metrics, references
from ..engine.adaptive import MIN_SPP, AdaptiveResult, AdaptiveSampling
from ..registration import register
from ..engine.references import Reference
from ..engine.render import (RenderResult, SceneFile, UniformPasses, open_scene_file,
                             render_scene_file)
from ..runtime import quiet_mitsuba
from . import choice
from .planning import Plan


@dataclass
class ErrorReport:
    """What a planned render's error came to (module docstring)."""

    target: float                    #: E, the plan's total relative error target
    predicted: float                 #: the plan's √(b² + n²)
    bias: float                      #: b, the pilot's depth bias
    noise: float | None              #: the render's relative noise (None: one pass)
    achieved: float | None = None    #: against the reference (None: none at hand)
    reference_spp: int | None = None

    @property
    def estimated(self) -> float | None:
        """√(n² + b²): the error the render's own noise and the pilot's bias amount to."""
        return None if self.noise is None else math.hypot(self.noise, self.bias)


@dataclass
class PlannedRender:
    """A plan's render (:func:`render_plan`): the result and its error report."""

    plan: Plan
    result: RenderResult | AdaptiveResult
    error: ErrorReport

    @property
    def image(self):
        return self.result.image

    def describe(self) -> str:
        """What the render did, as ``phonglab render --target-error`` prints it: its
        configuration, time against the prediction, and error (achieved against the cached
        reference, else estimated) against the target."""
        plan, result, error = self.plan, self.result, self.error
        target = f"target {plan.target_error:g}"
        if plan.uses_wavefront:
            lines = [f"rendered {plan.scene} with {plan.render.model}, {plan.render.sampling} "
                     f"sampling, max_depth {plan.max_depth} in {plan.variant}: "
                     f"{result.total_spp:.1f} spp on average, {result.seconds:.3g} s "
                     f"(predicted {plan.render.seconds:.3g} s steady state)"]
            if error.achieved is not None:
                lines.append(f"  error: achieved {error.achieved:.4g} against the cached "
                             f"reference ({error.reference_spp} spp); estimated "
                             f"{error.estimated:.4g}, {target}")
            else:
                lines.append(f"  error: estimated {error.estimated:.4g} (noise {error.noise:.4g} "
                             f"from the samples, depth bias {error.bias:.3g} from the pilot); "
                             f"{target}")
            return "\n".join(lines)
        times = result.pass_seconds
        # Steady state: the first pass may include JIT compilation; count it as a median pass.
        steady = statistics.median(times[1:]) * len(times) if len(times) > 1 else result.seconds
        rendered = sum(result.pass_spp) - plan.reused_spp   # its own, not the pilot's
        lines = [f"rendered {plan.scene} with {rendered} spp ({plan.render.sampler} "
                 f"sampler), max_depth {plan.max_depth} in {plan.variant}: "
                 f"{result.seconds:.3g} s ({steady:.3g} s steady state; predicted "
                 f"{plan.render.seconds:.3g} s)"]
        predicted = f"predicted {error.predicted:.4g}, {target}"
        if error.achieved is not None:
            lines.append(f"  error: achieved {error.achieved:.4g} against the cached reference "
                         f"({error.reference_spp} spp, max_depth -1); {predicted}")
        elif error.noise is not None:
            lines.append(f"  error: about {error.estimated:.4g} (noise {error.noise:.4g} "
                         f"estimated from {len(times)} passes, depth bias {error.bias:.3g} from "
                         f"the pilot; no cached reference: make one with 'phonglab plan "
                         f"{plan.scene} --make-reference 4096'); {predicted}")
        else:
            lines.append(f"  error: not measurable from one pass; {predicted}")
        return "\n".join(lines)


def sampling(plan: Plan, progress: bool = False,
             by_time: bool = False) -> UniformPasses | AdaptiveSampling:
    """How the plan's render samples (module docstring); ``by_time``: an adaptive render
    allocates by time (:func:`phonglab.engine.adaptive.render_adaptive`)."""
    chosen = plan.render
    if plan.reused is not None:   # combined with the pilot's renders: the spp chosen for that
        sampler = chosen.sampler if chosen.sampler != "independent" else None
        return UniformPasses(math.ceil(chosen.spp), chosen.passes, sampler, progress,
                             prior=plan.reused)
    if not plan.uses_wavefront:
        kw = plan.render_kwargs()
        return UniformPasses(kw["spp"], kw["passes"], kw.get("sampler"), progress)
    if chosen.sampling == "uniform":
        spp = max(2, math.ceil(chosen.spp))
        return AdaptiveSampling(plan.noise_target, min_spp=spp, max_spp=spp)
    return AdaptiveSampling(plan.noise_target, min_spp=MIN_SPP, by_time=by_time)


def integrator(plan: Plan) -> dict | None:
    """The ``mi.load_dict`` dictionary of the plan's model (None: the scene's own ``path``)."""
    if plan.render.model == "path":
        return None
    return choice.model_dict(plan.render.model, plan.max_depth,
                             plan.info if plan.info is not None else plan.scene,
                             plan.options.params)


def header(plan: Plan) -> dict[str, Any]:
    """What a planned render adds to its EXR header: target, predictions and the plan (and,
    for a wavefront render, max_depth, model and sampling)."""
    meta = {"target_error": plan.target_error, "predicted_error": plan.uniform.predicted_error,
            "predicted_seconds": plan.uniform.predicted_seconds, "planned": plan.to_dict()}
    if plan.uses_wavefront:
        meta.update(max_depth=plan.max_depth, model=plan.render.model,
                    sampling=plan.render.sampling)
    return meta


def _activate(plan: Plan) -> None:
    """The plan's variant, in which its loaded scene lives (the caller may have switched)."""
    if plan.loaded is not None:
        register(plan.variant)


@dataclass
class PreparedPlan:
    """A plan's scene opened for rendering without files (:func:`prepare`): :meth:`render`
    runs the render alone (what the bench times)."""

    plan: Plan
    how: UniformPasses | AdaptiveSampling
    scene_file: SceneFile

    def render(self, seed: int = 0) -> RenderResult | AdaptiveResult:
        _activate(self.plan)
        with quiet_mitsuba():
            return self.how.render(self.scene_file, seed)[0]


def prepare(plan: Plan) -> PreparedPlan:
    """The plan's scene (the pilot's, when the plan holds it), integrator and sampling, ready
    for renders that write no files."""
    how = sampling(plan)
    _activate(plan)
    with quiet_mitsuba():
        sf = open_scene_file(plan.scene, variant=how.variant(plan.variant),
                             max_depth=plan.max_depth, params=plan.options.params,
                             settings=how.settings(), integrator=integrator(plan),
                             loaded=plan.loaded, info=plan.info, quiet=how.quiet_load)
    return PreparedPlan(plan, how, sf)


def error_report(plan: Plan, result: RenderResult | AdaptiveResult,
                 reference: Reference | None = None) -> ErrorReport:
    """The render's error (module docstring): against ``reference`` (a
    :class:`phonglab.engine.references.Reference`), else the cached reference, when there is one."""
    if isinstance(result, AdaptiveResult):
        noise = result.estimated_error
    elif "combined_noise" in result.metadata:   # 1/√Σ n_j/V_j, with the pilot's weights
        noise = float(result.metadata["combined_noise"])
    elif result.stderr is None:
        noise = None
    elif plan.pilot.weight is not None:   # weighed by the pilot's image, not the render's own
        noise = math.sqrt(float(np.mean(result.stderr.astype(np.float64) ** 2
                                        * plan.pilot.weight)))
    else:
        noise = metrics.relative_noise(result.image, result.stderr)
    report = ErrorReport(plan.target_error, plan.uniform.predicted_error,
                         plan.uniform.predicted_bias, noise)
    if reference is None:
        reference = references.cached(plan.scene, params=plan.options.params,
                                      variant=references.variant_for_color(plan.color))
    if reference is not None:
        report.achieved = metrics.relative_rmse(result.image, reference.image,
                                                ref_stderr=reference.stderr)
        report.reference_spp = reference.spp
    return report


def render_plan(plan: Plan, *, seed: int | None = None, out: str | Path | None = None,
                reference: Reference | None = None, progress: bool = False,
                by_time: bool = False) -> PlannedRender:
    """Render ``plan`` (module docstring) with ``seed`` (default: the one it was planned for,
    :attr:`.PlanOptions.seed`) and report its error.

    With ``out`` the render writes its files as ``phonglab render`` does
    (:func:`phonglab.engine.render.render_scene_file`: image, standard error, preview, and the spp
    map for a wavefront render; the plan in the header, :func:`header`); without, nothing is
    written.  ``reference``: the converged image to measure the achieved error against
    (default: the cached one, when there is one).  ``progress`` shows a uniform render's
    passes.
    """
    seed = plan.options.seed if seed is None else seed
    if plan.repeats_pilot(seed):   # combining would count the same samples twice
        plan = plan.standalone()
    if out is None:
        result = prepare(plan).render(seed)
    else:
        _activate(plan)
        with quiet_mitsuba():
            result = render_scene_file(
                plan.scene, out, sampling(plan, progress, by_time), variant=plan.variant, seed=seed,
                max_depth=plan.max_depth, params=plan.options.params, integrator=integrator(plan),
                extra_metadata=header(plan), loaded=plan.loaded, info=plan.info)
    return PlannedRender(plan, result, error_report(plan, result, reference))
