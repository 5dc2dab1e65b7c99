#!/usr/bin/env bash
# Installs the Debian packages cairn needs, and only those that are missing.
# Idempotent: when everything is present it prints nothing and exits 0. `--bench` adds the large
# peers only bench/registration_vs_peers.cpp needs.
# Needs root (or passwordless sudo) only when something is missing.
set -euo pipefail

# One package per line, with the reason it is here.
PACKAGES=(
  build-essential      # g++ and make
  cmake                # the build system (>= 3.22)
  ninja-build          # fast, parallel builds
  ccache               # rebuilds in seconds while iterating
  pkg-config
  python3              # scripts/demo.sh formats its table with it
  libeigen3-dev        # dense linear algebra, the Lie groups in core
  libsuitesparse-dev   # CHOLMOD sparse Cholesky for the back end
  libopenblas0-pthread # BLAS for CHOLMOD's supernodal factorisation (faster than the default)
  libtbb-dev           # parallel loops (linearisation, matching)
  libcli11-dev         # the `cairn` command line
  nlohmann-json3-dev   # JSON reports and manifests
  libgtest-dev         # unit tests
  libgmock-dev
  libbenchmark-dev     # bench/
  libceres-dev         # only for side-by-side comparisons in bench/
  libcairo2-dev        # PNG/SVG plots and maps
  libyaml-cpp-dev      # slam2d configuration files
  libnanoflann-dev     # k-d tree of the Scan Context place recognition (lidar3d)
  zlib1g-dev           # reading .gz logs
  libbz2-dev           # reading .bz2 logs
  liblzma-dev          # reading .xz point clouds
  libopencv-dev        # vision/vslam: FAST, rotated BRIEF, PnP RANSAC, undistortion (imgcodecs only in tests)
  libpng-dev           # vision/image_file: reading the PNG images, writing features.png
  libjpeg-dev          # vision/image_file: reading JPEG images (libjpeg62-turbo)
  liblz4-dev           # bag: lz4-compressed chunks (ROS 1 bags, MCAP)
  libzstd-dev          # bag: zstd-compressed chunks (MCAP)
  libsqlite3-dev       # bag: rosbag2 SQLite3 storage (.db3)
  libgeographiclib-dev # gnss: geodetic <-> local east-north-up (LocalCartesian, WGS84)
  python3-dev          # the Python package (python/): Python.h for the extension module
  pybind11-dev         # the Python package: C++ bindings (pybind11 2.10, its CMake package)
  python3-numpy        # the Python package: arrays in and out
  python3-pytest       # the Python package's tests (python/tests) in make test
  python3-matplotlib   # examples/python: the plots
  python3-rosbag       # tests/bag/fixtures: independent ROS 1 bag writer/reader for the bag tests
  python3-sensor-msgs  # tests/bag/fixtures: ROS 1 sensor_msgs classes for the independent writer
  python3-nav-msgs     # tests/bag/fixtures: ROS 1 nav_msgs classes (Odometry reference)
  python3-geometry-msgs # tests/bag/fixtures: ROS 1 geometry_msgs classes (TransformStamped, poses)
  python3-tf2-msgs     # tests/bag/fixtures: ROS 1 tf2_msgs/TFMessage for /tf_static
  xz-utils             # tests/bag/fixtures/mcap/make_mcap.mjs reads the .pcd.xz scans with `xz`
  help2man             # man pages (cairn.1, cairn-slam3d.1, ...) from --help, installed by `make install`
  file                 # `make package`: CPack finds the ELF files for dpkg-shlibdeps (dpkg-dev) with it
  # Node.js 20 + npm (tests/bag/fixtures/mcap, independent MCAP writer/reader) are NOT listed: here
  # they come from NodeSource's `nodejs` package, which Conflicts/Provides `npm`; Debian's nodejs
  # (18) and npm would conflict with it. tests/bag/fixtures/make_all.sh skips the MCAP fixtures
  # when node or npm is missing.
)
# `install_deps.sh --bench` adds the registration peers of bench/registration_vs_peers.cpp. They
# pull in about 400 packages (Qt, Java, VTK), too many for every build, and only that benchmark
# uses them.
if [[ "${1:-}" == "--bench" ]]; then
  PACKAGES+=(
    libpcl-dev         # PCL 1.13: ICP, GICP, NDT
    libopen3d-dev      # Open3D 0.16: ICP, generalized ICP
  )
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "install_deps: missing Debian packages: ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    SUDO="sudo -n"
  else
    echo "install_deps: error: these packages must be installed as root:" >&2
    echo "  apt-get install ${missing[*]}" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install_deps: installed ${#missing[@]} package(s)"
