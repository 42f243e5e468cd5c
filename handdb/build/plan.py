"""What a build has to do, decided from the inbox and the database alone.

:func:`plan_build` scans the inbox, reads its X-ray tables (the joint ratios every clip's
bone lengths depend on), hashes each clip's files once and compares every stage key with
the one the clip was committed under. A committed clip the build would keep is checked
against the record of its files (:meth:`~handdb.store.database.Store.clip_damage`): one
whose files are missing or damaged is rebuilt from the inbox, and the plan says why
(:attr:`BuildPlan.repairs`), as it does for a stored X-ray, ratio or quarantine file that
no longer reads. An inbox clip whose id differs only in case from a stored clip's is
refused. It writes nothing: a build whose plan has nothing to
do finishes without running a single stage, and without starting Prefect.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import pyarrow as pa

from handdb.build.keys import STAGES, first_changed_stage, stage_keys, table_hash
from handdb.build.options import BuildOptions
from handdb.errors import DamagedFileError, InputError
from handdb.ingest import clip_content_hash, discover
from handdb.ingest.inbox import ClipEntry, clip_files
from handdb.ingest.registry import MARKERS_KIND, get_format
from handdb.ingest.xray import MAX_XRAY_NAME_BYTES, XRAY_SUFFIX, read_xray
from handdb.lengths.ratios import joint_ratios
from handdb.store import tables
from handdb.store.database import Store
from handdb.store.quarantine import Refusal, quarantine_table
from handdb.store.stamps import Hashed, entry_if_settled, entry_key, known_digest, stamp


@dataclass(frozen=True)
class PlannedClip:
    """One clip of the inbox and what it needs.

    Attributes
    ----------
    entry
        The clip's inbox entries.
    content_hash
        SHA-256 over its files.
    keys
        The key of each stage.
    start
        The first stage to run; ``None`` when the committed clip is current.
    markers
        Whether the clip's data is 3D markers.
    """

    entry: ClipEntry
    content_hash: str
    keys: dict[str, str]
    start: str | None
    markers: bool

    @property
    def clip_id(self) -> str:
        """The clip's id."""
        return self.entry.clip_id


@dataclass(frozen=True)
class XrayInputs:
    """The inbox's X-ray tables and the joint ratios they give.

    Attributes
    ----------
    measurements
        ``partition key -> rows`` of ``xray_measurements`` to write (files that changed).
    ratios
        Table ``joint_ratios`` from every measurement, stored and new.
    ratios_changed
        Whether ``ratios`` differs from the stored table.
    refusals
        Refused rows and files. A file refused whole keeps the rows stored for it.
    repairs
        Stored files that no longer read, each written again from the inbox.
    """

    measurements: dict[str, pa.Table]
    ratios: pa.Table
    ratios_changed: bool
    refusals: tuple[Refusal, ...]
    repairs: tuple[str, ...] = ()


@dataclass(frozen=True)
class BuildPlan:
    """Everything a build will do, before it does any of it."""

    inbox: str
    db: str
    options: BuildOptions
    clips: tuple[PlannedClip, ...]
    xray: XrayInputs
    refusals: tuple[Refusal, ...] = field(default=())
    repairs: tuple[str, ...] = field(default=())
    #: The digests of the inbox's clips and of the stored files checked, that stand after
    #: the plan (:mod:`handdb.store.stamps`), for the next build to hash only what changed.
    stamps: Mapping[str, Hashed] = field(default_factory=dict)

    @property
    def todo(self) -> tuple[PlannedClip, ...]:
        """Clips with a stage to run."""
        return tuple(c for c in self.clips if c.start is not None)

    @property
    def unchanged(self) -> tuple[PlannedClip, ...]:
        """Clips committed under their current keys."""
        return tuple(c for c in self.clips if c.start is None)

    def quarantine(self, store: Store, clip_refusals: list[Refusal]) -> pa.Table | None:
        """The ``quarantine`` table after the build, or ``None`` when it does not change."""
        damaged = _damaged(store, "quarantine", "quarantine") is not None
        previous = tables.empty("quarantine") if damaged else store.read_table("quarantine")
        refused = quarantine_table([*self.refusals, *self.xray.refusals, *clip_refusals],
                                   self.inbox, previous)
        return None if refused.equals(previous) and not damaged else refused

    @property
    def nothing_to_do(self) -> bool:
        """No clip to process and no X-ray table to store: only a run record to write.

        The quarantine may still change (a refused file edited but still refused); that is
        written without processing anything either.
        """
        return not self.todo and not self.xray.measurements and not self.xray.ratios_changed


