#!/usr/bin/env python3
"""Absolute pose error of an estimated trajectory against its ground truth, as `evo_ape -a`
(SE(3) Umeyama alignment, translation part), with a plot of both trajectories and of the error.

    python3 examples/python/evaluate_trajectory.py --out ape.png
    python3 examples/python/evaluate_trajectory.py --format tum \\
        --reference freiburg1_xyz-groundtruth.txt --estimate freiburg1_xyz-rgbdslam.txt --out ape.png

By default it evaluates ORB-SLAM on KITTI 00 from evo's test data, under $CAIRN_DATA_ROOT
(default: ../shared/data beside the repository); evo reports an RMSE of 1.3034 m for it.
"""

import argparse
import os
import pathlib

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import cairn  # noqa: E402

REPOSITORY = pathlib.Path(__file__).resolve().parents[2]
DATA_ROOT = pathlib.Path(os.environ.get("CAIRN_DATA_ROOT", REPOSITORY.parent / "shared" / "data"))
EVO_DATA = DATA_ROOT / "trajectories" / "trajectories-evo-testdata"


def parse_arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reference", default=str(EVO_DATA / "KITTI_00_gt.txt"), help="ground-truth trajectory")
    parser.add_argument("--estimate", default=str(EVO_DATA / "KITTI_00_ORB.txt"), help="estimated trajectory")
    parser.add_argument("--format", default="kitti", choices=["kitti", "tum", "euroc"],
                        help="format of both files (default: kitti, the default files' format)")
    parser.add_argument("--out", default="evaluate_trajectory.png", help="PNG to write (default: %(default)s)")
    return parser.parse_args()


def print_statistics(ape: "cairn.ApeResult") -> None:
    print(f"APE w.r.t. {ape.pose_relation} ({ape.unit}), {ape.alignment.method} alignment, "
          f"{len(ape.association)} of {ape.association.max_pairs} poses paired "
          f"{'by time' if ape.association.by_time else 'by index'}")
    for name in ("rmse", "mean", "median", "std", "min", "max", "sse"):
        print(f"  {name:8s}{ape.statistics[name]:14.6f}")


def widest_plane(positions: np.ndarray) -> tuple:
    """The two axes along which the reference extends most (x-z for KITTI's camera frame)."""
    extent = np.ptp(positions, axis=0)
    return tuple(sorted(np.argsort(extent)[-2:]))


def plot(ape: "cairn.ApeResult", path: str) -> None:
    reference = ape.reference[:, :3, 3]
    estimate = ape.estimate[:, :3, 3]
    a, b = widest_plane(reference)
    figure, (top, error) = plt.subplots(1, 2, figsize=(13, 5.5))

    top.plot(reference[:, a], reference[:, b], "--", color="grey", label="reference", zorder=3)
    path_plot = top.scatter(estimate[:, a], estimate[:, b], c=ape.errors, s=2, cmap="viridis",
                            label="estimate (aligned)")
    figure.colorbar(path_plot, ax=top, label=f"APE ({ape.unit})")
    top.set_xlabel("xyz"[a] + " (m)")
    top.set_ylabel("xyz"[b] + " (m)")
    top.set_aspect("equal", adjustable="datalim")
    top.legend(loc="best")
    top.set_title("trajectories")

    error.plot(ape.times, ape.errors, color="tab:blue", linewidth=0.8, label="APE")
    for name, style in (("rmse", "-"), ("mean", "--"), ("median", ":")):
        error.axhline(ape.statistics[name], color="tab:red", linestyle=style, label=name)
    error.set_xlabel("time since start (s)" if ape.association.by_time else "pose")
    error.set_ylabel(f"APE ({ape.unit})")
    error.legend(loc="upper left")
    error.set_title(f"APE w.r.t. {ape.pose_relation}, {ape.alignment.method} aligned")

    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def main() -> None:
    arguments = parse_arguments()
    reference = cairn.read_trajectory(arguments.reference, format=arguments.format)
    estimate = cairn.read_trajectory(arguments.estimate, format=arguments.format)
    # evo_ape -a: associate (by time when both have stamps), SE(3) Umeyama, translation error.
    ape = cairn.ape(reference, estimate, pose_relation="trans_part", align=True)
    print_statistics(ape)
    plot(ape, arguments.out)
    print(f"wrote {arguments.out}")


if __name__ == "__main__":
    main()
