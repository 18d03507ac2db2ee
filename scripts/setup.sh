#!/usr/bin/env bash
# Installs idyvins' dependencies from Debian's packages and npm (idempotent): `setup.sh demo` what
# `make demo` needs (the command and its report), `setup.sh` everything (tests, the ROS node,
# benchmarks, fuzzing). Runs `apt-get update` at most once, and only when something is missing.
set -euo pipefail

# What `make demo` needs: the compiler, the libraries of the idyvins command (bags of both formats,
# loop closure) and Node.js for the report page's bundle.
DEMO_PACKAGES=(
  build-essential cmake pkg-config python3
  libeigen3-dev libceres-dev libopencv-dev libyaml-cpp-dev
  libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
  # 8-bit gray PNGs (EuRoC's cameras) inflated by libdeflate, the rest by OpenCV
  libdeflate-dev
  # ROS1 bags without a ROS installation: rosbag_storage, the message headers, and the
  # headers its bag.h includes (pluginlib from ROS 2 in Debian)
  librosbag-storage-dev libsensor-msgs-dev libnav-msgs-dev libgeometry-msgs-dev
  libclass-loader-dev librcpputils-dev librcutils-dev libament-index-cpp-dev
  # ROS 2 bags without ROS 2: MCAP chunks (zstd, lz4, zlib's CRC) and rosbag2's sqlite3 storage
  libzstd-dev liblz4-dev zlib1g-dev libsqlite3-dev
  # loop closure: place recognition over binary descriptors (faiss; it links OpenMP and BLAS)
  libfaiss-dev
)
# What `make test` (and the ROS node, benchmarks, fuzzing, docs' commands) need on top.
TEST_PACKAGES=(
  libgtest-dev libgmock-dev libbenchmark-dev
  python3-numpy python3-matplotlib python3-pil python3-opencv python3-yaml
  # python3-rosbag writes the test bags
  python3-rosbag python3-sensor-msgs python3-nav-msgs python3-geometry-msgs
  # the ROS1 node idyvins_ros and its test: roscpp, tf2, cv_bridge, roscore, rosbag play / record;
  # its launch file's rviz and `rostopic echo /tf` (python3-tf2-msgs)
  libroscpp-dev libtf2-ros-dev libcv-bridge-dev libstd-msgs-dev ros-core python3-rospy python3-rosgraph
  rviz python3-tf2-msgs
  # make fuzz: libFuzzer and the sanitizers' runtime
  clang libclang-rt-14-dev
  # the format check (tests: CodeFormat): the tree as .clang-format writes it
  clang-format
  # bench --plan: the GNU parallel recipe and its test
  parallel
  # idyvins report's browser test (headless, driven by playwright-core from web/)
  chromium
)
MODE=${1:-all}
case "$MODE" in
  demo) PACKAGES=("${DEMO_PACKAGES[@]}") ;;
  all) PACKAGES=("${DEMO_PACKAGES[@]}" "${TEST_PACKAGES[@]}") ;;
  *) echo "usage: scripts/setup.sh [demo|all]  (demo: what make demo needs; all, the default: everything)" >&2; exit 2 ;;
esac

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

# The report page's libraries (three.js, uPlot) and build/test tools (esbuild, playwright-core)
# come from the npm registry into web/node_modules, pinned by web/package-lock.json; the build
# bundles them into the idyvins binary. Node.js and npm: the machine's, else Debian's.
# The ROS 2 bag tests' independent writer and reader (tests/ros2: @mcap/core, rosmsg2-serialization)
# the same way, into tests/ros2/node_modules.
npm_folder() {  # npm_folder DIR: npm ci there unless node_modules matches the lock file
  local dir=$1
  if [ -f "$dir/node_modules/.package-lock.json" ] && [ ! "$dir/package-lock.json" -nt "$dir/node_modules/.package-lock.json" ]; then
    return 0
  fi
  echo "setup: npm ci in $dir"
  (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error)
}
web_modules() {
  local root
  root="$(cd "$(dirname "$0")/.." && pwd)"
  npm_folder "$root/web"
  if [ "$MODE" = all ]; then npm_folder "$root/tests/ros2"; fi
}
if ! command -v npm > /dev/null; then missing+=(nodejs npm); fi

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup ($MODE): all ${#PACKAGES[@]} Debian packages already installed"
  web_modules
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
web_modules
echo "setup: done"
