"""handdb: a hand motion database.

Raw 2D hand keypoint tracks and X-ray bone measurements go in; clean 3D hand motion comes
out as Parquet tables queried with DuckDB, and as USD skeletal animation.

>>> import handdb
>>> con = handdb.connect("data/db")          # doctest: +SKIP
>>> con.sql("SELECT count(*) FROM joints_3d").fetchall()   # doctest: +SKIP
"""

from importlib.metadata import PackageNotFoundError, version

from handdb.store.query import connect, query

try:
    __version__ = version("handdb")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"

__all__ = ["__version__", "connect", "query"]
