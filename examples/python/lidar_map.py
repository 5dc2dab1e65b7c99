#!/usr/bin/env python3
"""3D LiDAR SLAM from Python on KITTI 00's key frames, and the map seen from above with the
trajectory on top, coloured by health.

    python3 examples/python/lidar_map.py --out map.png
    python3 examples/python/lidar_map.py --scans 40 --out map40.png

The loop feeds exactly what `cairn slam3d KEY_FRAMES --preset kitti --times keyframes.txt
--times-column 4` feeds, so the trajectory and map are that command's. The data is read under
$CAIRN_DATA_ROOT (default: ../shared/data beside the repository).
"""

import argparse
import collections
import os
import pathlib
import time

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import cairn  # noqa: E402

REPOSITORY = pathlib.Path(__file__).resolve().parents[2]
DATA_ROOT = pathlib.Path(os.environ.get("CAIRN_DATA_ROOT", REPOSITORY.parent / "shared" / "data"))
KEY_FRAMES = DATA_ROOT / "lidar3d" / "kitti00_keyframes"
HEALTH_COLOURS = {"ok": "tab:blue", "degraded": "tab:orange", "lost": "tab:red"}


def parse_arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scans", default=str(KEY_FRAMES / "key_frames"), help="folder of scans (default: KITTI 00 key frames)")
    parser.add_argument("--times", default=str(KEY_FRAMES / "keyframes.txt"), help="table of scan times (default: %(default)s)")
    parser.add_argument("--times-column", type=int, default=4, help="1-based column of --times (default: %(default)s)")
    parser.add_argument("--max-scans", type=int, default=0, help="process only the first N scans (default: all)")
    parser.add_argument("--preset", default="kitti", help="starting configuration, default or kitti (default: %(default)s)")
    parser.add_argument("--out", default="map.png", help="PNG to write (default: %(default)s)")
    return parser.parse_args()


def run(arguments: argparse.Namespace) -> tuple:
    """Feeds every scan; returns the finished LidarSlam, each scan's result and the wall time."""
    sequence = cairn.scan_sequence(arguments.scans, times=arguments.times, times_column=arguments.times_column,
                                   max_scans=arguments.max_scans)
    slam = cairn.LidarSlam(preset=arguments.preset)
    results = []
    start = time.perf_counter()
    for k, (path, stamp) in enumerate(sequence):
        result = slam.add_scan(cairn.read_point_cloud(path), stamp)
        results.append(result)
        if k == 0 or result.health != results[-2].health:
            axis = f", degenerate along {result.degenerate_axis}" if result.degenerate_axis else ""
            print(f"[scan {k}, t = {stamp:.3f} s] {result.health}{axis}")
    slam.finish()
    return slam, results, time.perf_counter() - start


def print_summary(slam: "cairn.LidarSlam", results: list, wall_s: float) -> None:
    per_scan_ms = 1e3 * np.array([r.timings["total_s"] for r in results])
    counts = collections.Counter(r.health for r in results)
    summary = slam.summary
    print(f"{len(results)} scans in {wall_s:.1f} s (reading included); odometry per scan {np.median(per_scan_ms):.1f} ms "
          f"median, {per_scan_ms.mean():.1f} ms mean, {per_scan_ms.max():.1f} ms max")
    print(f"health: {counts['ok']} ok, {counts['degraded']} degraded, {counts['lost']} lost; "
          f"{summary['map_segments']} map segment(s)")
    print(f"loop closure: {summary['keyframes']} keyframes, {len(summary['candidates'])} candidates verified, "
          f"{summary['loops_accepted']} accepted, {summary['loops_rejected_by_gnc']} rejected by GNC")


def plot(slam: "cairn.LidarSlam", path: str) -> None:
    points = slam.map_points()
    positions = slam.trajectory()[:, :3, 3]
    health = slam.health()
    figure, axes = plt.subplots(figsize=(10, 10))
    # Ground and low clutter faint, walls and trees dark: height clipped to the sensor's +-3 m.
    axes.scatter(points[:, 0], points[:, 1], c=np.clip(points[:, 2], -3, 3), s=0.05, cmap="Greys", linewidths=0)
    for k in range(1, len(positions)):
        axes.plot(positions[k - 1:k + 1, 0], positions[k - 1:k + 1, 1], color=HEALTH_COLOURS[health[k]], linewidth=2)
    for word, colour in HEALTH_COLOURS.items():
        axes.plot([], [], color=colour, linewidth=2, label=word)
    axes.plot(positions[0, 0], positions[0, 1], "o", color="black", label="start")
    axes.set_aspect("equal")
    axes.set_xlabel("x (m, first scan's frame)")
    axes.set_ylabel("y (m)")
    axes.set_title(f"cairn.LidarSlam: {len(points)} map points at {slam.map_voxel_m} m, {len(positions)} scans")
    axes.legend(loc="best")
    figure.tight_layout()
    figure.savefig(path, dpi=150)
    print(f"wrote {path}")


def main() -> None:
    arguments = parse_arguments()
    slam, results, wall_s = run(arguments)
    print_summary(slam, results, wall_s)
    plot(slam, arguments.out)


if __name__ == "__main__":
    main()
