"""The pipelines driven from Python (python/src/lidar3d.cpp, slam2d.cpp, vslam.cpp) against the `cairn` command.

Every expected value comes from the CLI's own output files for the same input (trajectories,
scans.csv, map.ply, map.pgm, report.json), never from the bindings: a Python loop that feeds the
same measurements must give the same numbers, exactly. The CLI writes numbers shortest-round-trip,
so Python's float() reads back the very doubles it held. Short stretches keep the file at a few
seconds.
"""

import json
import pathlib
import re
import subprocess
import threading

import numpy as np
import pytest

import cairn

KITTI_SCANS = 15  # the first KITTI 00 key frames (~1.5 s of slam3d)
ACES_SCANS = 300  # the first ACES scans (~48 s of the log)
KITTI_FRAMES = 8  # the first stereo frames of the KITTI extract
TUM_FRAMES = 6  # the first TUM fr1/desk frames (every 4th)


def run_cli(cli: str, *args) -> subprocess.CompletedProcess:
    result = subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, f"cairn {' '.join(map(str, args))} failed:\n{result.stderr}"
    return result


def read_numbers(path: pathlib.Path) -> list[list[float]]:
    """Whitespace-separated numbers per line, '#' lines skipped, read with Python's float()."""
    rows = []
    for line in path.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            rows.append([float(x) for x in line.split()])
    return rows


def read_kitti_poses(path: pathlib.Path) -> np.ndarray:
    """A KITTI trajectory file as N x 3 x 4."""
    return np.array(read_numbers(path), dtype=np.float64).reshape(-1, 3, 4)


def read_csv(path: pathlib.Path) -> list[dict[str, str]]:
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    return [dict(zip(header, line.split(","))) for line in lines[1:]]


def read_pgm(path: pathlib.Path) -> np.ndarray:
    """A binary PGM (P5, 8 bit) as rows of bytes."""
    data = path.read_bytes()
    match = re.match(rb"P5\s+(?:#[^\n]*\n\s*)*(\d+)\s+(\d+)\s+(\d+)\s", data)
    assert match, f"{path} is not a binary PGM"
    width, height = int(match.group(1)), int(match.group(2))
    return np.frombuffer(data[match.end():], dtype=np.uint8).reshape(height, width)


# ------------------------------------------------------------------------------------------------
# 3D LiDAR SLAM


@pytest.fixture
def kitti_keyframes(data) -> pathlib.Path:
    return data / "lidar3d" / "kitti00_keyframes"


def test_slam3d_from_python_gives_the_clis_trajectory_and_map(kitti_keyframes, cli, tmp_path):
    out = tmp_path / "cli"
    scans, times = kitti_keyframes / "key_frames", kitti_keyframes / "keyframes.txt"
    run_cli(cli, "slam3d", scans, "--preset", "kitti", "--times", times, "--times-column", 4,
            "--max-scans", KITTI_SCANS, "--out", out, "-q")

    sequence = cairn.scan_sequence(scans, times=times, times_column=4, max_scans=KITTI_SCANS)
    assert len(sequence) == KITTI_SCANS and sequence.times_from_file
    slam = cairn.LidarSlam(preset="kitti")
    results = [slam.add_scan(cairn.read_point_cloud(f), t) for f, t in sequence]
    slam.finish()

    poses = slam.trajectory()
    assert poses.shape == (KITTI_SCANS, 4, 4)
    np.testing.assert_array_equal(poses[:, :3, :], read_kitti_poses(out / "trajectory.kitti"))
    np.testing.assert_array_equal(poses[:, 3, :], np.tile([0.0, 0.0, 0.0, 1.0], (KITTI_SCANS, 1)))
    tum_times = [row[0] for row in read_numbers(out / "trajectory.tum")]
    np.testing.assert_allclose(slam.times(), tum_times, rtol=0, atol=5e-10)  # printed to 9 decimals

    report = json.loads((out / "report.json").read_text())
    assert slam.health() == [scan["health"] for scan in report["scans"]]
    assert [r.health for r in results] == slam.health()
    assert [r.segment for r in results] == [scan["segment"] for scan in report["scans"]]
    assert slam.summary["keyframes"] == report["loop_closure"]["keyframes"]
    assert slam.summary["loops_accepted"] == report["loop_closure"]["accepted"]
    config = slam.config()
    for section, keys in report["options"].items():  # the report leaves out the unused imu / gnss sections
        if isinstance(keys, dict):
            assert config[section] == keys, section

    map_points = slam.map_points()
    assert map_points.dtype == np.float32 and map_points.shape[1] == 3
    assert map_points.shape[0] == report["summary"]["map_points"]
    np.testing.assert_array_equal(map_points, cairn.read_point_cloud(str(out / "map.ply")).points)


