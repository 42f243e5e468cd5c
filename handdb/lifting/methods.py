"""The lifting methods by name, known without importing them (filled in :mod:`handdb.lifting`).

This module imports nothing heavy, so that the command line can list the methods and check
a name (``handdb build --lift``) without loading numba and scipy.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from handdb.registry import Registry

if TYPE_CHECKING:
    from handdb.lifting.registry import LiftMethod

#: Method used when a clip's sidecar names none.
DEFAULT_METHOD = "kinematic"

#: The 2D fit of the 33-DoF hand model (:mod:`handdb.lifting.model_fit`).
MODEL_FIT = "model-fit"

#: Every lifting method by name, filled in :mod:`handdb.lifting`.
METHODS: Registry[LiftMethod] = Registry("lifting method")


def available_methods() -> tuple[str, ...]:
    """Names of the registered lifting methods, sorted."""
    return tuple(sorted(METHODS))
