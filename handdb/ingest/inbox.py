"""Finding clips in the inbox and loading each into a :class:`~handdb.clip.Clip`.

:func:`discover` groups the inbox's entries by clip id: a clip is its sidecar
``<clip_id>.clip.json``, exactly one track file (any registered ``tracks`` format) and at
most one source of ground truth. Entries that cannot form a clip are refused with an
:class:`~handdb.errors.InputError` each; entries of other kinds (X-ray tables, marker
files) are handed over by format name; anything else is ignored. An entry is refused
when it is a symbolic link that leaves the inbox, is not a regular file (a folder where a
file belongs, a named pipe, a device), or names a clip whose id differs from another's
only in case; a clip with an entry refused so is refused by that entry alone.
:func:`load_clip` then reads one clip into dense arrays.
"""

from __future__ import annotations

import hashlib
import os
import stat
from collections import defaultdict
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from handdb.clip import Clip, ClipSpec, finite_points
from handdb.errors import InputError
from handdb.hand.skeletons import load_skeleton
from handdb.ingest.limits import (
    MAX_COORDINATE_METRES,
    MAX_PIXEL_COORDINATE,
    checked_size,
    file_kind,
    folder_files,
    quoted,
    visible,
)
from handdb.ingest.observations import Observations, Positions, check_joint_map_keys
from handdb.ingest.registry import (
    CLIP_KINDS,
    DATA_KINDS,
    MARKERS_KIND,
    SIDECAR_SUFFIX,
    InputFormat,
    get_format,
    match_format,
    registered_formats,
)
from handdb.ingest.sidecar import parse_sidecar, validate_clip_id

SIDECAR = "sidecar"

#: What to do with a file the tools write that no format reads, by its name's ending.
UNREAD_HINTS = {
    ".h5": "it is DeepLabCut's HDF5 table; handdb reads the CSV DeepLabCut writes beside it "
           "with save_as_csv=True, renamed {clip_id}.dlc.csv",
    ".csv": "name a CSV by its layout, {clip_id}.tracks.csv, .dlc.csv, .mediapipe.csv or "
            ".markers.csv",
    ".json": "name a JSON file by its tool, {clip_id}.mediapipe.json, .mediapipe-world.json "
             "or .interhand.json; OpenPose's files go in a folder {clip_id}.openpose",
    ".tsv": "a Qualisys export is read as {clip_id}.qtm.tsv",
    ".txt": "name a text export by its tool, {clip_id}.maya.txt or .dhg.txt",
}
#: Bytes read at a time when hashing an input file.
HASH_CHUNK_BYTES = 1 << 20


@dataclass(frozen=True)
class ClipEntry:
    """The inbox entries of one clip.

    Attributes
    ----------
    clip_id
        The clip's id, the common prefix of its file names.
    inbox
        The inbox folder (file names in the content hash are relative to it).
    sidecar
        ``<clip_id>.clip.json``.
    tracks
        The track file (or folder).
    track_format
        Name of the registered format of ``tracks``.
    truth
        The ground-truth file, or ``None``.
    truth_format
        Name of the registered format of ``truth``, or ``None``.
    """

    clip_id: str
    inbox: Path
    sidecar: Path
    tracks: Path
    track_format: str
    truth: Path | None = None
    truth_format: str | None = None

    @property
    def paths(self) -> tuple[Path, ...]:
        """The clip's inputs: sidecar, tracks, then truth if any."""
        return (self.sidecar, self.tracks) + ((self.truth,) if self.truth else ())


@dataclass(frozen=True)
class InboxScan:
    """What :func:`discover` found in an inbox.

    Attributes
    ----------
    clips
        One entry per complete clip, by clip id.
    refused
        One error per entry that cannot be read as part of a clip.
    others
        Inputs of other kinds by format name (``xray``, ``markers_csv``, ...).
    """

    clips: tuple[ClipEntry, ...]
    refused: tuple[InputError, ...]
    others: Mapping[str, tuple[Path, ...]] = field(default_factory=dict)


def _entries(inbox: Path) -> Iterator[tuple[str, str, str, Path]]:
    """Yield ``(kind, format name, clip id, path)`` for every recognised entry."""
    for path in sorted(inbox.iterdir()):
        if not visible(path.name):
            continue
        if path.name.endswith(SIDECAR_SUFFIX) and len(path.name) > len(SIDECAR_SUFFIX):
            yield SIDECAR, SIDECAR, path.name.removesuffix(SIDECAR_SUFFIX), path
        elif (match := match_format(path)) is not None:
            fmt, clip_id = match
            yield fmt.kind, fmt.name, clip_id, path


