#!/usr/bin/env python3
"""A `cairn slam3d --gnss` run's ENU trajectory against the simulator's truth, inside the tunnel.

`cairn simulate tunnel-3d` writes the LiDAR's true poses in its world (poses.txt, at the scans'
times.txt) and the true antenna positions of its fixes in an ENU frame at the receiver's origin
(gnss/truth.csv; manifest.json gnss.origin and gnss.world_yaw_deg). The run's trajectory_enu.tum is
in the ENU frame at its first fix (gnss/fixes.csv's first row). This script puts both in the
receiver's frame (the world turned by world_yaw_deg and placed by the fixes' truth; the run's
origin moved to its first fix) and prints the worst horizontal and 3D error while the LiDAR is
inside the tunnel (manifest passage.inside_time_s) and the horizontal error at the end. The local
tangent-plane conversion of the first fix is good to centimetres over the simulated extent.
docs/lidar3d.md ("GNSS") tabulates it.

    cairn simulate tunnel-3d --seed 4 --set gnss.outlier_fraction=0.05 --out tunnel
    cairn slam3d tunnel/scans --times tunnel/times.txt --imu tunnel/imu0 --gnss tunnel/gnss/fixes.csv \\
        --no-loop-closure --out run
    python3 bench/tunnel_gnss_errors.py tunnel run
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

WGS84_A = 6378137.0
WGS84_E2 = 6.69437999014e-3


def fail(message: str) -> None:
    print(f"tunnel_gnss_errors: {message}", file=sys.stderr)
    sys.exit(1)


def load(path: Path, **kwargs) -> np.ndarray:
    try:
        return np.genfromtxt(path, **kwargs)
    except (OSError, ValueError) as e:
        fail(f"{path}: {e}")


def find(node, key):
    if isinstance(node, dict):
        if key in node:
            return node[key]
        node = list(node.values())
    if isinstance(node, list):
        for value in node:
            found = find(value, key)
            if found is not None:
                return found
    return None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sim", type=Path, help="a `cairn simulate tunnel-3d` output folder with gnss/")
    parser.add_argument("run", type=Path, help="a `cairn slam3d --gnss` output folder (trajectory_enu.tum)")
    args = parser.parse_args()

    try:
        manifest = json.loads((args.sim / "manifest.json").read_text())
    except (OSError, json.JSONDecodeError) as e:
        fail(f"{args.sim / 'manifest.json'}: {e}")
    origin, yaw_deg, inside = find(manifest, "origin"), find(manifest, "world_yaw_deg"), find(manifest, "inside_time_s")
    if origin is None or yaw_deg is None or inside is None:
        fail(f"{args.sim / 'manifest.json'}: expected gnss.origin, gnss.world_yaw_deg and passage.inside_time_s")
    poses = load(args.sim / "poses.txt")
    times = load(args.sim / "times.txt")
    truth = load(args.sim / "gnss" / "truth.csv", delimiter=",", skip_header=2, names=True)
    fixes = load(args.sim / "gnss" / "fixes.csv", delimiter=",", skip_header=2, names=True)
    run = load(args.run / "trajectory_enu.tum", comments="#", ndmin=2)
    if poses.ndim != 2 or poses.shape[1] != 12 or len(times) != len(poses) or run.shape[1] != 8:
        fail("expected poses.txt (12 columns) with one times.txt row per pose, and trajectory_enu.tum (8 columns)")

    # The world in the receiver's ENU frame: turned by world_yaw_deg, placed by the fixes' truth.
    a = np.radians(yaw_deg)
    R = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    p_world = poses[:, [3, 7, 11]]
    at_fixes = np.stack([np.interp(truth["time_s"], times, p_world[:, k]) for k in range(3)], axis=1)
    t_enu = np.mean(np.stack([truth["east_m"], truth["north_m"], truth["up_m"]], axis=1) - at_fixes @ R.T, axis=0)

    # The run's origin (its first fix) in the receiver's frame, on the local tangent plane.
    lat0 = np.radians(origin["latitude_deg"])
    n = WGS84_A / np.sqrt(1.0 - WGS84_E2 * np.sin(lat0) ** 2)
    m = n * (1.0 - WGS84_E2) / (1.0 - WGS84_E2 * np.sin(lat0) ** 2)
    first = fixes[0]
    offset = np.array([np.radians(first["lon_deg"] - origin["longitude_deg"]) * n * np.cos(lat0),
                       np.radians(first["lat_deg"] - origin["latitude_deg"]) * m,
                       first["alt_m"] - origin["altitude_m"]])

    estimate = run[:, 1:4] + offset
    true_enu = np.stack([np.interp(run[:, 0], times, p_world[:, k]) for k in range(3)], axis=1) @ R.T + t_enu
    horizontal = np.linalg.norm(estimate[:, :2] - true_enu[:, :2], axis=1)
    full = np.linalg.norm(estimate - true_enu, axis=1)
    in_tunnel = (run[:, 0] >= inside[0]) & (run[:, 0] <= inside[1])
    if not in_tunnel.any():
        fail("no pose of the run lies inside the tunnel's time")
    print(f"inside the tunnel ({inside[0]:.1f}-{inside[1]:.1f} s, {int(in_tunnel.sum())} poses): worst horizontal "
          f"{horizontal[in_tunnel].max():.2f} m, worst 3D {full[in_tunnel].max():.2f} m; at the end horizontal "
          f"{horizontal[-1]:.2f} m")


if __name__ == "__main__":
    main()
