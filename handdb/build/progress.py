"""Progress reporting from the build to whoever is watching (the CLI's progress bar).

The build calls :func:`expect` once it knows how many clips there are and
:func:`advance` as each clip passes a stage; the CLI installs a reporter with
:func:`reporting`. Without a reporter the calls cost nothing.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Protocol


class Reporter(Protocol):
    """Receives progress events."""

    def expect(self, n_clips: int) -> None:
        """The build will go through ``n_clips`` clips."""

    def advance(self, clip_id: str, stage: str) -> None:
        """``clip_id`` finished ``stage`` (``"commit"``, ``"unchanged"``, ``"refused"``...)."""


_reporter: Reporter | None = None


def expect(n_clips: int) -> None:
    """Tell the reporter, if any, how many clips the build will go through."""
    if _reporter is not None:
        _reporter.expect(n_clips)


def advance(clip_id: str, stage: str) -> None:
    """Tell the reporter, if any, that ``clip_id`` finished ``stage``."""
    if _reporter is not None:
        _reporter.advance(clip_id, stage)


@contextlib.contextmanager
def reporting(reporter: Reporter) -> Iterator[None]:
    """Install ``reporter`` for the duration of the block."""
    global _reporter
    previous, _reporter = _reporter, reporter
    try:
        yield
    finally:
        _reporter = previous
