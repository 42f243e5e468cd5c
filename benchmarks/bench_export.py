"""Export speed for a long clip: joint rotations, USD (crate and text), BVH, mesh skinning.

Synthesises a ``rapid`` clip of the project's synthetic hand, exports it to a temporary
folder and prints frames per second of each step.

Run: ``.venv/bin/python benchmarks/bench_export.py [n_frames]`` (default 20 000).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's handdb, before any installed copy

from handdb.export.bvh import export_clip_bvh  # noqa: E402
from handdb.export.mesh import hand_mesh, posed_vertices  # noqa: E402
from handdb.export.rotations import joint_rotations  # noqa: E402
from handdb.export.usd import export_clip_usd  # noqa: E402
from handdb.hand.skeletons import bone_length_array, load_skeleton  # noqa: E402
from handdb.synthetic import synthesize_clip  # noqa: E402

SKINNED_FRAMES = 1000


def timed(label: str, n_frames: int, run) -> None:
    """Print wall and CPU time of ``run()``; frames/s is by CPU time (the machine is shared)."""
    start, start_cpu = time.perf_counter(), time.process_time()
    result = run()
    wall, cpu = time.perf_counter() - start, time.process_time() - start_cpu
    size = f" {Path(result).stat().st_size / 1e6:6.1f} MB" if isinstance(result, Path) else ""
    print(f"{label:<26} {n_frames:>6d} frames  wall {wall:6.2f} s  cpu {cpu:6.2f} s "
          f"{n_frames / cpu:8.0f} frames/s{size}")


def main(n_frames: int) -> None:
    clip = synthesize_clip("rapid", n_frames, seed=0)
    skeleton = load_skeleton(clip.skeleton)
    lengths = bone_length_array(skeleton, clip.bone_lengths)
    common = dict(skeleton=skeleton, xyz=clip.xyz, bone_lengths=lengths, fps=clip.fps)
    usd = dict(common, clip_id="bench", units=clip.units, hand=clip.hand)
    mesh = hand_mesh(skeleton, lengths)
    print(f"{skeleton.name}, {skeleton.n_joints} joints, mesh {len(mesh.faces)} faces")
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        timed("joint_rotations", n_frames, lambda: joint_rotations(clip.xyz, skeleton, lengths))
        timed("export_clip_usd .usdc", n_frames, lambda: export_clip_usd(out / "c.usdc", **usd))
        timed("export_clip_usd .usda", n_frames, lambda: export_clip_usd(out / "c.usda", **usd))
        timed("export_clip_usd .usdz", n_frames, lambda: export_clip_usd(out / "c.usdz", **usd))
        timed("export_clip_bvh", n_frames, lambda: export_clip_bvh(out / "c.bvh", **common,
                                                                 units=clip.units))
        frames = min(n_frames, SKINNED_FRAMES)
        timed("posed_vertices (skinning)", frames,
              lambda: posed_vertices(mesh, clip.xyz[:frames], skeleton, lengths))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 20_000)
