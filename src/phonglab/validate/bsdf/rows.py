r"""Rows of the lane-wise identity topics (``finite``, ``eval_pdf``, ``weight``, ``pdf``,
``component``, ``reciprocity``): many lanes reduced to one :class:`~phonglab.validate.bsdf.topics.Row`.

A row's ``measured`` is the largest finite per-lane value (:func:`max_finite`: a count of bad
lanes, a relative difference, or the excess over the lane's tolerance); the row passes when that
is finite and at most the tolerance (:func:`bounded_row`).  Its details count the lanes and name
the worst lane's directions (:func:`worst_lane`).  Non-finite lanes are the ``finite`` topic's
alone: the other topics drop them and count them here.  The reason texts say which tolerance a
row uses (:mod:`.config` derives them).
"""

from __future__ import annotations

import numpy as np

from .topics import Row

#: The reason text of a row compared at float32 round-off alone.
ROUND_OFF = "float32 round-off tolerance 2^-10 relative (roundoff.REL_TOL)"
#: ... of a row compared against each lane's round-off plus its sensitivity.
CONDITIONED = ("measured = max over lanes of rel_diff / (2^-10 + both sides' sensitivity to an "
               "8-ulp move of their input directions), must be ≤ 1 (roundoff.sensitivity)")
#: ... of a row whose failing lanes are searched again over an 8-ulp box (roundoff.refine).
BOXED = (CONDITIONED[:-1] + "; a lane that fails gets the evaluated side's sensitivity over "
         "every float32 wo within 8 ulps per component, roundoff.refine)")


def bounded_row(topic, name, measured, tol, reason, details, expected=0.0, lanes=None) -> Row:
    """A row that passes when ``measured`` is finite and ≤ ``tol``.

    ``lanes``: (per-lane values, {input name: per-lane array}) -- the row then carries the
    inputs of its failing lanes (finite values > ``tol``) as ``failing_lanes``, which a
    documented cause's signature is matched against (:mod:`.signatures`).
    """
    ok = measured is not None and np.isfinite(measured) and measured <= tol
    row = Row(topic, name, float(measured), expected, None, tol, "pass" if ok else "fail",
              reason, details)
    if lanes is not None and not ok:
        values, inputs = lanes
        values = np.asarray(values, np.float64)
        bad = np.isfinite(values) & (values > tol)
        row.failing_lanes = {k: np.asarray(v)[bad] for k, v in inputs.items()}
    return row


def worst_lane(rel: np.ndarray, wi: np.ndarray, wo: np.ndarray, extra: dict | None = None) -> dict:
    """details: lanes compared, non-finite lanes dropped, and the worst lane's directions
    (with the worst lane's value of each array in ``extra``)."""
    finite = np.isfinite(rel)
    d = {"lanes": int(rel.size), "nonfinite_dropped": int((~finite).sum())}
    if finite.any():
        k = int(np.nanargmax(np.where(finite, rel, -1.0)))
        d.update(worst_wi=wi[k].tolist(), worst_wo=wo[k].tolist())
        d.update({name: float(v[k]) for name, v in (extra or {}).items()})
    return d


def max_finite(rel: np.ndarray) -> float:
    """The largest finite lane value (0 when none is finite)."""
    finite = rel[np.isfinite(rel)]
    return float(finite.max()) if finite.size else 0.0


def worst_entry(ex, wi, wo, a, b, names) -> dict:
    """details of a comparison of Mueller matrices a, b (N, C, 4, 4): lanes compared and not
    compared, the worst lane's directions, its wavelength channel and entry (i, j) of M/M00
    that differ most, and both matrices there (named by ``names``)."""
    finite = np.isfinite(ex)
    d = {"lanes": int(ex.size), "not_compared": int((~finite).sum())}
    if finite.any() and ex.size:
        k = int(np.nanargmax(np.where(finite, ex, -1.0)))
        d.update(worst_wi=wi[k].tolist(), worst_wo=wo[k].tolist())
        # the wavelength and entry (i, j) of M/M00 that differ most in that lane
        with np.errstate(divide="ignore", invalid="ignore"):
            na = a[k] / a[k][:, :1, :1]
            nb = b[k] / b[k][:, :1, :1]
        diff = np.nan_to_num(np.abs(na - nb), nan=-1.0)
        c, i, j = np.unravel_index(int(np.argmax(diff)), diff.shape)
        d.update(worst_entry=f"M{i}{j}", worst_channel=int(c),
                 **{names[0]: np.round(a[k, c], 6).tolist(),
                    names[1]: np.round(b[k, c], 6).tolist()})
    return d
