#!/usr/bin/env bash
# Installs a built cairn into a fresh temporary prefix and uses it as another project would
# (issue 39; docs/use_from_cpp.md). Fails, saying which step, on any error:
#   1. `cmake --install BUILD_DIR --prefix <tmp>`; the installed `cairn --version`, and a command
#      that runs in the installed cairn-suite beside it;
#   2. every installed pkg-config file resolves (`pkg-config --cflags --libs [--static]`);
#   3. examples/consumer/backend_only, configured against the prefix with OpenCV's package disabled,
#      built and run on a pose graph: cairn::backend needs neither OpenCV nor cairo;
#   4. the same program compiled with `pkg-config cairn-backend` instead of CMake;
#   5. examples/consumer (backend, eval, lidar3d, io) built and run on the benchmark data;
#   6. when the build has the Python package: `import cairn` from the prefix (not the build tree),
#      optimising the same graph.
#
#   scripts/check_install.sh [BUILD_DIR]     (default: build)
#
# The data: $CAIRN_DATA_ROOT, else ../shared/data beside the clone; without it the script exits 77
# (skipped). KEEP=1 keeps the temporary folder. Consumers build with the compiler $CXX names
# (default: the one CMake finds).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$(cd "${1:-$ROOT/build}" && pwd)
DATA=${CAIRN_DATA_ROOT:-$ROOT/../shared/data}
WORK=$(mktemp -d "${TMPDIR:-/tmp}/cairn-check-install.XXXXXX")
if [[ "${KEEP:-0}" == 1 ]]; then
  echo "check_install: keeping $WORK"
else
  trap 'rm -rf "$WORK"' EXIT
fi
PREFIX=$WORK/prefix
step() { echo "check_install: $*"; }
fail() { echo "check_install: FAILED: $*" >&2; exit 1; }

GRAPH=$DATA/posegraph/se-sync/tinyGrid3D.g2o
if [[ ! -f "$GRAPH" ]]; then
  # As the GoogleTest suites do without the data: skipped (ctest's SKIP_RETURN_CODE 77), not failed.
  echo "check_install: skipped: benchmark data not found: $GRAPH (set CAIRN_DATA_ROOT)"
  exit 77
fi

step "installing $BUILD into $PREFIX"
cmake --install "$BUILD" --prefix "$PREFIX" > "$WORK/install.log" 2>&1 || { cat "$WORK/install.log"; fail "cmake --install"; }
[[ -f "$PREFIX/include/cairn/backend/pose_graph_job.hpp" ]] || fail "headers not installed under include/cairn"
[[ ! -e "$PREFIX/include/cairn/cli" ]] || fail "the CLI's headers were installed"
CONFIG=$(find "$PREFIX" -name cairnConfig.cmake | head -n 1)
[[ -n "$CONFIG" ]] || fail "no cairnConfig.cmake under $PREFIX"
PKGCONFIG_DIR=$(dirname "$(find "$PREFIX" -name cairn-core.pc | head -n 1)")
[[ -f "$PKGCONFIG_DIR/cairn-core.pc" ]] || fail "no cairn-core.pc under $PREFIX"

step "running the installed cairn"
"$PREFIX/bin/cairn" --version || fail "cairn --version"
# eval runs in cairn-suite: the front must find it beside itself in the installed layout.
"$PREFIX/bin/cairn" eval --help > /dev/null || fail "cairn eval --help (cairn-suite beside cairn)"
if command -v help2man > /dev/null; then
  [[ -f "$PREFIX/share/man/man1/cairn.1.gz" && -f "$PREFIX/share/man/man1/cairn-slam3d.1.gz" ]] || fail "man pages not installed"
fi

step "pkg-config files"
export PKG_CONFIG_PATH="$PKGCONFIG_DIR${PKG_CONFIG_PATH:+:$PKG_CONFIG_PATH}"
for pc in "$PKGCONFIG_DIR"/cairn-*.pc; do
  module=$(basename "$pc" .pc)
  pkg-config --print-errors --cflags --libs --static "$module" > /dev/null || fail "pkg-config $module"
