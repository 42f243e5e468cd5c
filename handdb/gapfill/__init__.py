"""Gap filling: complete the missing points of 2D hand tracks before lifting.

:func:`fill_gaps` is the entry point; :data:`METHODS` lists every method by name, registered
here. The thesis's five methods are named baselines (:mod:`handdb.gapfill.thesis`); the
offline methods use the frames after a gap too; ``auto``, the default, combines them per gap.

Importing this package registers the names only: each method's module (numba, scipy) is
imported when the method first runs, and :func:`fill_gaps` with its results when first used,
so that listing or checking a method name costs nothing.
"""

from typing import TYPE_CHECKING

from handdb.gapfill.methods import (
    DEFAULT_METHOD,
    METHODS,
    OFFLINE,
    THESIS,
    MethodInfo,
    method_names,
)
from handdb.lazy import LazyFunction, lazy_attributes

if TYPE_CHECKING:
    from handdb.gapfill.registry import (
        LEADING,
        SHORT_HISTORY,
        TRAILING,
        UNFILLED,
        WHOLE_CLIP,
        FillResult,
        GapFlag,
        fill_gaps,
    )


def _interpolation(kind: str) -> LazyFunction:
    return LazyFunction("handdb.gapfill.interpolate:interpolation_method", kind)


def _thesis(name: str) -> LazyFunction:
    return LazyFunction("handdb.gapfill.thesis:thesis_method", name)


for _info in (
    MethodInfo("linear", _interpolation("linear"), OFFLINE,
               "linear interpolation across each gap"),
    MethodInfo("cubic", _interpolation("cubic"), OFFLINE,
               "cubic spline through the observed samples"),
    MethodInfo("pchip", _interpolation("pchip"), OFFLINE,
               "shape-preserving cubic (PCHIP) through the observed samples"),
    MethodInfo("rigid", LazyFunction("handdb.gapfill.rigid:fill_rigid"), OFFLINE,
               "every missing point carried with the palm's affine motion"),
    MethodInfo("lowrank", LazyFunction("handdb.gapfill.lowrank:fill_lowrank"), OFFLINE,
               "iterated PCA reconstruction from the other joints"),
    MethodInfo(DEFAULT_METHOD, LazyFunction("handdb.gapfill.auto:fill_auto"), OFFLINE,
               "default: rigid palm, PCHIP short gaps, validated chain/regression"),
    MethodInfo("previous", _thesis("previous"), THESIS,
               "thesis method 1: the previous frame's value"),
    MethodInfo("previous-diff", _thesis("previous-diff"), THESIS,
               "thesis method 2: the last frame-to-frame change applied again"),
    MethodInfo("interfinger", _thesis("interfinger"), THESIS,
               "thesis method 3: method 2, reversed when the neighbouring finger turns"),
    MethodInfo("intrafinger", _thesis("intrafinger"), THESIS,
               "thesis method 4: method 2, reversed when the parent joint turns"),
    MethodInfo("intrafinger-rate", _thesis("intrafinger-rate"), THESIS,
               "thesis method 5: the parent joint's last change applied"),
):
    METHODS.add(_info.name, _info)
del _info

__getattr__ = lazy_attributes(__name__, dict.fromkeys(
    ("LEADING", "SHORT_HISTORY", "TRAILING", "UNFILLED", "WHOLE_CLIP", "FillResult", "GapFlag",
     "fill_gaps"), "handdb.gapfill.registry"))

#: Version of gap filling. Raise it when a change alters the output; it
#: enters the build keys (:mod:`handdb.build.keys`), a docstring edit or a speed-up does not.
VERSION = 7

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
    "MethodInfo",
    "fill_gaps",
    "method_names",
]
