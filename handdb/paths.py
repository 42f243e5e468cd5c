"""Where handdb finds its contracts (``schemas/``) and its default folders."""

from __future__ import annotations

import os
from pathlib import Path

#: The repository's ``schemas/`` folder: skeleton topologies, table schemas, SQL views.
SCHEMAS_DIR = Path(
    os.environ.get("HANDDB_SCHEMAS", Path(__file__).resolve().parents[1] / "schemas"))

#: Default inbox of raw inputs, overridable by ``HANDDB_INBOX`` or ``--inbox``.
DEFAULT_INBOX = "./data/inbox"

#: Default database folder, overridable by ``HANDDB_DB`` or ``--db``.
DEFAULT_DB = "./data/db"


def default_inbox() -> str:
    """Return the inbox folder: ``$HANDDB_INBOX`` or ``./data/inbox``."""
    return os.environ.get("HANDDB_INBOX", DEFAULT_INBOX)


def default_db() -> str:
    """Return the database location: ``$HANDDB_DB`` or ``./data/db``."""
    return os.environ.get("HANDDB_DB", DEFAULT_DB)