done

CMAKE_ARGS=(-G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$PREFIX")
[[ -n "${CXX:-}" ]] && CMAKE_ARGS+=(-DCMAKE_CXX_COMPILER="$CXX")

step "examples/consumer/backend_only (cairn::backend, OpenCV's package disabled)"
cmake -S "$ROOT/examples/consumer/backend_only" -B "$WORK/backend_only" "${CMAKE_ARGS[@]}" \
  -DCMAKE_DISABLE_FIND_PACKAGE_OpenCV=ON > "$WORK/backend_only.log" 2>&1 || { cat "$WORK/backend_only.log"; fail "configure backend_only"; }
if grep -Eq '^(OpenCV_DIR|CAIRO_[A-Z_]+):' "$WORK/backend_only/CMakeCache.txt"; then
  fail "configuring a cairn::backend consumer looked for OpenCV or cairo"
fi
cmake --build "$WORK/backend_only" > "$WORK/backend_only_build.log" 2>&1 || { cat "$WORK/backend_only_build.log"; fail "build backend_only"; }
"$WORK/backend_only/optimize_graph" "$GRAPH" "$WORK/optimized.g2o" || fail "optimize_graph"
[[ -s "$WORK/optimized.g2o" ]] || fail "optimize_graph wrote nothing"

step "the same program with pkg-config cairn-backend"
# Static libraries (the default build) need --static: their private dependencies come along.
STATIC=--static
if find "$PREFIX" -name 'libcairn_core.so' | grep -q .; then STATIC=; fi
read -r -a PC_FLAGS <<< "$(pkg-config --cflags --libs $STATIC cairn-backend)"
"${CXX:-c++}" -std=c++20 -O1 "$ROOT/examples/consumer/backend_only/optimize_graph.cpp" -o "$WORK/optimize_graph_pc" \
  "${PC_FLAGS[@]}" -Wl,-rpath,"$(dirname "$PKGCONFIG_DIR")" || fail "compile with pkg-config cairn-backend"
"$WORK/optimize_graph_pc" "$GRAPH" "$WORK/optimized_pc.g2o" > /dev/null || fail "optimize_graph built with pkg-config"

step "examples/consumer (backend, eval, lidar3d, io)"
cmake -S "$ROOT/examples/consumer" -B "$WORK/consumer" "${CMAKE_ARGS[@]}" > "$WORK/consumer.log" 2>&1 \
  || { cat "$WORK/consumer.log"; fail "configure examples/consumer"; }
cmake --build "$WORK/consumer" > "$WORK/consumer_build.log" 2>&1 || { cat "$WORK/consumer_build.log"; fail "build examples/consumer"; }
"$WORK/consumer/cairn_consumer" "$DATA" || fail "cairn_consumer"

PYTHON_PACKAGE=$(find "$PREFIX" -path '*/cairn/__init__.py' | head -n 1)
if grep -q '^CAIRN_BUILD_PYTHON:BOOL=ON' "$BUILD/CMakeCache.txt"; then
  step "import cairn from the prefix"
  [[ -n "$PYTHON_PACKAGE" ]] || fail "the Python package was not installed"
  PYTHON=$(sed -n 's/^Python_EXECUTABLE:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
  (cd "$WORK" && PYTHONPATH="$(dirname "$(dirname "$PYTHON_PACKAGE")")" "$PYTHON" -c "
import sys, cairn
assert cairn.__file__.startswith('$PREFIX'), cairn.__file__
r = cairn.optimize(sys.argv[1])
print('cairn', cairn.__version__, 'from', cairn.__file__, ': chi2', r.chi2)" "$GRAPH") || fail "import cairn from $PREFIX"
fi

step "passed"
