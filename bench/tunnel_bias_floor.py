#!/usr/bin/env python3
"""What the accelerometer's bias random walk alone costs along a tunnel's unobserved axis.

Where the LiDAR cannot see along the tunnel, only the IMU measures the motion along it. An
estimator that knew the accelerometer bias exactly when the LiDAR went blind, and held it there
(the best a causal estimator can do with a random walk: its expected future is its present
value), still ends off by the double integral of the bias' change over the blind stretch:

    e = integral_{t0}^{t1} integral_{t0}^{t} (b(s) - b(t0)) ds dt,   b the bias along the axis.

This script computes e from the simulator's exact ground truth (cairn simulate writes the true
biases in state_groundtruth_estimate0/data.csv, EuRoC's layout) for the blind stretch of a
LiDAR-inertial run (its longest run of scans whose registration was degenerate, inertial_states.csv).
The axis is the manifest's passage axis. docs/lidar3d.md ("LiDAR-inertial") tabulates it per seed.

    cairn simulate tunnel-3d --seed 3 --out tunnel3
    cairn slam3d tunnel3/scans --times tunnel3/times.txt --imu tunnel3/imu0 --no-loop-closure --out lio3
    python3 bench/tunnel_bias_floor.py tunnel3 lio3 [--json]
"""

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np


def fail(message: str) -> None:
    print(f"tunnel_bias_floor: {message}", file=sys.stderr)
    sys.exit(1)


def rotation_from_quaternion(w: float, x: float, y: float, z: float) -> np.ndarray:
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def blind_stretch(run: Path) -> tuple[float, float, int]:
    """The longest stretch of degenerate (IMU-carried) scans of the run, gaps of up to 1 s
    bridged: its first and last time and its number of degenerate scans."""
    path = run / "inertial_states.csv"
    if not path.is_file():
        fail(f"{path}: not found (the run must be `cairn slam3d ... --imu`)")
    times = []
    with path.open(newline="") as f:
        for line, row in enumerate(csv.DictReader(f), start=2):
            try:
                if int(row["degenerate"]) == 1:
                    times.append(float(row["time_s"]))
            except (KeyError, TypeError, ValueError):
                fail(f"{path}:{line}: expected the columns time_s and degenerate (0/1)")
    if not times:
        fail(f"{path}: no degenerate scan: the LiDAR never lost the axis, there is no blind stretch")
    best, start = (0, 0), 0
    for k in range(1, len(times) + 1):
        if k == len(times) or times[k] - times[k - 1] > 1.0:
            if times[k - 1] - times[start] >= times[best[1]] - times[best[0]]:
                best = (start, k - 1)
            start = k
    return times[best[0]], times[best[1]], best[1] - best[0] + 1


def passage_axis(sim: Path) -> np.ndarray:
    path = sim / "manifest.json"
    try:
        manifest = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as e:
        fail(f"{path}: {e}")

    def find(node):
        if isinstance(node, dict):
            if "passage" in node and isinstance(node["passage"], dict) and "axis_world" in node["passage"]:
                return node["passage"]["axis_world"]
            for value in node.values():
                found = find(value)
                if found is not None:
                    return found
        elif isinstance(node, list):
            for value in node:
                found = find(value)
                if found is not None:
                    return found
        return None

    axis = find(manifest)
    if axis is None or len(axis) != 3:
        fail(f"{path}: no passage.axis_world (not a tunnel or garage simulation?)")
    axis = np.asarray(axis, dtype=float)
    return axis / np.linalg.norm(axis)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sim", type=Path, help="a `cairn simulate` output folder (tunnel-3d, tunnel-spin-3d)")
    parser.add_argument("run", type=Path, help="a `cairn slam3d --imu` output folder on it")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()

    truth_path = args.sim / "state_groundtruth_estimate0" / "data.csv"
    try:
        truth = np.loadtxt(truth_path, delimiter=",", comments="#", ndmin=2)
    except (OSError, ValueError) as e:
        fail(f"{truth_path}: {e}")
    if truth.shape[1] < 17 or truth.shape[0] < 2:
        fail(f"{truth_path}: expected EuRoC's 17 columns and at least two rows")
    t = truth[:, 0] * 1e-9
    t0, t1, scans = blind_stretch(args.run)
    if not (t[0] <= t0 < t1 <= t[-1]):
        fail(f"the blind stretch {t0:.3f}-{t1:.3f} s lies outside the ground truth's {t[0]:.3f}-{t[-1]:.3f} s")
    axis_world = passage_axis(args.sim)
    inside = (t >= t0) & (t <= t1)
    # The bias (IMU frame) along the axis: b . (R_world_imu^T axis_world).
    bias = np.array([
        rotation_from_quaternion(*row[4:8]).T.dot(axis_world).dot(row[14:17]) for row in truth[inside]
    ])
    dt = np.diff(t[inside])
    change = bias - bias[0]
    velocity = np.concatenate([[0.0], np.cumsum(0.5 * (change[1:] + change[:-1]) * dt)])
    position = np.concatenate([[0.0], np.cumsum(0.5 * (velocity[1:] + velocity[:-1]) * dt)])
    result = {
        "blind_from_s": t0,
        "blind_to_s": t1,
        "degenerate_scans": scans,
        "bias_change_mps2": float(change[-1]),
        "floor_m": float(position[-1]),
    }
    if args.json:
        print(json.dumps(result))
    else:
        print(f"blind {t0:.2f}-{t1:.2f} s ({scans} degenerate scans): the accelerometer bias along the axis moved "
              f"{change[-1]:+.4f} m/s^2; holding it from the start of the stretch ends {position[-1]:+.2f} m off")


if __name__ == "__main__":
    main()
