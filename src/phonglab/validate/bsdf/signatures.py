r"""Signatures: which failing lanes (or χ² cells) of a BSDF row a documented cause explains.

A finding never explains a whole topic, only a *signature*: the rows it names and a region of
their inputs (exactly grazing incidence, a sample value on the singular point of a warp, the
bins below the horizon of a χ² cell, ...).  A row carries the inputs of its failing lanes
(``Row.failing_lanes``: ``wi``, ``wo``, ``sample1``, ``sample2``, ``component``, ``type`` per
lane, or the failing χ² cells' records under ``cell``); a region maps them to one boolean per
failing lane, True where the lane lies inside it.  :func:`phonglab.validate.known.mark_known`
makes a failing row KNOWN only when every failing lane lies in the region of a cause that
names the row, so a new failure in the same topic -- a lane elsewhere -- still fails.

A region that needs an input the row does not record covers nothing (the row stays a fail):
a signature can only be trusted where it can be checked.

χ² cells (:class:`Chi2Outside`).  A cell's record holds its histogram and expected counts as
(rows, columns) = (−cos θ_o, φ_o) bins, −cos θ_o from −1 to 1 (row 0 holds the normal
direction) and φ_o from −π to π: the (φ, −cos θ) parametrization of the sphere the χ² topic
bins in (``mi.chi2.SphericalDomain``'s).  A failing cell lies in
the signature when it passes the same test -- Pearson's χ² with bins of expected count < 5
pooled, dof = bins − 1, p ≥ the row's Šidák level -- on the bins *outside* the region: the
discrepancy is then confined to where the finding says it is.  The cell's ``expected`` is
N·∫pdf as the pdf says it (the χ² topic tests the shape against it times the cell's
``scale``; a finding's bins are held against the pdf itself).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from ... import stats

#: Tolerance of "on the singular sample point": sample values are float64 draws (or edges).
SAMPLE_TOL = 1e-6


@dataclass(frozen=True)
class Region:
    """A region of a row's inputs; subclasses say which failing lanes lie in it."""

    def covers(self, row) -> np.ndarray | None:      # pragma: no cover - interface
        """One boolean per failing lane of ``row`` (True: inside), or None when the row does not
        record the inputs the region needs."""
        raise NotImplementedError

    @property
    def text(self) -> str:                            # pragma: no cover - interface
        raise NotImplementedError


def _lanes(row, *names):
    lanes = row.failing_lanes or {}
    if not all(n in lanes for n in names):
        return None
    return [np.asarray(lanes[n]) for n in names]


@dataclass(frozen=True)
class GrazingIncidence(Region):
    """Exactly grazing incidence, cos θ_i = 0: a set of measure zero that a renderer reaches
    only where a ray meets a surface exactly edge-on."""

    def covers(self, row):
        got = _lanes(row, "wi")
        return None if got is None else got[0][:, 2] == 0.0

    @property
    def text(self):
        return "exactly grazing incidence cos θ_i = 0 (a measure-zero set of inputs)"


@dataclass(frozen=True)
class IncidenceFrom(Region):
    """Incidence at least ``cos_min`` away from grazing, |cos θ_i| ≥ ``cos_min``: a cause whose
    effect on a per-incidence row (``normalization``, ``energy``) is measured to vanish below
    it leaves that row's grazing cells to other causes."""

    cos_min: float

    def covers(self, row):
        got = _lanes(row, "wi")
        return None if got is None else np.abs(got[0][:, 2]) >= self.cos_min

    @property
    def text(self):
        return f"incidence |cos θ_i| ≥ {self.cos_min:g}"


@dataclass(frozen=True)
class BelowHorizon(Region):
    """Incidence at or below the horizon, cos θ_i ≤ 0."""

    def covers(self, row):
        got = _lanes(row, "wi")
        return None if got is None else got[0][:, 2] <= 0.0

    @property
    def text(self):
        return "incidence at or below the horizon, cos θ_i ≤ 0"


@dataclass(frozen=True)
class MaskedReflection(Region):
    """Pairs a reflection-only plugin masks off: cos θ_i ≤ 0 or cos θ_o ≤ 0 (its eval is 0
    there; a pdf computed from the masked-off lanes' garbage and returned unmasked is not)."""

    def covers(self, row):
        got = _lanes(row, "wi", "wo")
        return None if got is None else (got[0][:, 2] <= 0.0) | (got[1][:, 2] <= 0.0)

    @property
    def text(self):
        return "pairs outside a reflection lobe's support, cos θ_i ≤ 0 or cos θ_o ≤ 0"