def _link_refusal(path: Path, inbox: Path) -> InputError | None:
    """The refusal of a symbolic link ``path`` that leaves ``inbox`` or leads nowhere."""
    try:
        target = path.resolve()
    except (OSError, RuntimeError):  # a loop of links (RuntimeError before Python 3.13)
        return InputError(path, "is a symbolic link that leads back to itself (a loop of "
                          "links); replace it with the file it should point to")
    if target.is_relative_to(inbox.resolve()) and target.exists():
        return None
    shown = os.readlink(path) if path.is_symlink() else str(target)
    if not target.exists():
        return InputError(path, f"is a symbolic link to {shown}, which does not exist")
    return InputError(path, f"is a symbolic link to {shown}, outside the inbox; copy the "
                      "file into the inbox")


def entry_refusal(path: Path, inbox: Path, *, directory: bool) -> InputError | None:
    """Why the inbox entry ``path`` cannot be read, or ``None`` when it can.

    An entry may be a symbolic link only to something inside the inbox; a file entry
    must be a regular file, a folder entry a folder whose visible members link nowhere
    outside the inbox.
    """
    refusal = _link_refusal(path, inbox)
    if refusal is not None:
        return refusal
    mode = path.stat().st_mode
    if directory:
        members = (member for member in path.iterdir() if visible(member.name))
        return next((r for member in members if (r := _link_refusal(member, inbox))), None)
    if not stat.S_ISREG(mode):
        kind = "a file" if path.name.endswith(SIDECAR_SUFFIX) else "a regular file"
        return InputError(path, f"is {file_kind(mode)}; an inbox input must be {kind}")
    return None


def _case_collisions(clip_ids: list[str]) -> dict[str, str]:
    """Each clip id that differs from another only in case -> the message refusing it."""
    by_folded: dict[str, list[str]] = defaultdict(list)
    for clip_id in clip_ids:
        by_folded[clip_id.casefold()].append(clip_id)
    refused = {}
    for twins in by_folded.values():
        if len(twins) > 1:
            names = " and ".join(quoted(t) for t in sorted(twins))
            reason = (f"clip ids {names} differ only in case; they collide on file systems "
                      "that ignore case and in the database folder: rename one")
            refused.update(dict.fromkeys(twins, reason))
    return refused


def _unread_files(clip_id: str, inbox: Path) -> str:
    """What the refusal of a clip without a track file adds about its files no format read.

    Returns
    -------
    str
        ``""``, or ``"; '<name>' is not read: <hint>"`` for each entry of the inbox
        named ``<clip_id>.<anything>`` that is no sidecar and that no format claims: a file
        of the clip under a name handdb does not read, such as DeepLabCut's ``.h5``.
    """
    unread = sorted(path.name for path in inbox.glob(f"{clip_id}.*")
                    if not path.name.endswith(SIDECAR_SUFFIX) and match_format(path) is None)
    notes = []
    for name in unread:
        hint = next((text for end, text in UNREAD_HINTS.items() if name.endswith(end)), None)
        notes.append(f"{quoted(name)} is not read"
                     + (f": {hint.format(clip_id=clip_id)}" if hint else ""))
    return "".join(f"; {note}" for note in notes)


def _assemble(clip_id: str, inbox: Path,
              found: dict[str, list[tuple[str, Path]]]) -> ClipEntry | list[InputError]:
    """Make one clip of the entries found for ``clip_id``, or say why not."""
    sidecars, truths = found[SIDECAR], found["truth"]
    tracks = [entry for kind in DATA_KINDS for entry in found[kind]]
    track_suffixes = ", ".join(f.suffix for f in registered_formats() if f.kind in DATA_KINDS)
    if not sidecars:
        return [InputError(path, f"has no sidecar: add {clip_id}{SIDECAR_SUFFIX} (skeleton, "
                           "hand, fps, subject, units, camera) next to it", clip_id=clip_id)
                for _, path in tracks + truths]
    if not tracks:
        return [InputError(sidecars[0][1], f"clip '{clip_id}' has no track file: add "
                           f"{clip_id}<suffix> with one of the suffixes {track_suffixes}"
                           + _unread_files(clip_id, inbox), clip_id=clip_id)]
    if len(tracks) > 1:
        names = " and ".join(path.name for _, path in tracks)
        return [InputError(tracks[1][1], f"clip '{clip_id}' has two track files, {names}; "
                           "keep exactly one", clip_id=clip_id)]
    (track_format, track_path), = tracks
    truth_sources = truths + ([(track_format, track_path)]
                              if get_format(track_format).read_truth else [])
    if len(truth_sources) > 1:
        names = " and ".join(path.name for _, path in truth_sources)
        return [InputError(truths[0][1], f"clip '{clip_id}' has two sources of ground "
                           f"truth, {names}; keep one", clip_id=clip_id)]
    truth_format, truth_path = truths[0] if truths else (None, None)
    return ClipEntry(clip_id=clip_id, inbox=inbox, sidecar=sidecars[0][1], tracks=track_path,
                     track_format=track_format, truth=truth_path, truth_format=truth_format)


