"""The database: Parquet tables in a folder, one subfolder per table.

Layout under the database location (a local folder or any fsspec URL, e.g. ``s3://``)::

    <db>/<table>/<key>.parquet

where ``key`` is the clip id for per-clip tables, the source file stem for per-source
tables, the run id for ``runs`` and the table name for global tables (see ``partition``
in ``schemas/tables/*.json``). Every file is checked against its contract on write.

Writes are atomic per file: a file is written aside under a temporary name that no
reader matches (``*.parquet.tmp``) and then renamed into place. A clip's tables are
committed with its ``clips`` row last, so a clip whose ``clips`` row carries the current
build key is complete; a build interrupted at any point re-processes exactly the clips
it had not committed. Just before its ``clips`` row, a commit records every file the clip
needs (its tables' files, the ``clips`` file among them, and its USD) with size and
SHA-256 in ``clip_files``; :meth:`Store.clip_damage` checks a committed clip against that
record, and a build rebuilds from the inbox a clip whose files are missing or differ. A
build holds an exclusive lock on the database while it writes.

Everything the store writes or removes lies inside the database folder. The folder itself
may be a symbolic link (the user chose where it lives), but nothing inside it may be one:
a build refuses a database holding a link (:class:`~handdb.errors.DatabasePathError`
naming it) before it writes anything, and no write or removal goes through one.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import socket
import sys
import time
import uuid
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from functools import cached_property

import fsspec
import pyarrow as pa
import pyarrow.parquet as pq
from fsspec.implementations.local import LocalFileSystem

from handdb.errors import DamagedFileError, DatabaseLockedError, DatabasePathError, StoreError
from handdb.store import tables
from handdb.store.stamps import (
    STAMPS_FILE,
    Hashed,
    entry_if_settled,
    entry_key,
    known_digest,
    load_stamps,
    save_stamps,
    stamp,
)

#: Tables holding one file per clip; a clip commit replaces all of them.
CLIP_TABLES: tuple[str, ...] = tuple(
    name for name in tables.table_names() if tables.table_spec(name).partition == "clip"
)

#: The per-clip table recording every file a committed clip needs, with size and checksum.
FILES_TABLE = "clip_files"

#: What reading a damaged Parquet file raises (cut short, overwritten, not Parquet at all).
DAMAGE_ERRORS: tuple[type[Exception], ...] = (pa.ArrowInvalid, OSError)

LOCK_FILE = ".lock"

#: Bytes of the lock file that the OS lock covers on Windows (``msvcrt`` locks byte
#: ranges; a lock past the end of the file is allowed).
_WINDOWS_LOCK_SPAN = 1 << 20
PARQUET_SUFFIX = ".parquet"
TMP_SUFFIX = ".tmp"

#: How long a refused build waits for the lock's holder to write who it is: the holder
#: writes its pid just after it takes the lock, so a build refused in between would read
#: an empty file.
_HOLDER_WAIT_S = 0.5
_HOLDER_POLL_S = 0.01

#: ``os.open`` flag that refuses a symbolic link as the last part of a path (none on Windows,
#: where the lock file is checked before it is opened).
_NO_FOLLOW = getattr(os, "O_NOFOLLOW", 0)

#: Bytes read at a time when a file is hashed.
_HASH_CHUNK = 1 << 20


def encode(data: pa.Table) -> bytes:
    """The bytes of ``data`` as the store writes a Parquet file.

    zstd with column statistics; only the string columns are dictionary-encoded (a clip's
    few ids, joint and method names repeat on every row). A number column is written plain:
    its values rarely repeat, so a dictionary of it is about as long as the column, its
    indices come on top, and trying one costs much of the encoding
    (``benchmarks/RESULTS.md``).
    """
    strings = [field.name for field in data.schema if pa.types.is_string(field.type)]
    sink = pa.BufferOutputStream()
    pq.write_table(data, sink, compression="zstd", write_statistics=True,
                   use_dictionary=strings)
    return sink.getvalue().to_pybytes()


def _sized(payload: bytes) -> tuple[int, str]:
    """Size and SHA-256 (hex) of ``payload``."""
    return len(payload), hashlib.sha256(payload).hexdigest()


def _try_lock(fh) -> bool:
    """Take an exclusive OS lock on the open file ``fh`` without waiting; ``False`` if held."""
    if sys.platform == "win32":
        import msvcrt

        try:
            fh.seek(_WINDOWS_LOCK_SPAN)
            msvcrt.locking(fh.fileno(), msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True
    import fcntl

    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    return True


def _lock_holder(fh) -> str:
    """Who holds the lock on ``fh``, as its holder wrote it ("pid N on host")."""
    deadline = time.monotonic() + _HOLDER_WAIT_S
    while True:
        fh.seek(0)
        holder = fh.read().strip()
        if holder or time.monotonic() >= deadline:
            return holder or "another process"
        time.sleep(_HOLDER_POLL_S)


def _unlock(fh) -> None:
    """Release the lock :func:`_try_lock` took."""
    if sys.platform == "win32":
        import msvcrt

        fh.seek(_WINDOWS_LOCK_SPAN)
        msvcrt.locking(fh.fileno(), msvcrt.LK_UNLCK, 1)
        return
    import fcntl

    fcntl.flock(fh, fcntl.LOCK_UN)


@dataclass(frozen=True)
class Store:
    """A handdb database at ``url`` (a folder path or an fsspec URL)."""

    url: str

    @property
    def fs(self) -> fsspec.AbstractFileSystem:
        """The filesystem the database lives on."""
        return self._split[0]

    @property
    def root(self) -> str:
        """The database location within :attr:`fs`."""
        return self._split[1]

    @cached_property
    def _split(self) -> tuple[fsspec.AbstractFileSystem, str]:
        """The filesystem and the location on it, resolved once per :class:`Store`.

        A clip's export and commit ask for paths about 190 times; resolving the URL
        (``fsspec.core.url_to_fs``) each time cost 1-2 ms of a 300-frame clip's commit.
        """
        fs, root = fsspec.core.url_to_fs(self.url)
        return fs, root.rstrip("/")

    @cached_property
    def is_local(self) -> bool:
        """Whether the database is a folder on this machine."""
        return isinstance(self.fs, LocalFileSystem)

    def path(self, *parts: str) -> str:
        """Path of ``parts`` under the database root, on :attr:`fs`."""
        return "/".join([self.root, *parts])

    def uri(self, *parts: str) -> str:
        """Full URL of ``parts`` (a plain path for local databases)."""
        path = self.path(*parts)
        return path if self.is_local else self.fs.unstrip_protocol(path)

    def files_in(self, folder: str, suffix: str) -> list[str]:
        """Files directly in ``folder`` (a path on :attr:`fs`) named ``*<suffix>``, sorted.

        The folder is listed, never globbed, so a database path holding pattern characters
        (``db[1]``) names only itself. A folder that does not exist holds no file.
        """
        try:
            entries = self.fs.ls(folder, detail=True)
        except (FileNotFoundError, NotADirectoryError):
            return []
        return sorted(entry["name"] for entry in entries
                      if entry["type"] == "file" and entry["name"].endswith(suffix))

    def table_files(self, table: str) -> list[str]:
        """Committed Parquet files of ``table``, sorted."""
        return self.files_in(self.path(table), PARQUET_SUFFIX)

    def partition_keys(self, table: str) -> list[str]:
        """Keys of the committed partitions of ``table``, sorted."""
        return [path.rsplit("/", 1)[-1].removesuffix(PARQUET_SUFFIX)
                for path in self.table_files(table)]

    def checked(self, path: str) -> str:
        """``path`` (a path under the database root) when no part of it is a symbolic link.

        Raises
        ------
        DatabasePathError
            Naming the first part of ``path`` below the root that is a link.
        """
        if not self.is_local:
            return path
        current = self.root
        for part in path.removeprefix(f"{self.root}/").split("/"):
            current = f"{current}/{part}"
            if os.path.islink(current):
                raise DatabasePathError(
                    f"{current} is a symbolic link (to {os.readlink(current)}) inside the "
                    f"database {self.url}; handdb writes and removes files only inside the "
                    "database, never through a link: replace the link with the folder or "
                    "file it points to"
                )
        return path

    def makedirs(self, *parts: str) -> str:
        """Create the folder ``parts`` under the root (and those above it); return its path."""
        folder = self.checked(self.path(*parts))
        self.fs.makedirs(folder, exist_ok=True)
        return folder

    def check_links(self) -> None:
        """Refuse a local database that holds a symbolic link anywhere inside it.

        Raises
        ------
        DatabasePathError
            Naming the first link found.
        """
        if not self.is_local:
            return
        for folder, subfolders, files in os.walk(self.root):
            for name in sorted([*subfolders, *files]):
                self.checked(f"{folder}/{name}")

    def check_writable(self) -> None:
        """Make sure a build can use the database folder, creating it when only it is missing.

        Raises
        ------
        DatabasePathError
            When the path is a file, its parent folder is missing or is a file, or the
            folder cannot be written; the message names the path and what to change.
        """
        if not self.is_local:
            self.fs.makedirs(self.root, exist_ok=True)
            return
        root, parent = self.root, os.path.dirname(self.root)
        if os.path.exists(root) and not os.path.isdir(root):
            raise DatabasePathError(
                f"database path {root} is a file, not a folder: pass --db a folder (it is "
                "created when missing), or move the file away"
            )
        if not os.path.isdir(parent):
            what = "is a file" if os.path.exists(parent) else "does not exist"
            raise DatabasePathError(
                f"database folder {root} cannot be created: its parent {parent} {what}; "
                "create that folder first, or pass --db a path in an existing folder"
            )
        try:
            os.makedirs(root, exist_ok=True)
        except PermissionError:
            raise DatabasePathError(self._unwritable()) from None
        if not os.access(root, os.W_OK | os.X_OK):
            raise DatabasePathError(self._unwritable())

    def _unwritable(self) -> str:
        return (f"cannot write in the database folder {self.root}: make it writable "
                "(chmod u+w), or pass --db a folder you can write")

    def check_readable(self) -> None:
        """Make sure the database exists, to query it.

        Raises
        ------
        DatabasePathError
            When there is nothing at the path, a file, or a folder with no table of a
            handdb database.
        """
        if not self.fs.exists(self.root):
            raise DatabasePathError(
                f"there is no database at {self.url}: build one with 'handdb build --db "
                f"{self.url}', or pass --db the folder of a database"
            )
        if not self.fs.isdir(self.root):
            raise DatabasePathError(
                f"database path {self.url} is a file, not a database folder: pass --db the "
                "folder of a database"
            )
        if not any(self.fs.isdir(self.path(name)) for name in tables.table_names()):
            raise DatabasePathError(
                f"{self.url} is a folder, but not a handdb database (it has no table "
                f"folder): build one with 'handdb build --db {self.url}', or pass --db the "
                "folder of a database"
            )

    def partition_path(self, table: str, key: str) -> str:
        """Path of the file holding partition ``key`` of ``table``."""
        return self.path(table, f"{key}{PARQUET_SUFFIX}")

    def write(self, table: str, key: str, data: pa.Table) -> str:
        """Write partition ``key`` of ``table`` atomically (aside, then rename).

        The data is checked against the table's contract first; nothing is written when
        it does not conform.
        """
        return self._write_bytes(table, key, encode(tables.conform(table, data)))

    def _write_bytes(self, table: str, key: str, payload: bytes) -> str:
        """Write ``payload`` as partition ``key`` of ``table``, aside and then renamed."""
        self.makedirs(table)
        final = self.checked(self.partition_path(table, key))
        temp = f"{final}.{uuid.uuid4().hex}{TMP_SUFFIX}"
        with self.fs.open(temp, "wb") as fh:
            fh.write(payload)
        if self.is_local:
            os.replace(temp, final)
        else:
            self.fs.mv(temp, final)
        return final

    def read(self, table: str, key: str) -> pa.Table | None:
        """Partition ``key`` of ``table``, or ``None`` when it does not exist.

        Raises
        ------
        DamagedFileError
            When the file is there but cannot be read as the table.
        """
        path = self.partition_path(table, key)
        if not self.fs.exists(path):
            return None
        return self._read_file(table, path)

    def _read_file(self, table: str, path: str) -> pa.Table:
        try:
            with self.fs.open(path, "rb") as fh:
                return pq.read_table(fh, schema=tables.schema(table))
        except DAMAGE_ERRORS as exc:
            raise DamagedFileError(
                f"{self.uri(self.relative(path))} is damaged ({exc}); the next build writes "
                "it again from the inbox"
            ) from None

    def relative(self, path: str) -> str:
        """``path`` (on :attr:`fs`, under the root) relative to the database folder."""
        return path.removeprefix(f"{self.root}/")

    def read_table(self, table: str) -> pa.Table:
        """Every partition of ``table`` concatenated (an empty table when there is none).

        Raises
        ------
        DamagedFileError
            When one of its files cannot be read.
        """
        parts = [self._read_file(table, path) for path in self.table_files(table)]
        if not parts:
            return tables.empty(table)
        return pa.concat_tables(parts)

    def readable_rows(self, table: str) -> pa.Table:
        """Every partition of ``table`` that reads, concatenated; damaged files left out."""
        parts = []
        for path in self.table_files(table):
            with contextlib.suppress(DamagedFileError):
                parts.append(self._read_file(table, path))
        return pa.concat_tables(parts) if parts else tables.empty(table)

    def delete(self, table: str, key: str) -> None:
        """Remove partition ``key`` of ``table`` if it exists."""
        path = self.checked(self.partition_path(table, key))
        if self.fs.exists(path):
            self.fs.rm(path)

    def commit_clip(self, clip_id: str, clip_tables: dict[str, pa.Table]) -> None:
        """Replace every per-clip table of ``clip_id`` with ``clip_tables``.

        ``clip_tables`` must hold a ``clips`` row; per-clip tables it does not name are
        removed for this clip (a clip that lost its ground truth loses its ``truth_3d``).
        The files are recorded in ``clip_files`` (:data:`FILES_TABLE`) with the USD named
        in the ``clips`` row, and the ``clips`` row is written last: it marks the clip as
        complete.
        """
        if "clips" not in clip_tables:
            raise StoreError(f"commit of clip '{clip_id}' has no 'clips' row")
        unknown = sorted(set(clip_tables) - set(CLIP_TABLES))
        if unknown:
            raise StoreError(f"commit of clip '{clip_id}': {unknown} are not per-clip tables")
        if FILES_TABLE in clip_tables:
            raise StoreError(f"commit of clip '{clip_id}': '{FILES_TABLE}' is written by the "
                             "commit itself")
        conformed = {name: tables.conform(name, data) for name, data in clip_tables.items()}
        recorded: dict[str, tuple[int, str]] = {}
        for name in CLIP_TABLES:
            if name in ("clips", FILES_TABLE):
                continue
            if name in conformed:
                payload = encode(conformed[name])
                recorded[self.relative(self._write_bytes(name, clip_id, payload))] = _sized(payload)
            else:
                self.delete(name, clip_id)
        clips = encode(conformed["clips"])
        recorded[self.relative(self.partition_path("clips", clip_id))] = _sized(clips)
        usd_path = conformed["clips"].column("usd_path")[0].as_py()
        if usd_path is not None:
            recorded[usd_path] = self._fingerprint(usd_path)
        files = sorted(recorded)
        self.write(FILES_TABLE, clip_id, tables.from_columns(FILES_TABLE, {
            "clip_id": clip_id, "file": files,
            "bytes": [recorded[f][0] for f in files], "sha256": [recorded[f][1] for f in files],
        }))
        self._write_bytes("clips", clip_id, clips)

    def _fingerprint(self, relative: str) -> tuple[int, str]:
        """Size and SHA-256 of the file at ``relative`` in the database."""
        digest, size = hashlib.sha256(), 0
        with self.fs.open(self.path(relative), "rb") as fh:
            while chunk := fh.read(_HASH_CHUNK):
                digest.update(chunk)
                size += len(chunk)
        return size, digest.hexdigest()

    def clip_damage(self, clip_id: str) -> str | None:
        """Why committed clip ``clip_id`` cannot be trusted, or ``None`` when it can.

        Every file recorded at its commit (``clip_files``) must exist with the size and
        checksum it had then; each is hashed.
        """
        return self.checked_clip_files(clip_id, {})[0]

    def checked_clip_files(self, clip_id: str, known: Mapping[str, Hashed]
                           ) -> tuple[str | None, dict[str, Hashed]]:
        """:meth:`clip_damage`, hashing only the files whose stamps differ from ``known``.

        Returns
        -------
        damage : str or None
            Why the clip cannot be trusted, or ``None``.
        entries : dict
            The :class:`~handdb.store.stamps.Hashed` entries of its files that stand after
            the check (none when the clip is damaged, or the database is not local).
        """
        record_path = self.relative(self.partition_path(FILES_TABLE, clip_id))
        try:
            record = self.read(FILES_TABLE, clip_id)
        except DamagedFileError:
            return f"the record of its files, {record_path}, is damaged", {}
        if record is None:
            return f"the record of its files, {record_path}, is missing", {}
        rows = record.to_pydict()
        entries: dict[str, Hashed] = {}
        for file, size, sha256 in zip(rows["file"], rows["bytes"], rows["sha256"], strict=True):
            path = self.path(file)
            if not self.fs.isfile(path):
                return f"{file} is missing", {}
            if self.fs.size(path) != size:
                return f"{file} is damaged (it has changed size since the clip was committed)", {}
            digest, entry = self._stamped_digest(file, known)
            if digest != sha256:
                return f"{file} is damaged (its checksum differs from the commit's)", {}
            if entry is not None:
                entries[entry_key(entry.files)] = entry
        return None, entries

    def _stamped_digest(self, relative: str, known: Mapping[str, Hashed]
                        ) -> tuple[str, Hashed | None]:
        """SHA-256 of the file at ``relative``, from ``known`` while its stamp is unchanged.

        Also its entry, when it stands (only local files have stamps).
        """
        if not self.is_local:
            return self._fingerprint(relative)[1], None
        path = [self.path(relative)]
        digest = known_digest(known, path)
        if digest is not None:
            return digest, known[entry_key(path)]
        before, stamped = time.time_ns(), [stamp(path[0])]
        digest = self._fingerprint(relative)[1]
        return digest, entry_if_settled(path, stamped, digest, before)

    def stamps(self) -> dict[str, Hashed]:
        """The entries kept in the database folder (:mod:`handdb.store.stamps`)."""
        return load_stamps(self.path(STAMPS_FILE)) if self.is_local else {}

    def keep_stamps(self, entries: Mapping[str, Hashed]) -> None:
        """Keep ``entries`` in the database folder, in place of those it held."""
        if self.is_local:
            save_stamps(self.path(STAMPS_FILE), entries)

    def clip_build_keys(self) -> dict[str, str]:
        """``clip_id -> build_key`` of every committed clip whose ``clips`` file reads."""
        committed = self.readable_rows("clips").select(["clip_id", "build_key"]).to_pydict()
        return dict(zip(committed["clip_id"], committed["build_key"], strict=True))

    def clip_stage_keys(self) -> dict[str, dict[str, str]]:
        """``clip_id -> {stage: key}`` of every committed clip whose ``clips`` file reads."""
        committed = self.readable_rows("clips").select(["clip_id", "stage_keys"]).to_pydict()
        return {clip_id: json.loads(keys) for clip_id, keys in
                zip(committed["clip_id"], committed["stage_keys"], strict=True)}

    def remove_temporaries(self) -> int:
        """Delete files left half-written by an interrupted build; return how many.

        Only the table folders of this database are listed: temporaries are written nowhere
        else.
        """
        leftovers = [self.checked(path) for table in tables.table_names()
                     for path in self.files_in(self.checked(self.path(table)), TMP_SUFFIX)]
        for path in leftovers:
            self.fs.rm(path)
        return len(leftovers)

    @contextlib.contextmanager
    def lock(self) -> Iterator[None]:
        """Hold the database's exclusive build lock.

        On a local database the lock is an OS file lock, released by the kernel even when
        the build is killed. On other filesystems it is a lock file created exclusively.

        The database folder is checked first (:meth:`check_writable`), and, once the lock
        is held, everything inside it (:meth:`check_links`).

        Raises
        ------
        DatabaseLockedError
            When another build holds the lock.
        DatabasePathError
            When the database folder cannot be used, or holds a symbolic link.
        """
        self.check_writable()
        path = self.checked(self.path(LOCK_FILE))
        if self.is_local:
            try:
                descriptor = os.open(path, os.O_RDWR | os.O_CREAT | _NO_FOLLOW, 0o644)
            except PermissionError:
                raise DatabasePathError(self._unwritable()) from None
            except OSError as exc:
                raise DatabasePathError(
                    f"cannot open the lock file {path} ({exc.strerror}): remove it; no "
                    "build is running when none holds it"
                ) from None
            with os.fdopen(descriptor, "r+") as fh:
                if not _try_lock(fh):
                    holder = _lock_holder(fh)
                    raise DatabaseLockedError(
                        f"database {self.url} is being built by {holder}; wait for that "
                        "build to finish, then run again"
                    ) from None
                fh.seek(0)
                fh.truncate()
                fh.write(f"pid {os.getpid()} on {socket.gethostname()}")
                fh.flush()
                try:
                    self.check_links()
                    yield
                finally:
                    fh.seek(0)
                    fh.truncate()
                    _unlock(fh)
            return
        try:
            with self.fs.open(path, "xb") as fh:
                fh.write(f"pid {os.getpid()} on {socket.gethostname()}".encode())
        except FileExistsError:
            raise DatabaseLockedError(
                f"database {self.url} has a lock file {self.uri(LOCK_FILE)}: another build "
                "is running, or one was killed; remove the file if no build is running"
            ) from None
        try:
            yield
        finally:
            self.fs.rm(path)
