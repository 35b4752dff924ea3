"""Validation shared by phonglab's plugins, at load time and on ``params.update()``.

A reflectance is the fraction of incident light a surface reflects, so every
value a reflectance texture can return must lie in [0, 1], and the lobes of one
material together must not reflect more than they receive.  Every other numeric
parameter (an exponent, an attenuation coefficient, an ambient intensity) must be
a finite float32 number in its documented range (an unbounded intensity at most
``INTENSITY_MAX`` = 1e30, which leaves float32 headroom for the film's sums).  Errors are raised as
:class:`MaterialError` (a ``ValueError``) whose message is one sentence naming the
plugin, the parameter, the value and the fix, on one line.

Where the values are looked at:

* plain numbers and colours as the scene declared them (before Mitsuba turns them
  into textures, so that the error names the parameter);
* a bitmap's texel data itself, for any size (``mi.traverse(texture)['data']``):
  bilinear or nearest lookups are convex combinations of texels, so the texels
  bound every value the texture returns;
* the sum of several textures (energy conservation) on their common texels when
  the bitmaps share one grid, else on the texel centres of the finest one,
  evaluated in batches (no cap on the size in JIT variants; 64 x 64 in scalar
  variants, whose evaluation is a Python loop);
* in spectral variants, by evaluation over the visible wavelengths (a bitmap's
  data there are up-sampling coefficients, not reflectances).

Float32 limits: a value that overflows float32 (|x| > 3.4028235e38) counts as
non-finite; a scalar parameter or a constant texture whose value is denormal
(0 < |x| < 1.1754944e-38, flushed to 0 by float32 arithmetic, and an infinite
1/x) is refused; denormal texels of a bitmap or of an evaluated spectrum are
treated as 0, their limit, since they only ever multiply light.

Updates are transactional: :func:`commit` validates the values ``params.update()``
wrote, and on failure writes the last accepted values back into the plugin's
members (which are the traversed parameters themselves) before raising, so a
caller that catches the error keeps rendering exactly what it rendered before.
"""

from __future__ import annotations

import math
from typing import Callable, Iterator

import drjit as dr
import mitsuba as mi
import numpy as np

#: Slack for float rounding (spectral up-sampling, sRGB decoding) above a range's upper bound.
TOLERANCE = 1e-4
#: The smallest normal float32 number; non-zero magnitudes below it are denormal.
FLOAT32_TINY = float(np.finfo(np.float32).tiny)
#: The largest finite float32 number.
FLOAT32_MAX = float(np.finfo(np.float32).max)
#: The largest intensity an unbounded texture (whitted's ambient) may hold: 1e8 below
#: FLOAT32_MAX, the headroom Mitsuba's film needs (weights, colour conversion, sums).
INTENSITY_MAX = 1e30
_SCALAR_MAX_GRID = 64
_N_WAVELENGTH_ROWS = 32
_BATCH = 1 << 18   #: points per evaluation batch (memory stays bounded for any bitmap)


class MaterialError(ValueError):
    """An unphysical or malformed parameter of a phonglab plugin (material or lighting model)."""


def _fmt(x) -> str:
    return "[" + ", ".join(f"{float(v):.4g}" for v in np.atleast_1d(x)) + "]"


def _finite32(values: np.ndarray) -> np.ndarray:
    """Finite and representable in float32 (1e39 is finite in float64 but inf in float32)."""
    values = np.asarray(values, dtype=np.float64)
    return np.isfinite(values) & (np.abs(values) <= FLOAT32_MAX)


def _denormal(values: np.ndarray) -> np.ndarray:
    magnitude = np.abs(np.asarray(values, dtype=np.float64))
    return (magnitude > 0) & (magnitude < FLOAT32_TINY)


def _denormal_error(plugin: str, name: str, value: float) -> MaterialError:
    return MaterialError(
        f"{plugin}: '{name}' has the denormal value {value:.4g} (0 < |x| < {FLOAT32_TINY:.8g}, "
        f"which float32 arithmetic flushes to 0); use 0 or a value of at least "
        f"{FLOAT32_TINY:.8g}.")


# ----------------------------------------------------------------------------- numbers

