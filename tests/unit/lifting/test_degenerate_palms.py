"""Degenerate palms (the wrist and knuckles collinear or at one point) give NaN where they
have no plane, never numpy's 0/0 ``RuntimeWarning`` (issue 15)."""

import warnings

import numpy as np
import pytest

from handdb.hand.layout import palm_normals, unit_vectors
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.lifting.palm_states import arch_heights, palm_parts
from handdb.synthetic import synthesize_clip
from handdb.validation.plausibility import assess, flexion_angles

MEDIAPIPE = load_skeleton("mediapipe21")
KNUCKLES = MEDIAPIPE.indices(["index_mcp", "middle_mcp", "ring_mcp", "little_mcp"])


def degenerate(xyz, kind):
    """``xyz`` with its knuckles at the middle one's place, or on the wrist's line to it."""
    out = xyz.copy()
    wrist, middle = out[:, [0]], out[:, [KNUCKLES[1]]]
    if kind == "coincident":
        out[:, KNUCKLES] = middle
    else:
        out[:, KNUCKLES] = wrist + (middle - wrist) * np.array([0.9, 1.0, 1.1, 1.2])[:, None]
    return out


@pytest.fixture(scope="module")
def clip():
    return synthesize_clip("random", 12, seed=1)


def test_a_zero_vector_has_no_direction():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        units = unit_vectors(np.array([[3.0, 4.0, 0.0], [0.0, 0.0, 0.0]]))
    np.testing.assert_allclose(units[0], [0.6, 0.8, 0.0])
    assert np.isnan(units[1]).all()


@pytest.mark.parametrize("kind", ["coincident", "collinear"])
def test_a_degenerate_palm_is_judged_without_runtime_warnings(clip, kind):
    xyz = degenerate(clip.xyz, kind)
    wrist, index, little = xyz[:, 0], xyz[:, KNUCKLES[0]], xyz[:, KNUCKLES[-1]]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        normals = palm_normals(wrist, index, little, clip.hand)
        angles = flexion_angles(MEDIAPIPE, xyz, clip.hand)
        verdict = assess(MEDIAPIPE, "mm", clip.hand,
                         bone_length_array(MEDIAPIPE, clip.bone_lengths), xyz)
    assert np.isnan(normals).all(), "no plane, no normal"
    assert np.isnan(angles[("index", "mcp", "flexion")]).all()
    assert verdict.rows.shape == (12, MEDIAPIPE.n_joints)


def test_the_palm_normal_points_to_the_palmar_side_of_either_hand(clip):
    wrist, index, little = (clip.xyz[:, j] for j in (0, KNUCKLES[0], KNUCKLES[-1]))
    right, left = (palm_normals(wrist, index, little, hand) for hand in ("right", "left"))
    np.testing.assert_allclose(np.linalg.norm(right, axis=-1), 1.0)
    np.testing.assert_allclose(left, -right)


@pytest.mark.parametrize("kind", ["coincident", "collinear"])
def test_arch_heights_of_a_degenerate_palm_are_nan(clip, kind):
    parts = palm_parts(MEDIAPIPE)
    palm = degenerate(clip.xyz, kind)[:, parts.joints]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        heights = arch_heights(palm, parts, "right", 80.0)
    assert np.isnan(heights).all()
    assert np.isfinite(arch_heights(clip.xyz[:, parts.joints], parts, "right", 80.0)).all()
