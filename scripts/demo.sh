#!/usr/bin/env bash
# `make demo`: the best end-to-end job cairn can do today, on the benchmark data beside the clone
# (CAIRN_DATA_ROOT, default ../shared/data) or, without it, on the example graph in examples/.
# Today that is: 2D LiDAR SLAM on a simulated office (scored against its exact ground truth) and on
# the Freiburg benchmark logs (scored with their relations files); read and check every benchmark
# pose graph (formats, counts, structure, broken information matrices), optimise SE-Sync's graphs to their certified optima, reject false loop
# closures with GNC, bundle-adjust a BAL problem, 3D LiDAR SLAM on real KITTI scans and on a
# simulated street with reverse revisits, convert between formats, and convert trajectories.
set -euo pipefail
CAIRN=${1:-build/src/cairn/cli/cairn}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DATA=${CAIRN_DATA_ROOT:-$ROOT/../shared/data}
OUT=$ROOT/cairn-demo
rm -rf "$OUT"
mkdir -p "$OUT/info" "$OUT/converted"

echo "cairn demo: results go to $OUT"

echo
echo "2D LiDAR SLAM on a simulated office (180 beams, 1 cm range noise, drifting odometry):"
"$CAIRN" simulate office --seed 1 --out "$OUT/slam2d/office-sim" | sed 's/^/  /'
"$CAIRN" slam2d "$OUT/slam2d/office-sim/log.clf" --out "$OUT/slam2d/office" \
  --relations "$OUT/slam2d/office-sim/log.relations" 2> >(grep -v '^\[scan' >&2) | sed 's/^/  /'
echo "  ATE against the simulator's ground truth (SE(2) alignment):"
"$CAIRN" eval ape "$OUT/slam2d/office-sim/ground_truth.tum" "$OUT/slam2d/office/trajectory.tum" --align se2 \
  --plot "$OUT/slam2d/office/ape.png" | sed 's/^/    /'
echo "  map picture: $OUT/slam2d/office/map.png (trajectory coloured by health, loop closures in green)"
for log in aces intel; do
  if [[ -f "$DATA/laser2d/$log/$log.clf.bz2" ]]; then
    echo
    echo "2D LiDAR SLAM on the Freiburg $log log (Cartographer, Hess et al. 2016: see docs/benchmarks.md):"
    "$CAIRN" slam2d "$DATA/laser2d/$log/$log.clf.bz2" --out "$OUT/slam2d/$log" \
      --relations "$DATA/laser2d/$log/$log.relations" 2> >(grep -v '^\[scan' >&2) | sed 's/^/  /'
    echo "  map picture: $OUT/slam2d/$log/map.png"
  fi
done
kitti3d="$DATA/lidar3d/kitti00_keyframes"
if [[ -d "$kitti3d/key_frames" ]]; then
  echo
  echo "3D LiDAR SLAM on 110 real KITTI 00 scans (KISS-ICP measured beside it: docs/benchmarks.md):"
  "$CAIRN" slam3d "$kitti3d/key_frames" --preset kitti --times "$kitti3d/keyframes.txt" --times-column 4 \
    --ground-truth "$kitti3d/poses_keyframes.txt" --ground-truth-format kitti --out "$OUT/slam3d/kitti00" \
    2> >(grep -v '^\[scan' >&2) | sed 's/^/  /'
  echo "  map: $OUT/slam3d/kitti00/map.png, map.ply"
fi
echo
echo "3D LiDAR SLAM on a simulated street driven twice, the second lap reversed on the opposite lane:"
"$CAIRN" simulate street-3d-loops --seed 1 --out "$OUT/slam3d/street-sim" | sed 's/^/  /'
"$CAIRN" slam3d "$OUT/slam3d/street-sim/scans" --times "$OUT/slam3d/street-sim/times.txt" \
  --ground-truth "$OUT/slam3d/street-sim/poses.txt" --ground-truth-format kitti --out "$OUT/slam3d/street" \
  2> >(grep -v '^\[scan' >&2) | sed 's/^/  /'
rm -rf "$OUT/slam3d/street-sim/scans"  # 92 MB of simulated scans; the run's outputs stay
echo "  map: $OUT/slam3d/street/map.png (report.json lists every loop candidate and its decision)"

