"""handdb: a hand motion database.

Raw 2D hand keypoint tracks and X-ray bone measurements go in; clean 3D hand motion comes
out as Parquet tables queried with DuckDB, and as USD skeletal animation.

>>> import handdb
>>> con = handdb.connect("data/db")          # doctest: +SKIP
>>> con.sql("SELECT count(*) FROM joints_3d").fetchall()   # doctest: +SKIP
"""

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("handdb")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"

__all__ = ["__version__", "connect", "load_clip", "query"]

#: The public functions, imported on first use so that ``import handdb`` (and the command
#: line's start) does not load DuckDB and Arrow: name -> defining module.
_LAZY = {"connect": "handdb.store.query", "query": "handdb.store.query",
         "load_clip": "handdb.store.dataset"}


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'handdb' has no attribute {name!r}")
