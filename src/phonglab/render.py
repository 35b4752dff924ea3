"""Loading scenes with clear errors, rendering in passes, and writing EXR + PNG results.

Rendering in passes (independent seeds, equal sample counts) gives both the
image and a per-pixel standard error of its mean, which the statistical checks,
the convergence charts and the planner all use.
"""

from __future__ import annotations

import hashlib
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import __version__, exr, registration

REPO_ROOT = Path(__file__).resolve().parents[2]
SCENES_DIR = REPO_ROOT / "scenes_xml"


class PhonglabError(Exception):
    """An error for the user: one sentence saying what is wrong and how to fix it."""


def scene_path(name: str | Path) -> Path:
    """Resolve a scene given as a path or as a name in ``scenes_xml/`` (``cornell_phong``)."""
    p = Path(name)
    if p.is_file():
        return p
    for cand in (SCENES_DIR / p, SCENES_DIR / (str(p) + ".xml")):
        if cand.is_file():
            return cand
    raise PhonglabError(f"scene file not found: {name} (give a path to a Mitsuba XML file, or "
                        f"one of: {', '.join(sorted(q.stem for q in SCENES_DIR.glob('*.xml')))})")


def _malformed(where: str, why: str) -> PhonglabError:
    return PhonglabError(f"{where}: malformed XML ({why}); fix the markup there "
                         f"(an unclosed or mismatched tag, or a stray character).")


def scene_defaults(path: str | Path) -> dict[str, str]:
    """The ``<default name=... value=...>`` entries of a scene file (its tunable parameters)."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        line = exc.position[0] if exc.position else "?"
        why = re.sub(r":\s*line \d+, column \d+$", "", str(exc))
        raise _malformed(f"{path}, line {line}", why) from None
    return {d.get("name"): d.get("value") for d in root.iter("default") if d.get("name")}


def file_hash(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


_MI_LINE = re.compile(r"\(line (\d+)")
_UNREFERENCED = re.compile(r'unreferenced propert(?:y|ies) in (\w+) plugin of type "([^"]+)"')
_UNREFERENCED_NAME = re.compile(r'^\s*-\s*\w+\s+"([^"]+)"', re.MULTILINE)
_NOT_FOUND = re.compile(r'instantiate (\w+) plugin of type "([^"]+)".*Plugin "[^"]+" not found')
#: Scene-file names of phonglab's own plugins (whose parameters are all listed by traverse).
_OWN_PLUGINS = ("lambert", "phong")


def _plugin_parameters(plugin_type: str) -> list[str]:
    """XML parameter names of one of phonglab's plugins (its ``traverse`` keys), else []."""
    if plugin_type not in _OWN_PLUGINS:
        return []
    try:
        import mitsuba as mi

        return sorted({k.split(".")[0] for k in mi.traverse(mi.load_dict({"type": plugin_type})).keys()})
    except Exception:  # the listing is a courtesy; the error message stands without it
        return []


def _explain_load_error(path: Path, exc: Exception) -> PhonglabError:
    """Turn Mitsuba's loader error into one sentence naming the problem and the fix.

    Mitsuba words the cases as (3.9.1, the same for Python and built-in plugins):
    ``While loading F (line L, col C): Found 1 unreferenced property in bsdf plugin of
    type "phong":\n  - float "exponant": 3``; ``Parsing of XML file "F" failed: <why>
    (line L, col C)``; ``failed to instantiate bsdf plugin of type "x": [PluginManager]
    Plugin "x" not found!``; and a Python plugin's own exception with its traceback.
    """
    import difflib

    text = str(exc).strip()
    line_m = _MI_LINE.search(text)
    where = f"{path}, line {line_m.group(1)}" if line_m else str(path)
    # Mitsuba prefixes its messages with "[parser.cpp:444] ..." and may nest a Python traceback.
    core = re.sub(r"^\[[\w.]+:\d+\]\s*", "", text.splitlines()[-1] if text else type(exc).__name__)
    if "MaterialError" in text or "violates energy" in text or "must lie in" in text \
            or "'exponent'" in text:
        m = re.search(r"((?:phong|lambert): .*)", text)
        msg = m.group(1) if m else core
        return PhonglabError(f"{where}: {msg}")
    m = _UNREFERENCED.search(text)
    if m:
        kind, plugin_type = m.group(1), m.group(2)
        names = _UNREFERENCED_NAME.findall(text) or ["?"]
        known = _plugin_parameters(plugin_type)
        hints = [difflib.get_close_matches(n, known, n=1) for n in names]
        guess = "".join(f" (did you mean {h[0]!r}?)" for h in hints if h) if len(names) == 1 else ""
        listed = (f"its parameters are {', '.join(repr(k) for k in known)}" if known else
                  "see the Mitsuba plugin reference for its parameters")
        kind = "" if kind == "unknown" else f"{kind} "
        plural = "parameters" if len(names) > 1 else "parameter"
        return PhonglabError(
            f"{where}: the {kind}plugin {plugin_type!r} has no {plural} "
            f"{', '.join(repr(n) for n in names)}{guess}; fix the spelling or remove it "
            f"({listed}).")
    m = _NOT_FOUND.search(text)
    if m:
        kind, plugin_type = m.group(1), m.group(2)
        guess = difflib.get_close_matches(plugin_type, _OWN_PLUGINS, n=1)
        hint = f" (did you mean {guess[0]!r}?)" if guess else ""
        return PhonglabError(
            f"{where}: there is no {kind} plugin named {plugin_type!r}{hint}; use a Mitsuba "
            f"built-in or one of phonglab's ({', '.join(_OWN_PLUGINS)}), registered by "
            f"phonglab.register() before loading from Python.")
    if "Parsing of XML file" in text or "parse" in text.lower():
        why = re.sub(r'^Parsing of XML file "[^"]*" failed:\s*', "", core)
        why = re.sub(r"\s*\(line \d+, col \d+\)", "", why)
        return _malformed(where, why)
    return PhonglabError(f"{where}: could not load the scene: {core}")


