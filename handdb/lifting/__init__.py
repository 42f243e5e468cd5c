"""Depth reconstruction: lift a clip's 2D tracks to 3D and settle each bone's depth sign.

>>> from handdb.lifting import lift, available_methods          # doctest: +SKIP
>>> result = lift(uv, skeleton, bone_lengths, camera, method="kinematic")  # doctest: +SKIP

Methods: ``thesis`` and ``thesis-nocheck`` (the thesis's scaled-orthographic method with and
without its reflective-ambiguity rule, :mod:`handdb.lifting.thesis`), ``kinematic``, the
default (:mod:`handdb.lifting.kinematic`), and ``kinematic-refined``, the default polished
by nonlinear least squares (:mod:`handdb.lifting.refine`).
"""

from handdb.lifting import kinematic, model_fit, refine, thesis  # noqa: F401  (registers the methods)
from handdb.lifting.registry import (
    DEFAULT_METHOD,
    available_methods,
    bone_length_array,
    lift,
    register,
)
from handdb.lifting.result import LiftResult

__all__ = [
    "DEFAULT_METHOD",
    "LiftResult",
    "available_methods",
    "bone_length_array",
    "lift",
    "register",
]
