"""Filters, normals and segmentation from Python, against NumPy oracles."""

import numpy as np
import pytest

import multicue


def plane(n_side=40, z=1.0, spacing=0.01):
    u, v = np.meshgrid(np.arange(n_side), np.arange(n_side))
    return np.column_stack([u.ravel() * spacing, v.ravel() * spacing,
                            np.full(u.size, z)]).astype(np.float32)


def test_voxel_grid_gives_the_centroid_of_each_voxel():
    rng = np.random.default_rng(3)
    pts = rng.uniform(0, 0.1, size=(2000, 3)).astype(np.float32)
    out = multicue.voxel_grid(multicue.PointCloud(pts), leaf_size=0.05)
    inv = np.float32(1) / np.float32(0.05)  # voxel coordinates: floor(p * (1 / leaf)) in float
    keys = np.floor(pts * inv).astype(int)
    expected = {}
    for k in np.unique(keys, axis=0):
        expected[tuple(k)] = pts[np.all(keys == k, axis=1)].mean(axis=0)
    assert len(out) == len(expected)
    for p in out.points:
        k = tuple(np.floor(p * inv).astype(int))
        np.testing.assert_allclose(p, expected[k], atol=1e-5)


def test_voxel_grid_rejects_a_bad_leaf_size():
    with pytest.raises(multicue.InvalidArgument, match="leaf_size"):
        multicue.voxel_grid(multicue.PointCloud(plane()), leaf_size=-0.1)


def test_crop_box_matches_a_numpy_mask():
    pts = np.random.default_rng(4).uniform(-1, 1, size=(5000, 3)).astype(np.float32)
    pts[10] = np.nan
    cloud = multicue.PointCloud(pts)
    lo, hi = (-0.5, -0.2, 0.0), (0.5, 0.3, 0.9)
    inside = multicue.crop_box(cloud, lo, hi)
    mask = np.all((pts >= lo) & (pts <= hi), axis=1)
    np.testing.assert_array_equal(inside, np.flatnonzero(mask))
    outside = multicue.crop_box(cloud, lo, hi, negative=True)
    finite = np.all(np.isfinite(pts), axis=1)
    np.testing.assert_array_equal(outside, np.flatnonzero(finite & ~mask))
    assert len(multicue.select(cloud, inside)) == mask.sum()
    with pytest.raises(multicue.InvalidArgument, match="3 values"):
        multicue.crop_box(cloud, (0, 0), (1, 1, 1))


def test_remove_non_finite_and_outliers():
    pts = plane()
    pts = np.vstack([pts, [[5, 5, 5]], [[np.nan, 0, 0]]]).astype(np.float32)
    cloud = multicue.PointCloud(pts)
    finite = multicue.remove_non_finite(cloud)
    assert len(finite) == len(pts) - 1
    keep = multicue.statistical_outlier_removal(finite, k=8, std_ratio=2.0)
    assert len(pts) - 2 not in keep  # the far point
    assert len(keep) >= len(pts) - 2 - 50
    keep_r = multicue.radius_outlier_removal(finite, radius=0.02, min_neighbors=2)
    assert len(pts) - 2 not in keep_r
    assert len(keep_r) == len(pts) - 2  # every grid point has neighbours 1 cm away
    with pytest.raises(multicue.InvalidArgument):
        multicue.statistical_outlier_removal(finite, k=0)


def test_normals_of_a_plane_face_the_sensor():
    cloud = multicue.PointCloud(plane(z=1.0))
    undefined = multicue.estimate_normals(cloud, k=10)
    assert undefined == 0
    np.testing.assert_allclose(cloud.normals, np.tile([0, 0, -1], (len(cloud), 1)), atol=1e-4)
    np.testing.assert_allclose(cloud.curvature, 0, atol=1e-6)
    by_radius = cloud.copy()
    multicue.estimate_normals(by_radius, radius=0.025)
    np.testing.assert_allclose(by_radius.normals, cloud.normals, atol=1e-4)
    with pytest.raises(multicue.InvalidArgument):
        multicue.estimate_normals(cloud, k=2)
    with pytest.raises(multicue.InvalidArgument, match="organized"):
        multicue.estimate_normals(cloud, organized=True)


def test_support_plane_and_clusters_of_a_synthetic_table():
    # Camera convention (identity viewpoint): y points down, the table is the plane y = 0.5.
    rng = np.random.default_rng(5)
    table = np.column_stack([rng.uniform(-0.5, 0.5, 20000), np.full(20000, 0.5),
                             rng.uniform(1.0, 2.0, 20000)])
    box_a = rng.uniform([-0.3, 0.35, 1.2], [-0.2, 0.49, 1.3], size=(1500, 3))
    box_b = rng.uniform([0.2, 0.40, 1.6], [0.3, 0.49, 1.7], size=(800, 3))
    pts = np.vstack([table, box_a, box_b]).astype(np.float32)
    cloud = multicue.PointCloud(pts)
    s = multicue.find_support_plane(cloud)
    assert s["found"]
    np.testing.assert_allclose(s["plane"], [0, -1, 0, 0.5], atol=1e-3)
    assert set(range(20000)) <= set(s["inliers"].tolist()) | set(range(20000, len(pts)))
    assert len(s["inliers"]) >= 19000
    above = np.flatnonzero(pts[:, 1] < 0.49)
    clusters = multicue.euclidean_clustering(cloud, tolerance=0.02, subset=above,
                                             min_cluster_size=100)
    assert [len(c) for c in clusters] == [np.sum(above < 21500), np.sum(above >= 21500)]
    assert clusters[0].dtype == np.uint32
    with pytest.raises(multicue.InvalidArgument, match="tolerance"):
        multicue.euclidean_clustering(cloud, tolerance=0)


def test_empty_input_gives_empty_results():
    empty = multicue.PointCloud()
    assert len(multicue.voxel_grid(empty)) == 0
    assert len(multicue.crop_box(empty, (0, 0, 0), (1, 1, 1))) == 0
    assert multicue.euclidean_clustering(empty) == []
