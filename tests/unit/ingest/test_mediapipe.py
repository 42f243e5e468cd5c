import json

import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import mediapipe

IMAGE = {"width": 640, "height": 480}


def landmarks(x=0.5, y=0.25, extra=(0.0,)):
    return [[x, y, *extra]] * 21


def read_doc(tmp_path, spec_for, skeleton, doc, *, image=True):
    path = tmp_path / "clip.mediapipe.json"
    path.write_text(json.dumps(doc) if not isinstance(doc, str) else doc)
    spec = spec_for(tmp_path, image=IMAGE) if image else spec_for(tmp_path)
    return mediapipe.read(path, spec, skeleton)


def test_normalised_round_trip_scales_by_the_image_size(tmp_path, spec_for, mediapipe21,
                                                        noisy_track):
    uv, confidence = noisy_track
    path = tmp_path / "clip.mediapipe.json"
    mediapipe.write(path, uv, confidence, mediapipe21, image_size=(640, 480))
    assert json.loads(path.read_text())["coordinates"] == "normalized"
    obs = mediapipe.read(path, spec_for(tmp_path, image=IMAGE), mediapipe21)
    present = np.isfinite(uv[obs.frame, obs.joint]).all(axis=-1)
    np.testing.assert_allclose(obs.uv[present], uv[obs.frame, obs.joint][present], rtol=1e-12)
    np.testing.assert_array_equal(obs.confidence[present],
                                  confidence[obs.frame, obs.joint][present])
    np.testing.assert_array_equal(obs.confidence[~present], 0.0)
    assert obs.n_frames == uv.shape[0] and 3 not in obs.frame


def test_pixels_score_and_frames_without_a_hand(tmp_path, spec_for, mediapipe21):
    doc = {"coordinates": "pixels", "frames": [
        {"frame": 2, "handedness": "Right", "score": 0.8, "landmarks": landmarks(100, 200)},
        {"frame": 0, "landmarks": None},
        {"frame": 4},
    ]}
    obs = read_doc(tmp_path, spec_for, mediapipe21, doc, image=False)
    assert obs.n_frames == 5
    np.testing.assert_array_equal(obs.frame, 2)
    np.testing.assert_array_equal(obs.uv, [[100, 200]] * 21)
    np.testing.assert_array_equal(obs.confidence, 0.8)


def test_normalised_coordinates_without_image_size_point_at_the_sidecar(tmp_path, spec_for,
                                                                        mediapipe21):
    doc = {"frames": [{"frame": 0, "landmarks": landmarks()}]}
    with pytest.raises(InputError, match="need the image size") as info:
        read_doc(tmp_path, spec_for, mediapipe21, doc, image=False)
    assert info.value.file == str(tmp_path / "clip.clip.json")
    assert info.value.field == "image"


@pytest.mark.parametrize(("doc", "field", "message"), [
    ({"frames": [{"frame": 0, "landmarks": landmarks()[:20]}]}, "frames[0].landmarks",
     "has shape 20 x 3, expected 21 x N"),
    ({"frames": [{"frame": 0, "landmarks": landmarks(extra=())}]}, "frames[0].landmarks",
     "landmarks have 2 values"),
    ({"frames": [{"frame": 0, "landmarks": landmarks(x="a")}]}, "frames[0].landmarks",
     "list of numbers"),
    ({"frames": [{"frame": 0, "landmarks": landmarks(extra=(0.0, 2.0))}]},
     "frames[0].landmarks", r"visibility 2 is not in \[0, 1\] \(a logit\?\)"),
    ({"frames": [{"frame": 0, "score": "high", "landmarks": landmarks()}]}, "frames[0].score",
     "must be a finite number"),
    ({"frames": [{"frame": 0}, {"frame": -1}]}, "frames[1].frame", "whole number from 0"),
    ({"frames": [{"frame": 1.5}]}, "frames[0].frame", "whole number from 0"),
    ({"frames": [{"frame": 0}, {"frame": 0}]}, "frames[1].frame", "also frames\\[0\\]"),
    ({"frames": []}, "frames", "lists no frames"),
    ({"landmarks": []}, "frames", "with a 'frames' list"),
    ({"coordinates": "metres", "frames": [{"frame": 0}]}, "coordinates", "normalized, pixels"),
])
def test_bad_documents_name_the_json_path(tmp_path, spec_for, mediapipe21, doc, field, message):
    with pytest.raises(InputError, match=message) as info:
        read_doc(tmp_path, spec_for, mediapipe21, doc)
    assert info.value.file == str(tmp_path / "clip.mediapipe.json")
    assert info.value.field == field


def test_nan_literal_and_truncated_json(tmp_path, spec_for, mediapipe21):
    doc = json.dumps({"frames": [{"frame": 0, "landmarks": landmarks()}]}, indent=1)
    with pytest.raises(InputError, match="NaN or infinity"):
        read_doc(tmp_path, spec_for, mediapipe21, doc.replace("0.25", "NaN", 1))
    with pytest.raises(InputError, match="truncated") as info:
        read_doc(tmp_path, spec_for, mediapipe21, doc[: len(doc) // 2])
    assert info.value.line == doc[: len(doc) // 2].count("\n") + 1
