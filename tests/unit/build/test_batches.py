"""Batches of consecutive small clips: grouping, names, and clips run each on their own."""

from dataclasses import dataclass

import pytest

from handdb.build import batches as batching
from handdb.build.batches import BatchFailed, BatchRecorder, batch_name, batches, run_batch
from handdb.build.context import StageFailed


@dataclass(frozen=True)
class Clip:
    """A planned clip reduced to what grouping reads: its id and its input's bytes."""

    clip_id: str
    size: int


def grouped(sizes: list[int], in_flight: int, limit: int) -> list[list[str]]:
    clips = [Clip(f"c{i}", size) for i, size in enumerate(sizes)]
    found = batches(clips, in_flight, limit, size=lambda clip: clip.size)  # type: ignore[arg-type]
    return [[clip.clip_id for clip in batch] for batch in found]


def test_consecutive_small_clips_share_a_batch_up_to_the_byte_limit():
    assert grouped([3, 3, 3, 3, 3], in_flight=1, limit=7) == [["c0", "c1"], ["c2", "c3"], ["c4"]]


def test_a_large_clip_gets_a_batch_of_its_own():
    assert grouped([2, 2, 50, 2, 2], in_flight=1, limit=10) == \
        [["c0", "c1"], ["c2"], ["c3", "c4"]]


def test_a_small_build_keeps_a_batch_per_clip_in_flight():
    assert grouped([1] * 4, in_flight=4, limit=100) == [["c0"], ["c1"], ["c2"], ["c3"]]
    assert grouped([1] * 9, in_flight=4, limit=100) == \
        [["c0", "c1"], ["c2", "c3"], ["c4", "c5"], ["c6", "c7"], ["c8"]]


def test_every_clip_is_in_one_batch_in_order():
    sizes = [5, 1, 9, 2, 2, 30, 1, 1, 1, 7]
    assert sum(grouped(sizes, in_flight=2, limit=8), []) == [f"c{i}" for i in range(10)]


def test_a_batch_is_named_by_its_first_clip_and_how_many_follow():
    assert batch_name([Clip("alpha", 1)]) == "alpha"  # type: ignore[list-item]
    assert batch_name([Clip("alpha", 1), Clip("bravo", 1), Clip("c", 1)]) == \
        "alpha (+2)"  # type: ignore[list-item]


@pytest.fixture
def stages(monkeypatch):
    """``process_clip`` replaced: each clip's outcome is its id, ``broken`` clips fail."""
    broken: set[str] = set()
    ran: list[str] = []

    def process(item, context):
        ran.append(item.clip_id)
        if item.clip_id in broken:
            error = OSError("disk full")
            raise StageFailed(item.clip_id, "export", error) from error
        return f"result of {item.clip_id}"

    monkeypatch.setattr(batching, "process_clip", process)
    return broken, ran


def test_a_failing_clip_leaves_its_batch_mates_recorded_and_a_rerun_redoes_it_alone(stages):
    broken, ran = stages
    broken.add("b")
    recorded: list[tuple[str, str]] = []
    recorder = BatchRecorder(lambda item, outcome: recorded.append((item.clip_id, outcome)))
    batch = (Clip("a", 1), Clip("b", 1), Clip("c", 1))
    with pytest.raises(BatchFailed) as failed:
        run_batch(batch, None, recorder)  # type: ignore[arg-type]
    assert list(failed.value.failures) == ["b"]
    assert isinstance(failed.value.__cause__, OSError)
    assert recorded == [("a", "result of a"), ("c", "result of c")]

    broken.clear()
    assert run_batch(batch, None, recorder) == ["result of b"]  # type: ignore[arg-type]
    assert ran == ["a", "b", "c", "b"]
    assert recorded[-1] == ("b", "result of b")


def test_a_clip_is_recorded_once():
    recorded: list[str] = []
    recorder = BatchRecorder(lambda item, outcome: recorded.append(outcome))
    clip = Clip("a", 1)
    recorder(clip, "first")  # type: ignore[arg-type]
    recorder(clip, "again")  # type: ignore[arg-type]
    assert recorded == ["first"] and recorder.done(clip)  # type: ignore[arg-type]