def test_slam3d_from_arrays_equals_slam3d_from_point_clouds(kitti_keyframes, cli, tmp_path):
    # Each scan's odometry pose depends on the scans before it only: the CLI's first 6 scans.
    n = 6
    out = tmp_path / "cli"
    scans, times = kitti_keyframes / "key_frames", kitti_keyframes / "keyframes.txt"
    run_cli(cli, "slam3d", scans, "--preset", "kitti", "--times", times, "--times-column", 4,
            "--max-scans", n, "--no-loop-closure", "--out", out, "-q")
    slam = cairn.LidarSlam(preset="kitti", set={"loop_closure.enabled": False})
    for f, t in cairn.scan_sequence(scans, times=times, times_column=4, max_scans=n):
        points = np.ascontiguousarray(cairn.read_point_cloud(f).points, dtype=np.float64)  # any dtype goes in
        result = slam.add_scan(points, t)
        assert result.pose.shape == (4, 4)
    slam.finish()
    np.testing.assert_array_equal(slam.trajectory()[:, :3, :], read_kitti_poses(out / "trajectory.kitti"))


# ------------------------------------------------------------------------------------------------
# 2D LiDAR SLAM


def test_slam2d_from_python_gives_the_clis_trajectory_and_map(data, cli, tmp_path):
    log = data / "laser2d" / "aces" / "aces.clf.bz2"
    out = tmp_path / "cli"
    run_cli(cli, "slam2d", log, "--max-scans", ACES_SCANS, "--out", out, "-q")

    scans = cairn.read_carmen_log(log, max_scans=ACES_SCANS)
    assert len(scans) == ACES_SCANS and scans[0].tag == "FLASER"
    slam = cairn.Slam2d()
    for scan in scans:
        slam.add_scan(scan)
    slam.finish()

    rows = read_csv(out / "scans.csv")  # one row per scan, in log order
    expected = np.array([[float(r["x_m"]), float(r["y_m"]), float(r["theta_rad"])] for r in rows])
    np.testing.assert_array_equal(slam.trajectory(), expected)
    assert slam.health() == [r["health"] for r in rows]
    np.testing.assert_allclose(slam.times(), [float(r["time_s"]) for r in rows], rtol=0, atol=5e-10)
    report = json.loads((out / "report.json").read_text())
    assert slam.summary["keyframes"] == report["summary"]["keyframes"]

    # map.pgm: 0 occupied (p >= 0.65), 254 free (p <= 0.196), 205 unknown; the same cells.
    grid = slam.occupancy_grid()
    pgm = read_pgm(out / "map.pgm")
    p = grid.probability
    assert grid.resolution_m == pytest.approx(0.05)
    assert np.count_nonzero(p >= 0.65) == np.count_nonzero(pgm == 0)
    assert np.count_nonzero(p <= 0.196) == np.count_nonzero(pgm == 254)


def test_slam2d_from_arrays_equals_slam2d_from_log_records(data):
    scans = cairn.read_carmen_log(data / "laser2d" / "aces" / "aces.clf.bz2", max_scans=120)
    from_records, from_arrays = cairn.Slam2d(), cairn.Slam2d()
    for scan in scans:
        a = from_records.add_scan(scan)
        b = from_arrays.add_scan(scan.ranges, scan.angle_min, scan.angle_increment, scan.time,
                                 odometry=scan.odometry, max_range=scan.max_range)
        assert a.health == b.health
    np.testing.assert_array_equal(from_records.trajectory(), from_arrays.trajectory())


