"""The one cache of high-sample reference images that errors are measured against.

A reference is a render of a scene file with many samples per pixel, split into passes so
that it carries its per-pixel standard error (:func:`phonglab.engine.render.render_scene`); the
metrics subtract that noise (:func:`phonglab.engine.metrics.errors`).  It is rendered

* at **full depth** (``max_depth=-1``, the default): a ``path`` integrator without a depth
  limit, ended by Russian roulette and so unbiased, keeping the scene's ``rr_depth`` and
  ``hide_emitters`` — what the planner's error target and ``render --target-error`` mean;
* with the scene's **own integrator** (``max_depth=None``): the converged image of exactly
  the render under test — what the bench's error-versus-time curves compare with;
* or with a ``path`` integrator of a given depth.

Cache layout: ``<cache>/references/<scene stem>-<key>.exr`` and ``.stderr.exr`` beside it,
the key hashing the scene file's bytes, the parameters, the variant, the depth choice and
Mitsuba's version; the header records spp, passes, seed and render time.

A missing reference renders its passes one after the other here, or, given a
:class:`phonglab.parallel.Runner` that is not serial, as one job per pass on the cluster
(:func:`reference_pass`: pass k of ``spp_k`` samples with Mitsuba seed
:func:`~phonglab.engine.render.pass_seed` (seed, k), exactly the pass the serial loop renders).  The
passes are merged here in pass order by :class:`phonglab.engine.render.PassMerge`, the one merge of
:func:`~phonglab.engine.render.render_scene`: with N = Σ spp_k and per-pixel pass means x_k,
x̄ = Σ spp_k x_k / N and s² = (Σ spp_k x_k² / N − x̄²) · N / (N − N/P) / P (the weighted
sample variance of the P pass means, over P), so the per-pixel variance is kept and the
merge is bit-identical to the serial one whenever the pass images are (a box-filtered
scene's are; a wider filter's float32 atomic splats may differ by a few ulps,
docs/exr_and_compare.md).  A cached
reference with at least the asked spp is reused; a missing one (a clean clone) is rendered.
The cache lives where ``PHONGLAB_CACHE`` points; else in ``.bench_cache/`` of the source
checkout phonglab runs from (git-ignored); else, for an installed phonglab, whose own folder
may not be writable, in the user's cache folder (``$XDG_CACHE_HOME/phonglab`` or
``~/.cache/phonglab``).
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mitsuba as mi
import numpy as np

from . import exr
from ..errors import PhonglabError
from .metrics import as_hwc
from ..parallel import Job, Runner
from .render import PassMerge, pass_seed, pass_spps, render_pass, render_scene
from ..runtime import available_backend, quiet_mitsuba, variant_for
from .scenes import (SceneInfo, file_hash, inspect_scene, load_scene, path_integrator,
                     scene_path)


def default_cache_dir() -> Path:
    """``PHONGLAB_CACHE``; else the checkout's ``.bench_cache/`` (phonglab imported from
    ``src/phonglab`` beside a ``pyproject.toml``); else the user's cache folder."""
    if os.environ.get("PHONGLAB_CACHE"):
        return Path(os.environ["PHONGLAB_CACHE"])
    package = Path(__file__).resolve().parents[1]           # src/phonglab
    if package.parent.name == "src" and (package.parents[1] / "pyproject.toml").is_file():
        return package.parents[1] / ".bench_cache"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "phonglab"


#: Default cache folder; ``PHONGLAB_CACHE`` overrides it (:func:`default_cache_dir`).
CACHE_DIR = default_cache_dir()
#: Seed of reference renders: far from the seeds renders under test use (0, 1, 5000, ...).
REFERENCE_SEED = 1_000_000
#: Passes of a reference render (its standard error has PASSES − 1 degrees of freedom).
PASSES = 16


@dataclass
class Reference:
    """A cached reference: image and per-pixel standard error, (H, W, C) float32, and its header."""

    image: np.ndarray
    stderr: np.ndarray
    metadata: dict[str, Any]
    path: Path

    @property
    def spp(self) -> int:
        return int(self.metadata.get("spp", 0))


def variant_for_color(color: str) -> str:
    """The variant of a reference for a scene of colour model ``color`` ('mono', 'rgb',
    'spectral'): rgb on the best backend unless the scene carries spectral data (then
    spectral); a mono render is compared with the reference's luminance."""
    backend, _ = available_backend()
    return variant_for("spectral" if color == "spectral" else "rgb", backend)[0]


def default_variant(scene: str | Path, params: dict[str, Any] | None = None) -> str:
    """:func:`variant_for_color` of the scene's colour model (read from its XML)."""
    return variant_for_color(inspect_scene(scene, **(params or {})).color)


def cache_path(scene: str | Path, params: dict[str, Any] | None = None, variant: str = "llvm_ad_rgb",
               max_depth: int | None = -1, cache_dir: str | Path | None = None) -> Path:
    """Where the reference of this scene file, parameters, variant and depth choice lives."""
    path = scene_path(scene)
    h = hashlib.sha256(path.read_bytes())
    h.update(json.dumps(sorted((k, str(v)) for k, v in (params or {}).items())).encode())
    h.update(f"{variant}|{max_depth}|{mi.__version__}".encode())
    return Path(cache_dir or CACHE_DIR) / "references" / f"{path.stem}-{h.hexdigest()[:16]}.exr"


def cached(scene: str | Path, params: dict[str, Any] | None = None, variant: str | None = None,
           max_depth: int | None = -1, min_spp: int = 1,
           cache_dir: str | Path | None = None) -> Reference | None:
    """The cached reference with at least ``min_spp`` samples, or None."""
    try:
        variant = variant or default_variant(scene, params)
    except PhonglabError:
        return None
    return _read(cache_path(scene, params, variant, max_depth, cache_dir), min_spp)


