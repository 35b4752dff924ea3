"""The integrator validator's sizes (quick and default) and its fixed seeds.

Every render is a number of passes of ``spp`` samples per pixel, each pass with its own
Mitsuba seed (:func:`seed`: the run's seed, the topic and the scene give a stream, the pass
number its member, :func:`phonglab.engine.render.pass_seed`), so the passes are independent and their
spread measures the Monte Carlo error.
"""

from __future__ import annotations

from dataclasses import dataclass, field

#: Per-topic offsets of the seed (fixed: changing one topic never changes another's numbers).
SEED_OFFSETS = {"finite": 41, "bias": 42, "convergence": 43, "agreement": 44, "gradient": 45,
                "cost": 46}


def seed(run_seed: int, topic: str, scene: int = 0) -> int:
    """The base seed of one scene's renders in one topic (pass k adds k via pass_seed)."""
    return (int(run_seed) * 1009 + SEED_OFFSETS[topic]) * 101 + int(scene)


@dataclass
class Options:
    """Sizes of one integrator validation run; :func:`options` builds the default or quick ones."""

    quick: bool = False
    seed: int = 0
    res: int = 16                      #: film width = height of the analytic scenes
    finite_spp: int = 32               #: one pass per scene
    bias_spp: int = 512                #: per pass
    bias_passes: int = 20
    convergence_res: int = 32
    convergence_spp: tuple = (8, 64, 512, 4096)
    agreement_res: int = 32
    agreement_block: int = 4           #: block-mean tests over block × block pixels
    agreement_spp: int = 256           #: per pass, each side
    agreement_passes: int = 20
    gradient_spp: int = 256            #: per pass
    gradient_passes: int = 16
    cost_spp: int = 256
    cost_repeats: int = 3
    topics: tuple = field(default_factory=tuple)


def options(quick: bool = False, seed: int = 0, topics=()) -> Options:
    """The default sizes (≤ 5 min per integrator on 2 cores) or the quick ones (≤ 60 s)."""
    if not quick:
        return Options(seed=seed, topics=tuple(topics))
    return Options(quick=True, seed=seed, topics=tuple(topics), finite_spp=16, bias_spp=128,
                   bias_passes=12, convergence_spp=(4, 16, 64, 256), agreement_res=16,
                   agreement_spp=128, agreement_passes=12, gradient_spp=64, gradient_passes=10,
                   cost_spp=64, cost_repeats=2)
