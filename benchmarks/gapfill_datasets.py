"""The clips gap filling is measured on, and the conditions it is measured under.

Real data (``../shared/data``, skipped when absent; held out of tuning but the DHG sample):

* ``dhg``: the DHG-14/28 sample (95 frames, ``dhg22``, camera-frame metres), projected
  orthographically at 1 px per mm (u = x, v = y) and by a pinhole of 500 px focal length
  through the capture's own depths;
* ``mediapipe``: MediaPipe Hands' image landmarks of two hands over 64 frames (a real
  detector's output, ``mediapipe21``), in a 1280 x 720 image; the truth is what the
  detector reported;
* ``glove``: a Qualisys glove recording (6000 frames at 100 Hz, taken every third frame:
  2000 frames at 33 Hz, cut into five 400-frame clips), its 13 hand markers named as the
  joints they sit nearest (:data:`GLOVE_SKELETON`), seen from above orthographically at
  1 px per mm and by a 500 px pinhole 400 mm above the hand's highest point. Frames where
  Qualisys lost a marker are missing in the input and never scored.

Synthetic population clips (:func:`handdb.synthetic.synthesize_clip`, a new hand per seed),
the tuning set.

Conditions: a mask (``thesis-table-4.2`` on 100-frame clips, or 40 random interior gaps of
1-60 frames per 400 frames), Gaussian pixel noise of 0, 1 or 3 px on the input (the truth
stays clean) and, with noise, short dropouts (:data:`DROPOUT_SHARE` of the points in runs of
1-3 frames, missing in the input but not scored).

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/gapfill_datasets.py [--noise PX]
[--seeds N] [--synthetic-seeds N] [--datasets dhg,mediapipe,glove,synthetic] [--raw]``: per dataset
and projection (real first), the default's RMSE beside the best thesis method's, their
ratio and whether it meets the 5x target (figures in ``RESULTS-gapfill.md``).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from handdb.gapfill import METHODS, THESIS, fill_gaps, method_names  # noqa: E402
from handdb.gapfill.evaluate import RANDOM_GAPS_PER_FRAMES, RANDOM_MASK, THESIS_MASK  # noqa: E402
from handdb.gapfill.masks import (  # noqa: E402
    RANDOM_GAPS,
    THESIS_CLIP_FRAMES,
    random_gaps_mask,
    thesis_table_4_2_mask,
)
from handdb.hand.skeletons import Skeleton, load_skeleton  # noqa: E402
from handdb.synthetic.clips import synthesize_clip  # noqa: E402
from tests.support import real_data  # noqa: E402
from tests.support.paths import DHG_SAMPLE, REAL_TOOLS  # noqa: E402

DHG = DHG_SAMPLE
MEDIAPIPE = REAL_TOOLS / "mediapipe" / "hand_landmarks.csv"
GLOVE = REAL_TOOLS / "qualisys-glove" / "recording.tsv"

#: Pinhole focal length (pixels) and image centre of the projections of 3D captures.
FOCAL_PX = 500.0
CENTRE_PX = (960.0, 540.0)
#: The MediaPipe landmarks' image, pixels (the CSV keeps normalised coordinates only).
MEDIAPIPE_IMAGE = (1280.0, 720.0)
#: Every third glove frame (100 Hz to 33 Hz), in clips of this many frames.
GLOVE_STEP = 3
GLOVE_CLIP_FRAMES = 400
#: Height of the glove's pinhole above the hand's highest point, mm.
GLOVE_CAMERA_MM = 400.0
#: Short dropouts with noise: share of the points, and their run lengths (frames).
DROPOUT_SHARE = 0.02
DROPOUT_FRAMES = (1, 3)
NOISES_PX = (0.0, 1.0, 3.0)
MASKS = (THESIS_MASK, RANDOM_MASK)
PROJECTIONS = ("orthographic", "pinhole")

#: The glove's hand markers: (marker, joint it is named as, that joint's parent, finger,
#: role). The finger markers sit on the middle phalanges (29-39 mm from the tips).
GLOVE_MARKERS = (
    ("hand_top", "wrist", None, "palm", "wrist"),
    ("hand_left", "index_mcp", "wrist", "index", "mcp"),
    ("hand_right", "little_mcp", "wrist", "little", "mcp"),
    ("thumb_middle", "thumb_ip", "wrist", "thumb", "ip"),
    ("thumb_tip", "thumb_tip", "thumb_ip", "thumb", "tip"),
    ("index_middle", "index_dip", "index_mcp", "index", "dip"),
    ("index_tip", "index_tip", "index_dip", "index", "tip"),
    ("middle_middle", "middle_dip", "wrist", "middle", "dip"),
    ("middle_tip", "middle_tip", "middle_dip", "middle", "tip"),
    ("ring_middle", "ring_dip", "wrist", "ring", "dip"),
    ("ring_tip", "ring_tip", "ring_dip", "ring", "tip"),
    ("little_middle", "little_dip", "little_mcp", "little", "dip"),
    ("little_tip", "little_tip", "little_dip", "little", "tip"),
)


def glove_skeleton() -> Skeleton:
    """The skeleton of the glove's 13 hand markers (see :data:`GLOVE_MARKERS`)."""
    joints = tuple(joint for _, joint, _, _, _ in GLOVE_MARKERS)
    parents = np.array([-1 if parent is None else joints.index(parent)
                        for _, _, parent, _, _ in GLOVE_MARKERS], dtype=np.int64)
    parents.flags.writeable = False
    return Skeleton(name="glove13", joints=joints, parents=parents,
                    fingers=tuple(f for *_, f, _ in GLOVE_MARKERS),
                    roles=tuple(r for *_, r in GLOVE_MARKERS),
                    ids=tuple(range(len(joints))),
                    source_names=tuple(m for m, *_ in GLOVE_MARKERS))


