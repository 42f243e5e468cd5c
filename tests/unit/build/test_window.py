"""The sliding window of clips in flight: a slow clip holds back no other."""

from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass

import pytest

from handdb.build.window import sliding_window


@dataclass(frozen=True)
class Job:
    """A simulated clip in flight: which, when it started and when it will end."""

    item: int
    started: float
    ends: float


class Workers:
    """As many workers as the window holds, on a simulated clock: each job takes its time."""

    def __init__(self, durations: dict[int, float]) -> None:
        self.durations = durations
        self.clock = 0.0
        self.started: dict[int, float] = {}
        self.most_in_flight = 0
        self._in_flight = 0

    def submit(self, item: int) -> Job:
        self.started[item] = self.clock
        self._in_flight += 1
        self.most_in_flight = max(self.most_in_flight, self._in_flight)
        return Job(item, self.clock, self.clock + self.durations[item])

    def next_done(self, jobs) -> Job:
        done = min(jobs, key=lambda job: (job.ends, job.item))
        self.clock = done.ends
        self._in_flight -= 1
        return done


def test_a_slow_clip_holds_back_no_other():
    # Clip 0 is a marker fit (100 s); the nine others take 1 s; four in flight.
    workers = Workers({0: 100.0, **{i: 1.0 for i in range(1, 10)}})
    finished = [(item, job.ends) for item, job in
                sliding_window(range(10), 4, workers.submit, workers.next_done)]
    # Fixed windows of four would start clips 4-7 only when clip 0 ends, at 100 s.
    assert all(workers.started[i] < 100.0 for i in range(1, 10))
    # Three slots stay free beside it: the nine short clips start at 0, 1 and 2 s.
    assert max(workers.started.values()) == 2.0
    assert finished[-1] == (0, 100.0)
    assert [item for item, _ in finished[:-1]] == list(range(1, 10))


def test_submission_order_and_limit():
    workers = Workers({i: float(10 - i) for i in range(6)})
    order = [item for item, _ in sliding_window(range(6), 2, workers.submit,
                                                workers.next_done)]
    assert sorted(order) == list(range(6))
    assert list(workers.started) == list(range(6))
    assert workers.most_in_flight == 2
    # Clip 1 (9 s) ends before clip 0 (10 s); clip 2 starts in its place at 9 s.
    assert order[0] == 1 and workers.started[2] == 9.0


@pytest.mark.parametrize("limit", [0, 1])
def test_a_window_of_one_runs_one_at_a_time(limit):
    workers = Workers(dict.fromkeys(range(3), 1.0))
    order = [item for item, _ in sliding_window(range(3), limit, workers.submit,
                                                workers.next_done)]
    assert order == [0, 1, 2] and workers.most_in_flight == 1


def test_it_drives_a_real_thread_pool():
    with ThreadPoolExecutor(max_workers=2) as pool:
        results = {item: future.result() for item, future in sliding_window(
            range(8), 3, lambda i: pool.submit(pow, i, 2),
            lambda futures: next(as_completed(futures)))}
    assert results == {i: i * i for i in range(8)}
