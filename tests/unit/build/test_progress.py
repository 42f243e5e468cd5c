"""Progress of a build: events as stages start, an ETA from the clips done, two displays."""

import io

import pytest
from rich.console import Console
from rich.progress import Progress

from handdb.build import BuildOptions, build_in_process, progress
from handdb.build.keys import STAGES
from handdb.cli.progress import LineProgress, LiveProgress, Tally, build_reporter, duration


class Clock:
    """A clock the test moves."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


class Recorder:
    """Every event, in order."""

    def __init__(self) -> None:
        self.events: list[tuple[str, ...]] = []

    def expect(self, n_clips: int) -> None:
        self.events.append(("expect", str(n_clips)))

    def started(self, clip_id: str, stage: str) -> None:
        self.events.append(("started", clip_id, stage))

    def finished(self, clip_id: str, outcome: str) -> None:
        self.events.append(("finished", clip_id, outcome))


def test_the_eta_is_the_pace_of_the_clips_done():
    assert progress.eta_seconds(30.0, 3, 6) == pytest.approx(60.0)
    assert progress.eta_seconds(30.0, 0, 6) is None
    assert progress.eta_seconds(30.0, 3, 0) == 0.0


def test_durations_read_as_a_person_says_them():
    assert [duration(s) for s in (4.4, 65, 3725)] == ["4 s", "1 min 05 s", "1 h 02 min"]


def test_the_tally_counts_unchanged_and_refused_clips_as_through_but_not_as_pace():
    clock = Clock()
    tally = Tally(clock)
    tally.expect(6)
    tally.finished("old", progress.UNCHANGED)
    assert tally.eta() is None and tally.status() == "1/6 clips"
    tally.started("a", "ingest")
    tally.started("bad", "ingest")
    tally.finished("bad", progress.REFUSED)
    assert tally.eta() is None
    clock.now += 10.0
    tally.started("a", "lift")
    assert tally.in_flight == {"a": "lift"}
    tally.finished("a", progress.DONE)
    # One clip processed in 10 s, three to go: 30 s.
    assert tally.eta() == pytest.approx(30.0)
    assert tally.status() == "3/6 clips, about 30 s left"


def test_plain_lines_name_the_stage_in_flight_and_carry_no_escape_codes():
    clock, stream = Clock(), io.StringIO()
    lines = LineProgress(stream, Tally(clock), clock)
    lines.expect(2)
    lines.finished("old", progress.UNCHANGED)
    lines.started("a", "lift")
    clock.now += 4.0
    lines.finished("a", progress.REFUSED)
    assert stream.getvalue().splitlines() == [
        "    0.0 s  build: 2 clips in the inbox",
        "    0.0 s  a: lifting to 3D",
        "    4.0 s  a: refused (2/2 clips)",
    ]


def test_the_live_display_shows_a_line_per_clip_in_flight():
    console = Console(file=io.StringIO(), force_terminal=True, width=120)
    with Progress(console=console, auto_refresh=False) as bar:
        live = LiveProgress(bar, Tally())
        live.expect(3)
        live.started("a", "ingest")
        live.started("b", "ingest")
        live.started("a", "gap_fill")
        shown = {task.description.strip(): task.fields["status"] for task in bar.tasks}
        assert shown == {"clips": "0/3 clips", "a": "gap filling",
                         "b": "reading the clip's files"}
        live.finished("a", progress.DONE)
        assert [task.description.strip() for task in bar.tasks] == ["clips", "b"]
        assert bar.tasks[0].completed == 1


def test_a_reporter_is_plain_lines_off_a_terminal():
    with build_reporter(Console(file=io.StringIO())) as reporter:
        assert isinstance(reporter, LineProgress)
    with build_reporter(Console(file=io.StringIO(), force_terminal=True)) as reporter:
        assert isinstance(reporter, LiveProgress)


def test_a_build_reports_each_stage_as_it_starts(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "alpha", seed=1)
    recorder = Recorder()
    with progress.reporting(recorder):
        build_in_process(inbox, str(tmp_path / "db"), BuildOptions(export_usd=False),
                         workers=1)
    assert recorder.events == [
        ("expect", "1"),
        *(("started", "alpha", stage) for stage in (*STAGES, "commit")),
        ("finished", "alpha", progress.DONE),
    ]


@pytest.mark.slow
def test_a_marker_clip_shows_its_model_fit_in_flight(tmp_path, dhg_sample):
    import json
    import shutil

    from tests.support.real_tools import SIDECAR_3D

    inbox = tmp_path / "inbox"
    inbox.mkdir()
    shutil.copy(dhg_sample, inbox / "dhg.dhg.txt")
    (inbox / "dhg.clip.json").write_text(json.dumps(SIDECAR_3D | {"skeleton": "dhg22"}))
    recorder = Recorder()
    with progress.reporting(recorder):
        build_in_process(inbox, str(tmp_path / "db"), BuildOptions(export_usd=False))
    stages = [event[2] for event in recorder.events if event[0] == "started"]
    assert stages[:2] == ["ingest", "model_fit"] and "lengths" not in stages
    assert recorder.events[-1] == ("finished", "dhg", progress.DONE)
