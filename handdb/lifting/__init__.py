"""Depth reconstruction: lift a clip's 2D tracks to 3D and settle each bone's depth sign.

>>> from handdb.lifting import lift, available_methods          # doctest: +SKIP
>>> result = lift(uv, skeleton, bone_lengths, camera, method="kinematic")  # doctest: +SKIP

Methods: ``thesis`` and ``thesis-nocheck`` (the thesis's scaled-orthographic method with and
without its reflective-ambiguity rule, :mod:`handdb.lifting.thesis`), ``kinematic``, the
default (:mod:`handdb.lifting.kinematic`), ``kinematic-refined``, the default polished
by nonlinear least squares (:mod:`handdb.lifting.refine`), and ``model-fit``, the 33-DoF
hand model fitted to the 2D points (:mod:`handdb.lifting.model_fit`).

Importing this package registers the names only: each method's module (numba, scipy) is
imported when the method first runs, and :func:`lift` and :class:`LiftResult` when first
used, so that listing or checking a method name costs nothing.
"""

from typing import TYPE_CHECKING

from handdb.lazy import LazyFunction, lazy_attributes
from handdb.lifting.methods import DEFAULT_METHOD, METHODS, MODEL_FIT, available_methods

if TYPE_CHECKING:
    from handdb.lifting.registry import lift
    from handdb.lifting.result import LiftResult

METHODS.add("thesis", LazyFunction("handdb.lifting.thesis:lift_thesis"))
METHODS.add("thesis-nocheck", LazyFunction("handdb.lifting.thesis:lift_thesis_nocheck"))
METHODS.add(DEFAULT_METHOD, LazyFunction("handdb.lifting.kinematic:lift_kinematic"))
METHODS.add("kinematic-refined", LazyFunction("handdb.lifting.refine:lift_refined"))
METHODS.add(MODEL_FIT, LazyFunction("handdb.lifting.model_fit:fit_2d"))

#: Version of lifting. Raise it when a change alters the output; it
#: enters the build keys (:mod:`handdb.build.keys`), a docstring edit or a speed-up does not.
VERSION = 6

__getattr__ = lazy_attributes(__name__, {"lift": "handdb.lifting.registry",
                                         "LiftResult": "handdb.lifting.result"})

__all__ = [
    "DEFAULT_METHOD",
    "METHODS",
    "LiftResult",
    "available_methods",
    "lift",
]