def load_scene(path: str | Path, variant: str | None = None, **params) -> Any:
    """Load a Mitsuba XML scene with phonglab's plugins registered.

    Args:
        path: scene file, or a scene name from ``scenes_xml/``.
        variant: Mitsuba variant to set first (default: the active one, else llvm_ad_rgb).
        **params: values for the scene's ``<default name=...>`` entries (spp, ...).

    Raises:
        PhonglabError: missing file, malformed XML, unknown parameter, unphysical material.
    """
    import mitsuba as mi

    path = scene_path(path)
    registration.register(variant)
    try:
        return mi.load_file(str(path), **{k: v for k, v in params.items() if v is not None})
    except Exception as exc:  # Mitsuba raises RuntimeError with its own text
        raise _explain_load_error(path, exc) from exc


@dataclass
class RenderResult:
    """A rendered image, its per-pixel standard error and how it was made."""

    image: np.ndarray                 #: (H, W, C) float32 mean radiance
    stderr: np.ndarray | None         #: (H, W, C) standard error of the mean (None for 1 pass)
    seconds: float                    #: wall time of the passes (the first includes JIT compile)
    pass_seconds: list[float] = field(default_factory=list)
    metadata: dict[str, Any] = field(default_factory=dict)
    #: (passes, C) mean over all pixels of each pass: its spread gives the standard error of
    #: the image mean without assuming independent pixels (reconstruction filters correlate them).
    pass_means: np.ndarray | None = None
    pass_spp: list[int] = field(default_factory=list)

    def mean_and_stderr(self) -> tuple[np.ndarray, np.ndarray | None]:
        """Per-channel image mean and its standard error from the pass means."""
        mean = self.image.reshape(-1, self.image.shape[-1]).mean(axis=0)
        if self.pass_means is None or len(self.pass_means) < 2:
            return mean, None
        w = np.asarray(self.pass_spp, dtype=np.float64)[:, None]
        spp = w.sum()
        var = np.sum(w * (self.pass_means - mean) ** 2, axis=0) / (spp - spp / len(w))
        return mean, np.sqrt(var / len(w))


def _to_numpy(img) -> np.ndarray:
    a = np.array(img, dtype=np.float32)
    return a if a.ndim == 3 else a[..., None]


def pass_seed(seed: int, k: int) -> int:
    """Mitsuba seed of pass k: (seed·1_000_003 + k) mod 2³² (mi.render takes a 32-bit seed)."""
    return (int(seed) * 1_000_003 + int(k)) % (1 << 32)


