"""Readers and writers from Python: the same files as `cairn convert` / `cairn info` write and read,
and bad input raised as cairn.ParseError with the file and line."""

import subprocess

import numpy as np
import pytest

import cairn


def evo_file(data, name):
    return str(data / "trajectories" / "trajectories-evo-testdata" / name)


def test_tum_trajectory_written_as_the_cli_writes_it(data, cli, tmp_path):
    source = evo_file(data, "freiburg1_xyz-groundtruth.txt")
    trajectory = cairn.read_trajectory(source)
    assert len(trajectory) == trajectory.poses.shape[0] == trajectory.times.shape[0]
    # The first line of the file, read here with numpy: stamp tx ty tz qx qy qz qw.
    with open(source) as lines:
        fields = next(line for line in lines if not line.startswith("#")).split()
    first = np.array([float(f) for f in fields])
    seconds, fraction = fields[0].split(".")
    assert trajectory.stamps_ns[0] == int(seconds) * 10**9 + int(fraction.ljust(9, "0"))
    assert trajectory.times[0] == pytest.approx(first[0], abs=1e-6)
    np.testing.assert_allclose(trajectory.positions[0], first[1:4], atol=1e-12)
    np.testing.assert_allclose(trajectory.poses[0][:3, :3], cairn.SO3.from_quaternion(first[4:8]).matrix(), atol=1e-12)
    cairn.write_trajectory(str(tmp_path / "py.kitti"), trajectory, times=str(tmp_path / "py_times.txt"))
    subprocess.run([cli, "convert", source, str(tmp_path / "cli.kitti"), "--out-times",
                    str(tmp_path / "cli_times.txt")], check=True, capture_output=True)
    assert (tmp_path / "py.kitti").read_bytes() == (tmp_path / "cli.kitti").read_bytes()
    assert (tmp_path / "py_times.txt").read_bytes() == (tmp_path / "cli_times.txt").read_bytes()


def test_trajectory_from_arrays_round_trips_through_tum(tmp_path):
    poses = np.stack([cairn.SE3.exp([k, 0.5 * k, 0.0, 0.0, 0.0, 0.1 * k]).matrix() for k in range(5)])
    trajectory = cairn.Trajectory(poses, times=np.arange(5) * 0.1 + 1000.0)
    cairn.write_trajectory(str(tmp_path / "t.tum"), trajectory)
    back = cairn.read_trajectory(str(tmp_path / "t.tum"))
    np.testing.assert_allclose(back.poses, poses, atol=1e-9)
    np.testing.assert_array_equal(back.stamps_ns, trajectory.stamps_ns)


def test_kitti_poses_are_kept_as_written(data):
    trajectory = cairn.read_trajectory(evo_file(data, "KITTI_00_gt.txt"), format="kitti")
    rows = np.loadtxt(evo_file(data, "KITTI_00_gt.txt"), max_rows=3)
    np.testing.assert_array_equal(trajectory.poses[:3, :3, :].reshape(3, 12), rows)
    assert not trajectory.has_times()


def test_bad_trajectories_name_the_file_and_line(tmp_path):
    bad = tmp_path / "bad.tum"
    bad.write_text("1.0 0 0 0 0 0 0 1\n2.0 0 0 zero 0 0 0 1\n")
    with pytest.raises(cairn.ParseError) as error:
        cairn.read_trajectory(str(bad))
    assert error.value.file == str(bad) and error.value.line == 2
    assert str(bad) in str(error.value)
    with pytest.raises(ValueError, match=r"\(N, 4, 4\)"):
        cairn.Trajectory(np.zeros((3, 3, 3)))
    with pytest.raises(ValueError, match="one time"):
        cairn.Trajectory(np.broadcast_to(np.eye(4), (3, 4, 4)), times=[0.0, 1.0])
    with pytest.raises(ValueError, match="format"):
        cairn.read_trajectory(str(bad), format="csv")


def test_graphs_read_with_their_structure(data):
    graph = cairn.read_graph(str(data / "posegraph" / "se-sync" / "smallGrid3D.g2o"))
    assert graph.dimension == 3
    assert graph.poses.shape[1:] == (4, 4) and graph.poses.shape[0] == len(graph.ids)
    assert graph.edges.shape == (graph.measurements.shape[0], 2)
    assert graph.information.shape[1:] == (6, 6)
    np.testing.assert_allclose(graph.information, graph.information.transpose(0, 2, 1))
    toro = cairn.read_graph(str(data / "posegraph" / "toro" / "w100.graph"))
    assert toro.dimension == 2 and toro.information.shape[1:] == (3, 3)


def test_point_cloud_read_viewed_and_written(data, tmp_path):
    path = data / "lidar3d" / "kitti00_keyframes" / "key_frames" / "key_frame_0.pcd.xz"
    cloud = cairn.read_point_cloud(str(path))
    assert cloud.points.dtype == np.float32 and cloud.points.shape == (len(cloud), 3)
    assert not cloud.points.flags.writeable
    assert np.isfinite(cloud.points).all()
    cairn.write_point_cloud(str(tmp_path / "c.ply"), cloud)
    np.testing.assert_array_equal(cairn.read_point_cloud(str(tmp_path / "c.ply")).points, cloud.points)
    made = cairn.PointCloud(np.asarray(cloud.points, dtype=np.float64)[:10], intensity=np.arange(10))
    assert len(made) == 10 and made.intensity.dtype == np.float32
    with pytest.raises(ValueError, match="not finite"):
        cairn.PointCloud(np.array([[0.0, np.nan, 1.0]]))
    truncated = tmp_path / "t.pcd"
    truncated.write_bytes(b"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                          b"WIDTH 10\nHEIGHT 1\nPOINTS 10\nDATA binary\n" + bytes(20))
    with pytest.raises(cairn.ParseError) as error:
        cairn.read_point_cloud(str(truncated))
    assert error.value.file == str(truncated)


def test_bag_point_clouds_as_an_independent_writer_wrote_them(tmp_path):
    # Written by ROS's own python3-rosbag and sensor_msgs (Debian packages), read by cairn.
    rosbag = pytest.importorskip("rosbag")
    import genpy
    from sensor_msgs import point_cloud2
    from std_msgs.msg import Header

    rng = np.random.default_rng(7)
    clouds = [rng.uniform(-20, 20, size=(100 + 10 * k, 3)).astype(np.float32) for k in range(3)]
    path = tmp_path / "clouds.bag"
    with rosbag.Bag(str(path), "w") as bag:
        for k, points in enumerate(clouds):
            header = Header(stamp=genpy.Time(1000 + k, 250_000_000), frame_id="velodyne")
            bag.write("/points", point_cloud2.create_cloud_xyz32(header, points.tolist()), t=header.stamp)
    info = cairn.bag_info(str(path))
    assert [t["name"] for t in info["topics"]] == ["/points"]
    read = list(cairn.BagPointClouds(str(path), "/points"))
    assert [stamp for stamp, _ in read] == [(1000 + k) * 10**9 + 250_000_000 for k in range(3)]
    for (_, cloud), points in zip(read, clouds):
        np.testing.assert_array_equal(cloud.points, points)
    with pytest.raises(cairn.ParseError):
        cairn.BagPointClouds(str(path), "/missing")
    not_a_bag = tmp_path / "not.bag"
    not_a_bag.write_bytes(b"#ROSBAG V2.0\n" + bytes(10))
    with pytest.raises(cairn.ParseError) as error:
        cairn.bag_info(str(not_a_bag))
    assert error.value.file == str(not_a_bag)
