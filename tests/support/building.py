"""Build a database as the command line does, on a chosen runner, for the tests."""

from __future__ import annotations

import json
from pathlib import Path

from handdb.build import BuildOptions, BuildSummary, run_build

#: Factor on every bone length that makes a clip no hand could produce (flagged by a build).
GIANT_FACTOR = 3.0


def run(inbox: str | Path, db: str, *, runner: str = "thread", workers: int = 2,
        address: str | None = None, **options) -> BuildSummary:
    """:func:`handdb.build.run_build` with ``options`` as keyword arguments of
    :class:`~handdb.build.BuildOptions` (``compare`` as any sequence)."""
    if "compare" in options:
        options["compare"] = tuple(options["compare"])
    return run_build(str(inbox), db, BuildOptions(**options), runner=runner, workers=workers,
                     address=address)


def build_demo_clips(root: Path, clip_ids: tuple[str, ...], options: BuildOptions
                     ) -> str:
    """Build a database of some of the demo's clips in this process, under ``root``.

    The demo inbox is written to ``root / "demo"``, the clips' files moved to
    ``root / "inbox"``, and the database built at ``root / "db"`` (returned) by
    :func:`handdb.build.build_in_process`; every clip must be processed.
    """
    from handdb.build import build_in_process
    from handdb.demo import write_demo_inbox

    demo, inbox = root / "demo", root / "inbox"
    write_demo_inbox(demo)
    inbox.mkdir()
    for clip_id in clip_ids:
        for path in demo.glob(f"{clip_id}.*"):
            path.rename(inbox / path.name)
    db = str(root / "db")
    summary = build_in_process(inbox, db, options)
    assert sorted(summary.processed) == sorted(clip_ids)
    return db


def scale_bones(inbox: Path, clip_id: str, factor: float) -> None:
    """Multiply every bone length in the sidecar of ``clip_id`` in ``inbox`` by ``factor``."""
    sidecar = inbox / f"{clip_id}.clip.json"
    doc = json.loads(sidecar.read_text())
    doc["bone_lengths"] = {bone: factor * length for bone, length in doc["bone_lengths"].items()}
    sidecar.write_text(json.dumps(doc))
