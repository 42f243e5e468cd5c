"""The default method on real hands and on the synthetic population, against the thesis.

Real captures: DHG in its own view (orthographic and pinhole, as
``test_real_capture.py``) and the InterHand2.6M hands turned to fixed views, as single
frames and as rigid pseudo-clips (:mod:`tests.support.real_data`). Every real capture
skips cleanly when ``../shared/data`` is absent.
"""

import numpy as np
import pytest

from handdb.clip import Camera
from handdb.hand.skeletons import bone_length_array, frame_bone_lengths, load_skeleton
from handdb.lifting import lift
from handdb.lifting.geometry import accumulate_depths, projected_lengths
from handdb.synthetic.clips import synthesize_clip
from tests.support import real_data
from tests.unit.lifting.conftest import ORTHOGRAPHIC

#: Fixed views of the InterHand hands: this many rotations uniform over SO(3), seed 0, at
#: the middle of :data:`tests.support.real_data.DISTANCE_MM`.
N_VIEWS, VIEW_SEED, VIEW_DISTANCE_MM = 8, 0, 500.0

#: Issue 4's targets: mean root-relative |dZ| (mm) and bone-sign accuracy orthographically,
#: |dZ| through a pinhole.
TARGET_DZ_MM, TARGET_SIGN_ACCURACY, TARGET_PINHOLE_DZ_MM = 5.0, 0.95, 10.0

#: Least share of InterHand pseudo-clip frames whose thumb base the default puts on the
#: right side of the wrist, per camera (the thesis gets about half).
THUMB_BASE_ACCURACY = {"orthographic": 0.9, "pinhole": 0.8}


def dhg_view(dhg_mm, camera_model):
    """The DHG capture in its own frame as the camera frame, 1 pixel per mm or f = 500."""
    if camera_model == "orthographic":
        return dhg_mm[..., :2], ORTHOGRAPHIC
    uv = dhg_mm[..., :2] / dhg_mm[..., 2:] * real_data.FOCAL_PX + real_data.PRINCIPAL_POINT
    return uv, Camera("pinhole", real_data.FOCAL_PX, real_data.FOCAL_PX,
                      *real_data.PRINCIPAL_POINT)


def interhand_views(real_tools, pseudo: bool):
    """``(capture, camera-frame truth)`` for every InterHand hand in every fixed view."""
    captures = real_data.load_interhand(real_tools / "interhand"
                                        / "test_interhand2.6m_joint_3d.json")
    assert len(captures) >= 4
    for view, rotation in enumerate(real_data.view_rotations(N_VIEWS, VIEW_SEED)):
        for capture in captures:
            xyz = capture.xyz
            if pseudo:
                xyz = real_data.pseudo_clip(xyz[0], np.random.default_rng([VIEW_SEED, view]))
            yield capture, real_data.camera_view(xyz, rotation, VIEW_DISTANCE_MM)


def pooled_errors(cases, camera_model, methods=("kinematic", "thesis")):
    """Every method's errors pooled over ``(capture, truth)`` cases, by method."""
    errors = {}
    for capture, truth in cases:
        skeleton = load_skeleton(capture.skeleton)
        lengths = real_data.median_bone_lengths(capture.xyz, skeleton)
        uv, camera = real_data.project(truth, camera_model)
        for method in methods:
            result = lift(uv, skeleton, lengths, camera, method=method, hand=capture.hand)
            errors.setdefault(method, real_data.Errors(skeleton)).add(truth, result.xyz)
    return errors


@pytest.fixture(scope="module", params=["orthographic", "pinhole"])
def dhg_errors(request, dhg_mm):
    uv, camera = dhg_view(dhg_mm, request.param)
    skeleton = load_skeleton("dhg22")
    lengths = real_data.median_bone_lengths(dhg_mm, skeleton)
    errors = {}
    for method in ("kinematic", "thesis"):
        errors[method] = real_data.Errors(skeleton)
        errors[method].add(dhg_mm, lift(uv, skeleton, lengths, camera, method=method,
                                        hand="right").xyz)
    return request.param, errors


@pytest.fixture(scope="module", params=[(camera, pseudo) for camera in ("orthographic",
                                                                        "pinhole")
                                        for pseudo in (False, True)],
                ids=lambda p: f"{p[0]}-{'pseudo-clips' if p[1] else 'single-frames'}")
def interhand_errors(request, real_tools):
    camera, pseudo = request.param
    return request.param, pooled_errors(interhand_views(real_tools, pseudo), camera)


