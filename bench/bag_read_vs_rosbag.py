#!/usr/bin/python3
"""Bag read throughput and peak memory: cairn (bench_bag_read) against python3-rosbag on the same
ROS 1 bags, in one run (issue 37; docs/benchmarks.md "Reading bags").

The bags are made here, at benchmark time, by python3-rosbag from the shared KITTI key frames
(DATA_ROOT/lidar3d/kitti00_keyframes: 110 scans, every point, as sensor_msgs/PointCloud2 with
x y z intensity, see tests/bag/fixtures/make_ros1_bags.py): the 110 scans once (1x) and the
110 scans written R times with their stamps shifted (Rx, the same messages, R times the size),
uncompressed, plus lz4 and bz2 copies of 1x. For each bag, alternately, --repeat times each:
  * cairn, container only:   bench_bag_read BAG            (stream every message's bytes)
  * cairn, decoded:          bench_bag_read BAG --decode   (every message into a Value tree)
  * cairn, points:           bench_bag_read BAG --points   (PointCloud2 further into points)
  * rosbag, raw:             Bag.read_messages(raw=True)   (stream every message's bytes)
  * rosbag, decoded:         Bag.read_messages()           (every message into its genpy class)
wall time and peak resident memory from /usr/bin/time (GNU time's %e and %M). Prints a Markdown
table of medians.

Usage: /usr/bin/python3 bench/bag_read_vs_rosbag.py BENCH_BAG_READ [--data DATA_ROOT]
       [--work DIR] [--repeat 3] [--times 4]
"""

import argparse
import lzma
import os
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'tests', 'bag', 'fixtures'))
import make_ros1_bags as fixtures  # noqa: E402  (python3-rosbag and the PCD reader)
import rosbag  # noqa: E402

ROSBAG_READ = r'''
import sys, rosbag
n = 0
with rosbag.Bag(sys.argv[1]) as b:
    for topic, msg, t in b.read_messages(raw=sys.argv[2] == "raw"):
        n += 1
print(n)
'''


def make_bags(data_root, work, times):
    folder = os.path.join(data_root, 'lidar3d', 'kitti00_keyframes')
    frames = fixtures.read_keyframes(folder, 1000)
    clouds = []
    for k, stamp_ns, pcd in frames:
        with open(pcd, 'rb') as f:
            clouds.append((k, stamp_ns, fixtures.parse_pcd(lzma.decompress(f.read()), pcd)))
    span_ns = frames[-1][1] - frames[0][1] + 100_000_000
    bags = {}
    for name, repeat, compression in (('1x', 1, rosbag.Compression.NONE), (f'{times}x', times, rosbag.Compression.NONE),
                                      ('1x-lz4', 1, rosbag.Compression.LZ4), ('1x-bz2', 1, rosbag.Compression.BZ2)):
        path = os.path.join(work, f'kitti_{name}.bag')
        bags[name] = path
        if os.path.exists(path):
            continue
        with rosbag.Bag(path + '.part', 'w', compression=compression) as bag:
            for r in range(repeat):
                for k, stamp_ns, xyz in clouds:
                    t = stamp_ns + r * span_ns
                    bag.write('/velodyne_points', fixtures.point_cloud(k, t, xyz, 1), fixtures.ros_time(t))
        os.rename(path + '.part', path)
    return bags


def timed(command):
    out = subprocess.run(['/usr/bin/time', '-f', '%e %M'] + command, capture_output=True, text=True, check=True)
    seconds, kib = out.stderr.strip().splitlines()[-1].split()
    return float(seconds), int(kib) / 1024.0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bench_bag_read')
    parser.add_argument('--data', default=os.environ.get('CAIRN_DATA_ROOT', os.path.join(HERE, '..', '..', 'shared', 'data')))
    parser.add_argument('--work', default='/tmp/cairn_bag_bench')
    parser.add_argument('--repeat', type=int, default=3)
    parser.add_argument('--times', type=int, default=4)
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    bags = make_bags(args.data, args.work, args.times)
    readers = {
        'cairn, container': lambda p: [args.bench_bag_read, p],
        'cairn, decoded': lambda p: [args.bench_bag_read, p, '--decode'],
        'cairn, points': lambda p: [args.bench_bag_read, p, '--points'],
        'rosbag, raw': lambda p: ['/usr/bin/python3', '-c', ROSBAG_READ, p, 'raw'],
        'rosbag, decoded': lambda p: ['/usr/bin/python3', '-c', ROSBAG_READ, p, 'decoded'],
    }
    print('| bag | MB | reader | s (median) | MB/s | peak RSS MB |')
    print('|---|---|---|---|---|---|')
    for name, path in bags.items():
        size_mb = os.path.getsize(path) / 1e6
        results = {reader: [] for reader in readers}
        for _ in range(args.repeat):
            for reader, command in readers.items():  # alternating: the machine's noise hits all alike
                results[reader].append(timed(command(path)))
        for reader, runs in results.items():
            s = statistics.median(r[0] for r in runs)
            rss = max(r[1] for r in runs)
            print(f'| {name} | {size_mb:.0f} | {reader} | {s:.2f} | {size_mb / s if s > 0 else 0:.0f} | {rss:.0f} |')
        sys.stdout.flush()


if __name__ == '__main__':
    main()
