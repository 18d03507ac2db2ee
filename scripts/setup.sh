#!/usr/bin/env bash
# Installs idyvins' build dependencies from Debian's packages (idempotent).
# Runs `apt-get update` at most once, and only when something is missing.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libceres-dev libopencv-dev libyaml-cpp-dev
  libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3-numpy python3-matplotlib python3-pil
  # ROS1 bags without a ROS installation: rosbag_storage, the message headers, and the
  # headers its bag.h includes (pluginlib from ROS 2 in Debian); python3-rosbag writes the test bags
  librosbag-storage-dev libsensor-msgs-dev libnav-msgs-dev libgeometry-msgs-dev
  libclass-loader-dev librcpputils-dev librcutils-dev libament-index-cpp-dev
  python3-rosbag python3-sensor-msgs python3-nav-msgs python3-geometry-msgs
  # the ROS1 node idyvins_ros and its test: roscpp, tf2, cv_bridge, roscore, rosbag play / record
  libroscpp-dev libtf2-ros-dev libcv-bridge-dev libstd-msgs-dev ros-core python3-rospy python3-rosgraph
  # loop closure: place recognition over binary descriptors (faiss; it links OpenMP and BLAS)
  libfaiss-dev
  # make fuzz: libFuzzer and the sanitizers' runtime
  clang libclang-rt-14-dev
  # bench --plan: the GNU parallel recipe and its test
  parallel
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} Debian packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