def _read(path: Path, min_spp: int) -> Reference | None:
    """The reference stored at ``path`` (and its ``.stderr.exr``) if it has ``min_spp`` samples."""
    se_path = exr.stderr_path(path)
    if not (path.is_file() and se_path.is_file()):
        return None
    image, meta = exr.read(path)
    stderr, _ = exr.read(se_path)
    ref = Reference(as_hwc(image), as_hwc(stderr), meta, path)
    return ref if ref.spp >= min_spp else None


def reference(scene: str | Path, spp: int, params: dict[str, Any] | None = None,
              variant: str | None = None, max_depth: int | None = -1, passes: int = PASSES,
              seed: int = REFERENCE_SEED, cache_dir: str | Path | None = None,
              progress: bool = False, runner: Runner | None = None) -> Reference:
    """The reference of ``scene`` with at least ``spp`` samples: from the cache, else rendered.

    Args:
        scene: scene file, or the name of a shipped scene (``cornell_phong``).
        spp: samples per pixel the reference must have at least.
        params: values for the scene's ``<default>`` entries.
        variant: Mitsuba variant (default: :func:`default_variant`).
        max_depth: -1 full depth, None the scene's own integrator, d a path tracer of depth d.
        passes, seed: how a missing reference is rendered (pass k uses pass_seed(seed, k)).
        runner: where the passes of a missing reference render (default: here, one by one).
    """
    params = {k: v for k, v in (params or {}).items() if v is not None}
    # The XML is read once: for the default variant, or (on a cache miss) for the integrator.
    info = inspect_scene(scene, **params) if variant is None else None
    variant = variant or variant_for_color(info.color)
    path = cache_path(scene, params, variant, max_depth, cache_dir)
    found = _read(path, spp)
    if found is not None:
        return found
    info = info or inspect_scene(scene, **params)
    with quiet_mitsuba():
        loaded = load_scene(info.path, variant, **params)
    if runner is None or runner.serial:
        integrator = None if max_depth is None else path_integrator(max_depth, info)
        result = render_scene(loaded, spp, seed=seed, passes=passes, progress=progress,
                              integrator=integrator)
    else:
        result = _render_on(runner, info, loaded, spp, params, variant, max_depth, passes, seed)
    meta = {"scene": str(info.path), "scene_sha256": file_hash(info.path), "variant": variant,
            "spp": spp, "passes": passes, "seed": seed,
            "max_depth": "scene's integrator" if max_depth is None else max_depth,
            "params": {k: str(v) for k, v in params.items()},
            "render_seconds": round(result.seconds, 3), "mitsuba_version": mi.__version__}
    exr.write(path, result.image, meta)
    exr.write(exr.stderr_path(path), result.stderr, meta)
    return Reference(result.image, result.stderr, meta, path)


def _render_on(runner: Runner, info: SceneInfo, loaded, spp: int, params: dict[str, Any],
               variant: str, max_depth: int | None, passes: int, seed: int):
    """The reference render as one job per pass on ``runner``, merged here in pass order."""
    per_pass = pass_spps(loaded, spp, passes)
    text = info.path.read_text()
    jobs = [Job(reference_pass, (str(info.path), text, params, variant, max_depth, w,
                                 pass_seed(seed, k)), key=k)
            for k, w in enumerate(per_pass)]
    merged = PassMerge(spp, len(per_pass))
    ready: dict[int, Any] = {}

    def merge_in_order(job: Job, image) -> None:
        # Passes come back in any order; they are added in pass order (bit-identical merge).
        ready[job.key] = image
        while len(merged.weights) in ready:
            k = len(merged.weights)
            merged.add(ready.pop(k), per_pass[k])

    t0 = time.perf_counter()
    start = len(runner.timings)
    runner.run(jobs, merge_in_order, desc="reference passes")
    pass_seconds = [t.seconds for t in sorted(runner.timings[start:], key=lambda t: t.key)]
    return merged.result(time.perf_counter() - t0, pass_seconds)


_pass_scenes: dict[tuple, tuple[Any, Any]] = {}     # per process: (scene, integrator) by key


def reference_pass(scene_file: str, text: str, params: dict[str, Any], variant: str,
                   max_depth: int | None, spp: int, mitsuba_seed: int):
    """One pass of a reference render, as a job: (H, W, C) float64 image.

    The scene travels as its XML text; a worker where ``scene_file`` is missing or differs
    loads the text from a file of its own (phonglab's scenes name no other files).  The
    loaded scene is kept for the next pass of the same reference in this process.
    """
    digest = hashlib.sha256(text.encode()).hexdigest()
    key = (digest, tuple(sorted((k, str(v)) for k, v in params.items())), variant, max_depth)
    if key not in _pass_scenes:
        path = Path(scene_file)
        if not (path.is_file() and path.read_text() == text):
            path = Path(tempfile.gettempdir()) / "phonglab-scenes" / digest[:16] / path.name
            path.parent.mkdir(parents=True, exist_ok=True)
            with exr.atomic_path(path, ".xml") as tmp:
                Path(tmp).write_text(text)
        with quiet_mitsuba():
            loaded = load_scene(path, variant, **params)
        integrator = (None if max_depth is None
                      else path_integrator(max_depth, inspect_scene(path, **params)))
        _pass_scenes.clear()                 # one reference at a time: keep memory bounded
        _pass_scenes[key] = (loaded, integrator)
    loaded, integrator = _pass_scenes[key]
    return render_pass(loaded, spp, mitsuba_seed, integrator=integrator)
