"""Load-time validation shared by phonglab's BSDF plugins.

A reflectance is the fraction of incident light a surface reflects, so every
value a reflectance texture can return must lie in [0, 1], and the lobes of one
material together must not reflect more than they receive.  The textures are
evaluated where their values live: once for a constant, on every texel centre
of a bitmap (up to 1024 x 1024), and over the visible range of wavelengths in
spectral variants.  Errors are raised as :class:`MaterialError` (a
``ValueError``) naming the plugin, the parameter and the fix.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

#: Slack for float rounding (spectral up-sampling, sRGB decoding) in range checks.
TOLERANCE = 1e-4
_MAX_GRID = 1024
_SCALAR_MAX_GRID = 64
_N_WAVELENGTH_ROWS = 32


class MaterialError(ValueError):
    """An unphysical or malformed material parameter."""


def _uv_grid(textures) -> tuple[int, int]:
    width = height = 1
    for tex in textures:
        if tex.is_spatially_varying():
            res = tex.resolution()
            width, height = max(width, int(res[0])), max(height, int(res[1]))
            width, height = max(width, 2), max(height, 2)
    cap = _MAX_GRID if dr.is_jit_v(mi.Float) else _SCALAR_MAX_GRID
    return min(width, cap), min(height, cap)


def texture_values(textures) -> list[np.ndarray]:
    """Values of several textures on one common set of points.

    Returns one array per texture of shape (channels, points): texel centres
    of the finest bitmap, times a sweep of wavelengths in spectral variants.
    """
    width, height = _uv_grid(textures)
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    uu, vv = (a.ravel() for a in np.meshgrid(u, v, indexing="xy"))
    rows = _N_WAVELENGTH_ROWS if mi.is_spectral else 1
    uu, vv = np.tile(uu, rows), np.tile(vv, rows)
    n = uu.size
    if mi.is_spectral:
        lo, hi = float(mi.MI_CIE_MIN), float(mi.MI_CIE_MAX)
        # Each point carries 4 wavelengths: rows x 4 evenly spread values in total.
        lam = np.linspace(lo, hi, rows * 4).reshape(rows, 4)
        lam = np.repeat(lam, width * height, axis=0)
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


def load_reflectances(plugin: str, props, names_defaults) -> tuple[list, list[np.ndarray]]:
    """Read and range-check reflectance parameters: (textures, values on common points).

    Plain numbers and colours are checked as the scene declared them, before Mitsuba
    turns them into textures (so the error names the parameter); textures are
    evaluated by :func:`texture_values` and checked the same way.
    """
    declared = [declared_value(props, n, d) for n, d in names_defaults]
    plain = all(d is not None for d in declared)
    if plain:
        for (name, _), values in zip(names_defaults, declared):
            check_reflectance_range(plugin, name, values)
    textures = [props.get_texture(name, default) for name, default in names_defaults]
    if plain:
        channels = max(d.shape[0] for d in declared)
        return textures, [np.broadcast_to(d, (channels, 1)) for d in declared]
    values = texture_values(textures)
    for (name, _), v in zip(names_defaults, values):
        check_reflectance_range(plugin, name, v)
    return textures, values


def _fmt(x: np.ndarray) -> str:
    return "[" + ", ".join(f"{float(v):.4g}" for v in np.atleast_1d(x)) + "]"


def check_reflectance_range(plugin: str, name: str, values: np.ndarray) -> None:
    """Raise :class:`MaterialError` unless every value lies in [0, 1]."""
    if not np.all(np.isfinite(values)):
        raise MaterialError(
            f"{plugin}: '{name}' has non-finite values (NaN or Inf); give a reflectance in [0, 1].")
    lo, hi = values.min(axis=1), values.max(axis=1)
    if np.any(lo < -TOLERANCE) or np.any(hi > 1 + TOLERANCE):
        raise MaterialError(
            f"{plugin}: '{name}' must lie in [0, 1] in every channel (a reflectance is the "
            f"fraction of light reflected), but ranges from {_fmt(lo)} to {_fmt(hi)}. "
            f"Use values in [0, 1].")


def check_energy(plugin: str, names: tuple[str, ...], values: list[np.ndarray]) -> None:
    """Raise :class:`MaterialError` when the lobes' reflectances sum to more than 1 anywhere."""
    total = sum(values)
    worst = total.max(axis=1)
    if np.any(worst > 1 + TOLERANCE):
        at = int(np.argmax(total.max(axis=0)))
        parts = " + ".join(f"{n} {_fmt(v[:, at])}" for n, v in zip(names, values))
        raise MaterialError(
            f"{plugin}: {parts} = {_fmt(total[:, at])} exceeds 1: the material violates energy "
            f"conservation (it would reflect more light than it receives). Lower "
            f"{' or '.join(repr(n) for n in names)} so that their sum is at most 1 in every "
            f"channel; phonglab never rescales it silently.")


def check_exponent(plugin: str, value) -> float:
    """The Phong exponent as a float, or :class:`MaterialError` when it is unusable."""
    try:
        p = float(value)
    except (TypeError, ValueError):
        raise MaterialError(f"{plugin}: 'exponent' must be a number, got {value!r}.") from None
    if not math.isfinite(p) or p < 0:
        raise MaterialError(
            f"{plugin}: 'exponent' must be a finite number >= 0 (the shininess p of cos^p α), "
            f"got {p}. Use 0 for a uniform lobe, larger values for sharper highlights.")
    return p


def scalar_of(value) -> float:
    """A Python float from a Dr.Jit scalar or one-entry array."""
    if isinstance(value, (int, float)):
        return float(value)
    return float(np.array(value).ravel()[0])