# ------------------------------------------------------------------------------------------------
# Visual SLAM


def test_vslam_stereo_from_python_gives_the_clis_trajectory(data, cli, tmp_path):
    folder = data / "visual" / "kitti_extract_seq2"
    out = tmp_path / "cli"
    run_cli(cli, "vslam", folder, "--max-frames", KITTI_FRAMES, "--out", out, "-q")

    sequence = cairn.read_image_sequence(folder)
    assert sequence.kind == "stereo" and sequence.layout == "kitti"
    slam = cairn.VisualSlam(sequence.calibration, "stereo", dataset="kitti")
    for k in range(KITTI_FRAMES):
        left = cairn.read_gray_image(sequence.images[k])
        right = cairn.read_gray_image(sequence.right_images[k])
        assert left.dtype == np.uint8 and left.ndim == 2
        result = slam.add_frame(left, right, sequence.times[k])
        assert result.health in ("ok", "degraded", "lost")
    poses = slam.trajectory()
    assert poses.shape == (KITTI_FRAMES, 4, 4)
    np.testing.assert_array_equal(poses[:, :3, :], read_kitti_poses(out / "trajectory.kitti"))
    report = json.loads((out / "report.json").read_text())
    assert slam.summary["frames_ok"] == report["summary"]["ok"]
    assert slam.summary["keyframes"] == report["summary"]["keyframes"]
    assert slam.map_points().shape == (report["summary"]["map_points"], 3)  # map_points.ply


def test_vslam_rgbd_with_depth_in_metres_gives_the_clis_trajectory(data, cli, tmp_path):
    folder = data / "visual" / "tum_fr1_desk_every4th"
    out = tmp_path / "cli"
    run_cli(cli, "vslam", folder, "--camera", "tum-fr1", "--max-frames", TUM_FRAMES, "--out", out, "-q")

    sequence = cairn.read_image_sequence(folder)
    assert sequence.kind == "rgbd"
    calibration = cairn.tum_calibration("tum-fr1")
    slam = cairn.VisualSlam(calibration, "rgbd", dataset=sequence.layout)
    for k in range(TUM_FRAMES):
        gray = cairn.read_gray_image(sequence.images[k])
        depth_m = cairn.read_depth_image(sequence.depth_images[k]) / calibration.depth_units_per_m
        slam.add_frame(gray, sequence.times[k], depth=depth_m)  # float metres: rounded back to the units
    np.testing.assert_array_equal(slam.trajectory()[:, :3, :], read_kitti_poses(out / "trajectory.kitti"))


def test_vslam_map_saved_from_python_localises_as_the_cli_does(data, cli, tmp_path):
    """VisualSlam.save_map writes a map `cairn vslam --localize-in` reads; VisualSlam.localize_in gives its poses exactly."""
    folder = data / "visual" / "kitti_extract_seq2"
    sequence = cairn.read_image_sequence(folder)
    slam = cairn.VisualSlam(sequence.calibration, "stereo", dataset="kitti")
    with pytest.raises(ValueError, match="no keyframe yet"):
        slam.save_map(tmp_path / "early.cvsm")
    for k in range(KITTI_FRAMES):
        slam.add_frame(cairn.read_gray_image(sequence.images[k]), cairn.read_gray_image(sequence.right_images[k]), sequence.times[k])
    slam.save_map(tmp_path / "map.cvsm")
    first = KITTI_FRAMES // 2
    out = tmp_path / "cli"
    run_cli(cli, "vslam", folder, "--localize-in", tmp_path / "map.cvsm", "--first-frame", first, "--max-frames", KITTI_FRAMES - first,
            "--out", out, "-q")
    localiser = cairn.VisualSlam.localize_in(tmp_path / "map.cvsm", dataset="kitti")
    assert localiser.localization_only and not slam.localization_only
    for k in range(first, KITTI_FRAMES):
        localiser.add_frame(cairn.read_gray_image(sequence.images[k]), cairn.read_gray_image(sequence.right_images[k]), sequence.times[k])
    np.testing.assert_array_equal(localiser.trajectory()[:, :3, :], read_kitti_poses(out / "trajectory.kitti"))
    assert localiser.summary["keyframes"] == 0
    assert localiser.keyframe_poses().shape == slam.keyframe_poses().shape


