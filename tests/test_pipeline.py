import pyarrow as pa

from handdb.build import stages as pipeline
from handdb.store.database import Store
from handdb.store.quarantine import Refusal


def test_a_refused_clip_passes_every_later_stage_unchanged(tmp_path):
    refusal = Refusal(file="a.clip.json", reason="no bone length", error_type="BoneLengthError",
                      field="bone_lengths", clip_id="a")
    options = pipeline.BuildOptions()
    stages = [
        lambda r: pipeline.resolve_bone_lengths(r, pa.table({})),
        lambda r: pipeline.fill(r, options),
        lambda r: pipeline.lift_clip(r, options),
        lambda r: pipeline.validate(r, options),
        lambda r: pipeline.export(r, Store(str(tmp_path / "db")), options),
    ]
    for stage in stages:
        assert stage(refusal) is refusal
    assert not (tmp_path / "db").exists()
