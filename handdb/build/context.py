"""What every clip of a build shares, and how writing one fails.

Apart from :mod:`handdb.build.process` (which imports every stage, numba and scipy among
them) so that a build with nothing to do never loads the stages.
"""

from __future__ import annotations

from dataclasses import dataclass

import pyarrow as pa

from handdb.build.options import BuildOptions
from handdb.errors import HanddbError
from handdb.store.database import Store


@dataclass(frozen=True)
class BuildContext:
    """What every clip of a build shares: where it reads and writes, and how it computes."""

    inbox: str
    db: str
    options: BuildOptions
    ratios: pa.Table

    @property
    def store(self) -> Store:
        """The database."""
        return Store(self.db)


class StageFailed(HanddbError):
    """Writing a clip's results into the database failed: the build fails that clip.

    The database's storage is at fault (a full disk, a path that is a file), not the
    clip; the next build tries the clip again. The original error is the ``__cause__``;
    ``stage`` names where it happened.
    """

    def __init__(self, clip_id: str, stage: str, error: BaseException) -> None:
        self.clip_id = clip_id
        self.stage = stage
        super().__init__(f"{stage}: {type(error).__name__}: {error}")
