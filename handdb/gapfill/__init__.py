"""Gap filling: complete the missing points of 2D hand tracks before lifting.

:func:`fill_gaps` is the entry point; :data:`METHODS` lists every method by name, registered
here. The thesis's five methods are named baselines (:mod:`handdb.gapfill.thesis`); the
offline methods use the frames after a gap too; ``auto``, the default, combines them per gap.
"""

from handdb.gapfill.auto import fill_auto
from handdb.gapfill.interpolate import interpolation_method
from handdb.gapfill.lowrank import fill_lowrank
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
    MethodInfo,
    fill_gaps,
    method_names,
)
from handdb.gapfill.rigid import fill_rigid
from handdb.gapfill.thesis import thesis_method

for _info in (
    MethodInfo("linear", interpolation_method("linear"), OFFLINE,
               "linear interpolation across each gap"),
    MethodInfo("cubic", interpolation_method("cubic"), OFFLINE,
               "cubic spline through the observed samples"),
    MethodInfo("pchip", interpolation_method("pchip"), OFFLINE,
               "shape-preserving cubic (PCHIP) through the observed samples"),
    MethodInfo("rigid", fill_rigid, OFFLINE,
               "every missing point carried with the palm's affine motion"),
    MethodInfo("lowrank", fill_lowrank, OFFLINE,
               "iterated PCA reconstruction from the other joints"),
    MethodInfo(DEFAULT_METHOD, fill_auto, OFFLINE,
               "default: rigid palm, PCHIP short gaps, validated chain/regression"),
    MethodInfo("previous", thesis_method("previous"), THESIS,
               "thesis method 1: the previous frame's value"),
    MethodInfo("previous-diff", thesis_method("previous-diff"), THESIS,
               "thesis method 2: the last frame-to-frame change applied again"),
    MethodInfo("interfinger", thesis_method("interfinger"), THESIS,
               "thesis method 3: method 2, reversed when the neighbouring finger turns"),
    MethodInfo("intrafinger", thesis_method("intrafinger"), THESIS,
               "thesis method 4: method 2, reversed when the parent joint turns"),
    MethodInfo("intrafinger-rate", thesis_method("intrafinger-rate"), THESIS,
               "thesis method 5: the parent joint's last change applied"),
):
    METHODS.add(_info.name, _info)
del _info

#: Version of gap filling. Raise it when a change alters the output; it
#: enters the build keys (:mod:`handdb.build.keys`), a docstring edit or a speed-up does not.
VERSION = 3

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