def losing_bones(errors):
    ours, thesis = errors["kinematic"].bone_signs(), errors["thesis"].bone_signs()
    return {bone: (round(ours[bone], 3), round(thesis[bone], 3)) for bone in thesis
            if ours[bone] < thesis[bone]}


def test_the_default_beats_the_thesis_on_depth_on_dhg(dhg_errors):
    _, errors = dhg_errors
    assert errors["kinematic"].summary()["all"]["dz"] < errors["thesis"].summary()["all"]["dz"]


#: Why the default loses bones to the thesis on DHG in its own view (figures in
#: benchmarks/RESULTS-real.md).
DHG_SHORTFALL = {
    "orthographic": "DHG's tracker bones vary by up to 15 mm; facing the camera as the thesis "
                    "assumes, its distal bones come out in the image plane (a clamped depth, "
                    "counted as a wrong sign) more often at the template's scale than at "
                    "eq. 6's (156 clamped signs against 75), and lose to it on three bones; "
                    "the little middle phalanx is flipped instead (38 frames against 28), "
                    "where the tracker flexes the little MCP or PIP past its range of motion",
    "pinhole": "the per-frame plane fit flips DHG's non-rigid palm centre behind the wrist "
               "in 2 of 95 frames (wrist->palm 97.9 against 100 %)",
}


def test_the_default_is_as_good_as_the_thesis_on_every_dhg_bone(dhg_errors, request):
    camera, errors = dhg_errors
    request.applymarker(pytest.mark.xfail(strict=True, reason=DHG_SHORTFALL[camera]))
    assert losing_bones(errors) == {}


def test_the_default_s_signs_meet_the_target_on_dhg_once_its_tracker_s_lengths_are_known(
        dhg_mm):
    """DHG in its own view misses the orthographic target through its tracker's lengths,
    not its signs: the default's depth signs, with each bone's span from its true length in
    that frame (eq. 5 at the view's scale, 1 px per mm), put it within the target
    (benchmarks/RESULTS-real.md, 2026-12-03)."""
    skeleton = load_skeleton("dhg22")
    lengths = real_data.median_bone_lengths(dhg_mm, skeleton)
    uv, camera = dhg_view(dhg_mm, "orthographic")
    lifted = lift(uv, skeleton, lengths, camera, method="kinematic", hand="right").xyz
    parents = np.where(skeleton.parents < 0, skeleton.root, skeleton.parents)
    sign = np.where(lifted[..., 2] < lifted[:, parents, 2], -1.0, 1.0)
    span = np.sqrt(np.clip(frame_bone_lengths(dhg_mm, skeleton) ** 2
                           - projected_lengths(uv, skeleton) ** 2, 0.0, None))
    span[:, skeleton.root] = 0.0
    relifted = np.concatenate([uv, accumulate_depths(sign * span, skeleton)[..., None]], axis=-1)
    errors = real_data.Errors(skeleton)
    errors.add(dhg_mm, relifted)
    assert errors.summary()["all"]["dz"] <= TARGET_DZ_MM


#: Noisy DHG: pixel noise and the seeds of its draws (those of
#: ``benchmarks/real_captures.py``, which reports the same case pooled).
DHG_NOISE_PX, DHG_NOISE_SEEDS = 3.0, (7, 8, 9, 10)


def test_the_default_beats_the_thesis_on_depth_on_every_noisy_dhg_draw(dhg_mm, request):
    """Each draw on its own: the default must not lose on a clip that a pooled figure hides."""
    request.applymarker(pytest.mark.xfail(strict=True, reason=(
        "on draw 7 the palm takes its other Necker pose in every frame (91.4 mm against the "
        "thesis's 57.2): the clip's summed finger anatomy prefers it, the thumb's by 850 "
        "nats. Choosing by the evidence over independent frames, or capping each finger's "
        "lead per frame, fixes this draw only through an artefact (the clip's thumb height "
        "estimated under a tilt the kept round leaves) and flips clips of DHG's random "
        "views at 2 px instead; with the height consistent the model prefers the mirror "
        "(docs/depth-reconstruction.md, Mirror ambiguity)")))
    skeleton = load_skeleton("dhg22")
    lengths = real_data.median_bone_lengths(dhg_mm, skeleton)
    clean, camera = dhg_view(dhg_mm, "orthographic")
    losing = {}
    for seed in DHG_NOISE_SEEDS:
        rng = np.random.default_rng([seed, int(round(10 * DHG_NOISE_PX))])
        uv = clean + rng.normal(scale=DHG_NOISE_PX, size=clean.shape)
        dz = {}
        for method in ("kinematic", "thesis"):
            errors = real_data.Errors(skeleton)
            errors.add(dhg_mm, lift(uv, skeleton, lengths, camera, method=method,
                                    hand="right").xyz)
            dz[method] = round(errors.summary()["all"]["dz"], 1)
        if dz["kinematic"] > dz["thesis"]:
            losing[seed] = dz
    assert losing == {}


