"""multicue.PointCloud: NumPy views without copies, fields, files and errors."""

import numpy as np
import pytest

import multicue


def random_points(n, seed=0):
    return np.random.default_rng(seed).uniform(-1, 1, size=(n, 3)).astype(np.float32)


def test_points_are_a_view_of_the_cloud_storage():
    xyz = random_points(1000)
    cloud = multicue.PointCloud(xyz)
    view = cloud.points
    assert view.dtype == np.float32
    assert view.shape == (1000, 3)
    assert view.strides == (12, 4)
    assert not view.flags.owndata
    assert view.flags.writeable
    # Two views share one buffer: the C++ vector's.
    assert cloud.points.ctypes.data == view.ctypes.data
    np.testing.assert_array_equal(view, xyz)
    # Writing through the view changes the cloud (seen by a copy made in C++).
    view[7] = (1.5, 2.5, 3.5)
    np.testing.assert_array_equal(cloud.to_numpy()[7], (1.5, 2.5, 3.5))
    # The constructor copied: the source array is untouched.
    assert not np.shares_memory(xyz, view)


def test_a_view_keeps_its_cloud_alive():
    cloud = multicue.PointCloud(random_points(10))
    view = cloud.points
    expected = view.copy()
    del cloud
    np.testing.assert_array_equal(view, expected)


def test_to_numpy_is_an_owning_copy():
    cloud = multicue.PointCloud(random_points(20))
    copy = cloud.to_numpy()
    assert copy.flags.owndata
    copy[0] = 9
    assert cloud.points[0, 0] != 9


def test_assigning_points_copies_in_place_and_keeps_views():
    cloud = multicue.PointCloud(random_points(50))
    view = cloud.points
    cloud.points = np.zeros((50, 3))
    assert np.all(view == 0)
    # Another count is fine without other fields...
    cloud.points = random_points(5)
    assert len(cloud) == 5 and cloud.width == 5 and cloud.height == 1
    # ...but not with them.
    cloud.labels = np.arange(5, dtype=np.uint32)
    with pytest.raises(multicue.InvalidArgument, match="other fields"):
        cloud.points = random_points(6)


def test_fields_are_views_or_none():
    n = 8
    cloud = multicue.PointCloud(random_points(n), normals=np.tile([0, 0, 1], (n, 1)),
                                colors=np.full((n, 3), 200, np.uint8),
                                labels=np.arange(n, dtype=np.uint32))
    assert cloud.normals.strides == (12, 4)
    assert not cloud.normals.flags.owndata
    assert cloud.colors.shape == (n, 4)
    assert np.all(cloud.colors[:, 3] == 255)  # opaque when given r, g, b
    assert cloud.labels.dtype == np.uint32
    cloud.labels[3] = 42
    assert cloud.labels[3] == 42
    assert cloud.curvature is None and cloud.intensity is None
    cloud.intensity = np.linspace(0, 1, n)
    assert cloud.intensity.dtype == np.float32
    cloud.normals = None
    assert cloud.normals is None
    assert "labels" in repr(cloud)


def test_bad_shapes_raise_value_errors():
    with pytest.raises(multicue.InvalidArgument, match=r"shape \(N, 3\), got \(4, 2\)"):
        multicue.PointCloud(np.zeros((4, 2)))
    cloud = multicue.PointCloud(random_points(4))
    with pytest.raises(ValueError, match="labels"):
        cloud.labels = np.zeros(3, np.uint32)
    with pytest.raises(ValueError, match="normals has 2 rows"):
        cloud.normals = np.zeros((2, 3))
    with pytest.raises(ValueError, match="width \\* height"):
        cloud.set_organized(3, 2)
    assert issubclass(multicue.InvalidArgument, multicue.Error)


def test_organized_layout():
    cloud = multicue.PointCloud(random_points(6))
    cloud.set_organized(3, 2)
    assert cloud.is_organized and cloud.width == 3 and cloud.height == 2


@pytest.mark.parametrize("suffix,encoding", [(".pcd", "ascii"), (".pcd", "binary"),
                                             (".pcd", "compressed"), (".ply", "binary")])
def test_files_round_trip(tmp_path, suffix, encoding):
    n = 100
    cloud = multicue.PointCloud(random_points(n), normals=np.tile([0, 1, 0], (n, 1)),
                                colors=np.random.default_rng(1).integers(0, 255, (n, 3),
                                                                        dtype=np.uint8),
                                labels=np.arange(n, dtype=np.uint32))
    cloud.sensor_origin = (0.1, 0.2, 0.3)
    path = tmp_path / f"c{suffix}"
    multicue.write(path, cloud, encoding)
    back = multicue.read(str(path))
    np.testing.assert_allclose(back.points, cloud.points, rtol=1e-6)
    np.testing.assert_allclose(back.normals, cloud.normals)
    np.testing.assert_array_equal(back.colors, cloud.colors)
    np.testing.assert_array_equal(back.labels, cloud.labels)
    if suffix == ".pcd":
        np.testing.assert_allclose(back.sensor_origin, (0.1, 0.2, 0.3))


def test_extra_fields_of_a_file(tmp_path):
    path = tmp_path / "extra.pcd"
    path.write_text("VERSION 0.7\nFIELDS x y z temperature\nSIZE 4 4 4 2\nTYPE F F F U\n"
                    "COUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\n"
                    "DATA ascii\n0 0 0 300\n1 1 1 65000\n")
    cloud = multicue.read(path)
    assert cloud.extra_field_names == ["temperature"]
    t = cloud.extra_field("temperature")
    assert t.dtype == np.uint16
    np.testing.assert_array_equal(t, [300, 65000])
    with pytest.raises(KeyError):
        cloud.extra_field("pressure")


def test_bad_files_raise_io_errors(tmp_path):
    with pytest.raises(multicue.IoError, match="missing.pcd"):
        multicue.read(tmp_path / "missing.pcd")
    truncated = tmp_path / "truncated.pcd"
    truncated.write_bytes(b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                          b"WIDTH 10\nHEIGHT 1\nPOINTS 10\nDATA binary\n" + bytes(20))
    with pytest.raises(multicue.FormatError, match="truncated.pcd"):
        multicue.read(truncated)
    assert issubclass(multicue.FormatError, OSError)
    with pytest.raises(multicue.InvalidArgument, match="encoding|zip"):
        multicue.write(tmp_path / "x.pcd", multicue.PointCloud(random_points(3)), "zip")


def test_sequences_convert_and_other_objects_are_refused():
    cloud = multicue.PointCloud([[0, 0, 0], [1, 2, 3]])
    np.testing.assert_array_equal(cloud.points[1], (1, 2, 3))
    cloud.labels = [4, 5]
    np.testing.assert_array_equal(cloud.labels, (4, 5))
    assert len(multicue.select(cloud, [1])) == 1
    with pytest.raises(multicue.InvalidArgument, match="got a str"):
        multicue.PointCloud("points")