@dataclass(frozen=True)
class SamplePoint(Region):
    """sample2 at one point of [0, 1)² (a warp's singular point), to :data:`SAMPLE_TOL`."""

    point: tuple[float, float]

    def covers(self, row):
        got = _lanes(row, "sample2")
        if got is None:
            return None
        return np.all(np.abs(got[0].reshape(-1, 2) - np.asarray(self.point)) <= SAMPLE_TOL, axis=1)

    @property
    def text(self):
        return f"sample2 = ({self.point[0]:g}, {self.point[1]:g}) (a measure-zero sample value)"


@dataclass(frozen=True)
class SampleEdgeAtNormalIncidence(Region):
    """sample2 on an edge of [0, 1]² (a component 0 or ≥ 1 − :data:`SAMPLE_TOL`) at normal
    incidence wi = (0, 0, 1): a concentric-disk warp maps the square's edge to the unit
    circle, where a visible-normal sampler's projection has z = 0."""

    def covers(self, row):
        got = _lanes(row, "wi", "sample2")
        if got is None:
            return None
        wi, u = got[0], got[1].reshape(-1, 2)
        edge = np.any((u <= 0.0) | (u >= 1.0 - SAMPLE_TOL), axis=1)
        return edge & (wi[:, 2] == 1.0)

    @property
    def text(self):
        return ("sample2 on an edge of [0, 1]² at normal incidence (a measure-zero set of "
                "sample values)")


@dataclass(frozen=True)
class Grazing(Region):
    """A grazing pair: min(|cos θ_i|, |cos θ_o|) ≤ ``cos_max``."""

    cos_max: float

    def covers(self, row):
        got = _lanes(row, "wi", "wo")
        if got is None:
            return None
        wi, wo = got
        return np.minimum(np.abs(wi[:, 2]), np.abs(wo[:, 2])) <= self.cos_max

    @property
    def text(self):
        return f"grazing pairs, min(|cos θ_i|, |cos θ_o|) ≤ {self.cos_max:g}"


@dataclass(frozen=True)
class IncidencePlaneY0(Region):
    """wi within ``y_max`` of the plane y = 0 (|wi.y| ≤ y_max): the azimuth where a frame built
    from a fixed axis that is not projected flips its rotation's sign (mitsuba3#1963)."""

    y_max: float

    def covers(self, row):
        got = _lanes(row, "wi")
        return None if got is None else np.abs(got[0][:, 1]) <= self.y_max

    @property
    def text(self):
        return f"incidence within |wi.y| ≤ {self.y_max:g} of the plane y = 0"


@dataclass(frozen=True)
class ParameterAt(Region):
    """A parameter row (``gradient``) measured with every entry of its parameter at one of
    ``values`` (``details["value_range"]``): a range end, where a lobe switches on or a term
    has a kink."""

    values: tuple[float, ...]

    def covers(self, row):
        vr = (row.details or {}).get("value_range")
        if vr is None:
            return None
        lo, hi = vr
        return np.array([lo == hi and any(abs(lo - v) <= 1e-6 * max(1.0, abs(v))
                                          for v in self.values)])

    @property
    def text(self):
        return ("the parameter at " + " or ".join(f"{v:g}" for v in self.values)
                + " (an end of its range)")


@dataclass(frozen=True)
class ComponentOutOfRange(Region):
    """Samples whose sampled_component is ≥ component_count() (``details["flags"]``)."""

    def covers(self, row):
        got = _lanes(row, "component")
        flags = (row.details or {}).get("flags")
        if got is None or flags is None:
            return None
        return got[0] >= len(flags)

    @property
    def text(self):
        return "samples whose sampled_component is ≥ component_count()"


@dataclass(frozen=True)
class ComponentOfAnotherLobe(Region):
    """Samples whose sampled_type fits the flags of another component than the one reported
    (a numbering mistake, not a lobe that no component declares)."""

    def covers(self, row):
        got = _lanes(row, "component", "type")
        flags = (row.details or {}).get("flags")
        if got is None or flags is None:
            return None
        comp, stype = got
        lobes = np.asarray(stype) & 0xFF       # the lobe bits of mi.BSDFFlags (All = 255)
        fits = [((lobes & ~f) == 0) & (lobes != 0) for f in flags]
        other = np.zeros(len(comp), bool)
        for k, fit in enumerate(fits):
            other |= fit & (comp != k)
        return other

    @property
    def text(self):
        return "samples whose sampled_type belongs to another declared component"