# ------------------------------------------------------------------------------------------------
# Bad input: an exception naming what is wrong, never a crash


def box_points(n: int = 2000, seed: int = 1) -> np.ndarray:
    """Points on the walls of a 20 x 10 x 4 m room around the sensor."""
    rng = np.random.default_rng(seed)
    p = rng.uniform([-10, -5, -2], [10, 5, 2], size=(n, 3))
    axis = rng.integers(0, 3, size=n)
    half = np.array([10.0, 5.0, 2.0])
    p[np.arange(n), axis] = np.sign(rng.uniform(-1, 1, size=n)) * half[axis]
    return p.astype(np.float32)


def test_lidar_slam_refuses_bad_arrays():
    slam = cairn.LidarSlam()
    with pytest.raises(ValueError, match="points"):
        slam.add_scan(np.zeros((10, 2)), 0.0)
    bad = box_points()
    bad[7, 1] = np.nan
    with pytest.raises(ValueError, match="points"):
        slam.add_scan(bad, 0.0)
    with pytest.raises(ValueError, match="point_times"):
        slam.add_scan(box_points(), 0.0, point_times=np.zeros(5))
    with pytest.raises(ValueError, match="ring"):
        slam.add_scan(box_points(), 0.0, ring=np.full(2000, -1))
    with pytest.raises(ValueError, match="time"):
        slam.add_scan(box_points(), float("nan"))
    assert len(slam) == 0


def test_lidar_slam_time_must_increase_and_the_run_goes_on():
    slam = cairn.LidarSlam()
    slam.add_scan(box_points(), 1.0)
    with pytest.raises(ValueError):
        slam.add_scan(box_points(), 1.0)
    with pytest.raises(ValueError):
        slam.add_scan(box_points(), 0.5)
    slam.add_scan(box_points(), 1.1)
    assert len(slam) == 2 and slam.trajectory().shape == (2, 4, 4)
    with pytest.raises(RuntimeError, match="finish"):
        slam.map_points()
    slam.finish()
    with pytest.raises(RuntimeError, match="finish"):
        slam.add_scan(box_points(), 1.2)


def test_unknown_config_keys_and_bad_values_are_named():
    with pytest.raises(ValueError, match="odometry.no_such_key"):
        cairn.LidarSlam(set={"odometry.no_such_key": 1})
    with pytest.raises(ValueError, match="voxel_size_m"):
        cairn.LidarSlam(set={"odometry.voxel_size_m": "many"})
    with pytest.raises(ValueError, match="invalid configuration"):
        cairn.LidarSlam(set={"odometry.voxel_size_m": -1.0})
    with pytest.raises(ValueError, match="front_end.no_such_key"):
        cairn.Slam2d(set={"front_end.no_such_key": 0.5})
    with pytest.raises(ValueError, match="orb.no_such_key"):
        cairn.VisualSlam(cairn.CameraCalibration(500, 500, 320, 240, baseline_m=0.1), set={"orb.no_such_key": 3})
    with pytest.raises(ValueError):  # cairn.ParseError is a ValueError
        cairn.LidarSlam(config="/nonexistent/slam3d.yaml")
    with pytest.raises(ValueError):
        cairn.LidarSlam(preset="no-such-preset")