def check_number(plugin: str, name: str, value, meaning: str, fix: str,
                 minimum: float = 0.0) -> float:
    """``value`` as a float, or :class:`MaterialError` unless finite in float32, normal and >= minimum.

    ``meaning`` says what the parameter is, ``fix`` what to give instead (both lower case).
    """
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise MaterialError(f"{plugin}: '{name}' must be a number ({meaning}), got "
                            f"{value!r}; {fix}.") from None
    if not _finite32(x) or x < minimum:
        overflow = " (beyond float32's range)" if math.isfinite(x) and not _finite32(x) else ""
        raise MaterialError(f"{plugin}: '{name}' must be >= {minimum:g} and finite ({meaning}), "
                            f"got {x!r}{overflow}; {fix}.")
    if _denormal(x):
        raise _denormal_error(plugin, name, x)
    return x


def check_exponent(plugin: str, value) -> float:
    """The Phong exponent as a float, or :class:`MaterialError` when it is unusable."""
    return check_number(plugin, "exponent", value, "the shininess p of cos^p α",
                        "use 0 for a uniform lobe, larger values for sharper highlights")


def scalar_of(value) -> float:
    """A Python float from a Dr.Jit scalar or one-entry array."""
    if isinstance(value, (int, float)):
        return float(value)
    return float(np.array(value).ravel()[0])


# ----------------------------------------------------------------------------- texture values

def texel_data(texture) -> np.ndarray | None:
    """A bitmap texture's texels as a float32 array (height, width, channels), else None.

    None for textures without texel data (constants, procedural ones) and in spectral
    variants, where a bitmap stores spectral up-sampling coefficients.

    The values are those the texture returns, not its storage: Mitsuba keeps an 8-bit
    bitmap's bytes as they are (``TensorXu8``) and decodes them at lookup (x/255, then the
    sRGB transfer curve unless ``raw``), so integer texels are decoded by evaluating the
    texture at each texel's centre, where its bilinear lookup returns that texel alone.
    """
    if mi.is_spectral or not texture.is_spatially_varying():
        return None
    params = mi.traverse(texture)
    if "data" not in params:
        return None
    stored = np.asarray(params["data"])
    if stored.ndim < 2:
        return None
    if not np.issubdtype(stored.dtype, np.floating):
        if not dr.is_jit_v(mi.Float) and stored.shape[0] * stored.shape[1] > _SCALAR_MAX_GRID ** 2:
            return None      # evaluated on value_batches' capped grid instead (one lane a call)
        return _decoded_texels(texture, params, stored.shape[0], stored.shape[1])
    data = stored.astype(np.float32)
    return data.reshape(data.shape[0], data.shape[1], -1)


def _decoded_texels(texture, params, height: int, width: int) -> np.ndarray:
    """(height, width, channels) float32: the texture evaluated at its texel centres.

    The centres are given in the texture's own (u, v); the surface uv that reaches them is
    the inverse of the texture's ``to_uv`` transform applied to them.
    """
    u, v = np.meshgrid((np.arange(width) + 0.5) / width, (np.arange(height) + 0.5) / height,
                       indexing="xy")
    uv = np.stack([u.ravel(), v.ravel(), np.ones(u.size)])
    if "to_uv" in params:
        uv = np.linalg.inv(np.array(params["to_uv"].matrix, dtype=np.float64)) @ uv
    out = np.concatenate([batch[0] for batch in (
        _evaluate([texture], uv[0, s:s + _BATCH], uv[1, s:s + _BATCH])
        for s in range(0, uv.shape[1], _BATCH))], axis=1)
    return out.T.reshape(height, width, -1).astype(np.float32)


def _evaluate(textures, uu: np.ndarray, vv: np.ndarray) -> list[np.ndarray]:
    """Each texture at the points (uu, vv) (times a sweep of wavelengths in spectral
    variants): one (channels, points) float64 array per texture."""
    rows = _N_WAVELENGTH_ROWS if mi.is_spectral else 1
    m = uu.size
    uu, vv = np.tile(uu, rows), np.tile(vv, rows)
    n = uu.size
    if mi.is_spectral:
        lo, hi = float(mi.MI_CIE_MIN), float(mi.MI_CIE_MAX)
        # Each point carries 4 wavelengths: rows x 4 evenly spread values in total.
        lam = np.repeat(np.linspace(lo, hi, rows * 4).reshape(rows, 4), m, axis=0)
    if dr.is_jit_v(mi.Float):
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.uv = mi.Point2f(mi.Float(uu.astype(np.float32)), mi.Float(vv.astype(np.float32)))
        if mi.is_spectral:
            si.wavelengths = mi.Spectrum(*(mi.Float(lam[:, k].astype(np.float32)) for k in range(4)))
        out = []
        for tex in textures:
            value = np.atleast_2d(np.array(tex.eval(si), dtype=np.float64))
            # A constant texture may return a width-1 (literal) array: broadcast it.
            out.append(np.broadcast_to(value, (value.shape[0], n)))
        return out
    out = [[] for _ in textures]
    for i in range(n):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.uv = mi.Point2f(float(uu[i]), float(vv[i]))
        if mi.is_spectral:
            si.wavelengths = mi.Spectrum(*(float(x) for x in lam[i]))
        for k, tex in enumerate(textures):
            out[k].append(np.array(tex.eval(si), dtype=np.float64).ravel())
    return [np.array(o).T for o in out]