@dataclass(frozen=True)
class Union(Region):
    """A lane inside any of ``regions``."""

    regions: tuple[Region, ...]

    def covers(self, row):
        masks = [r.covers(row) for r in self.regions]
        masks = [m for m in masks if m is not None]
        if not masks:
            return None
        out = np.zeros(len(masks[0]), bool)
        for m in masks:
            out |= m
        return out

    @property
    def text(self):
        return " or ".join(r.text for r in self.regions)


# ----------------------------------------------------------------------------- χ² cells
def _cells(row):
    cells = (row.failing_lanes or {}).get("cell")
    level = (row.details or {}).get("level")
    return (None, None) if cells is None or level is None else (cells, level)


def _counts(cell):
    if "histogram" not in cell or "expected" not in cell:
        return None, None
    return (np.asarray(cell["histogram"], np.float64), np.asarray(cell["expected"], np.float64))


@dataclass(frozen=True)
class Chi2Outside(Region):
    """Failing χ² cells that pass on the bins outside ``bins`` ("below_horizon": cos θ_o < 0;
    "normal_plane": the φ_o columns holding 0 and ±π, i.e. wo.y = 0)."""

    bins: str

    def covers(self, row):
        cells, level = _cells(row)
        return None if cells is None else np.array([self._explains(c, level) for c in cells])

    def _explains(self, cell, level) -> bool:
        obs, exp = _counts(cell)
        if obs is None:
            return False
        inside = bin_mask(self.bins, obs.shape)
        if not inside.any() or inside.all():
            return False
        return stats.pearson_chi2(obs[~inside], exp[~inside]).p_value >= level

    @property
    def text(self):
        return {"below_horizon": "χ² cells whose discrepancy lies below the horizon "
                                 "(they pass on the bins with cos θ_o > 0)",
                "normal_plane": "χ² cells whose discrepancy lies in the plane wo.y = 0 (they "
                                "pass on the bins off φ_o = 0, ±π)"}[self.bins]


@dataclass(frozen=True)
class Chi2Excess(Region):
    """Failing χ² cells with a significant excess of samples in ``bins`` (as
    :class:`Chi2Outside`): observed − expected there ≥ z·√expected, z the one-sided normal
    quantile at the row's level.  A weaker signature than :class:`Chi2Outside`, for a sampler
    that collapses a lobe into a set of measure zero: the samples missing elsewhere leave a
    deficit shaped like that lobe, which no other bin set isolates."""

    bins: str

    def covers(self, row):
        cells, level = _cells(row)
        if cells is None:
            return None
        z = float(-special.ndtri(level))
        out = []
        for c in cells:
            obs, exp = _counts(c)
            if obs is None:
                out.append(False)
                continue
            inside = bin_mask(self.bins, obs.shape)
            o, e = obs[inside].sum(), exp[inside].sum()
            out.append(bool(e > 0 and o - e >= z * math.sqrt(e)))
        return np.array(out, bool)

    @property
    def text(self):
        return {"normal_plane": "χ² cells with a significant excess of samples in the plane "
                                "wo.y = 0 (the bins at φ_o = 0, ±π)",
                "below_horizon": "χ² cells with a significant excess of samples below the "
                                 "horizon"}[self.bins]


def bin_mask(bins: str, shape) -> np.ndarray:
    """The bins of a (−cos θ_o, φ_o) histogram of ``shape``
    (:class:`phonglab.validate.sphere_bins.Grid`) in the named set:
    ``below_horizon`` every row with some wo below the horizon, ``normal_plane`` the φ_o
    columns that hold 0 or ±π (wo.y = 0; a value on a column edge marks both columns)."""
    rows, cols = shape
    out = np.zeros(shape, bool)
    if bins == "below_horizon":
        upper = -1.0 + 2.0 * (np.arange(rows) + 1) / rows      # upper edge of −cos θ_o
        out[upper > 1e-12, :] = True
    elif bins == "normal_plane":
        edges = -math.pi + 2.0 * math.pi * np.arange(cols + 1) / cols
        for phi in (-math.pi, 0.0, math.pi):
            j = np.flatnonzero((edges[:-1] <= phi + 1e-12) & (edges[1:] >= phi - 1e-12))
            out[:, j] = True
    else:
        raise ValueError(f"unknown χ² bin region {bins!r}")
    return out
