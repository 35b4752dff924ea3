"""Physics conformance of any Mitsuba 3 BSDF: :func:`validate_bsdf` and its :class:`Report`."""

from .report import STATUSES, TOPICS, Report, Row, table

__all__ = ["Report", "Row", "STATUSES", "TOPICS", "table"]
