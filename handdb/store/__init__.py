"""The store: Parquet tables under a folder or URL, checked against their contracts.

:class:`Store` reads and writes partitions atomically (:mod:`handdb.store.database`);
:mod:`handdb.store.tables` holds the Arrow contracts of ``schemas/tables``;
:func:`connect` and :func:`query` give DuckDB views over every table
(:mod:`handdb.store.query`); :mod:`handdb.store.quarantine` records refused inputs.
"""

from handdb.store.database import Store
from handdb.store.query import connect, query

__all__ = ["Store", "connect", "query"]
