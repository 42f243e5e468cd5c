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
it had not committed. A build holds an exclusive lock on the database while it writes.

Everything the store writes or removes lies inside the database folder. The folder itself
may be a symbolic link (the user chose where it lives), but nothing inside it may be one:
a build refuses a database holding a link (:class:`~handdb.errors.DatabasePathError`
naming it) before it writes anything, and no write or removal goes through one.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import uuid
from collections.abc import Iterator
from dataclasses import dataclass

import fsspec
import pyarrow as pa
import pyarrow.parquet as pq
from fsspec.implementations.local import LocalFileSystem

from handdb.errors import DatabaseLockedError, DatabasePathError, StoreError
from handdb.store import tables

#: Tables holding one file per clip; a clip commit replaces all of them.
CLIP_TABLES: tuple[str, ...] = tuple(
    name for name in tables.table_names() if tables.table_spec(name).partition == "clip"
)

LOCK_FILE = ".lock"

#: Bytes of the lock file that the OS lock covers on Windows (``msvcrt`` locks byte
#: ranges; a lock past the end of the file is allowed).
_WINDOWS_LOCK_SPAN = 1 << 20
PARQUET_SUFFIX = ".parquet"
TMP_SUFFIX = ".tmp"

#: ``os.open`` flag that refuses a symbolic link as the last part of a path (none on Windows,
#: where the lock file is checked before it is opened).
_NO_FOLLOW = getattr(os, "O_NOFOLLOW", 0)


def _try_lock(fh) -> bool:
    """Take an exclusive OS lock on the open file ``fh`` without waiting; ``False`` if held."""
    if os.name == "nt":
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


def _unlock(fh) -> None:
    """Release the lock :func:`_try_lock` took."""
    if os.name == "nt":
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
        return self._split()[0]

    @property
    def root(self) -> str:
        """The database location within :attr:`fs`."""
        return self._split()[1]

    def _split(self) -> tuple[fsspec.AbstractFileSystem, str]:
        fs, root = fsspec.core.url_to_fs(self.url)
        return fs, root.rstrip("/")

    @property
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
        data = tables.conform(table, data)
        self.makedirs(table)
        final = self.checked(self.partition_path(table, key))
        temp = f"{final}.{uuid.uuid4().hex}{TMP_SUFFIX}"
        with self.fs.open(temp, "wb") as fh:
            pq.write_table(data, fh, compression="zstd", write_statistics=True)
        if self.is_local:
            os.replace(temp, final)
        else:
            self.fs.mv(temp, final)
        return final

    def read(self, table: str, key: str) -> pa.Table | None:
        """Partition ``key`` of ``table``, or ``None`` when it does not exist."""
        path = self.partition_path(table, key)
        if not self.fs.exists(path):
            return None
        with self.fs.open(path, "rb") as fh:
            return pq.read_table(fh, schema=tables.schema(table))

    def read_table(self, table: str) -> pa.Table:
        """Every partition of ``table`` concatenated (an empty table when there is none)."""
        parts = []
        for path in self.table_files(table):
            with self.fs.open(path, "rb") as fh:
                parts.append(pq.read_table(fh, schema=tables.schema(table)))
        if not parts:
            return tables.empty(table)
        return pa.concat_tables(parts)

    def delete(self, table: str, key: str) -> None:
        """Remove partition ``key`` of ``table`` if it exists."""
        path = self.checked(self.partition_path(table, key))
        if self.fs.exists(path):
            self.fs.rm(path)

    def commit_clip(self, clip_id: str, clip_tables: dict[str, pa.Table]) -> None:
        """Replace every per-clip table of ``clip_id`` with ``clip_tables``.

        ``clip_tables`` must hold a ``clips`` row; per-clip tables it does not name are
        removed for this clip (a clip that lost its ground truth loses its ``truth_3d``).
        The ``clips`` row is written last: it marks the clip as complete.
        """
        if "clips" not in clip_tables:
            raise StoreError(f"commit of clip '{clip_id}' has no 'clips' row")
        unknown = sorted(set(clip_tables) - set(CLIP_TABLES))
        if unknown:
            raise StoreError(f"commit of clip '{clip_id}': {unknown} are not per-clip tables")
        conformed = {name: tables.conform(name, data) for name, data in clip_tables.items()}
        for name in CLIP_TABLES:
            if name == "clips":
                continue
            if name in conformed:
                self.write(name, clip_id, conformed[name])
            else:
                self.delete(name, clip_id)
        self.write("clips", clip_id, conformed["clips"])

    def clip_build_keys(self) -> dict[str, str]:
        """``clip_id -> build_key`` of every committed clip."""
        committed = self.read_table("clips").select(["clip_id", "build_key"]).to_pydict()
        return dict(zip(committed["clip_id"], committed["build_key"], strict=True))

    def clip_stage_keys(self) -> dict[str, dict[str, str]]:
        """``clip_id -> {stage: key}`` of every committed clip."""
        committed = self.read_table("clips").select(["clip_id", "stage_keys"]).to_pydict()
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
                    fh.seek(0)
                    holder = fh.read().strip() or "another process"
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
