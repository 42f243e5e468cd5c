"""Consecutive small clips grouped into batches, so an orchestrator pays its cost per batch.

Prefect spends about 26 ms of CPU on each task it runs, which is as much as the stages of
a small clip. :func:`batches` groups the plan's clips to process, in order, into batches
of at most :data:`BATCH_BYTES` of input: a clip of 5000 frames or more is a batch of its
own, a batch of 300-frame clips holds about nine. The size of a clip's files stands for
its frames, which are not known before it is read. Batches are also kept at least as many
as the clips in flight, so that a small build still keeps every worker busy.
:class:`BatchRecorder` takes each clip's outcome as soon as its batch's worker has it,
and :func:`run_batch` runs a batch's clips, each on its own, skipping those already
recorded, so that running a batch again redoes only the clips that failed.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence

from handdb.build.context import BuildContext, StageFailed
from handdb.build.plan import PlannedClip
from handdb.build.process import process_clip
from handdb.build.stages import ClipResult
from handdb.ingest.inbox import clip_files
from handdb.store.quarantine import Refusal

#: Most bytes of input files in a batch of several clips, about nine clips of 300 frames
#: with their ground truth (0.86 MB each); a clip larger than this is a batch of its own.
BATCH_BYTES = 8 * 2**20

#: Clip ids a batch's name lists before counting the rest.
NAMED_CLIPS = 1

Outcome = ClipResult | Refusal | StageFailed


def clip_bytes(item: PlannedClip) -> int:
    """The size of ``item``'s input files, bytes."""
    return sum(file.stat().st_size for file in clip_files(item.entry))


def batches(todo: Sequence[PlannedClip], in_flight: int, limit: int = BATCH_BYTES,
            size: Callable[[PlannedClip], int] = clip_bytes) -> list[tuple[PlannedClip, ...]]:
    """Group ``todo``, in order, into batches of consecutive clips.

    Parameters
    ----------
    todo
        The clips to process, in the order to start them.
    in_flight
        The batches run at once; a batch holds at most ``len(todo) // in_flight`` clips,
        so that there are at least this many batches while there are as many clips.
    limit
        Most bytes of input in a batch of several clips.
    size
        The bytes of a clip's input.

    Returns
    -------
    list of tuple of PlannedClip
        Every clip of ``todo`` once, in order; a clip of more than ``limit`` bytes alone.
    """
    most_clips = max(1, len(todo) // max(1, in_flight))
    grouped: list[tuple[PlannedClip, ...]] = []
    batch: list[PlannedClip] = []
    batch_bytes = 0
    for item in todo:
        item_bytes = size(item)
        if batch and (batch_bytes + item_bytes > limit or len(batch) == most_clips):
            grouped.append(tuple(batch))
            batch, batch_bytes = [], 0
        batch.append(item)
        batch_bytes += item_bytes
    if batch:
        grouped.append(tuple(batch))
    return grouped


def batch_name(batch: Sequence[PlannedClip]) -> str:
    """The clips of ``batch`` for a task's name: ``clip_a`` or ``clip_a (+7)``."""
    named = ", ".join(item.clip_id for item in batch[:NAMED_CLIPS])
    rest = len(batch) - NAMED_CLIPS
    return f"{named} (+{rest})" if rest > 0 else named


class BatchFailed(StageFailed):
    """Writing some clips of a batch into the database failed; the others are recorded.

    ``failures`` holds each failed clip's :class:`StageFailed`; the first one's cause is
    this error's ``__cause__`` as well, so that a retry policy sees the ``OSError``.
    """

    def __init__(self, failures: dict[str, StageFailed]) -> None:
        first = next(iter(failures.values()))
        cause = first.__cause__ or first
        super().__init__(first.clip_id, first.stage, cause)
        self.__cause__ = cause
        self.failures = failures


class BatchRecorder:
    """Takes each clip's outcome, from any worker thread, as soon as it is known.

    ``record`` is called once per clip, under a lock, with the clip and its outcome (a
    result or a refusal; a stage failure is recorded by the caller once its batch is
    given up, see :func:`run_batch`).
    """

    def __init__(self, record: Callable[[PlannedClip, Outcome], None]) -> None:
        self._record = record
        self._lock = threading.Lock()
        self._done: set[str] = set()

    def done(self, item: PlannedClip) -> bool:
        """Whether ``item``'s outcome is recorded."""
        with self._lock:
            return item.clip_id in self._done

    def __call__(self, item: PlannedClip, outcome: Outcome) -> None:
        """Record ``item``'s ``outcome`` (once)."""
        with self._lock:
            if item.clip_id in self._done:
                return
            self._done.add(item.clip_id)
            self._record(item, outcome)


def run_batch(batch: Sequence[PlannedClip], context: BuildContext,
              recorder: BatchRecorder) -> list[Outcome]:
    """Process the clips of ``batch`` not yet recorded, each on its own, recording each.

    A clip's refusal or stage failure leaves the batch's other clips to run and commit.

    Returns
    -------
    list
        The outcome of each clip run, in order.

    Raises
    ------
    BatchFailed
        After every clip ran, when a stage failed on some (their outcomes are not
        recorded, so that running the batch again retries them alone).
    """
    outcomes: list[Outcome] = []
    failures: dict[str, StageFailed] = {}
    for item in batch:
        if recorder.done(item):
            continue
        try:
            outcome: Outcome = process_clip(item, context)
        except StageFailed as failure:
            failures[item.clip_id] = failure
            outcomes.append(failure)
            continue
        recorder(item, outcome)
        outcomes.append(outcome)
    if failures:
        raise BatchFailed(failures)
    return outcomes