@dataclass(frozen=True)
class Case:
    """One clip to score: clean image points, which of them exist, and where they come from.

    Attributes
    ----------
    dataset
        ``dhg``, ``mediapipe``, ``glove`` or ``synthetic``.
    projection
        ``orthographic``, ``pinhole`` or ``detector`` (MediaPipe's own image points).
    clip
        Names the clip within its dataset.
    uv
        ``(T, J, 2) float64``, pixels: the truth, NaN where the capture has no point.
    skeleton
        The clip's skeleton.
    held_out
        Never used to choose the method or its constants.
    """

    dataset: str
    projection: str
    clip: str
    uv: np.ndarray
    skeleton: Skeleton
    held_out: bool


def _pinhole(xyz: np.ndarray) -> np.ndarray:
    """Camera-frame points ``(..., 3)`` mm to pixels ``(..., 2)``."""
    return FOCAL_PX * xyz[..., :2] / xyz[..., 2:3] + np.asarray(CENTRE_PX)


def dhg_cases() -> list[Case]:
    """The DHG sample, orthographic and pinhole (empty when the data is absent)."""
    if not DHG.is_file():
        return []
    capture = real_data.load_dhg(DHG)
    xyz, skeleton = capture.xyz, load_skeleton(capture.skeleton)
    return [Case("dhg", "orthographic", "dhg", xyz[..., :2].copy(), skeleton, False),
            Case("dhg", "pinhole", "dhg", _pinhole(xyz), skeleton, False)]


def mediapipe_cases() -> list[Case]:
    """The MediaPipe CSV's two hands, one case each (empty when the data is absent)."""
    if not MEDIAPIPE.is_file():
        return []
    rows = np.loadtxt(MEDIAPIPE, delimiter=",", skiprows=1)
    frame, hand, landmark = (rows[:, k].astype(np.int64) for k in range(3))
    uv = np.full((frame.max() + 1, hand.max() + 1, landmark.max() + 1, 2), np.nan)
    uv[frame, hand, landmark] = rows[:, 3:5] * np.asarray(MEDIAPIPE_IMAGE)
    skeleton = load_skeleton("mediapipe21")
    return [Case("mediapipe", "detector", f"hand{h}", uv[:, h].copy(), skeleton, True)
            for h in range(uv.shape[1])]


def glove_markers() -> np.ndarray:
    """The glove's hand markers, ``(T, 13, 3)`` mm, NaN where lost."""
    with GLOVE.open() as fh:
        header = {}
        for line in fh:
            key, *values = line.rstrip("\n").split("\t")
            header[key] = values
            if key == "MARKER_NAMES":
                break
        names = header["MARKER_NAMES"]
        columns = [2 + 3 * names.index(marker) + axis for marker, *_ in GLOVE_MARKERS
                   for axis in range(3)]
        table = np.genfromtxt(fh, delimiter="\t", skip_header=1, usecols=columns,
                              missing_values=("", "NULL", "nan"), filling_values=np.nan)
    return table.reshape(len(table), len(GLOVE_MARKERS), 3)


