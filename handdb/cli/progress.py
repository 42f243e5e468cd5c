"""A build's progress on the terminal: a live display, or one plain line per event.

On a terminal, :class:`LiveProgress` draws a bar over the clips with an ETA, and one line
per clip in flight naming the stage it is in now. Anywhere else (a pipe, a log file, CI)
:class:`LineProgress` writes one plain line per stage started and per clip through, with
no cursor movement and no colour. :func:`build_reporter` picks one.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator
from typing import IO

from rich.console import Console
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn

from handdb.build import progress

#: Rich redraws of the live display per second.
REFRESH_PER_SECOND = 4


def duration(seconds: float) -> str:
    """``seconds`` as ``"42 s"``, ``"3 min 05 s"`` or ``"1 h 02 min"``."""
    seconds = round(seconds)
    if seconds < 60:
        return f"{seconds} s"
    minutes, seconds = divmod(seconds, 60)
    if minutes < 60:
        return f"{minutes} min {seconds:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"


class Tally:
    """What a display shows, from the build's events: clips through, in flight, the ETA.

    Safe to call from several threads (the stages run in worker threads).

    Parameters
    ----------
    clock
        Seconds, monotonic (:func:`time.monotonic`; a test passes its own).
    """

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._clock = clock
        self._lock = threading.Lock()
        self.n_clips = 0
        self.n_through = 0
        #: Clips that ran every stage (done or failed): the pace of the ETA.
        self.n_paced = 0
        self.first_start: float | None = None
        #: Clip id -> the stage it is in.
        self.in_flight: dict[str, str] = {}

    def expect(self, n_clips: int) -> None:
        """The build goes through ``n_clips`` clips."""
        self.n_clips = n_clips

    def started(self, clip_id: str, stage: str) -> None:
        """``clip_id`` starts ``stage``."""
        with self._lock:
            if self.first_start is None:
                self.first_start = self._clock()
            self.in_flight[clip_id] = stage

    def finished(self, clip_id: str, outcome: str) -> None:
        """``clip_id`` is through with ``outcome``."""
        with self._lock:
            self.in_flight.pop(clip_id, None)
            self.n_through += 1
            self.n_paced += outcome in (progress.DONE, progress.FAILED)

    def eta(self) -> float | None:
        """Seconds left at the pace of the clips processed so far (``None``: no pace yet)."""
        if self.first_start is None:
            return None
        return progress.eta_seconds(self._clock() - self.first_start, self.n_paced,
                                    self.n_clips - self.n_through)

    def status(self) -> str:
        """``"3/9 clips, about 1 min 10 s left"``."""
        text = f"{self.n_through}/{self.n_clips} clips"
        eta = self.eta()
        return text if eta is None or self.n_through == self.n_clips else (
            f"{text}, about {duration(eta)} left")


class LiveProgress:
    """The live display: a bar over the clips, and a line per clip in flight."""

    def __init__(self, bar: Progress, tally: Tally) -> None:
        self._bar = bar
        self._tally = tally
        self._main = bar.add_task("clips", total=None, status="planning")
        self._clips: dict[str, TaskID] = {}
        self._lock = threading.Lock()

    def expect(self, n_clips: int) -> None:
        """Size the bar to ``n_clips``."""
        self._tally.expect(n_clips)
        self._bar.update(self._main, total=n_clips, status=self._tally.status())

    def started(self, clip_id: str, stage: str) -> None:
        """Show ``clip_id``'s line with the stage it starts."""
        self._tally.started(clip_id, stage)
        with self._lock:
            if clip_id not in self._clips:
                self._clips[clip_id] = self._bar.add_task(f"  {clip_id}", total=None,
                                                          status="")
            task = self._clips[clip_id]
        self._bar.update(task, status=progress.STAGE_WORK[stage])

    def finished(self, clip_id: str, outcome: str) -> None:
        """Drop ``clip_id``'s line, move the bar, give the ETA."""
        self._tally.finished(clip_id, outcome)
        with self._lock:
            task = self._clips.pop(clip_id, None)
        if task is not None:
            self._bar.remove_task(task)
        self._bar.update(self._main, advance=1, status=self._tally.status())


class LineProgress:
    """One plain line per stage started and per clip through, for logs and pipes.

    Each line starts with the seconds since the build started. Clips found unchanged are
    not listed (there may be thousands; the summary counts them).
    """

    def __init__(self, stream: IO[str], tally: Tally,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self._stream = stream
        self._tally = tally
        self._clock = clock
        self._start = clock()
        self._lock = threading.Lock()

    def _line(self, text: str) -> None:
        """Write ``text`` after the seconds since the build started."""
        with self._lock:
            self._stream.write(f"{self._clock() - self._start:7.1f} s  {text}\n")
            self._stream.flush()

    def expect(self, n_clips: int) -> None:
        """Say how many clips the build goes through."""
        self._tally.expect(n_clips)
        self._line(f"build: {n_clips} clips in the inbox")

    def started(self, clip_id: str, stage: str) -> None:
        """Say which stage ``clip_id`` starts."""
        self._tally.started(clip_id, stage)
        self._line(f"{clip_id}: {progress.STAGE_WORK[stage]}")

    def finished(self, clip_id: str, outcome: str) -> None:
        """Say how ``clip_id`` ended, how far the build is and the ETA."""
        self._tally.finished(clip_id, outcome)
        if outcome != progress.UNCHANGED:
            self._line(f"{clip_id}: {outcome} ({self._tally.status()})")


@contextlib.contextmanager
def build_reporter(console: Console) -> Iterator[LiveProgress | LineProgress]:
    """The reporter for ``console``: live on a terminal, plain lines anywhere else."""
    tally = Tally()
    if not console.is_terminal:
        yield LineProgress(console.file, tally)
        return
    columns = (TextColumn("[bold]{task.description}"), BarColumn(),
               TextColumn("{task.fields[status]}"), TimeElapsedColumn())
    with Progress(*columns, console=console, transient=True,
                  refresh_per_second=REFRESH_PER_SECOND) as bar:
        yield LiveProgress(bar, tally)