def test_config_keys_apply_as_the_cli_applies_them():
    slam = cairn.LidarSlam(set={"odometry.voxel_size_m": 0.75, "loop_closure.enabled": False}, preset="kitti")
    config = slam.config()
    assert config["odometry"]["voxel_size_m"] == 0.75
    assert config["odometry"]["deskew"] == "off"  # from the kitti preset


def test_slam2d_refuses_bad_scans_and_takes_backward_time():
    slam = cairn.Slam2d()
    with pytest.raises(ValueError, match="ranges"):
        slam.add_scan(np.ones((2, 180)), -np.pi / 2, np.pi / 180, 0.0)
    ranges = np.full(180, 3.0)
    ranges[5] = np.nan
    with pytest.raises(ValueError, match="ranges"):
        slam.add_scan(ranges, -np.pi / 2, np.pi / 180, 0.0)
    with pytest.raises(ValueError, match="odometry"):
        slam.add_scan(np.full(180, 3.0), -np.pi / 2, np.pi / 180, 0.0, odometry=(0.0, 1.0))
    # inf / NaN with a max range: no-returns, as cairn reads a bag's LaserScan.
    ranges[5] = np.inf
    slam.add_scan(ranges, -np.pi / 2, np.pi / 180, 1.0, odometry=(0.0, 0.0, 0.0), max_range=30.0)
    # Intel's log goes backwards in time 631 times: the pipeline takes it.
    slam.add_scan(np.full(180, 3.0), -np.pi / 2, np.pi / 180, 0.5)
    assert slam.trajectory().shape == (2, 3)


def test_visual_slam_takes_imu_readings_and_refuses_bad_ones(data):
    # The API only: visual-inertial tracking itself is measured in C++ on rendered images with the
    # simulator's IMU (tests/vslam/test_visual_inertial.cpp); no real images with an IMU are here.
    camera = cairn.CameraCalibration(718.856, 718.856, 607.1928, 185.2157, baseline_m=0.5372)
    T_imu_camera = np.eye(4)
    T_imu_camera[:3, 3] = [0.05, 0.0, 0.0]
    calibration = data / "inertial" / "euroc_v1_01" / "mav0" / "imu0" / "sensor.yaml"
    slam = cairn.VisualSlam(camera, "stereo", imu=True, T_imu_camera=T_imu_camera, imu_calibration=calibration)
    assert slam.inertial == {"enabled": True, "initialised": False}
    slam.add_imu(0.0, [0.0, 0.0, 0.01], [0.0, 0.0, 9.81])
    times = np.arange(1, 11) * 0.005
    slam.add_imu(times, np.zeros((10, 3)), np.tile([0.0, 0.0, 9.81], (10, 1)))
    with pytest.raises(ValueError, match="not after the previous"):
        slam.add_imu(0.01, [0.0, 0.0, 0.0], [0.0, 0.0, 9.81])
    with pytest.raises(ValueError, match="not finite"):
        slam.add_imu(1.0, [np.nan, 0.0, 0.0], [0.0, 0.0, 9.81])
    with pytest.raises(ValueError, match="expected time"):
        slam.add_imu(times, np.zeros((9, 3)), np.zeros((10, 3)))
    with pytest.raises(ValueError, match="T_imu_camera"):
        cairn.VisualSlam(camera, "stereo", imu=True, T_imu_camera=np.eye(3))
    with pytest.raises(ValueError, match="go with imu=True"):
        cairn.VisualSlam(camera, "stereo", T_imu_camera=np.eye(4))
    with pytest.raises(ValueError, match="without imu=True"):
        cairn.VisualSlam(camera, "stereo").add_imu(0.0, [0.0, 0.0, 0.0], [0.0, 0.0, 9.81])
    assert cairn.VisualSlam(camera, "stereo").inertial == {"enabled": False, "initialised": False}
    assert slam.summary["frames_carried_by_imu"] == 0