def _readable(store: Store, table: str, key: str) -> pa.Table | None:
    """Partition ``key`` of ``table``, or ``None`` when it is missing or damaged."""
    try:
        return store.read(table, key)
    except DamagedFileError:
        return None


def _damaged(store: Store, table: str, key: str) -> str | None:
    """The repair of partition ``key`` of ``table`` when it is there but does not read."""
    try:
        store.read(table, key)
    except DamagedFileError as exc:
        return str(exc)
    return None


def _damaged_files(store: Store, partitions: list[tuple[str, str]]) -> list[str]:
    """What is wrong with each of the ``(table, key)`` partitions that is there but damaged."""
    return [damage for table, key in partitions if (damage := _damaged(store, table, key))]


def read_xray_inputs(paths: list[Path], store: Store) -> XrayInputs:
    """Read the inbox's X-ray tables; work out the joint ratios they give with the stored ones.

    Each file's measurements stand for that file's partition of ``xray_measurements``. A
    file refused whole (not a table of measurements at all) leaves its stored partition as
    it was.
    """
    keys = store.partition_keys("xray_measurements")
    repairs = _damaged_files(store, [*(("xray_measurements", key) for key in keys),
                                     ("joint_ratios", "joint_ratios")])
    partitions = {key: _readable(store, "xray_measurements", key) for key in keys}
    refusals: list[Refusal] = []
    changed: dict[str, pa.Table] = {}
    for path in sorted(paths):
        if len(path.name.removesuffix(XRAY_SUFFIX).encode()) > MAX_XRAY_NAME_BYTES:
            refusals.append(Refusal.from_error(InputError(
                path, f"has a name of {len(path.name.encode())} bytes: the database stores "
                f"an X-ray file under its name, so give it at most {MAX_XRAY_NAME_BYTES} "
                f"bytes before '{XRAY_SUFFIX}'", field="file name")))
            continue
        measurements, errors = read_xray(path)
        refusals += [Refusal.from_error(error) for error in errors]
        if errors and measurements.num_rows == 0:
            continue
        key = path.name.removesuffix(XRAY_SUFFIX)
        measurements = tables.conform("xray_measurements", measurements)
        if partitions.get(key) != measurements:
            changed[key] = measurements
        partitions[key] = measurements
    present = [partitions[key] for key in sorted(partitions) if partitions[key] is not None]
    every = pa.concat_tables(present) if present else tables.empty("xray_measurements")
    ratios = tables.conform("joint_ratios", joint_ratios(every))
    previous = _readable(store, "joint_ratios", "joint_ratios")
    return XrayInputs(measurements=changed, ratios=ratios,
                      ratios_changed=previous is None or not previous.equals(ratios),
                      refusals=tuple(refusals), repairs=tuple(repairs))


