#!/usr/bin/python3
"""3D LiDAR SLAM driven from Python against `cairn slam3d` on the same scans, in one run (issue 39;
docs/benchmarks.md "cairn from Python").

The scans: the shared KITTI 00 key frames (DATA_ROOT/lidar3d/kitti00_keyframes, 110 scans), with
`--preset kitti --times keyframes.txt --times-column 4`. Alternately, --repeat times each:
  * CLI:    cairn slam3d KEY_FRAMES ... --out DIR         (its own outputs: trajectories, map.ply,
            map.png, report.json)
  * Python: cairn.scan_sequence + cairn.read_point_cloud + LidarSlam.add_scan per scan, finish(),
            then the poses saved with numpy  (the loop of examples/python/lidar_map.py)
Both are timed as whole processes (interpreter start and imports included), and also by their own
clock around the scans: the CLI's "N scans in T s" line and the Python loop's perf_counter. Checks
that the Python poses equal the CLI's trajectory.kitti (17 significant digits) exactly. Prints a Markdown table of medians.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/python_slam3d_vs_cli.py build/src/cairn/cli/cairn
       [--data DATA_ROOT] [--repeat 3]
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy

PYTHON_RUN = r'''
import sys, time, cairn, numpy
scans, times, out = sys.argv[1:4]
start = time.perf_counter()
sequence = cairn.scan_sequence(scans, times=times, times_column=4)
slam = cairn.LidarSlam(preset="kitti")
for path, stamp in sequence:
    slam.add_scan(cairn.read_point_cloud(path), stamp)
slam.finish()
loop_s = time.perf_counter() - start
numpy.save(out, slam.trajectory())
print(f"loop {loop_s:.3f}")
'''


def timed(command, env=None):
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        sys.exit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    return time.perf_counter() - start, done.stdout + done.stderr


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cli", help="the cairn executable")
    parser.add_argument("--data", default=os.environ.get("CAIRN_DATA_ROOT", "../shared/data"))
    parser.add_argument("--repeat", type=int, default=3)
    arguments = parser.parse_args()
    key_frames = os.path.join(arguments.data, "lidar3d", "kitti00_keyframes")
    scans, times = os.path.join(key_frames, "key_frames"), os.path.join(key_frames, "keyframes.txt")
    results = {"CLI": ([], []), "Python": ([], [])}
    with tempfile.TemporaryDirectory() as work:
        for _ in range(arguments.repeat):
            wall, text = timed([arguments.cli, "slam3d", scans, "--preset", "kitti", "--times", times,
                                "--times-column", "4", "--out", os.path.join(work, "cli"), "--overwrite"])
            loop = float(re.search(r"scans in ([0-9.]+) s", text).group(1))
            results["CLI"][0].append(wall)
            results["CLI"][1].append(loop)
            wall, text = timed([sys.executable, "-c", PYTHON_RUN, scans, times, os.path.join(work, "python.npy")])
            results["Python"][0].append(wall)
            results["Python"][1].append(float(re.search(r"loop ([0-9.]+)", text).group(1)))
        # trajectory.kitti holds 17 significant digits: parsed, it is the CLI's poses exactly.
        cli_poses = numpy.loadtxt(os.path.join(work, "cli", "trajectory.kitti")).reshape(-1, 3, 4)
        python_poses = numpy.load(os.path.join(work, "python.npy"))[:, :3, :]
        identical = cli_poses.shape == python_poses.shape and bool((cli_poses == python_poses).all())
    print(f"poses identical to the CLI's trajectory.kitti: {identical} ({len(cli_poses)} poses)")
    print("| run | process wall [s] (median of %d) | scans loop [s] (median) |" % arguments.repeat)
    print("|---|---|---|")
    for name, (walls, loops) in results.items():
        print(f"| {name} | {statistics.median(walls):.2f} | {statistics.median(loops):.2f} |")
    cli_loop, python_loop = (statistics.median(results[n][1]) for n in ("CLI", "Python"))
    print(f"Python loop / CLI loop: {python_loop / cli_loop:.3f}")
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