def test_visual_slam_refuses_wrong_images():
    camera = cairn.CameraCalibration(718.856, 718.856, 607.1928, 185.2157, baseline_m=0.5372)
    slam = cairn.VisualSlam(camera, "stereo")
    gray = np.zeros((376, 1241), dtype=np.uint8)
    with pytest.raises(ValueError, match="left"):
        slam.add_frame(gray.astype(np.float32), gray, 0.0)
    with pytest.raises(ValueError, match="right"):
        slam.add_frame(gray, np.zeros((376, 1241, 3), dtype=np.uint8), 0.0)
    with pytest.raises(ValueError, match="stereo"):
        slam.add_frame(gray, 0.0)
    with pytest.raises(ValueError, match="kind"):
        cairn.VisualSlam(camera, "trinocular")
    with pytest.raises(ValueError, match="implausible"):
        cairn.VisualSlam(cairn.CameraCalibration(1e7, 1e7, 607, 185, baseline_m=0.5), "stereo").add_frame(gray, gray, 0.0)
    rgbd = cairn.VisualSlam(cairn.tum_calibration("tum-fr1"), "rgbd")
    with pytest.raises(ValueError, match="depth"):
        rgbd.add_frame(np.zeros((480, 640), dtype=np.uint8), 0.0)
    with pytest.raises(ValueError, match="depth"):
        rgbd.add_frame(np.zeros((480, 640), dtype=np.uint8), 0.0, depth=np.zeros((480, 640), dtype=np.int8))


def test_pipelines_run_in_threads_and_serialise_shared_calls():
    # add_scan releases the GIL; a LidarSlam shared between threads takes one call at a time.
    scans = [box_points(seed=seed) for seed in range(6)]
    one_thread = {"odometry.threads": 1}  # results independent of how TBB splits the work

    def feed(slam):
        for k, points in enumerate(scans):
            slam.add_scan(points, 0.1 * k)

    sequential = cairn.LidarSlam(set=one_thread)
    feed(sequential)
    a, b = cairn.LidarSlam(set=one_thread), cairn.LidarSlam(set=one_thread)
    threads = [threading.Thread(target=feed, args=(slam,)) for slam in (a, b)]
    for thread in threads:
        thread.start()
    while any(thread.is_alive() for thread in threads):
        assert a.trajectory().shape[1:] == (4, 4)  # reads between a's scans, never during one
    for thread in threads:
        thread.join()
    np.testing.assert_array_equal(a.trajectory(), sequential.trajectory())
    np.testing.assert_array_equal(b.trajectory(), sequential.trajectory())


def test_register_equals_the_cli(data, cli, tmp_path):
    """cairn.register and `cairn register --json` give the same transform on a KITTI pair."""
    frames = data / "lidar3d" / "kitti00_keyframes" / "key_frames"
    source, target = frames / "key_frame_21.pcd.xz", frames / "key_frame_20.pcd.xz"
    run_cli(cli, "register", source, target, "--global", "--json", tmp_path / "cli.json")
    expected = json.loads((tmp_path / "cli.json").read_text())
    result = cairn.register(cairn.read_point_cloud(str(source)), cairn.read_point_cloud(str(target)), global_=True)
    assert result["accepted"] and expected["accepted"]
    np.testing.assert_array_equal(np.array(result["T_target_source"]), np.array(expected["T_target_source"]))
    with pytest.raises(ValueError, match="method"):
        cairn.register(cairn.read_point_cloud(str(source)), cairn.read_point_cloud(str(target)), method="ndt")


def test_lidar_inertial_slam_equals_the_cli_with_imu(cli, tmp_path):
    """LidarSlam(imu=...) gives `cairn slam3d --imu`'s trajectory on the first 40 scans of the simulated tunnel."""
    sim = tmp_path / "tunnel"
    run_cli(cli, "simulate", "tunnel-3d", "--seed", "1", "-q", "--out", sim)
    scans = 40
    run_cli(cli, "slam3d", sim / "scans", "--times", sim / "times.txt", "--max-scans", scans, "--no-loop-closure",
            "--imu", sim / "imu0", "-q", "--out", tmp_path / "cli")
    slam = cairn.LidarSlam(set={"loop_closure.enabled": False}, imu=str(sim / "imu0"))
    assert slam.has_imu
    for path, stamp in cairn.scan_sequence(str(sim / "scans"), times=str(sim / "times.txt"), max_scans=scans):
        slam.add_scan(cairn.read_point_cloud(path), stamp)
    slam.finish()
    np.testing.assert_array_equal(slam.trajectory()[:, :3, :], read_kitti_poses(tmp_path / "cli" / "trajectory.kitti"))
    with pytest.raises(ValueError, match="go with imu"):
        cairn.LidarSlam(imu_time_offset=0.1)
    with pytest.raises(cairn.ParseError):
        cairn.LidarSlam(imu=str(tmp_path / "no_such_imu.csv"))