def glove_cases() -> list[Case]:
    """The glove's 400-frame clips, orthographic and pinhole (empty when absent)."""
    if not GLOVE.is_file():
        return []
    xyz = glove_markers()[::GLOVE_STEP]
    skeleton = glove_skeleton()
    # Seen from above: image x, y along the lab's x and -y; depth down from the camera.
    camera = np.stack([xyz[..., 0], -xyz[..., 1],
                       np.nanmax(xyz[..., 2]) + GLOVE_CAMERA_MM - xyz[..., 2]], axis=-1)
    cases = []
    for start in range(0, len(xyz) - GLOVE_CLIP_FRAMES + 1, GLOVE_CLIP_FRAMES):
        part = camera[start:start + GLOVE_CLIP_FRAMES]
        name = f"glove{start // GLOVE_CLIP_FRAMES}"
        cases += [Case("glove", "orthographic", name, part[..., :2].copy(), skeleton, True),
                  Case("glove", "pinhole", name, _pinhole(part), skeleton, True)]
    return cases


def synthetic_cases(seeds: Iterable[int], n_frames: int = 400,
                    motions: Sequence[str] = ("rapid", "wave", "clench", "random"),
                    skeleton: str = "mediapipe21") -> list[Case]:
    """Synthetic clips of a hand population: every motion, seed and projection."""
    cases = []
    for seed in seeds:
        for motion in motions:
            for projection in PROJECTIONS:
                clip = synthesize_clip(motion, n_frames, seed=seed, camera=projection,
                                       skeleton=skeleton)
                cases.append(Case("synthetic", projection, f"{motion}-{seed}", clip.uv,
                                  load_skeleton(skeleton), False))
    return cases


def real_cases() -> list[Case]:
    """Every real case whose data is present."""
    return [*dhg_cases(), *mediapipe_cases(), *glove_cases()]


def dropouts(n_frames: int, n_joints: int, rng: np.random.Generator) -> np.ndarray:
    """Short dropouts: ``(T, J) bool``, about :data:`DROPOUT_SHARE` of the points."""
    shortest, longest = DROPOUT_FRAMES
    n_runs = round(DROPOUT_SHARE * n_frames * n_joints / np.mean(DROPOUT_FRAMES))
    length = rng.integers(shortest, longest + 1, size=n_runs)
    start = rng.integers(0, max(n_frames - longest, 1), size=n_runs)
    joint = rng.integers(0, n_joints, size=n_runs)
    hidden = np.zeros((n_frames, n_joints), dtype=bool)
    for j, a, n in zip(joint, start, length, strict=True):
        hidden[a:a + n, j] = True
    return hidden


def segments(mask: str, n_frames: int, skeleton: Skeleton, seed: int
             ) -> list[tuple[slice, np.ndarray]]:
    """The frame ranges filled on their own under ``mask``, with the points it hides."""
    if mask == THESIS_MASK:
        pattern = thesis_table_4_2_mask(skeleton)
        starts = range(0, max(n_frames - THESIS_CLIP_FRAMES + 1, 1), THESIS_CLIP_FRAMES)
        return [(slice(s, s + THESIS_CLIP_FRAMES), pattern[:n_frames - s]) for s in starts]
    n_gaps = max(1, round(RANDOM_GAPS * n_frames / RANDOM_GAPS_PER_FRAMES))
    return [(slice(0, n_frames), random_gaps_mask(n_frames, skeleton.n_joints,
                                                  n_gaps=n_gaps, seed=seed))]


@dataclass(frozen=True)
class Scores:
    """Squared errors summed over the scored points, and their count, per method."""

    squares: dict[str, float]
    count: int

    def rmse(self, method: str) -> float:
        """RMSE of ``method``, pixels."""
        return float(np.sqrt(self.squares[method] / self.count)) if self.count else np.nan

    def __add__(self, other: Scores) -> Scores:
        return Scores({m: s + other.squares[m] for m, s in self.squares.items()},
                      self.count + other.count)


