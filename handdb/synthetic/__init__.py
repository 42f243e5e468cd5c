"""Synthetic hands and motions with exact 3D ground truth.

>>> from handdb.synthetic import synthesize_clip
>>> clip = synthesize_clip("clench", 60, camera="pinhole", seed=1)
>>> clip.xyz.shape, clip.uv.shape
((60, 21, 3), (60, 21, 2))

Every seed draws another hand of the population (:mod:`handdb.hand.population`) and moves
it with the kinematic model (:mod:`handdb.hand.model`). Modules: :mod:`.hands` (which
hand), :mod:`.kinematics` (joint angles and the model's poses), :mod:`.motions` (clench,
rapid, wave, random), :mod:`.projection` (orthographic and pinhole cameras), :mod:`.clips`
(clips with truth).
"""

from handdb.synthetic.clips import (
    SyntheticClip,
    render_clip,
    synthesize_clip,
    thesis_clench_clip,
)
from handdb.synthetic.hands import make_hand, thesis_hand
from handdb.synthetic.kinematics import ANGLE_LIMITS, ANGLE_NAMES, local_positions, model_poses
from handdb.synthetic.motions import MOTIONS, Motion, make_motion
from handdb.synthetic.projection import project_orthographic, project_pinhole

__all__ = [
    "ANGLE_LIMITS", "ANGLE_NAMES", "MOTIONS", "Motion", "SyntheticClip", "local_positions",
    "make_hand", "make_motion", "model_poses", "project_orthographic", "project_pinhole",
    "render_clip", "synthesize_clip", "thesis_clench_clip", "thesis_hand",
]