def test_localize3d_from_python_equals_the_cli(kitti_keyframes, cli, tmp_path):
    """A map saved by LidarSlam.save_map serves `cairn localize3d`, and Localizer3d gives its poses exactly."""
    scans, times = kitti_keyframes / "key_frames", kitti_keyframes / "keyframes.txt"
    sequence = list(cairn.scan_sequence(scans, times=times, times_column=4, max_scans=KITTI_SCANS))
    slam = cairn.LidarSlam(preset="kitti")
    for path, stamp in sequence:
        slam.add_scan(cairn.read_point_cloud(path), stamp)
    with pytest.raises(RuntimeError, match="finish"):
        slam.save_map(tmp_path / "early.c3dm")
    slam.finish()
    slam.save_map(tmp_path / "map.c3dm")
    # Scans 8-14 of the mapped stretch, as files given one by one, with their KITTI times.
    files = [path for path, _ in sequence[8:]]
    (tmp_path / "times.txt").write_text("".join(f"{stamp!r}\n" for _, stamp in sequence[8:]))
    run_cli(cli, "localize3d", *files, "--map", tmp_path / "map.c3dm", "--times", tmp_path / "times.txt",
            "--out", tmp_path / "cli", "-q")
    rows = read_csv(tmp_path / "cli" / "scans.csv")
    localizer = cairn.Localizer3d(tmp_path / "map.c3dm")
    for (path, stamp), row in zip(sequence[8:], rows):
        result = localizer.add_scan(cairn.read_point_cloud(path), stamp)
        assert result["localised"] == (row["localised"] == "1")
        assert result["health"] == row["health"]
        if result["localised"]:
            pose = result["pose"]
            np.testing.assert_array_equal(pose[:3, 3], [float(row["x"]), float(row["y"]), float(row["z"])])
    assert len(localizer) == len(rows) == len(files)
    poses, stamps = localizer.trajectory()
    assert poses.shape[0] == stamps.shape[0] >= len(files) - 2  # relocalised within the first 3 scans
    assert localizer.report()["summary"]["localised"] == poses.shape[0]
    # The same with an odometry step on every tracked scan.
    run_cli(cli, "localize3d", *files, "--map", tmp_path / "map.c3dm", "--times", tmp_path / "times.txt",
            "--out", tmp_path / "cli_odometry", "-q", "--odometry-while-tracking")
    rows = read_csv(tmp_path / "cli_odometry" / "scans.csv")
    localizer = cairn.Localizer3d(tmp_path / "map.c3dm", odometry_while_tracking=True)
    for (path, stamp), row in zip(sequence[8:], rows):
        result = localizer.add_scan(cairn.read_point_cloud(path), stamp)
        assert result["localised"] == (row["localised"] == "1")
        if result["localised"]:
            np.testing.assert_array_equal(result["pose"][:3, 3], [float(row["x"]), float(row["y"]), float(row["z"])])
    assert localizer.report()["options"]["odometry_while_tracking"] is True
    assert all(row["odometry_health"] != "not run" for row in rows)
    (tmp_path / "cut.c3dm").write_bytes((tmp_path / "map.c3dm").read_bytes()[:1000])
    with pytest.raises(cairn.ParseError, match="cut.c3dm"):
        cairn.Localizer3d(tmp_path / "cut.c3dm")
