"""perceive() from Python against `multicue perceive` (the demo scene's and an mOSD frame's
result.json)."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import multicue


def without_run_details(result):
    return {k: v for k, v in result.items() if k not in ("input", "timings_ms")}


def test_perceive_gives_what_the_cli_writes(cli, demo, tmp_path):
    scene = demo / "scene.pcd"
    subprocess.run([cli, "perceive", str(scene), "--out", str(tmp_path), "--no-report", "-q"],
                   check=True)
    expected = json.loads((tmp_path / "result.json").read_text())
    cloud = multicue.read(scene)
    result, objects, categories = multicue.perceive(cloud, input=str(scene))
    assert result["format"] == multicue.RESULT_FORMAT == "multicue.result/2"
    assert result["input"] == str(scene)
    assert len(result["objects"]) >= 3
    assert without_run_details(result) == without_run_details(expected)
    assert set(result["timings_ms"]) == set(expected["timings_ms"]) - {"load"}

    # The per-point arrays are labels.pcd's fields.
    labels = multicue.read(tmp_path / "labels.pcd")
    assert objects.dtype == np.uint32 and categories.dtype == np.uint8
    assert objects.shape == (len(cloud),)
    np.testing.assert_array_equal(objects, labels.labels)
    np.testing.assert_array_equal(objects, labels.extra_field("object"))
    np.testing.assert_array_equal(categories, labels.extra_field("category"))
    for o in result["objects"]:
        assert np.count_nonzero(objects == o["id"]) == o["points"]
        assert multicue.CATEGORIES[np.bincount(categories[objects == o["id"]]).argmax()] == \
            o["category"]


def test_perceive_of_an_mosd_frame_gives_what_the_cli_writes(cli, tmp_path):
    data = pathlib.Path(os.environ.get("MULTICUE_SHARED_DATA_DIR", ""))
    frame = data / "scans" / "mosd-learn" / "learn33.pcd"
    if not frame.exists():
        pytest.skip("the shared data (scans/mosd-learn) is not here")
    subprocess.run([cli, "perceive", str(frame), "--out", str(tmp_path), "--no-report", "-q"],
                   check=True)
    expected = json.loads((tmp_path / "result.json").read_text())
    result, objects, _ = multicue.perceive(multicue.read(frame), input=str(frame))
    assert len(result["objects"]) >= 3
    assert without_run_details(result) == without_run_details(expected)
    labels = multicue.read(tmp_path / "labels.pcd")
    np.testing.assert_array_equal(objects, labels.extra_field("object"))


def test_perceive_reads_a_configuration_dict(demo):
    cloud = multicue.read(demo / "scene.pcd")
    result, _, _ = multicue.perceive(cloud, {"clustering": {}, "threads": 1})
    assert result["support"] is not None
    with pytest.raises(multicue.InvalidArgument, match="clustering.bogus"):
        multicue.perceive(cloud, {"clustering": {"bogus": 1}})
    with pytest.raises(ValueError, match="dict"):
        multicue.perceive(cloud, "threads=1")


def test_perceive_refuses_an_empty_cloud():
    with pytest.raises(multicue.DataError):
        multicue.perceive(multicue.PointCloud())