def discover(inbox: str | Path) -> InboxScan:
    """Group the entries of ``inbox`` into clips.

    Raises
    ------
    InputError
        If ``inbox`` is not a folder.
    """
    inbox = Path(inbox)
    if not inbox.is_dir():
        raise InputError(inbox, "is not a folder; give the inbox holding the clips' files")
    grouped: dict[str, dict[str, list[tuple[str, Path]]]] = defaultdict(
        lambda: defaultdict(list))
    others: dict[str, list[Path]] = defaultdict(list)
    refused: list[InputError] = []
    unreadable: set[str] = set()
    for kind, format_name, clip_id, path in _entries(inbox):
        if kind not in (SIDECAR, *CLIP_KINDS):
            others[format_name].append(path)
            continue
        try:
            validate_clip_id(clip_id, path)
        except InputError as exc:
            refused.append(exc)
            continue
        directory = kind != SIDECAR and get_format(format_name).directory
        refusal = entry_refusal(path, inbox, directory=directory)
        if refusal is not None:
            refusal.clip_id = clip_id
            refused.append(refusal)
            unreadable.add(clip_id)
            continue
        grouped[clip_id][kind].append((format_name, path))
    collisions = _case_collisions(list(grouped))
    clips = []
    for clip_id in sorted(grouped):
        if clip_id in unreadable:
            continue
        if clip_id in collisions:
            refused.extend(InputError(path, collisions[clip_id], field="clip_id",
                                      clip_id=clip_id)
                           for entries in grouped[clip_id].values() for _, path in entries)
            continue
        outcome = _assemble(clip_id, inbox, grouped[clip_id])
        if isinstance(outcome, ClipEntry):
            clips.append(outcome)
        else:
            refused.extend(outcome)
    return InboxScan(clips=tuple(clips), refused=tuple(refused),
                     others={name: tuple(paths) for name, paths in others.items()})


def inbox_relative(path: str | Path, inbox: str | Path) -> str:
    """``path`` relative to ``inbox`` (POSIX separators), or as given when outside it."""
    try:
        return Path(path).resolve().relative_to(Path(inbox).resolve()).as_posix()
    except ValueError:
        return str(path)


def _files(path: Path) -> list[Path]:
    """``path`` itself, or the files of the folder ``path`` its reader reads."""
    if not path.is_dir():
        return [path]
    match = match_format(path)
    members = match[0].members if match is not None else None
    return members(path) if members is not None else folder_files(path)


def clip_files(entry: ClipEntry) -> list[Path]:
    """The files :func:`clip_content_hash` reads, in the order it reads them."""
    return [file for path in entry.paths for file in _files(path)]


def clip_content_hash(entry: ClipEntry) -> str:
    """SHA-256 (hex) over the clip's input files: their names and bytes, in a fixed order.

    The sidecar comes first, then the track file (a folder's files in name order), then
    the truth file; each contributes its path relative to the inbox, its size and its
    bytes, so renaming, editing or moving bytes between files changes the hash. A folder
    contributes the files its reader reads (:attr:`InputFormat.members
    <handdb.ingest.registry.InputFormat.members>`). Files are read in chunks, each
    checked against :data:`~handdb.ingest.limits.MAX_FILE_BYTES` first.

    Raises
    ------
    InputError
        If a file is not a regular file or is larger than the limit.
    """
    digest = hashlib.sha256()
    for file in clip_files(entry):
        size = checked_size(file)
        digest.update(file.relative_to(entry.inbox).as_posix().encode() + b"\0")
        digest.update(f"{size}\0".encode())
        with file.open("rb") as stream:
            while chunk := stream.read(HASH_CHUNK_BYTES):
                digest.update(chunk)
    return digest.hexdigest()


