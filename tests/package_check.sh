#!/bin/bash
# The installed package as a user meets it: `cmake --install` into a fresh prefix, a project
# outside the repository builds docs/examples/run_euroc.cpp with find_package(idyvins) and
# again with pkg-config, and the embedded system's outputs equal `idyvins run`'s on a
# rendered sequence (same threads and feedback delay: byte-identical files).
#
# Usage: tests/package_check.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
BUILD=$1; SRC=$2; WORK=$3
rm -rf "$WORK"; mkdir -p "$WORK"
PREFIX=$WORK/prefix
cmake --install "$BUILD" --prefix "$PREFIX" > "$WORK/install.log"
for f in include/idyvins/pipeline/system.h include/idyvins/core/params.h lib/libidyvins_pipeline.a \
         lib/cmake/idyvins/idyvinsConfig.cmake lib/cmake/idyvins/idyvinsConfigVersion.cmake \
         lib/pkgconfig/idyvins.pc bin/idyvins; do
  [ -f "$PREFIX/$f" ] || { echo "not installed: $f"; exit 1; }
done

cmake -S "$SRC/tests/package" -B "$WORK/consumer" -DCMAKE_PREFIX_PATH="$PREFIX" \
      -DEXAMPLES_DIR="$SRC/docs/examples" -DCMAKE_BUILD_TYPE=Release > "$WORK/consumer_configure.log"
cmake --build "$WORK/consumer" -j2 > "$WORK/consumer_build.log" || { tail -30 "$WORK/consumer_build.log"; exit 1; }

PKG_CONFIG_PATH="$PREFIX/lib/pkgconfig" g++ -std=c++17 -O1 "$SRC/docs/examples/run_euroc.cpp" -o "$WORK/run_euroc_pc" \
  $(PKG_CONFIG_PATH="$PREFIX/lib/pkgconfig" pkg-config --cflags --libs idyvins) 2> "$WORK/pkgconfig_build.log" ||
  { tail -20 "$WORK/pkgconfig_build.log"; exit 1; }
set +e; "$WORK/run_euroc_pc" > /dev/null 2>&1; rc=$?; set -e
[ "$rc" = 2 ] || { echo "pkg-config build: usage exit $rc, expected 2"; exit 1; }

IDY=$PREFIX/bin/idyvins
"$IDY" simulate --scene city --level mid --seed 4 --duration 4 -o "$WORK/seq" > "$WORK/simulate.log"
CFG=$WORK/seq/config/sim_stereo_imu_config.yaml
mkdir -p "$WORK/lib"
"$WORK/consumer/run_euroc" "$CFG" "$WORK/seq" "$WORK/lib" > "$WORK/lib.log"
"$IDY" run -c "$CFG" -d "$WORK/seq" -o "$WORK/cli" > "$WORK/cli.log"
for f in trajectory.tum trajectory.csv state.csv map_static.ply map_dynamic.ply; do
  cmp -s "$WORK/lib/$f" "$WORK/cli/$f" || { echo "embedded and idyvins run differ: $f"; exit 1; }
done
lines=$(wc -l < "$WORK/lib/trajectory.tum")
[ "$lines" -gt 20 ] || { echo "trajectory too short: $lines poses"; exit 1; }
/usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert len(d['frames']) > 50, len(d['frames'])" \
  "$WORK/lib/stats.json"
# The ROS package, when the node was built: roslaunch finds it in the installed tree.
if [ -x "$PREFIX/lib/idyvins/idyvins_ros" ]; then
  args=$(ROS_PACKAGE_PATH="$PREFIX/share" roslaunch --args idyvins "$PREFIX/share/idyvins/launch/idyvins.launch" \
         config:=/c.yaml 2>&1) || { echo "roslaunch cannot start the installed node: $args"; exit 1; }
  case "$args" in *share/idyvins/idyvins_ros*) ;; *) echo "roslaunch: unexpected command: $args"; exit 1;; esac
  /usr/bin/python3 -c "import yaml,sys; d=yaml.safe_load(open(sys.argv[1])); assert d['Visualization Manager']['Global Options']['Fixed Frame']=='world'" \
    "$PREFIX/share/idyvins/rviz/idyvins.rviz"
fi
echo "package check: installed $(du -sh "$PREFIX" | cut -f1); consumer and pkg-config builds; $lines poses identical to idyvins run"
