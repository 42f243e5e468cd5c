import numpy as np
import pytest

from handdb.hand.layout import hand_layout
from handdb.lifting.finger_geometry import FingerCandidates, anchor_joints
from handdb.lifting.hand_prior import score_fingers, score_mirrored_fingers


def _mirror_candidates(xy, abs_dz, palm_z, skeleton, layout):
    """Orthographic candidates with both palm states written out: ``palm_z``, ``-palm_z``."""
    anchors = anchor_joints(layout)
    points = np.stack([np.broadcast_to(xy[:, None, anchors, 0], (len(xy), 2, len(anchors))),
                       np.broadcast_to(xy[:, None, anchors, 1], (len(xy), 2, len(anchors))),
                       np.stack([palm_z, -palm_z], axis=1)[:, :, anchors]], axis=-1)
    chains = layout.chains
    planar = xy[:, chains] - xy[:, skeleton.parents[chains]]             # (T, F, 3, 2)
    depth = abs_dz[:, chains]
    bones = np.concatenate([np.stack([planar, planar], axis=3),
                            np.stack([depth, -depth], axis=3)[..., None]],
                           axis=-1)[:, None]                             # (T, 1, F, 3, 2, 3)
    return FingerCandidates(anchors=points, bones=(bones[:, :, :, 0, :, None, None],
                                                   bones[:, :, :, 1, None, :, None],
                                                   bones[:, :, :, 2, None, None, :]))


@pytest.mark.parametrize("hand", ["right", "left"])
def test_mirrored_scores_equal_the_written_out_mirror_bit_for_bit(rapid_clip, hand):
    clip, skeleton, lengths = rapid_clip
    layout = hand_layout(skeleton)
    rng = np.random.default_rng(0)
    xy = clip.xyz[..., :2] / 10.0
    xy[rng.random(xy.shape[:2]) < 0.02] = np.nan
    abs_dz = np.abs(clip.xyz[..., 2] - clip.xyz[:, skeleton.parents.clip(0), 2])
    palm_z = clip.xyz[..., 2] - clip.xyz[:, skeleton.root, None, 2]
    got = score_mirrored_fingers(xy, abs_dz, palm_z, lengths, layout, hand)
    want = score_fingers(_mirror_candidates(xy, abs_dz, palm_z, skeleton, layout), lengths,
                         layout, hand)
    for name in ("anatomy", "evidence", "bone_log_odds", "best"):
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name))