def test_a_dhg_draw_lifted_in_its_other_necker_pose_is_flagged(dhg_mm):
    """Nothing unsure is stored as settled: a clip whose depths are nearer the truth
    mirrored (every root-relative depth negated) than as lifted must say its mirror is
    ambiguous."""
    skeleton = load_skeleton("dhg22")
    lengths = real_data.median_bone_lengths(dhg_mm, skeleton)
    clean, camera = dhg_view(dhg_mm, "orthographic")
    truth = dhg_mm[..., 2] - dhg_mm[:, skeleton.root, None, 2]
    unflagged = []
    for noise_px in (2.0, 3.0, 4.0):
        for seed in DHG_NOISE_SEEDS:
            rng = np.random.default_rng([seed, int(round(10 * noise_px))])
            uv = clean + rng.normal(scale=noise_px, size=clean.shape)
            result = lift(uv, skeleton, lengths, camera, method="kinematic", hand="right")
            depth = result.xyz[..., 2] - result.xyz[:, skeleton.root, None, 2]
            flipped = np.mean(np.abs(depth - truth)) > np.mean(np.abs(depth + truth))
            if flipped and not result.mirror_ambiguous:
                unflagged.append((noise_px, seed))
    assert unflagged == []


def test_the_default_beats_the_thesis_on_depth_on_interhand(interhand_errors):
    _, errors = interhand_errors
    assert errors["kinematic"].summary()["all"]["dz"] < errors["thesis"].summary()["all"]["dz"]


def test_the_default_is_as_good_as_the_thesis_on_every_interhand_bone(interhand_errors):
    _, errors = interhand_errors
    assert losing_bones(errors) == {}


@pytest.mark.parametrize("camera", ["orthographic", "pinhole"])
def test_the_thumb_base_sign_is_recovered_on_interhand_pseudo_clips(real_tools, camera):
    errors = pooled_errors(interhand_views(real_tools, pseudo=True), camera)
    ours = errors["kinematic"].bone_signs()["wrist->thumb_cmc"]
    assert ours >= THUMB_BASE_ACCURACY[camera]
    assert ours > errors["thesis"].bone_signs()["wrist->thumb_cmc"]


def population_clip(motion, camera, seed, hand):
    clip = synthesize_clip(motion, 300, camera=camera, seed=seed, hand=hand)
    skeleton = load_skeleton(clip.skeleton)
    cam = Camera(**clip.camera) if camera == "pinhole" else ORTHOGRAPHIC
    result = lift(clip.uv, skeleton, bone_length_array(skeleton, clip.bone_lengths), cam,
                  hand=hand)
    errors = real_data.Errors(skeleton)
    errors.add(clip.xyz, result.xyz)
    return errors.summary(), result


@pytest.mark.parametrize("hand", ["right", "left"])
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("motion", ["rapid", "random"])
def test_hands_of_the_population_meet_the_orthographic_targets(motion, seed, hand):
    summary, _ = population_clip(motion, "orthographic", seed, hand)
    assert summary["all"]["dz"] <= TARGET_DZ_MM
    assert summary["all"]["sign"] >= TARGET_SIGN_ACCURACY


#: Clean population clips whose chirality only the palm's arch tells, weakly.
WEAK_CHIRALITY = {("rapid", 0), ("random", 0)}


@pytest.mark.parametrize("hand", ["right", "left"])
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("motion", ["rapid", "random"])
def test_the_population_s_mirror_is_settled(motion, seed, hand, request):
    if (motion, seed) in WEAK_CHIRALITY:
        request.applymarker(pytest.mark.xfail(strict=True, reason=(
            "the template's two chiralities score the fingers alike; the palm's fit prefers "
            "the right one by 3-4 nats summed over 300 frames, under 1 nat over the clip's "
            "independent frames: flagged as unsure, though the pose chosen is right")))
    _, result = population_clip(motion, "orthographic", seed, hand)
    assert not result.mirror_ambiguous


@pytest.mark.parametrize("hand", ["right", "left"])
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("motion", ["rapid", "random"])
def test_hands_of_the_population_meet_the_pinhole_target(motion, seed, hand):
    summary, _ = population_clip(motion, "pinhole", seed, hand)
    assert summary["all"]["dz"] <= TARGET_PINHOLE_DZ_MM
