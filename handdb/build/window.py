"""A sliding window of clips in flight: a new clip starts as soon as any one finishes.

Submitting clips in fixed windows and waiting for a whole window lets one slow clip (a
marker fit takes a minute) hold back every clip of the next window while the workers idle.
:func:`sliding_window` keeps at most ``limit`` clips in flight instead, whatever runs them:
the library's thread pool (:func:`~handdb.build.run.build_in_process`, with
:func:`concurrent.futures.as_completed`) or Prefect's task runner (``flows/build.py``, with
``prefect.futures.as_completed``). Bounding what is in flight bounds memory by the largest
clips held at once.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable, Iterator
from itertools import islice
from typing import TypeVar

T = TypeVar("T")
F = TypeVar("F")

#: Clips in flight per worker: each worker has its next clip queued as it finishes one,
#: and memory holds at most this many clips per worker.
IN_FLIGHT_PER_WORKER = 2


def sliding_window(items: Iterable[T], limit: int, submit: Callable[[T], F],
                   next_done: Callable[[Collection[F]], F]) -> Iterator[tuple[T, F]]:
    """Submit ``items`` in order, at most ``limit`` unfinished at once; yield each as it ends.

    Parameters
    ----------
    items
        What to submit, in the order to start it.
    limit
        Most items submitted and not yet yielded (at least 1).
    submit
        Starts one item and returns its future.
    next_done
        Given the futures in flight, waits until one is finished and returns it.

    Yields
    ------
    tuple
        ``(item, future)``, in the order they finished; the next item is submitted before
        each is yielded, so the workers stay busy while the caller records it.
    """
    queue = iter(items)
    in_flight: dict[F, T] = {submit(item): item for item in islice(queue, max(1, limit))}
    while in_flight:
        done = next_done(in_flight.keys())
        item = in_flight.pop(done)
        for following in islice(queue, 1):
            in_flight[submit(following)] = following
        yield item, done
