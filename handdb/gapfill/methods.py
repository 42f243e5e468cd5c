"""The gap-filling methods by name, known without importing them.

:data:`METHODS` is filled in :mod:`handdb.gapfill`. This module imports nothing heavy, so
that the command line can list the methods and check a name (``handdb build --gap-fill``)
without loading numba and scipy.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from handdb.registry import Registry

if TYPE_CHECKING:
    from handdb.gapfill.registry import MethodOutput

#: The method :func:`~handdb.gapfill.registry.fill_gaps` uses unless told otherwise.
DEFAULT_METHOD = "auto"

#: Family of the five methods of the thesis (causal extrapolation).
THESIS = "thesis"
#: Family of the offline methods (frames after a gap are known).
OFFLINE = "offline"

#: A method: ``(uv, missing, skeleton, **params) -> MethodOutput`` (see
#: :mod:`handdb.gapfill.registry`).
GapFiller = Callable[..., "MethodOutput"]


@dataclass(frozen=True)
class MethodInfo:
    """A registered method: its name, function, family and a one-line summary."""

    name: str
    fill: GapFiller
    family: str
    summary: str


#: Every gap-filling method by name, filled in :mod:`handdb.gapfill`.
METHODS: Registry[MethodInfo] = Registry("gap-filling method")


def method_names(family: str | None = None) -> tuple[str, ...]:
    """Names of the registered methods, of one family or of all, in registration order."""
    return tuple(info.name for info in METHODS.values() if family in (None, info.family))