def plan_build(inbox: str | Path, db: str, options: BuildOptions) -> BuildPlan:
    """Decide what a build of ``inbox`` into ``db`` has to do; write nothing.

    Raises
    ------
    InputError
        If ``inbox`` is not a folder.
    """
    store = Store(db)
    known = store.stamps()
    stamps: dict[str, Hashed] = {}
    scan = discover(Path(inbox))
    xray = read_xray_inputs(list(scan.others.get("xray", ())), store)
    ratios_hash = table_hash(xray.ratios)
    stored = store.clip_stage_keys()
    committed = set(store.partition_keys("clips"))
    clips, repairs = [], _damaged_files(store, [("quarantine", "quarantine")])
    repairs += xray.repairs
    refusals = [Refusal.from_error(e) for e in scan.refused]
    for entry in scan.clips:
        twin = _stored_twin(entry, committed, store)
        if twin is not None:
            refusals.append(Refusal.from_error(twin))
            continue
        try:
            digest, hashed = _content_hash(entry, known)
        except InputError as error:
            refusals.append(Refusal.from_error(error))
            continue
        stamps.update(hashed)
        markers = get_format(entry.track_format).kind == MARKERS_KIND
        keys = stage_keys(digest, options, ratios_hash, marker_clip=markers)
        start = first_changed_stage(keys, stored.get(entry.clip_id))
        damage, checked = _clip_damage(store, entry.clip_id, committed, stored, start, known)
        stamps.update(checked)
        if damage is not None:
            repairs.append(f"clip {entry.clip_id}: {damage}; rebuilt from the inbox")
            start = STAGES[0]
        clips.append(PlannedClip(entry=entry, content_hash=digest, keys=keys, start=start,
                                 markers=markers))
    return BuildPlan(inbox=str(inbox), db=db, options=options, clips=tuple(clips), xray=xray,
                     refusals=tuple(refusals), repairs=tuple(repairs), stamps=stamps)


def _content_hash(entry: ClipEntry, known: Mapping[str, Hashed]
                  ) -> tuple[str, dict[str, Hashed]]:
    """:func:`~handdb.ingest.clip_content_hash`, from ``known`` while no file has changed.

    Also the entry of the hash, by its key, when it stands (its files are settled). The
    hash covers file names relative to the inbox, so the inbox is part of the key.

    Raises
    ------
    InputError
        If a file is not a regular file or is larger than the limit.
    """
    files, scope = [str(file) for file in clip_files(entry)], str(entry.inbox)
    key = entry_key(files, scope)
    digest = known_digest(known, files, scope)
    if digest is not None:
        return digest, {key: known[key]}
    before, stamped = time.time_ns(), [stamp(file) for file in files]
    digest = clip_content_hash(entry)
    hashed = entry_if_settled(files, stamped, digest, before)
    return digest, {} if hashed is None else {key: hashed}


def _stored_twin(entry: ClipEntry, committed: set[str], store: Store) -> InputError | None:
    """The refusal of an inbox clip whose id differs only in case from a stored clip's.

    The two would share their files on a file system that ignores case (macOS, Windows),
    and a database folder copied to one.
    """
    folded = entry.clip_id.casefold()
    twins = sorted(c for c in committed if c.casefold() == folded and c != entry.clip_id)
    if not twins:
        return None
    return InputError(
        entry.sidecar,
        f"clip id {entry.clip_id!r} differs only in case from the clip {twins[0]!r} stored in "
        f"the database {store.url}; they would share their files where case is ignored: "
        f"name the clip {twins[0]!r} again, or give it an id of its own",
        field="clip_id", clip_id=entry.clip_id)


def _clip_damage(store: Store, clip_id: str, committed: set[str],
                 stored: dict[str, dict[str, str]], start: str | None,
                 known: Mapping[str, Hashed]) -> tuple[str | None, dict[str, Hashed]]:
    """Why the committed clip ``clip_id`` must be rebuilt whole, or ``None``.

    A clip rebuilt whole anyway (``start`` is the first stage) is not checked; one whose
    ``clips`` file does not read is damaged, and one the build would keep, in whole or in
    part, is checked against the record of its files, hashing those whose stamps differ
    from ``known``; the entries of its files that stand come with the answer.
    """
    if clip_id not in committed or (start == STAGES[0] and clip_id in stored):
        return None, {}
    if clip_id not in stored:
        return f"clips/{clip_id}.parquet is damaged", {}
    return store.checked_clip_files(clip_id, known)
