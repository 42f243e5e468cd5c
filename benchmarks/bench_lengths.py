"""Bone lengths from partial knowledge: the default against the thesis's reference frame.

For each dataset, each scenario of what the user knows (the five proximal phalanges, the
middle finger's proximal phalanx alone, nothing) and pixel noise of 0 and 2 px, prints the
mean absolute error of the bones not given (mm), the same for the thesis's reference hand
(one frame assumed flat, :func:`handdb.lengths.estimate.reference_frame_lengths`), the
worst relative error, the share of bones whose error lies within two of the
uncertainties the default reports, and the median of those uncertainties (mm).

Datasets, all seen through a pinhole camera (500 px focal length):

* ``synthetic``: hands of the population (:mod:`handdb.hand.population`), four motions,
  six seeds, 300 frames; and the same hands in clips that show less: the first
  :data:`SHORT_FRAMES` frames, one pose held for the whole clip (its middle frame), and
  every joint jittered in 3D by :data:`JITTER_MM` per frame, so that the bones change
  length from frame to frame as a tracker's do (the truth is then each bone's median
  length, as for DHG);
* ``DHG``: the real DHG sample (``../shared/data/dhg-sample``, a depth tracker's joints,
  95 frames), eight random views at 400 mm, its median bone lengths the truth;
* ``InterHand``: the bone lengths of the real InterHand2.6M hands
  (``../shared/data/real-tools/interhand``, right hands) moved by synthetic motions.

The estimator was developed on the synthetic hands and on DHG; InterHand's hands were
held out.

Run: ``.venv/bin/python benchmarks/bench_lengths.py``.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's handdb, before any installed copy

from handdb.clip import Clip  # noqa: E402
from handdb.hand.model import build_hand_model  # noqa: E402
from handdb.hand.skeletons import Skeleton, frame_bone_lengths, load_skeleton  # noqa: E402
from handdb.ingest.sidecar import parse_sidecar  # noqa: E402
from handdb.lengths.bone_lengths import clip_bone_lengths  # noqa: E402
from handdb.lengths.estimate import reference_frame_lengths  # noqa: E402
from handdb.synthetic import make_motion, project_pinhole, render_clip, synthesize_clip  # noqa: E402

SHARED = REPO / ".." / "shared" / "data"
DHG = SHARED / "dhg-sample" / "skeletons_world.txt"
INTERHAND = SHARED / "real-tools" / "interhand" / "test_interhand2.6m_joint_3d.json"

#: InterHand2.6M's joint order per hand (tip to base per finger, then the wrist) as
#: mediapipe21's (wrist, then base to tip per finger).
INTERHAND_TO_MEDIAPIPE = np.array([20] + [f * 4 + k for f in range(5) for k in (3, 2, 1, 0)])

SCENARIOS = {
    "five": ("thumb_ip", "index_pip", "middle_pip", "ring_pip", "little_pip"),
    "one": ("middle_pip",),
    "none": (),
}
NOISE_PX = (0.0, 2.0)
FOCAL_PX, CENTRE_PX = 500.0, (960.0, 540.0)
CAMERA = {"model": "pinhole", "fx": FOCAL_PX, "fy": FOCAL_PX, "cx": CENTRE_PX[0],
          "cy": CENTRE_PX[1]}
SYNTHETIC_MOTIONS = ("rapid", "wave", "random", "clench")
SYNTHETIC_SEEDS = range(6)
N_FRAMES = 300
DHG_VIEWS, DHG_DISTANCE_MM = 8, 400.0
SHORT_FRAMES = 30
JITTER_MM = 3.0
INTERHAND_DISTANCE_MM = 350.0


def as_clip(uv: np.ndarray, skeleton: Skeleton, known: dict[str, float], folder: Path) -> Clip:
    sidecar = folder / "bench.clip.json"
    sidecar.write_text(json.dumps({
        "skeleton": skeleton.name, "hand": "right", "fps": 30, "subject": "s", "units": "mm",
        "camera": CAMERA, "bone_lengths": known}))
    return Clip(spec=parse_sidecar(sidecar), skeleton=skeleton, uv=uv,
                confidence=np.full(uv.shape[:2], np.nan), truth=None, source_format="bench",
                source_files=(str(sidecar),), content_hash="0" * 64)


def score(uv: np.ndarray, skeleton: Skeleton, truth: np.ndarray, folder: Path) -> dict:
    """Per scenario: (default error, reference-frame error, worst relative, coverage,
    median uncertainty)."""
    out = {}
    for name, joints in SCENARIOS.items():
        known = {j: float(truth[skeleton.index(j)]) for j in joints}
        result = clip_bone_lengths(as_clip(uv, skeleton, known, folder))
        unknown = [b for b in skeleton.bones[:, 1] if skeleton.joints[b] not in known]
        error = np.abs(result.lengths - truth)[unknown]
        reference = np.nan
        if joints:
            given = np.array([known.get(j, np.nan) for j in skeleton.joints])
            reference = np.nanmean(np.abs(reference_frame_lengths(uv, skeleton, given)
                                          - truth)[unknown])
        out[name] = (error.mean(), reference, (error / truth[unknown]).max(),
                     np.mean(error < 2.0 * result.uncertainty[unknown]),
                     np.median(result.uncertainty[unknown]))
    return out


def report(label: str, rows: list[dict]) -> None:
    for name in SCENARIOS:
        a = np.array([r[name] for r in rows])
        reference = f"{np.nanmean(a[:, 1]):6.2f}" if np.isfinite(a[:, 1]).any() else "     -"
        print(f"| {label} | {name} | {a[:, 0].mean():.2f} | {reference} | "
              f"{a[:, 2].max():.2f} | {a[:, 3].mean():.2f} | {np.median(a[:, 4]):.2f} |")


def median_lengths(xyz: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    return np.median(frame_bone_lengths(xyz, skeleton), axis=0)


def synthetic(noise: float, folder: Path) -> None:
    variants = {"": [], f", first {SHORT_FRAMES} frames": [], ", held pose": [],
                f", joints jittered {JITTER_MM:g} mm": []}
    for seed in SYNTHETIC_SEEDS:
        for motion in SYNTHETIC_MOTIONS:
            clip = synthesize_clip(motion, N_FRAMES, seed=seed, noise_px=noise,
                                   camera="pinhole")
            skeleton = load_skeleton(clip.skeleton)
            truth = np.array([clip.bone_lengths.get(j, np.nan) for j in skeleton.joints])
            rng = np.random.default_rng(seed)
            held = np.repeat(clip.xyz[N_FRAMES // 2][None], N_FRAMES, axis=0)
            jittered = clip.xyz + rng.normal(0.0, JITTER_MM, clip.xyz.shape)
            rows = iter(variants.values())
            next(rows).append(score(clip.uv, skeleton, truth, folder))
            next(rows).append(score(clip.uv[:SHORT_FRAMES], skeleton, truth, folder))
            for xyz, lengths in ((held, truth), (jittered, median_lengths(jittered, skeleton))):
                uv = project_pinhole(xyz, FOCAL_PX, FOCAL_PX, *CENTRE_PX)
                next(rows).append(score(uv + rng.normal(0.0, noise, uv.shape), skeleton,
                                        lengths, folder))
    for variant, rows in variants.items():
        report(f"synthetic{variant}, {noise:g} px", rows)


def dhg(noise: float, folder: Path) -> None:
    if not DHG.is_file():
        print(f"| DHG | absent: {DHG} | | | | | |")
        return
    xyz = np.loadtxt(DHG).reshape(-1, 22, 3) * 1000.0
    skeleton = load_skeleton("dhg22")
    truth = median_lengths(xyz, skeleton)
    rng = np.random.default_rng(0)
    rows = []
    for rotation in Rotation.random(DHG_VIEWS, random_state=0):
        camera = rotation.apply((xyz - xyz.reshape(-1, 3).mean(axis=0)).reshape(-1, 3))
        camera = camera.reshape(xyz.shape) + [0.0, 0.0, DHG_DISTANCE_MM]
        uv = project_pinhole(camera, FOCAL_PX, FOCAL_PX, *CENTRE_PX)
        uv = uv + rng.normal(0.0, noise, uv.shape)
        rows.append(score(uv, skeleton, truth, folder))
    report(f"DHG (real), {noise:g} px", rows)


def interhand(noise: float, folder: Path) -> None:
    if not INTERHAND.is_file():
        print(f"| InterHand | absent: {INTERHAND} | | | | | |")
        return
    skeleton = load_skeleton("mediapipe21")
    rows = []
    for capture in json.loads(INTERHAND.read_text()).values():
        for frame in capture.values():
            world = np.asarray(frame["world_coord"], dtype=float)[INTERHAND_TO_MEDIAPIPE]
            if not np.asarray(frame["joint_valid"], bool).ravel()[INTERHAND_TO_MEDIAPIPE].all():
                continue
            lengths = median_lengths(world[None], skeleton)
            model = build_hand_model("right", {skeleton.joints[j]: float(lengths[j])
                                               for j in skeleton.bones[:, 1]})
            for seed, motion in enumerate(SYNTHETIC_MOTIONS[:3]):
                clip = render_clip(model, make_motion(motion, N_FRAMES, 30.0, seed),
                                   camera="pinhole", distance=INTERHAND_DISTANCE_MM,
                                   noise_px=noise, seed=seed)
                truth = np.array([clip.bone_lengths.get(j, np.nan) for j in skeleton.joints])
                rows.append(score(clip.uv, skeleton, truth, folder))
    report(f"InterHand lengths (real, held out), {noise:g} px", rows)


def main() -> None:
    print("| dataset | known | default mm | reference frame mm | worst relative | "
          "within 2 sd | median sd mm |")
    print("|---|---|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as folder:
        for noise in NOISE_PX:
            for dataset in (dhg, interhand, synthetic):
                dataset(noise, Path(folder))


if __name__ == "__main__":
    main()