def render_scene(scene, spp: int, seed: int = 0, passes: int = 1, sensor: int = 0,
                 progress: bool = False, integrator=None) -> RenderResult:
    """Render ``scene`` with ``spp`` samples per pixel split into ``passes`` equal passes.

    Pass k uses seed ``(seed * 1_000_003 + k) mod 2³²`` (Mitsuba's seeds are 32-bit); the image is the mean of the passes
    and, with two or more passes, ``stderr`` is the per-pixel standard error of
    that mean (sample standard deviation across passes / √passes).
    """
    import drjit as dr
    import mitsuba as mi

    if spp < 1:
        raise PhonglabError(f"spp (samples per pixel) must be >= 1, got {spp}; ask for at "
                            f"least one sample (--spp 1)")
    passes = max(1, min(int(passes), int(spp)))
    per_pass = [spp // passes + (1 if k < spp % passes else 0) for k in range(passes)]
    iterator = range(passes)
    if progress:
        from tqdm import tqdm

        iterator = tqdm(iterator, desc="rendering", unit="pass", leave=False)
    total = None
    total_sq = None
    times = []
    means = []
    t_start = time.perf_counter()
    for k in iterator:
        t0 = time.perf_counter()
        img = mi.render(scene, spp=per_pass[k], seed=pass_seed(seed, k), sensor=sensor,
                        integrator=integrator)
        dr.eval(img)
        arr = _to_numpy(img).astype(np.float64)
        times.append(time.perf_counter() - t0)
        means.append(arr.reshape(-1, arr.shape[-1]).mean(axis=0))
        # Passes of unequal spp are weighted by their sample counts.
        w = per_pass[k]
        total = arr * w if total is None else total + arr * w
        total_sq = arr * arr * w if total_sq is None else total_sq + arr * arr * w
    seconds = time.perf_counter() - t_start
    mean = total / spp
    stderr = None
    if passes > 1:
        # Pass means are unbiased estimates with variance σ²/spp_k: weighted sample variance.
        var_pass = np.maximum(total_sq / spp - mean * mean, 0.0) * spp / (spp - spp / passes)
        stderr = np.sqrt(var_pass / passes).astype(np.float32)
    return RenderResult(mean.astype(np.float32), stderr, seconds, times,
                        pass_means=np.array(means), pass_spp=per_pass)


def auto_exposure(image: np.ndarray, darken_only: bool = False) -> float:
    """Stops that put the 99th percentile of ``image`` at 0.8 (0 for a black image).

    With ``darken_only`` an image that already fits (99th percentile <= 1) keeps exposure 0,
    so radiance renders are previewed as they are and only graphics-unit images (whose
    values the seed's formula does not bound) are brought into range.
    """
    p = float(np.percentile(np.nan_to_num(np.asarray(image, np.float64)), 99))
    if p <= 0 or (darken_only and p <= 1.0):
        return 0.0
    return float(np.log2(0.8 / p))


def to_srgb(image: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """Linear radiance → display sRGB in [0, 1] (exposure in stops, clipped; IEC 61966-2-1).

    A one-channel (H, W, 1) image comes back as (H, W).
    """
    img = np.asarray(image, dtype=np.float64) * (2.0 ** exposure)
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[..., 0]
    img = np.clip(np.nan_to_num(img, nan=0.0, posinf=1.0), 0.0, 1.0)
    return np.where(img <= 0.0031308, 12.92 * img, 1.055 * np.power(img, 1 / 2.4) - 0.055)


def preview_png(path: str | Path, image: np.ndarray, exposure: float = 0.0) -> Path:
    """Write an 8-bit sRGB preview (exposure in stops, clipped) of a linear image."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    srgb = to_srgb(image, exposure)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    plt.imsave(path, srgb, cmap="gray" if srgb.ndim == 2 else None, vmin=0.0, vmax=1.0)
    return path


def render_file(scene: str | Path, out: str | Path, spp: int | None = None,
                variant: str | None = None, seed: int = 0, passes: int | None = None,
                max_depth: int | None = None, progress: bool = True,
                png: bool = True, extra_metadata: dict[str, Any] | None = None) -> RenderResult:
    """Load, render and write ``out`` (EXR with provenance) plus a PNG preview beside it.

    ``extra_metadata`` is added to the EXR header (the planner records its plan there).
    """
    import mitsuba as mi

    path = scene_path(scene)
    declared = scene_defaults(path)
    params = {k: v for k, v in (("spp", spp), ("max_depth", max_depth))
              if v is not None and k in declared}
    loaded = load_scene(path, variant, **params)
    integrator = None
    if max_depth is not None and "max_depth" not in declared:
        # The scene does not expose its depth: render with a path tracer of the asked depth.
        integrator = mi.load_dict({"type": "path", "max_depth": int(max_depth)})
    sensor = loaded.sensors()[0]
    spp = int(spp or sensor.sampler().sample_count())
    passes = passes or (min(spp, 8) if spp >= 16 else 1)
    result = render_scene(loaded, spp, seed=seed, passes=passes, progress=progress,
                          integrator=integrator)
    integrator = integrator or loaded.integrator()
    result.metadata = {
        "scene": str(path), "scene_sha256": file_hash(path), "variant": mi.variant(),
        "spp": spp, "passes": passes, "seed": seed,
        "integrator": integrator.class_name() if hasattr(integrator, "class_name") else str(type(integrator)),
        "max_depth": _max_depth(integrator), "render_seconds": round(result.seconds, 4),
        "phonglab_version": __version__, "mitsuba_version": mi.__version__,
    }
    result.metadata.update(extra_metadata or {})
    out = Path(out)
    exr.write(out, result.image, result.metadata)
    if result.stderr is not None:
        exr.write(out.with_name(out.stem + ".stderr.exr"), result.stderr, result.metadata)
    if png:
        ev = auto_exposure(result.image, darken_only=True)
        result.metadata["preview_exposure_ev"] = round(ev, 2)
        preview_png(out.with_suffix(".png"), result.image, exposure=ev)
    return result


def _max_depth(integrator) -> int | None:
    import mitsuba as mi

    try:
        params = mi.traverse(integrator)
        if "max_depth" in params:
            return int(params["max_depth"])
    except Exception:
        pass
    text = str(integrator)
    m = re.search(r"max_depth\s*=\s*(-?\d+)", text)
    return int(m.group(1)) if m else None


def relative_rmse(image: np.ndarray, reference: np.ndarray, eps: float = 1e-2) -> float:
    """√mean(((x − r)/(r + eps))²): relative RMSE, eps guarding dark pixels."""
    image, reference = np.asarray(image, np.float64), np.asarray(reference, np.float64)
    return float(math.sqrt(np.mean(((image - reference) / (np.abs(reference) + eps)) ** 2)))