kitti_visual="$DATA/visual/kitti_extract_seq2"
tum_visual="$DATA/visual/tum_fr1_desk_every4th"
if [[ -d "$kitti_visual/image_l" ]]; then
  echo
  echo "Stereo visual SLAM on 51 real KITTI frames (ORB-SLAM2-style; docs/vslam.md on the extract's 3.6 % scale):"
  "$CAIRN" vslam "$kitti_visual" --out "$OUT/vslam/kitti" 2> >(grep -v '^\[frame\|^cairn vslam: no' >&2) | sed 's/^/  /'
  echo "  pictures: $OUT/vslam/kitti/trajectory.png, features.png"
  if [[ -d "$tum_visual/rgb" ]]; then
    echo
    echo "RGB-D visual SLAM on TUM fr1/desk (every 4th frame), place recognition with a vocabulary trained on the KITTI images:"
    "$CAIRN" vocabulary train "$kitti_visual/image_l" -L 4 --out "$OUT/vslam/kitti.voc" -q
    "$CAIRN" vslam "$tum_visual" --camera tum-fr1 --vocabulary "$OUT/vslam/kitti.voc" --out "$OUT/vslam/tum" \
      2> >(grep -v '^\[frame\|^cairn vslam:' >&2) | sed 's/^/  /'
    echo "  report: $OUT/vslam/tum/report.json (maps, loop candidates and why each was accepted or rejected)"
  fi
fi

graphs=()
if [[ -d "$DATA/posegraph" ]]; then
  while IFS= read -r f; do graphs+=("$f"); done < <(find "$DATA/posegraph" -type f ! -name SOURCE.txt | sort)
else
  echo "benchmark data not found at $DATA (set CAIRN_DATA_ROOT); using examples/ only"
fi
graphs+=("$ROOT/examples/square_loop.g2o")

printf '\n%-34s %-5s %3s %7s %7s %7s %6s %5s %9s %s\n' file fmt dim poses edges loops comps guess "non-PD" notes
start=$(date +%s%N)
for g in "${graphs[@]}"; do
  name=$(basename "$g")
  json="$OUT/info/${name%.*}.json"
  if ! "$CAIRN" info "$g" --json "$json" > "$OUT/info/${name%.*}.txt" 2> "$OUT/info/${name%.*}.warnings.txt"; then
    printf '%-34s FAILED: %s\n' "$name" "$(head -1 "$OUT/info/${name%.*}.warnings.txt")"
    continue
  fi
  python3 - "$json" "$name" <<'PY'
import json, sys
j = json.load(open(sys.argv[1])); name = sys.argv[2]
notes = []
if j.get("unknown_records"): notes.append("skipped " + ",".join(f"{k}x{v['count']}" for k, v in j["unknown_records"].items()))
if j.get("toro_information_order") == "g2o": notes.append("EDGE2 info in g2o order")
if j.get("edges_without_information"): notes.append(f"{j['edges_without_information']} edges without info")
print(f"{name[:34]:<34} {j['format']:<5} {j['dimension']:>2}D {j['poses']:>7} {j['edges']:>7} {j['loop_closure_edges']:>7} "
      f"{j['connected_components']:>6} {'yes' if j['has_initial_guess'] else 'no':>5} {j['information_not_positive_definite']:>9} {'; '.join(notes)}")
PY
done
end=$(date +%s%N)
printf '\nchecked %d graphs in %d ms (cairn info, one process per file)\n' "${#graphs[@]}" $(( (end - start) / 1000000 ))