def score(case: Case, mask: str, noise_px: float, methods: Sequence[str], seed: int = 0,
          **params: object) -> Scores:
    """Hide ``case``'s points under ``mask`` (with noise and dropouts) and score ``methods``.

    ``params`` go to the default method only. Scored: the hidden points the capture has.
    """
    rng = np.random.default_rng(seed)
    exists = np.isfinite(case.uv).all(axis=-1)
    noisy = case.uv + rng.normal(0.0, noise_px, case.uv.shape) if noise_px else case.uv
    extra = (dropouts(*exists.shape, rng) if noise_px
             else np.zeros(exists.shape, dtype=bool))
    squares = dict.fromkeys(methods, 0.0)
    count = 0
    for frames, hidden in segments(mask, len(case.uv), case.skeleton, seed):
        truth = case.uv[frames]
        scored = hidden & exists[frames]
        observed = exists[frames] & ~hidden & ~extra[frames]
        count += int(scored.sum())
        for method in methods:
            kwargs = params if method == "auto" else {}
            filled = fill_gaps(noisy[frames], observed, case.skeleton, method, **kwargs).uv
            squares[method] += float(np.sum((filled - truth)[scored] ** 2))
    return Scores(squares, count)


def thesis_methods() -> tuple[str, ...]:
    """The thesis's five methods."""
    return method_names(THESIS)


def best_thesis(scores: Scores) -> tuple[str, float]:
    """The thesis method with the lowest RMSE, and that RMSE."""
    best = min(thesis_methods(), key=scores.rmse)
    return best, scores.rmse(best)


def table(cases: Sequence[Case], noise_px: float, seeds: Sequence[int],
          **params: object) -> list[tuple[str, str, str, Scores]]:
    """Scores of the default and the thesis methods, pooled per dataset and projection."""
    methods = ("auto", *thesis_methods())
    rows = []
    groups = dict.fromkeys((c.dataset, c.projection) for c in cases)
    for dataset, projection in groups:
        chosen = [c for c in cases if (c.dataset, c.projection) == (dataset, projection)]
        for mask in MASKS:
            total = None
            # Without noise the Table 4.2 mask is the same for every seed.
            mask_seeds = seeds if mask == RANDOM_MASK or noise_px else seeds[:1]
            for case in chosen:
                for seed in mask_seeds:
                    scores = score(case, mask, noise_px, methods, seed=seed, **params)
                    total = scores if total is None else total + scores
            rows.append((dataset, projection, mask, total))
    return rows


def main() -> None:
    """Print the default against the best thesis method per dataset, projection and mask."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--noise", type=float, default=0.0, help="input noise, pixels")
    parser.add_argument("--seeds", type=int, default=4, help="mask seeds per real clip")
    parser.add_argument("--synthetic-seeds", type=int, default=2,
                        help="synthetic hands (each in every motion and projection)")
    parser.add_argument("--datasets", default="dhg,mediapipe,glove,synthetic")
    parser.add_argument("--raw", action="store_true",
                        help="the default fills from the tracks as observed (smooth=False)")
    args = parser.parse_args()
    wanted = args.datasets.split(",")
    cases = [c for c in real_cases() if c.dataset in wanted]
    if "synthetic" in wanted:
        cases += synthetic_cases(range(args.synthetic_seeds))
    started = time.process_time()
    unsmoothed = "; auto unsmoothed" if args.raw else ""
    print(f"noise {args.noise:g} px{unsmoothed}; RMSE over the hidden points, pixels")
    print(f"{'dataset':10s} {'projection':12s} {'held out':8s} {'mask':17s} {'points':>7s} "
          f"{'auto':>8s} {'best thesis':>24s} {'ratio':>6s} {'5x':>3s}")
    held = {c.dataset: c.held_out for c in cases}
    params = {"smooth": False} if args.raw else {}
    for dataset, projection, mask, scores in table(cases, args.noise, range(args.seeds),
                                                   **params):
        best, best_rmse = best_thesis(scores)
        ratio = best_rmse / scores.rmse("auto")
        print(f"{dataset:10s} {projection:12s} {'yes' if held[dataset] else 'no':8s} "
              f"{mask:17s} {scores.count:7d} {scores.rmse('auto'):8.2f} "
              f"{best:>16s} {best_rmse:7.2f} {ratio:6.2f} {'met' if ratio >= 5 else 'no':>3s}")
    print(f"{time.process_time() - started:.0f} CPU seconds")


__all__ = ["Case", "MASKS", "METHODS", "NOISES_PX", "Scores", "best_thesis", "dhg_cases",
           "glove_cases", "glove_markers", "glove_skeleton", "mediapipe_cases", "real_cases",
           "score", "synthetic_cases", "table"]


if __name__ == "__main__":
    main()
