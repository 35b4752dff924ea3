r"""Comparing two images: error norms, the mean difference with its standard error, a difference map.

With ``A`` the image under test and ``B`` the reference, per value (pixel i, channel c)
``d_ic = A_ic − B_ic``, over n pixels and C channels:

* RMSE            = √( Σ d_ic² / (nC) )
* relative MSE    = Σ d_ic² / (B_ic² + ε) / (nC),  ε = 10⁻² guarding dark pixels
  (:mod:`phonglab.engine.metrics`, the one definition phonglab uses everywhere)
* mean difference  d̄ = Σ m_i / n with m_i = Σ_c d_ic / C the pixel's channel mean.

Its standard error comes from one of two sources (:attr:`Comparison.stderr_source`):

* ``"stderr files"``: the per-pixel standard errors s^A, s^B of two independent renders
  (``phonglab render`` writes them to ``<out>.stderr.exr`` from its independent passes).
  Channels of one pixel share their paths, so the pixel mean's standard error is bounded by
  the mean of the channel errors (perfect correlation, the conservative case):
  SE(d̄) = √( Σ_i ((s̄^A_i)² + (s̄^B_i)²) ) / n.
* ``"pixel differences"``: the spread of the pixel means, SE(d̄) = sd(m_i) / √n (sample
  standard deviation, ddof = 1).  It treats the pixels as independent draws, so it also
  counts structured differences as spread.

Both assume independent pixels; a wide reconstruction filter (Mitsuba's default
``gaussian``) correlates neighbours slightly and makes either estimate a little small.
``z = d̄ / SE`` and the two-sided p-value ``2 (1 − Φ(|z|))`` test "same expected image".

The test is undefined, and z and p are None with :attr:`Comparison.undefined` saying why, when
SE = 0 (identical or constant images: no spread to compare against), when there is one pixel
(no spread to estimate), and when A and B are one render (the same ``render_id``, or the same
file): a render compared with itself is not an independent sample, so p = 1 would be a
tautology, not evidence.  No statistic is ever NaN, and the JSON form is strict JSON.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from . import exr, metrics
from ..errors import CompareError
from .exr import stderr_path
from .metrics import REL_EPS, as_hwc
from ..stats import two_sided_p


@dataclass
class Comparison:
    """Numbers comparing image A with reference B (see the module docstring for the math)."""

    shape: tuple[int, ...]          #: (H, W, C) of both images
    rmse: float                     #: √mean((A − B)²)
    rel_mse: float                  #: mean((A − B)² / (B² + ε))
    mean_diff: float                #: mean(A − B)
    mean_diff_stderr: float         #: its standard error
    stderr_source: str              #: "stderr files" or "pixel differences"
    z: float | None                 #: mean_diff / mean_diff_stderr (None: see ``undefined``)
    p_value: float | None           #: two-sided, for "A and B have the same expectation"
    max_abs_diff: float             #: max |A − B|
    mean_a: float                   #: mean(A)
    mean_b: float                   #: mean(B)
    channel_mean_diff: list[float] = field(default_factory=list)  #: mean(A − B) per channel
    eps: float = REL_EPS
    undefined: str | None = None    #: why z and p are undefined (None when they are defined)

    def summary(self) -> str:
        """A few lines for people."""
        rel = (f" ({100 * self.mean_diff / self.mean_b:+.3g} % of mean(B))"
               if self.mean_b != 0 else "")
        lines = [
            f"pixels      : {self.shape[0]} x {self.shape[1]}, {self.shape[2]} channel(s)",
            f"mean A, B   : {self.mean_a:.6g}, {self.mean_b:.6g}",
            f"RMSE        : {self.rmse:.6g}",
            f"relMSE      : {self.rel_mse:.6g}   (eps = {self.eps:g})",
            f"max |A - B| : {self.max_abs_diff:.6g}",
            f"mean A - B  : {self.mean_diff:+.6g} +- {self.mean_diff_stderr:.3g} (1 s.e., from "
            f"{self.stderr_source}){rel}",
            f"z, p        : {self.z:+.3f}, p = {self.p_value:.3g} (two-sided, H0: same expected "
            f"image)" if self.undefined is None else f"z, p        : undefined: {self.undefined}",
        ]
        return "\n".join(lines)

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["shape"] = list(self.shape)
        return d


def _shape_text(shape) -> str:
    return " x ".join(str(s) for s in shape)


def compare_arrays(a, b, stderr_a=None, stderr_b=None, eps: float = REL_EPS,
                   names: tuple[str, str] = ("A", "B"),
                   not_independent: str | None = None) -> Comparison:
    """Compare image ``a`` with reference ``b`` (arrays).

    Args:
        a, b: (H, W) or (H, W, C) images of the same shape.
        stderr_a, stderr_b: per-pixel standard errors of a and b (same shape), or None.
            The standard error of the mean difference uses them when both are given,
            the spread of the pixel differences otherwise.
        eps: ε of the relative MSE.
        names: how errors name the two images (file names from :func:`compare_files`).
        not_independent: why A and B are not independent renders (None when they are): the
            test of "same expected image" is then undefined and says so.

    Raises:
        CompareError: shapes differ, or a value is NaN/Inf.
    """
    a, b = as_hwc(a, names[0]), as_hwc(b, names[1])
    if a.shape != b.shape:
        raise CompareError(
            f"{names[0]} is {_shape_text(a.shape)} but {names[1]} is {_shape_text(b.shape)} "
            f"(height x width x channels); compare images rendered at the same resolution "
            f"in the same colour variant")
    for name, img in zip(names, (a, b)):
        bad = ~np.isfinite(img)
        if bad.any():
            raise CompareError(f"{name} has {int(bad.sum())} NaN or infinite values; "
                               f"fix the render that produced it before comparing")
    d = a - b
    n = d.shape[0] * d.shape[1]
    pixel_mean = d.mean(axis=2).ravel()
    mean_diff = float(pixel_mean.mean())
    if stderr_a is not None and stderr_b is not None:
        sa, sb = as_hwc(stderr_a, f"{names[0]}'s stderr"), as_hwc(stderr_b, f"{names[1]}'s stderr")
        for which, s in ((names[0], sa), (names[1], sb)):
            if s.shape != a.shape:
                raise CompareError(
                    f"the standard-error image of {which} is {_shape_text(s.shape)} but the "
                    f"image is {_shape_text(a.shape)}; give the .stderr.exr written with it")
            if not np.all(np.isfinite(s)) or np.any(s < 0):
                raise CompareError(f"the standard-error image of {which} has negative or "
                                   f"non-finite values; give the .stderr.exr written with it")
        # Conservative pixel-mean error: channels of one pixel may be perfectly correlated.
        var = sa.mean(axis=2) ** 2 + sb.mean(axis=2) ** 2
        se = float(math.sqrt(var.sum()) / n)
        source = "stderr files"
    else:
        se = float(pixel_mean.std(ddof=1) / math.sqrt(n)) if n > 1 else 0.0
        source = "pixel differences"
    undefined = not_independent
    if undefined is None and n < 2 and source == "pixel differences":
        undefined = ("one pixel has no spread to estimate the standard error from; give the "
                     "renders' .stderr.exr files")
    elif undefined is None and not se > 0:
        undefined = ("the mean difference has zero standard error (the images are identical or "
                     "constant, with no noise to test against)")
    z = p = None
    if undefined is None:
        z = float(mean_diff / se)
        p = float(two_sided_p(z))
    norms = metrics.errors(a, b, eps=eps)         # both images are finite (checked above)
    return Comparison(
        shape=tuple(int(s) for s in a.shape),
        rmse=norms["rmse"], rel_mse=norms["rel_mse"],
        mean_diff=mean_diff, mean_diff_stderr=se, stderr_source=source, z=z, p_value=p,
        max_abs_diff=float(np.max(np.abs(d))), mean_a=float(a.mean()), mean_b=float(b.mean()),
        channel_mean_diff=[float(x) for x in d.mean(axis=(0, 1))], eps=eps, undefined=undefined)


def compare_files(path_a: str | Path, path_b: str | Path, stderr_a: str | Path | None = None,
                  stderr_b: str | Path | None = None, auto_stderr: bool = True,
                  eps: float = REL_EPS) -> tuple[Comparison, np.ndarray, np.ndarray, dict, dict]:
    """Compare EXR ``path_a`` with reference ``path_b``.

    Standard-error images are taken from ``stderr_a``/``stderr_b`` when given, else (with
    ``auto_stderr``) from ``<name>.stderr.exr`` beside each image when both exist.

    Returns:
        (comparison, image A, image B, metadata A, metadata B).
    """
    img_a, meta_a = exr.read(path_a)
    img_b, meta_b = exr.read(path_b)
    names_a, names_b = meta_a.get("channels"), meta_b.get("channels")
    if names_a != names_b and img_a.shape == img_b.shape:
        shown = [", ".join(n) if n else "by its shape (R, G, B / Y)" for n in (names_a, names_b)]
        raise CompareError(f"{path_a} holds channels {shown[0]} but {path_b} holds {shown[1]}; "
                           f"compare renders of films with the same pixel_format")
    if stderr_a is None and stderr_b is None and auto_stderr:
        cand_a, cand_b = stderr_path(path_a), stderr_path(path_b)
        if cand_a.is_file() and cand_b.is_file():
            stderr_a, stderr_b = cand_a, cand_b
    if (stderr_a is None) != (stderr_b is None):
        given = "--stderr-a" if stderr_a is not None else "--stderr-b"
        other = "--stderr-b" if stderr_a is not None else "--stderr-a"
        raise CompareError(f"{given} was given without {other}; give the standard-error images "
                           f"of both renders, or neither (then the pixel differences are used)")
    sa = _stderr_of(path_a, meta_a, stderr_a)
    sb = _stderr_of(path_b, meta_b, stderr_b)
    result = compare_arrays(img_a, img_b, sa, sb, eps=eps,
                            names=(str(path_a), str(path_b)),
                            not_independent=same_render(path_a, path_b, meta_a, meta_b))
    return result, img_a, img_b, meta_a, meta_b


def same_render(path_a, path_b, meta_a: dict, meta_b: dict) -> str | None:
    """Why A and B are one render (the same file, or the same ``render_id``), else None."""
    if Path(path_a).resolve() == Path(path_b).resolve():
        return (f"A and B are the same file ({path_b}); a render compared with itself is not "
                f"an independent sample: compare it with another render")
    rid = meta_a.get("render_id")
    if rid is not None and rid == meta_b.get("render_id"):
        return (f"A and B are one render (both carry render_id {rid}): they are not "
                f"independent samples, so no test of 'same expected image' applies")
    return None


def _stderr_of(image_path, image_meta: dict, path) -> np.ndarray | None:
    """The standard-error image at ``path`` (None for None), refused when it belongs to another render.

    ``phonglab render`` writes the same ``render_id`` into an image and its ``.stderr.exr``;
    a standard-error file whose id differs from its image's (or that lacks one when the image
    has one) was left by another render, and its errors would not describe this image.
    """
    if path is None:
        return None
    stderr, meta = exr.read(path)
    image_id = image_meta.get("render_id")
    if image_id is not None and meta.get("render_id") != image_id:
        raise CompareError(f"{path} belongs to another render than {image_path} (their "
                           f"render_id headers differ); render {image_path} again, give its own "
                           f"standard-error file, or use --no-stderr-files")
    return stderr


def describe_metadata(meta: dict) -> str:
    """One line of provenance from a phonglab EXR header (empty when there is none)."""
    if not meta:
        return "(no phonglab metadata)"
    parts = []
    for key, fmt in (("scene", "{}"), ("spp", "{} spp"), ("variant", "{}"), ("seed", "seed {}"),
                     ("integrator", "{}"), ("max_depth", "max_depth {}"),
                     ("render_seconds", "{} s")):
        if meta.get(key) is not None:
            parts.append(fmt.format(meta[key]))
    return ", ".join(parts)


def diff_figure(a, b, title: str = "A − B", robust_percentile: float = 99.0):
    """A matplotlib Figure of the signed difference (channel mean of A − B).

    Diverging colormap (``RdBu_r``: red where A is brighter, blue where B is), symmetric
    limits at the given percentile of |A − B| so that a few fireflies do not wash it out.
    """
    d = (as_hwc(a, "A") - as_hwc(b, "B")).mean(axis=2)
    lim = float(np.percentile(np.abs(d), robust_percentile)) if d.size else 0.0
    if not lim > 0:
        lim = float(np.max(np.abs(d))) or 1.0
    h, w = d.shape
    fig = Figure(figsize=(min(10.0, max(3.5, 4.0 * w / h + 1.0)), 4.0), layout="constrained")
    ax = fig.add_subplot()
    im = ax.imshow(d, cmap="RdBu_r", vmin=-lim, vmax=lim, interpolation="nearest")
    ax.set_title(title, fontsize=10)
    ax.set_xticks([])
    ax.set_yticks([])
    fig.colorbar(im, ax=ax, shrink=0.85, label=f"A − B (clipped at ±{lim:.3g}, "
                                                 f"{robust_percentile:g}th pct of |A − B|)")
    return fig


def write_diff_png(path: str | Path, a, b, title: str = "A − B") -> Path:
    """Write :func:`diff_figure` as a PNG (atomically, like the EXR files)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = diff_figure(a, b, title)
    with exr.atomic_path(path, ".png") as tmp:
        fig.savefig(tmp, dpi=110)
    return path
