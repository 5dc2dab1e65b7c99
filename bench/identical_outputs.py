#!/usr/bin/env python3
"""Are two builds of cairn giving the same answers? Issue 36's check for refactors.

Runs the real-data jobs that a refactor of the pipelines must not change (slam2d on ACES, Intel
and MIT CSAIL; slam3d on the 110 KITTI 00 scans; vslam on KITTI stereo and TUM RGB-D; optimize
with GNC on a pose graph) and records a SHA-256 of every output file, except the ones that hold
wall-clock times. report.json is compared with its timing fields removed.

    python3 bench/identical_outputs.py build/src/cairn/cli/cairn --out /tmp/after [--against /tmp/before]

With --against, the two runs' digests are compared and every difference is printed; the exit
status is 1 if any output differs. Trajectories that differ are also compared numerically (largest
absolute difference of any column), for the case where an order of floating-point sums changed.
Standard library only; data from CAIRN_DATA_ROOT (default ../shared/data).
"""
import argparse
import csv
import hashlib
import json
import os
import shutil
import subprocess
import sys
import time

TIMING_KEYS = {"seconds", "wall_seconds", "time_s", "elapsed_s", "timing", "timings", "timers",
               "duration_s", "seconds_per_scan", "seconds_per_frame", "wall_time_s", "stage_seconds",
               "per_scan_ms", "per_frame_ms", "ms", "runtime"}


def is_timing(key):
    """Wall-clock fields: they differ from run to run of one build."""
    return (key in TIMING_KEYS or "second" in key or key.endswith("_ms") or "timer" in key
            or "timing" in key or (key.endswith("_s") and key != "time_s") or key == "time_s")


def strip_timings(node):
    if isinstance(node, dict):
        return {k: strip_timings(v) for k, v in node.items() if not is_timing(k)}
    if isinstance(node, list):
        return [strip_timings(v) for v in node]
    if isinstance(node, str) and OUT_PREFIX[0] and node.startswith(OUT_PREFIX[0]):
        return "<out>" + node[len(OUT_PREFIX[0]):]
    return node


OUT_PREFIX = [""]


def csv_without_timings(path):
    """A CSV's text without its wall-clock columns (names ending in _ms or _s, except time_s)."""
    with open(path, encoding="utf-8") as f:
        rows = list(csv.reader(f))
    if not rows:
        return b""
    keep = [i for i, name in enumerate(rows[0]) if not (name.endswith("_ms") or (name.endswith("_s") and name != "time_s"))]
    return "\n".join(",".join(row[i] for i in keep if i < len(row)) for row in rows).encode()


def jobs(data, out):
    laser = os.path.join(data, "laser2d")
    jobs = []
    for log in ("aces", "intel", "mit-csail"):
        jobs.append((f"slam2d-{log}", ["slam2d", f"{laser}/{log}/{log}.clf.bz2", "--out", f"{out}/slam2d-{log}"]))
    jobs.append(("slam2d-intel-map", ["slam2d", f"{laser}/intel/intel.clf.bz2", "--max-scans", "900",
                                      "--out", f"{out}/slam2d-intel-map", "--save-map", f"{out}/slam2d-intel-map.map"]))
    jobs.append(("localize2d-intel", ["localize2d", f"{laser}/intel/intel.clf.bz2", "--map", f"{out}/slam2d-intel-map.map",
                                      "--first-scan", "1200", "--max-scans", "400", "--out", f"{out}/localize2d-intel"]))
    jobs.append(("landmarks-sim", ["simulate", "landmarks", "--seed", "3", "--out", f"{out}/landmarks-sim", "-q"]))
    jobs.append(("landmarks-ekf", ["landmarks", f"{out}/landmarks-sim", "--association", "jcbb",
                                   "--spurious-fraction", "0.1", "--out", f"{out}/landmarks-ekf", "-q"]))
    jobs.append(("landmarks-graph", ["landmarks", f"{out}/landmarks-sim", "--method", "graph", "--association", "nn",
                                     "--out", f"{out}/landmarks-graph", "-q"]))
    kitti3d = os.path.join(data, "lidar3d", "kitti00_keyframes")
    jobs.append(("slam3d-kitti00", ["slam3d", f"{kitti3d}/key_frames", "--preset", "kitti",
                                    "--times", f"{kitti3d}/keyframes.txt", "--times-column", "4",
                                    "--ground-truth", f"{kitti3d}/poses_keyframes.txt",
                                    "--ground-truth-format", "kitti", "--out", f"{out}/slam3d-kitti00"]))
    kitti_visual = os.path.join(data, "visual", "kitti_extract_seq2")
    tum_visual = os.path.join(data, "visual", "tum_fr1_desk_every4th")
    jobs.append(("vslam-kitti", ["vslam", kitti_visual, "--out", f"{out}/vslam-kitti"]))
    jobs.append(("vocabulary", ["vocabulary", "train", f"{kitti_visual}/image_l", "-L", "4",
                                "--out", f"{out}/kitti.voc", "-q"]))
    jobs.append(("vslam-tum", ["vslam", tum_visual, "--camera", "tum-fr1", "--vocabulary", f"{out}/kitti.voc",
                               "--out", f"{out}/vslam-tum"]))
    graph = os.path.join(data, "posegraph", "se-sync", "intel.g2o")
    if os.path.exists(graph):
        jobs.append(("optimize-intel-gnc", ["optimize", graph, "--robust", "gnc", "--output", f"{out}/optimize-intel.g2o",
                                            "--report", f"{out}/optimize-intel.json"]))
    return jobs


