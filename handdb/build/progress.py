"""Progress reporting from the build to whoever is watching (the command line's display).

The build calls :func:`expect` once it knows how many clips there are, :func:`started` as
a clip *starts* each stage (so a display shows the stage in flight, not the last one done)
and :func:`finished` once per clip with how it ended; the command line installs a reporter
with :func:`reporting`. Without a reporter the calls cost nothing. Stages run in worker
threads, so a reporter must take calls from several threads at once.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Protocol

#: What each stage does, for messages.
STAGE_WORK: dict[str, str] = {
    "ingest": "reading the clip's files", "lengths": "estimating bone lengths",
    "gap_fill": "gap filling", "lift": "lifting to 3D", "validate": "validation",
    "export": "writing its USD and previews", "commit": "storing its tables",
    "model_fit": "fitting the hand model to its markers",
}

#: How a clip ended: processed and committed.
DONE = "done"
#: Nothing of the clip changed since the last build.
UNCHANGED = "unchanged"
#: Its input was refused (see the ``quarantine`` table).
REFUSED = "refused"
#: A stage failed on it (the database's storage; the next build tries again).
FAILED = "failed"


class Reporter(Protocol):
    """Receives progress events."""

    def expect(self, n_clips: int) -> None:
        """The build will go through ``n_clips`` clips."""

    def started(self, clip_id: str, stage: str) -> None:
        """``clip_id`` starts ``stage``, a key of :data:`STAGE_WORK`.

        A marker clip's model fit, which stands for three stages, is ``model_fit``.
        """

    def finished(self, clip_id: str, outcome: str) -> None:
        """``clip_id`` ended: ``outcome`` is DONE, UNCHANGED, REFUSED or FAILED."""


_reporter: Reporter | None = None


def expect(n_clips: int) -> None:
    """Tell the reporter, if any, how many clips the build will go through."""
    if _reporter is not None:
        _reporter.expect(n_clips)


def started(clip_id: str, stage: str) -> None:
    """Tell the reporter, if any, that ``clip_id`` starts ``stage``."""
    if _reporter is not None:
        _reporter.started(clip_id, stage)


def finished(clip_id: str, outcome: str) -> None:
    """Tell the reporter, if any, that ``clip_id`` ended with ``outcome``."""
    if _reporter is not None:
        _reporter.finished(clip_id, outcome)


def eta_seconds(elapsed: float, n_done: int, n_left: int) -> float | None:
    """Seconds until the last clip is through, at the pace of the clips done so far.

    Parameters
    ----------
    elapsed
        Seconds since the first clip started processing (start-up before it excluded).
    n_done
        Clips that ran every stage so far (unchanged clips, which cost a hash, and refused
        ones, most stopped at their first stage, would make the pace too quick).
    n_left
        Clips still to process.

    Returns
    -------
    float or None
        ``elapsed / n_done * n_left``: with several workers ``elapsed`` already holds
        their overlap; ``None`` until a clip is done.
    """
    if n_done <= 0:
        return None
    return elapsed / n_done * max(0, n_left)


@contextlib.contextmanager
def reporting(reporter: Reporter) -> Iterator[None]:
    """Install ``reporter`` for the duration of the block."""
    global _reporter
    previous, _reporter = _reporter, reporter
    try:
        yield
    finally:
        _reporter = previous
