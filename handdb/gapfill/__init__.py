"""Gap filling: complete the missing points of 2D hand tracks before lifting.

:func:`fill_gaps` is the entry point; :data:`METHODS` lists every method by name. The
thesis's five methods are named baselines (:mod:`handdb.gapfill.thesis`); the offline
methods use the frames after a gap too; ``auto``, the default, combines them per gap.
"""

from handdb.gapfill import auto, interpolate, lowrank, rigid, thesis  # noqa: F401  (registers)
from handdb.gapfill.registry import (
    DEFAULT_METHOD,
    LEADING,
    METHODS,
    OFFLINE,
    SHORT_HISTORY,
    THESIS,
    TRAILING,
    UNFILLED,
    WHOLE_CLIP,
    FillResult,
    GapFlag,
    UnknownMethodError,
    fill_gaps,
    method_names,
)

__all__ = [
    "DEFAULT_METHOD",
    "METHODS",
    "LEADING",
    "OFFLINE",
    "SHORT_HISTORY",
    "THESIS",
    "TRAILING",
    "UNFILLED",
    "WHOLE_CLIP",
    "FillResult",
    "GapFlag",
    "UnknownMethodError",
    "fill_gaps",
    "method_names",
]
