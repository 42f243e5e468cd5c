"""Synthetic hands and motions with exact 3D ground truth.

>>> from handdb.synthetic import synthesize_clip
>>> clip = synthesize_clip("clench", 60, camera="pinhole", seed=1)
>>> clip.xyz.shape, clip.uv.shape
((60, 21, 3), (60, 21, 2))

Modules: :mod:`.hand_model` (proportions, rest pose, the hand frame), :mod:`.kinematics`
(joint angles, limits, forward kinematics), :mod:`.motions` (clench, rapid, wave, random),
:mod:`.projection` (orthographic and pinhole cameras), :mod:`.clips` (clips with truth).
"""

from handdb.synthetic.clips import (
    SyntheticClip,
    render_clip,
    synthesize_clip,
    thesis_clench_clip,
)
from handdb.synthetic.hand_model import HandModel, HandProportions, make_hand, thesis_hand
from handdb.synthetic.kinematics import (
    ANGLE_LIMITS,
    ANGLE_NAMES,
    forward_kinematics,
    local_kinematics,
)
from handdb.synthetic.motions import MOTIONS, Motion, make_motion
from handdb.synthetic.projection import project_orthographic, project_pinhole

__all__ = [
    "ANGLE_LIMITS", "ANGLE_NAMES", "MOTIONS", "HandModel", "HandProportions", "Motion",
    "SyntheticClip", "forward_kinematics", "local_kinematics", "make_hand", "make_motion",
    "project_orthographic", "project_pinhole", "render_clip", "synthesize_clip",
    "thesis_clench_clip", "thesis_hand",
]
