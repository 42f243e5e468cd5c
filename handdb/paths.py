"""Where handdb finds its contracts (``schemas/``) and its default folders."""

from __future__ import annotations

from pathlib import Path

#: The contracts: skeleton topologies, table schemas, SQL views. The repository's top-level
#: ``schemas/`` folder, reached through the package (``handdb/schemas`` links to it in a
#: source tree; the wheel carries a copy), so that an installed handdb finds them too.
SCHEMAS_DIR = Path(__file__).resolve().parent / "schemas"

#: Default inbox of raw inputs, overridable by ``HANDDB_INBOX`` or ``--inbox``.
DEFAULT_INBOX = "./data/inbox"

#: Default database folder, overridable by ``HANDDB_DB`` or ``--db``.
DEFAULT_DB = "./data/db"
