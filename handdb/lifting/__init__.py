"""Depth reconstruction: lift a clip's 2D tracks to 3D and settle each bone's depth sign.

>>> from handdb.lifting import lift, available_methods          # doctest: +SKIP
>>> result = lift(uv, skeleton, bone_lengths, camera, method="kinematic")  # doctest: +SKIP

Methods: ``thesis`` and ``thesis-nocheck`` (the thesis's scaled-orthographic method with and
without its reflective-ambiguity rule, :mod:`handdb.lifting.thesis`), ``kinematic``, the
default (:mod:`handdb.lifting.kinematic`), and ``kinematic-refined``, the default polished
by nonlinear least squares (:mod:`handdb.lifting.refine`).
"""

from handdb.lifting.kinematic import lift_kinematic
from handdb.lifting.model_fit import METHOD as MODEL_FIT
from handdb.lifting.model_fit import fit_2d
from handdb.lifting.refine import lift_refined
from handdb.lifting.registry import (
    DEFAULT_METHOD,
    METHODS,
    available_methods,
    lift,
)
from handdb.lifting.result import LiftResult
from handdb.lifting.thesis import lift_thesis, lift_thesis_nocheck

METHODS.add("thesis", lift_thesis)
METHODS.add("thesis-nocheck", lift_thesis_nocheck)
METHODS.add(DEFAULT_METHOD, lift_kinematic)
METHODS.add("kinematic-refined", lift_refined)
METHODS.add(MODEL_FIT, fit_2d)

#: Version of lifting. Raise it when a change alters the output; it
#: enters the build keys (:mod:`handdb.build.keys`), a docstring edit or a speed-up does not.
VERSION = 3

__all__ = [
    "DEFAULT_METHOD",
    "METHODS",
    "LiftResult",
    "available_methods",
    "lift",
]