def _same_grid(textures, data) -> bool:
    """Whether the bitmaps share one texel grid (same size and uv transform)."""
    if len({d.shape[:2] for d in data}) != 1:
        return False
    uv = [np.array(mi.traverse(t)["to_uv"].matrix, dtype=np.float64)
          if "to_uv" in mi.traverse(t) else None for t in textures]
    return all(u is None for u in uv) or all(
        u is not None and np.array_equal(u, uv[0]) for u in uv)


def value_batches(textures) -> Iterator[list[np.ndarray]]:
    """The textures' values on one common set of points, in batches of bounded size.

    Yields lists with one (channels, points) float64 array per texture, all with the
    same channel count: the texels of the bitmaps when they share one grid, else the
    texel centres of the finest texture (times a sweep of wavelengths in spectral
    variants), else a single point for constant textures.
    """
    varying = [t for t in textures if t.is_spatially_varying()]
    if not varying:
        yield _broadcast(_evaluate(textures, np.array([0.5]), np.array([0.5])))
        return
    data = [texel_data(t) for t in varying]
    if all(d is not None for d in data) and _same_grid(varying, data):
        yield from _texel_batches(textures, varying, data)
        return
    width = height = 2
    for tex in varying:
        res = tex.resolution()
        width, height = max(width, int(res[0])), max(height, int(res[1]))
    if not dr.is_jit_v(mi.Float):
        width, height = min(width, _SCALAR_MAX_GRID), min(height, _SCALAR_MAX_GRID)
    u = (np.arange(width) + 0.5) / width
    rows = _N_WAVELENGTH_ROWS if mi.is_spectral else 1
    step = max(1, _BATCH // (width * rows))
    for start in range(0, height, step):
        v = (np.arange(start, min(start + step, height)) + 0.5) / height
        uu, vv = (a.ravel() for a in np.meshgrid(u, v, indexing="xy"))
        yield _broadcast(_evaluate(textures, uu, vv))


def _texel_batches(textures, varying, data) -> Iterator[list[np.ndarray]]:
    """Batches of texels of bitmaps on one grid, constants broadcast beside them."""
    constant = [t for t in textures if not t.is_spatially_varying()]
    const_values = dict(zip((id(t) for t in constant),
                            _evaluate(constant, np.array([0.5]), np.array([0.5]))))
    flat = {id(t): d.reshape(-1, d.shape[-1]) for t, d in zip(varying, data)}
    n = next(iter(flat.values())).shape[0]
    for start in range(0, n, _BATCH):
        stop = min(start + _BATCH, n)
        yield _broadcast([flat[id(t)][start:stop].T.astype(np.float64) if id(t) in flat
                          else const_values[id(t)] for t in textures])


def _broadcast(values: list[np.ndarray]) -> list[np.ndarray]:
    channels = max(v.shape[0] for v in values)
    points = max(v.shape[1] for v in values)
    return [np.broadcast_to(v, (channels, points)) for v in values]


class Summary:
    """Per-texture range of values, and the worst point of their sum, over all batches."""

    def __init__(self, textures):
        n = len(textures)
        self.lo: list = [None] * n
        self.hi: list = [None] * n
        self.finite = [True] * n
        self.denormal: list = [None] * n     # a denormal value of a constant texture, if any
        self.worst_total = None              # (channels,) sum of the values at the worst point
        self.worst_parts: list = []          # each texture's (channels,) value there
        for batch in value_batches(textures):
            self._add(batch)
        for k, tex in enumerate(textures):
            data = texel_data(tex)
            if data is not None:             # a bitmap's own texels bound its values exactly
                self.finite[k] = bool(np.all(_finite32(data)))
                self.lo[k], self.hi[k] = _nan_min_max(data.reshape(-1, data.shape[-1]).T)
            elif not tex.is_spatially_varying() and not mi.is_spectral:
                bad = self.lo[k][_denormal(self.lo[k])]
                self.denormal[k] = float(bad[0]) if bad.size else None

    def _add(self, batch: list[np.ndarray]) -> None:
        for k, v in enumerate(batch):
            self.finite[k] = self.finite[k] and bool(np.all(_finite32(v)))
            lo, hi = _nan_min_max(v)
            self.lo[k] = lo if self.lo[k] is None else np.minimum(self.lo[k], lo)
            self.hi[k] = hi if self.hi[k] is None else np.maximum(self.hi[k], hi)
        total = np.nan_to_num(sum(batch), nan=-np.inf)
        at = int(np.argmax(total.max(axis=0)))
        if self.worst_total is None or total[:, at].max() > self.worst_total.max():
            self.worst_total = total[:, at].copy()
            self.worst_parts = [v[:, at].copy() for v in batch]


def _nan_min_max(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel min and max of (channels, points), ignoring NaN (reported separately)."""
    v = np.where(np.isnan(values), np.inf, values)
    lo = v.min(axis=1)
    v = np.where(np.isnan(values), -np.inf, values)
    return lo, v.max(axis=1)


# ----------------------------------------------------------------------------- range checks

def check_range(plugin: str, name: str, lo, hi, finite: bool = True, denormal=None,
                upper: float = 1.0, slack: float = TOLERANCE) -> None:
    """Raise :class:`MaterialError` unless the values are finite, not denormal and in
    [0, upper·(1 + slack)] in every channel (``upper`` 1: a reflectance, else an intensity;
    ``slack`` the float32 headroom of evaluated textures, 0 for a value the scene wrote)."""
    reflectance = upper == 1.0
    what = "a reflectance in [0, 1]" if reflectance else f"an intensity in [0, {upper:g}]"
    if not finite:
        raise MaterialError(
            f"{plugin}: '{name}' has non-finite values (NaN or Inf); give {what}.")
    if denormal is not None:
        raise _denormal_error(plugin, name, denormal)
    # No slack below 0: a value of -1e-30 already darkens a pixel below 0.
    if np.any(np.asarray(lo) < 0) or np.any(np.asarray(hi) > upper * (1 + slack)):
        if reflectance:
            rule = ("must lie in [0, 1] in every channel (a reflectance is the fraction of "
                    "light reflected)")
        else:
            rule = (f"must lie in [0, {upper:g}] in every channel (a light intensity, "
                    f"with float32 headroom for the sums over lights, samples and pixels)")
        raise MaterialError(f"{plugin}: '{name}' {rule}, but ranges from {_fmt(lo)} to "
                            f"{_fmt(hi)}; use values in [0, {upper:g}].")


def check_reflectance_range(plugin: str, name: str, values: np.ndarray,
                            declared: bool = False) -> None:
    """Raise :class:`MaterialError` unless every value (channels, points) lies in [0, 1]
    (``declared``: values the scene wrote, which must not be denormal either)."""
    values = np.asarray(values, dtype=np.float64)
    bad = values[_denormal(values)] if declared else np.zeros(0)
    lo, hi = _nan_min_max(values)
    check_range(plugin, name, lo, hi, bool(np.all(_finite32(values))),
                float(bad[0]) if bad.size else None)


def check_energy(plugin: str, names, total, parts) -> None:
    """Raise :class:`MaterialError` when the lobes' reflectances ``parts`` (each (channels,)
    at the worst point) sum to ``total`` > 1."""
    if np.any(total > 1 + TOLERANCE):
        summed = " + ".join(f"{n} {_fmt(v)}" for n, v in zip(names, parts))
        raise MaterialError(
            f"{plugin}: {summed} = {_fmt(total)} exceeds 1: the material violates energy "
            f"conservation (it would reflect more light than it receives). Lower "
            f"{' or '.join(repr(n) for n in names)} so that their sum is at most 1 in every "
            f"channel; phonglab never rescales it silently.")


def check_textures(plugin: str, textures: dict, energy: bool = False,
                   upper: float = 1.0) -> None:
    """Validate textures {name: texture}: each in range, and their sum <= 1 when ``energy``."""
    summary = Summary(list(textures.values()))
    for k, name in enumerate(textures):
        check_range(plugin, name, summary.lo[k], summary.hi[k], summary.finite[k],
                    summary.denormal[k], upper)
    if energy:
        check_energy(plugin, tuple(textures), summary.worst_total, summary.worst_parts)


def declared_value(props, name: str, default: float) -> np.ndarray | None:
    """The value a scene wrote for ``name`` when it is a plain number or colour, as (channels, 1).

    None for textures and spectra (their values are known only by evaluation).  Checking
    the declared colour matters in spectral variants: the smooth spectrum Mitsuba
    up-samples from an RGB colour can exceed its RGB components at some wavelengths
    (RGB 0.6, 0.3, 0.2 reaches 0.97 near 830 nm), which is a property of the
    up-sampling, not of the material the user described.
    """
    if name not in props:
        return np.array([[default]])
    kind = props.type(name)
    if kind == mi.Properties.Type.Float:
        return np.array([[float(props.get(name))]])
    if kind == mi.Properties.Type.Color:
        return np.array(props.get(name), dtype=np.float64).reshape(-1, 1)
    return None


def load_textures(plugin: str, props, names_defaults, energy: bool = False,
                  unbounded: bool = False) -> list:
    """Read and check texture parameters [(name, default)]: the textures, in order.

    Reflectances (``unbounded`` False) must lie in [0, 1] (and sum to at most 1 when
    ``energy``); unbounded textures (an intensity) in [0, INTENSITY_MAX].  Plain
    numbers and colours are checked as the scene declared them, before Mitsuba turns
    them into textures (so the error names the parameter); textures by evaluation.
    """
    upper = INTENSITY_MAX if unbounded else 1.0
    declared = [declared_value(props, n, d) for n, d in names_defaults]
    for (name, _), values in zip(names_defaults, declared):
        if values is not None:
            lo, hi = _nan_min_max(values)
            bad = values[_denormal(values)]
            # No slack for a reflectance the scene wrote: Mitsuba's own colour texture then
            # refuses anything above 1 with its RuntimeError ("Invalid RGB reflectance value
            # [0, 0, 1.0001]"), not phonglab's one sentence.
            check_range(plugin, name, lo, hi, bool(np.all(_finite32(values))),
                        float(bad[0]) if bad.size else None, upper,
                        slack=0.0 if upper == 1.0 else TOLERANCE)
    get = props.get_unbounded_texture if unbounded else props.get_texture
    textures = [get(name, default) for name, default in names_defaults]
    if all(d is not None for d in declared):
        if energy:
            channels = max(d.shape[0] for d in declared)
            parts = [np.broadcast_to(d, (channels, 1))[:, 0] for d in declared]
            check_energy(plugin, tuple(n for n, _ in names_defaults), sum(parts), parts)
        return textures
    check_textures(plugin, {n: t for (n, _), t in zip(names_defaults, textures)}, energy, upper)
    return textures


# ----------------------------------------------------------------------------- transactions

def _copy(value):
    """A copy of a traversed value that later in-place writes to the original do not reach."""
    return dr.copy(value) if dr.is_array_v(value) else value


def snapshot(members: dict) -> dict:
    """The current values behind a plugin's traversed members {name: array or texture}."""
    out = {}
    for name, obj in members.items():
        if isinstance(obj, mi.Object):
            params = mi.traverse(obj)
            out[name] = {k: _copy(params[k]) for k in params.keys()}
        else:
            out[name] = _copy(obj)
    return out


def restore(members: dict, saved: dict) -> None:
    """Write the values of :func:`snapshot` back into the same member objects.

    The members are the very objects ``mi.traverse`` hands out, so the caller's
    parameter map reads the restored values too.  A texture is told through its own
    ``parameters_changed`` (a bitmap rebuilds its lookup structure).
    """
    for name, obj in members.items():
        value = saved[name]
        if isinstance(value, dict):
            params = mi.traverse(obj)
            keys = [k for k in value if k in params
                    and not params.flags(k) & mi.ParamFlags.ReadOnly]
            for k in keys:
                params[k] = value[k]
            obj.parameters_changed(keys)
        elif dr.is_array_v(obj):
            mi.set_property(obj, value)


def commit(members: dict, accepted: dict | None, validate: Callable[[], None],
           derive: Callable[[], None]) -> dict:
    """One transactional update: validate the members' new values and re-derive.

    On :class:`MaterialError` the ``accepted`` values are restored and re-derived before
    the error propagates; otherwise returns the new accepted snapshot.
    """
    try:
        validate()
    except MaterialError:
        if accepted is not None:
            restore(members, accepted)
            derive()
        raise
    derive()
    return snapshot(members)