def _dense(rows: Observations | Positions, values: np.ndarray, n_frames: int) -> np.ndarray:
    """Scatter per-row ``values`` ``(N, ...)`` into ``(T, J, ...)``, NaN elsewhere.

    Rows that give every (frame, joint) once in order (a complete long-form file) are
    ``values`` reshaped, copied without the scatter.
    """
    shape = (n_frames, rows.skeleton.n_joints) + values.shape[1:]
    flat = rows.frame * rows.skeleton.n_joints + rows.joint
    if flat.size == n_frames * rows.skeleton.n_joints and np.all(flat[1:] > flat[:-1]):
        return np.array(values, dtype=np.float64).reshape(shape)
    dense = np.full(shape, np.nan)
    dense.reshape((-1,) + values.shape[1:])[flat] = values
    return dense


def _check_plausible(spec: ClipSpec, observations: Observations | Positions,
                     truth: Positions | None, track_format: InputFormat) -> None:
    """Refuse coordinates no hand can have.

    Coordinates beyond the limits of :mod:`handdb.ingest.limits`, and a 2D track whose
    every point lies within a pixel of the origin (normalised, not pixels).
    """
    three_d = track_format.kind == MARKERS_KIND
    metres = MAX_COORDINATE_METRES / spec.meters_per_unit
    observations.check_magnitude(metres if three_d else MAX_PIXEL_COORDINATE,
                                 spec.units if three_d else "px")
    if isinstance(observations, Observations):
        observations.check_pixels("coordinates" in track_format.sidecar_keys)
    if truth is not None:
        truth.check_magnitude(metres, spec.units)


def load_clip(entry: ClipEntry, content_hash: str | None = None) -> Clip:
    """Read one clip: sidecar, tracks and ground truth, as dense arrays.

    ``T`` is the number of frames the track file spans (for the ground truth too, if it
    runs longer). ``content_hash`` is the clip's :func:`content_hash` when the caller has
    it already.

    Raises
    ------
    InputError
        For the first problem in any of the clip's files, with ``clip_id`` set.
    """
    try:
        track_format = get_format(entry.track_format)
        truth_format = get_format(entry.truth_format) if entry.truth_format else None
        three_d = track_format.kind == MARKERS_KIND
        read_by = track_format.sidecar_keys + (truth_format.sidecar_keys if truth_format
                                               else ())
        spec = parse_sidecar(entry.sidecar, entry.clip_id, three_d=three_d, read_by=read_by)
        skeleton = load_skeleton(spec.skeleton)
        observations = track_format.read(entry.tracks, spec, skeleton)
        points = observations.xyz if three_d else observations.uv
        if not finite_points(points).any():
            raise InputError(entry.tracks, "holds no point of the hand in any frame")
        if truth_format is not None:
            truth_rows = truth_format.read(entry.truth, spec, skeleton)
        elif track_format.read_truth is not None:
            truth_rows = track_format.read_truth(entry.tracks, spec, skeleton)
        else:
            truth_rows = None
        _check_plausible(spec, observations, truth_rows, track_format)
        named = {str(entry.tracks): observations.names}
        if truth_rows is not None and entry.truth is not None:
            named[str(entry.truth)] = truth_rows.names
        check_joint_map_keys(spec, named)
        hash_hex = content_hash or clip_content_hash(entry)
    except InputError as exc:
        exc.clip_id = exc.clip_id or entry.clip_id
        raise
    except OSError as exc:
        raise InputError(exc.filename or entry.tracks, f"cannot be read: {exc.strerror}",
                         clip_id=entry.clip_id) from exc
    n_frames = max(observations.n_frames, truth_rows.n_frames if truth_rows else 0)
    no_points = np.full((n_frames, skeleton.n_joints), np.nan)
    return Clip(
        spec=spec,
        skeleton=skeleton,
        uv=(np.stack([no_points, no_points], axis=-1) if three_d
            else _dense(observations, observations.uv, n_frames)),
        confidence=no_points if three_d else _dense(observations, observations.confidence,
                                                    n_frames),
        truth=_dense(truth_rows, truth_rows.xyz, n_frames) if truth_rows else None,
        markers=_dense(observations, observations.xyz, n_frames) if three_d else None,
        source_format=track_format.name,
        source_files=tuple(str(path) for path in entry.paths),
        content_hash=hash_hex,
        sampling=observations.sampling,
    )