def digest_tree(out):
    digests = {}
    for root, _, files in os.walk(out):
        for name in sorted(files):
            path = os.path.join(root, name)
            rel = os.path.relpath(path, out)
            if name.endswith(".csv"):
                content = csv_without_timings(path)
            elif name.endswith(".json"):
                OUT_PREFIX[0] = out.rstrip("/")
                with open(path, encoding="utf-8") as f:
                    content = json.dumps(strip_timings(json.load(f)), sort_keys=True).encode()
            else:
                with open(path, "rb") as f:
                    content = f.read()
            digests[rel] = hashlib.sha256(content).hexdigest()
    return digests


def numeric_difference(a, b):
    """Largest absolute difference between two whitespace-separated numeric text files, or None."""
    try:
        with open(a) as fa, open(b) as fb:
            la = [l.split() for l in fa if l.strip() and not l.startswith("#")]
            lb = [l.split() for l in fb if l.strip() and not l.startswith("#")]
        if len(la) != len(lb) or any(len(x) != len(y) for x, y in zip(la, lb)):
            return None
        return max((abs(float(x) - float(y)) for ra, rb in zip(la, lb) for x, y in zip(ra, rb)), default=0.0)
    except (ValueError, UnicodeDecodeError):
        return None


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("cairn")
    parser.add_argument("--out", required=True)
    parser.add_argument("--against")
    parser.add_argument("--only", help="comma-separated job names")
    args = parser.parse_args()
    data = os.path.realpath(os.environ.get("CAIRN_DATA_ROOT", os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data")))
    os.makedirs(args.out, exist_ok=True)
    only = set(args.only.split(",")) if args.only else None
    for name, command in jobs(data, args.out):
        if only and name not in only and name not in ("vocabulary", "landmarks-sim", "slam2d-intel-map"):
            continue
        for stale in (os.path.join(args.out, name), os.path.join(args.out, name.replace("-gnc", "") + ".g2o"),
                      os.path.join(args.out, name + ".map")):
            if os.path.isdir(stale):
                shutil.rmtree(stale)
            elif os.path.exists(stale):
                os.remove(stale)
        start = time.monotonic()
        result = subprocess.run([args.cairn] + command, capture_output=True, text=True)
        print(f"{name:22s} exit {result.returncode}  {time.monotonic() - start:7.1f} s", flush=True)
        if result.returncode != 0:
            print(result.stderr[-2000:], file=sys.stderr)
    digests = digest_tree(args.out)
    with open(os.path.join(args.out, "..", os.path.basename(args.out.rstrip("/")) + ".digests.json"), "w") as f:
        json.dump(digests, f, indent=1, sort_keys=True)
    if not args.against:
        return 0
    before = digest_tree(args.against)
    differ = 0
    for rel in sorted(set(before) | set(digests)):
        if only and not any(rel.startswith(job) for job in only):
            continue
        if before.get(rel) != digests.get(rel):
            differ += 1
            diff = numeric_difference(os.path.join(args.against, rel), os.path.join(args.out, rel))
            note = f" (largest numeric difference {diff:.3g})" if diff is not None else ""
            print(f"differs: {rel}{note}")
    print(f"{len(digests)} outputs, {differ} differ")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