mkdir -p "$OUT/optimized"
if [[ -d "$DATA/posegraph/se-sync" ]]; then
  echo
  echo "Pose-graph optimisation, SE-Sync's objective from a chordal start, against the certified optima"
  echo "of ../shared/data/README.md:"
  printf '%-16s %18s %18s %9s\n' graph "cairn f" "SE-Sync f*" "time[s]"
  for pair in CSAIL:31.703715883737345 intel:52.348227285553435 manhattan:6431.3913872099165 \
              kitti_00:125.69351454148867 smallGrid3D:1025.3980207410884 cubicle:717.13403923218959; do
    g=${pair%%:*}; fstar=${pair#*:}
    start=$(date +%s%N)
    "$CAIRN" optimize "$DATA/posegraph/se-sync/$g.g2o" -o "$OUT/optimized/$g.g2o" --objective chordal --init chordal \
      -q --report "$OUT/optimized/$g.json" > /dev/null 2> "$OUT/optimized/$g.log"
    end=$(date +%s%N)
    f=$(python3 -c "import json; print('%.10g' % json.load(open('$OUT/optimized/$g.json'))['final_f_chordal'])")
    printf '%-16s %18s %18s %9.2f\n' "$g" "$f" "$fstar" "$(( (end - start) / 1000000 ))e-3"
  done
  echo
  echo "False loop closures: intel.g2o plus 785 random ones (as many as the true loop closures), GNC:"
  "$CAIRN" corrupt "$DATA/posegraph/se-sync/intel.g2o" --outliers 785 --seed 1 -o "$OUT/optimized/intel_corrupted.g2o"
  "$CAIRN" optimize "$OUT/optimized/intel_corrupted.g2o" -o "$OUT/optimized/intel_gnc.g2o" --robust gnc \
    --max-iterations 30 -q --report "$OUT/optimized/intel_gnc.json" | head -1
  python3 - "$OUT/optimized/intel_gnc.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
rejected = j["gnc"]["rejected"]
false_rejected = sum(1 for e in rejected if e["edge_index"] >= 2512)
print(f"  rejected {false_rejected} of 785 false and {len(rejected) - false_rejected} of 785 true loop closures")
PY
fi

if [[ -f "$DATA/bal/problem-16-22106-pre.txt.bz2" ]]; then
  echo
  echo "Bundle adjustment of BAL's problem-16-22106 (the file Ceres' documentation runs; it reports"
  echo "a final cost of 1.803390e+04; docs/benchmarks.md has the side-by-side timing):"
  mkdir -p "$OUT/ba"
  "$CAIRN" ba "$DATA/bal/problem-16-22106-pre.txt.bz2" -o "$OUT/ba/problem-16-22106.txt" \
    --report "$OUT/ba/problem-16-22106.json" -q | sed 's/^/  /'
fi

echo
echo "Simulation: a corridor of identical doors (perceptual aliasing), ground truth and sensor logs:"
"$CAIRN" simulate corridor-aliasing --seed 1 --out "$OUT/simulated/corridor-aliasing" | sed 's/^/  /'

echo
"$CAIRN" convert "$ROOT/examples/square_loop.g2o" "$OUT/converted/square_loop.graph"
if [[ -d "$DATA/posegraph" ]]; then
  "$CAIRN" convert "$DATA/posegraph/toro/w20000.txt" "$OUT/converted/w20000.g2o" --from toro 2>&1 | sed 's/^/  /'
  "$CAIRN" convert "$DATA/posegraph/se-sync/sphere2500.g2o" "$OUT/converted/sphere2500.graph"
fi
T="$DATA/trajectories/trajectories-evo-testdata"
if [[ -d "$T" ]]; then
  "$CAIRN" convert "$T/KITTI_00_gt.txt" "$OUT/converted/KITTI_00_gt.tum" --from kitti --times "$T/KITTI_00_gt_times.txt"
  "$CAIRN" convert "$T/V102_groundtruth.csv" "$OUT/converted/V102_groundtruth.tum"
  echo
  "$CAIRN" info "$OUT/converted/KITTI_00_gt.tum"
fi

cat <<MSG

Done. Look at:
  $OUT/slam2d/<run>/map.png          maps with the trajectory coloured by health and the loop closures
  $OUT/slam2d/<run>/report.json      timings, every loop candidate and why it was accepted or not, health events
  $OUT/info/<graph>.txt / .json     what each graph holds (cairn info)
  $OUT/info/<graph>.warnings.txt    what cairn noticed (indefinite information, skipped records)
  $OUT/optimized/                   optimised graphs, JSON reports with per-iteration logs (cairn optimize)
  $OUT/ba/                          the bundle-adjusted BAL problem and its report (cairn ba)
  $OUT/slam3d/<run>/map.png          3D LiDAR maps from above, trajectory by health (map.ply: the points)
  $OUT/slam3d/<run>/report.json      per-scan stages, health events, every loop candidate and its decision
  $OUT/simulated/corridor-aliasing/world.png   the simulated world and trajectories (cairn simulate)
  $OUT/converted/                   the same data in other formats (cairn convert)
Next: cairn --help, docs/slam2d.md, docs/lidar3d.md, docs/evaluation.md, docs/backend.md, docs/formats.md, docs/conventions.md
MSG
