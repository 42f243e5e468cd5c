"""Clip ids name files in the database: matched whole, and unique whatever the case."""

import pytest

from handdb.build import BuildOptions, build_in_process
from handdb.errors import InputError
from handdb.ingest.sidecar import validate_clip_id
from handdb.store.query import query

OPTIONS = BuildOptions(export_usd=False)


@pytest.mark.parametrize("clip_id", ["bad\n", "bad\r\n", "\nbad", "a/b", "..", "a..b", "-a",
                                     "x" * 129])
def test_a_clip_id_is_matched_whole(clip_id):
    with pytest.raises(InputError, match="is not allowed"):
        validate_clip_id(clip_id, "inbox/x.clip.json")


def test_two_inbox_clips_differing_only_in_case_are_refused(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "Fist", seed=1)
    write_clip(inbox, "fist", seed=2)
    write_clip(inbox, "wave", seed=3)
    summary = build_in_process(inbox, str(tmp_path / "db"), OPTIONS)
    assert summary.processed == ["wave"]
    refused = {(r.clip_id, r.field) for r in summary.refusals}
    assert refused == {("Fist", "clip_id"), ("fist", "clip_id")}
    assert all("'Fist' and 'fist' differ only in case" in r.reason for r in summary.refusals)


def test_an_inbox_clip_differing_only_in_case_from_a_stored_one_is_refused(tmp_path, write_clip):
    inbox, db = tmp_path / "inbox", str(tmp_path / "db")
    inbox.mkdir()
    write_clip(inbox, "Fist", seed=1)
    assert build_in_process(inbox, db, OPTIONS).processed == ["Fist"]
    for path in inbox.iterdir():
        path.rename(inbox / path.name.replace("Fist", "fist"))
    summary = build_in_process(inbox, db, OPTIONS)
    assert summary.processed == []
    [refusal] = summary.refusals
    assert refusal.clip_id == "fist" and refusal.field == "clip_id"
    assert refusal.file.endswith("fist.clip.json")
    assert "'fist' differs only in case from the clip 'Fist' stored" in refusal.reason
    stored = query(db, "SELECT clip_id FROM clips").to_pylist()
    assert stored == [{"clip_id": "Fist"}]
    assert query(db, "SELECT clip_id FROM quarantine").to_pylist() == [{"clip_id": "fist"}]
