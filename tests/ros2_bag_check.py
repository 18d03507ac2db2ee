#!/usr/bin/python3
"""ROS 2 bags against EuRoC folders, through the idyvins command (CTest). The bags are written by
implementations independent of idyvins: @mcap/core and @foxglove/rosmsg2-serialization
(tests/ros2/write_bag.mjs) for MCAP, Python's sqlite3 for rosbag2's .db3 storage.

ros2_bag_check.py setup IDYVINS WORK   simulate a short sequence, write ROS 2 bags of it
ros2_bag_check.py run IDYVINS WORK     run on the folder and on each bag: byte-identical outputs; convert alike
ros2_bag_check.py info IDYVINS WORK    info on the folder and on a bag: same counts, rates and gaps, topics listed
ros2_bag_check.py bad IDYVINS WORK     damaged bags: exit code 1 and one clear line each (offsets for MCAP)
ros2_bag_check.py simulate IDYVINS WORK  simulate --format mcap, read back by @mcap/core and rosmsg2-serialization
"""
import base64
import filecmp
import json
import os
import shutil
import sqlite3
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
WRITER = os.path.join(HERE, "ros2", "write_bag.mjs")
READER = os.path.join(HERE, "ros2", "read_bag.mjs")
# (name, storage, layout, compression, encoding, ground truth kind, its topic)
VARIANTS = [
    ("plain_mono8_odometry.mcap", "mcap", "file", "none", "mono8", "odometry", "/odometry"),
    ("zstd_rgb8_transform.mcap", "mcap", "file", "zstd", "rgb8", "transform", "/vicon/firefly_sbx/firefly_sbx"),
    ("lz4_png_pose", "mcap", "folder", "lz4", "png", "pose", "/pose"),
    ("sqlite3_mono8_point", "sqlite3", "folder", "none", "mono8", "point", "/leica/position"),
    ("bare_mono8_odometry.db3", "sqlite3", "file", "none", "mono8", "odometry", "/odometry"),
]
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def sh(cmd):
    return subprocess.run(cmd, capture_output=True, text=True)


def seq(work):
    return os.path.join(work, "seq")


def config(work):
    return os.path.join(seq(work), "config", "sim_stereo_imu_config.yaml")


def write_db3(records_json, db_path):
    """rosbag2's sqlite3 storage (schema of ROS 2 Jazzy) from the writer's CDR records."""
    data = json.load(open(records_json))
    con = sqlite3.connect(db_path)
    con.executescript(
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
        "CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);"
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
        " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL, type_description_hash TEXT NOT NULL);"
        "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL,"
        " data BLOB NOT NULL);"
        "CREATE INDEX timestamp_idx ON messages (timestamp ASC);")
    con.execute("INSERT INTO schema VALUES (4, 'jazzy')")
    ids = {}
    for k, (topic, type_) in enumerate(sorted(data["topics"].items()), start=1):
        ids[topic] = k
        con.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '', '')", (k, topic, type_))
    con.executemany("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)",
                    [(ids[t], int(ns), base64.b64decode(b)) for t, ns, b in data["records"]])
    con.commit()
    con.close()
    counts = {}
    for t, _, _ in data["records"]:
        counts[t] = counts.get(t, 0) + 1
    return data["topics"], counts


def write_variant(work, name, storage, layout, compression, encoding, gt, extra=()):
    out = os.path.join(work, name)
    records = out + ".records.json"
    args = ["node", WRITER, seq(work), out if storage == "mcap" else records, "--compression", compression, "--encoding", encoding, "--groundtruth", gt]
    if storage == "mcap":
        r = sh(args + ["--storage", "mcap", "--layout", layout] + list(extra))
        check(r.returncode == 0, "write %s %s" % (name, r.stderr.strip()[-300:]))
        return
    r = sh(args + ["--storage", "records"] + list(extra))
    check(r.returncode == 0, "write %s records %s" % (name, r.stderr.strip()[-300:]))
    if r.returncode != 0:
        return
    if layout == "file":
        write_db3(records, out)
        os.remove(records)
        return
    os.makedirs(out)
    db = os.path.join(out, name + "_0.db3")
    topics, counts = write_db3(records, db)
    os.remove(records)
    lines = ["rosbag2_bagfile_information:", "  version: 5", "  storage_identifier: sqlite3",
             "  topics_with_message_count:"]
    for t, type_ in sorted(topics.items()):
        lines += ["    - topic_metadata:", "        name: " + t, "        type: " + type_,
                  "        serialization_format: cdr", "      message_count: %d" % counts[t]]
    lines += ['  compression_format: ""', '  compression_mode: ""', "  relative_file_paths:",
              "    - " + os.path.basename(db)]
    open(os.path.join(out, "metadata.yaml"), "w").write("\n".join(lines) + "\n")


def setup(idy, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    r = sh([idy, "simulate", "--scene", "city", "--level", "high", "--seed", "1", "--duration", "3", "--out",
            seq(work)])
    check(r.returncode == 0, "simulate: " + r.stderr.strip()[-200:])
    for name, storage, layout, comp, enc, gt, _ in VARIANTS:
        write_variant(work, name, storage, layout, comp, enc, gt)
    # Small bags to damage.
    write_variant(work, "small.mcap", "mcap", "file", "zstd", "mono8", "odometry", ["--frames", "12"])
    write_variant(work, "small.db3", "sqlite3", "file", "none", "mono8", "odometry", ["--frames", "12"])


def topics_config(work, name, compressed):
    """The sequence's config, with image_transport's compressed topics when `compressed`."""
    if not compressed:
        return config(work)
    dst = os.path.join(work, "config_" + name)
    shutil.rmtree(dst, ignore_errors=True)
    shutil.copytree(os.path.dirname(config(work)), dst)
    path = os.path.join(dst, os.path.basename(config(work)))
    text = open(path).read()
    for k in ["image0_topic", "image1_topic"]:  # the sequence's config names no topics: the defaults
        check(k not in text, "the sequence's config has no %s" % k)
    open(path, "w").write(text + '\nimage0_topic: "/cam0/image_raw/compressed"\n'
                          'image1_topic: "/cam1/image_raw/compressed"\n')
    return path


def run(idy, dataset, out, cfg, extra=()):
    r = sh([idy, "run", "-c", cfg, "-d", dataset, "-o", out, "--mode", "idy", "--threads", "1"] + list(extra))
    return r, (json.load(open(os.path.join(out, "stats.json")))["summary"] if r.returncode == 0 else None)


def test_run(idy, work):
    ref_out = os.path.join(work, "out_folder")
    r, ref = run(idy, seq(work), ref_out, config(work))
    check(r.returncode == 0 and ref is not None and "ate_rmse_m" in ref, "run on the folder")
    for name, _, _, _, enc, _, topic in VARIANTS:
        out = os.path.join(work, "out_" + name)
        r, s = run(idy, os.path.join(work, name), out, topics_config(work, name, enc == "png"),
                   ["--groundtruth-topic", topic])
        check(r.returncode == 0, "run on %s: %s" % (name, r.stderr.strip()[-300:]))
        if r.returncode != 0:
            continue
        for f in ["trajectory.tum", "trajectory.csv", "state.csv", "map_static.ply", "map_dynamic.ply"]:
            check(filecmp.cmp(os.path.join(ref_out, f), os.path.join(out, f), shallow=False),
                  "%s: %s byte-identical to the folder's" % (name, f))
        check(s.get("ate_rmse_m") == ref["ate_rmse_m"], "%s: ATE %s == folder's %s" % (
            name, s.get("ate_rmse_m"), ref["ate_rmse_m"]))
    # convert from two storages: the same EuRoC folder, and run on it as on the original.
    converted = []
    for name, _, _, _, _, _, topic in [VARIANTS[1], VARIANTS[3]]:
        conv = os.path.join(work, "converted_" + name)
        shutil.rmtree(conv, ignore_errors=True)
        r = sh([idy, "convert", os.path.join(work, name), conv, "-c", config(work), "--groundtruth-topic", topic])
        check(r.returncode == 0, "convert %s: %s" % (name, r.stderr.strip()[-300:]))
        converted.append(conv)
    cmp = filecmp.dircmp(converted[0], converted[1])
    check(r.returncode == 0 and not cmp.diff_files and not cmp.left_only and not cmp.right_only and all(
        filecmp.cmp(os.path.join(converted[0], "mav0", d, f), os.path.join(converted[1], "mav0", d, f), shallow=False)
        for d in ["imu0", "cam0", "cam1"] for f in ["data.csv"]),
        "convert: an MCAP and a sqlite3 bag give the same EuRoC folder")
    r, s = run(idy, converted[0], os.path.join(work, "out_converted"), config(work))
    check(r.returncode == 0 and filecmp.cmp(os.path.join(ref_out, "trajectory.tum"),
                                            os.path.join(work, "out_converted", "trajectory.tum"), shallow=False),
          "convert then run: trajectory byte-identical to the original folder's")


def info_json(idy, args):
    r = sh([idy, "info", "--json"] + args)
    return r, (json.loads(r.stdout) if r.returncode == 0 else None)


def test_info(idy, work):
    r, folder = info_json(idy, [seq(work)])
    check(r.returncode == 0, "info on the folder")
    for name, _, _, comp, _, _, topic in [VARIANTS[1], VARIANTS[3]]:
        r, bag = info_json(idy, [os.path.join(work, name), "--groundtruth-topic", topic, "-c", config(work)])
        check(r.returncode == 0, "info on %s: %s" % (name, r.stderr.strip()[-300:]))
        if r.returncode != 0:
            continue
        for stream in ["imu", "cam0", "cam1", "stereo_pairs", "groundtruth"]:
            check(bag[stream] == folder[stream], "%s: %s stats equal the folder's" % (name, stream))
        topics = {t["topic"]: (t["type"], t["count"]) for t in bag["topics"]}
        check(topics.get("/imu0") == ("sensor_msgs/msg/Imu", folder["imu"]["count"]), "%s: /imu0 listed" % name)
        check(topics.get("/cam0/image_raw") == ("sensor_msgs/msg/Image", folder["cam0"]["count"]),
              "%s: /cam0/image_raw listed" % name)
        check(bag["format"] == "rosbag2" and (comp == "none" or comp in bag["bag_format"]),
              "%s: format %s, %s" % (name, bag["format"], bag["bag_format"]))
    r = sh([idy, "info", os.path.join(work, VARIANTS[1][0]), "-c", config(work)])
    check(r.returncode == 0 and "ROS 2 bag (mcap, chunks zstd)" in r.stdout and "max gap" in r.stdout,
          "info text names the storage and compression, rates and gaps")


def first_chunk(data):
    """Offset and length of an MCAP file's first chunk record."""
    pos = 8
    while pos + 9 <= len(data):
        opcode, length = data[pos], struct.unpack("<Q", data[pos + 1:pos + 9])[0]
        if opcode == 6:
            return pos, length
        pos += 9 + length
    raise ValueError("no chunk")


def damaged(work, src, name, how):
    """A copy of `src` damaged by `how`: truncate (60 %), flip (a byte in the middle of the first chunk)."""
    data = bytearray(open(os.path.join(work, src), "rb").read())
    if how == "truncate":
        data = data[:len(data) * 6 // 10]
    else:
        pos, length = first_chunk(data)
        data[pos + 9 + length // 2] ^= 0xFF
    open(os.path.join(work, name), "wb").write(bytes(data))
    return os.path.join(work, name)


def test_bad(idy, work):
    meta_dir = os.path.join(work, "compressed_folder")
    shutil.rmtree(meta_dir, ignore_errors=True)
    shutil.copytree(os.path.join(work, "lz4_png_pose"), meta_dir)
    meta = os.path.join(meta_dir, "metadata.yaml")
    text = open(meta).read()
    open(meta, "w").write(text.replace('compression_format: ""', "compression_format: zstd"))
    missing = os.path.join(work, "missing_file_folder")
    shutil.rmtree(missing, ignore_errors=True)
    shutil.copytree(os.path.join(work, "lz4_png_pose"), missing)
    os.remove(os.path.join(missing, "lz4_png_pose_0.mcap"))
    cases = [
        (damaged(work, "small.mcap", "truncated.mcap", "truncate"), "not a readable MCAP file"),
        (damaged(work, "small.mcap", "flipped.mcap", "flip"), "not a readable MCAP file"),
        (damaged(work, "small.db3", "truncated.db3", "truncate"), "sqlite3"),
        (meta_dir, "compression_format 'zstd'"),
        (missing, "lz4_png_pose_0.mcap: no such file"),
    ]
    for path, expected in cases:
        r = sh([idy, "run", "-c", config(work), "-d", path, "-o", os.path.join(work, "out_bad")])
        lines = [l for l in r.stderr.splitlines() if l.strip()]
        check(r.returncode == 1, "%s: exit code %d (1 expected)" % (os.path.basename(path), r.returncode))
        check(len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0],
              "%s: one clear line containing '%s', got %r" % (os.path.basename(path), expected, lines))
    r = sh([idy, "run", "-c", config(work), "-d", os.path.join(work, "truncated.mcap"), "-o",
            os.path.join(work, "out_bad")])
    check("byte " in r.stderr, "the truncated MCAP is refused with a byte offset: %s" % r.stderr.strip())


def test_simulate(idy, work):
    """simulate --format mcap (zstd and lz4 chunks), read back by @mcap/core and rosmsg2-serialization
    (tests/ros2/read_bag.mjs): VIODE's topics in ROS 2's types, the folder's values; run alike."""
    import cv2
    folder = os.path.join(work, "sim_folder")
    shutil.rmtree(folder, ignore_errors=True)
    scene = ["--scene", "parking_lot", "--level", "mid", "--seed", "2", "--duration", "3"]
    r = sh([idy, "simulate"] + scene + ["--out", folder])
    check(r.returncode == 0, "simulate the EuRoC folder: " + r.stderr.strip()[-200:])
    imu = [l.split(",") for l in open(os.path.join(folder, "mav0", "imu0", "data.csv")) if not l.startswith("#")]
    cams = [l.split(",") for l in open(os.path.join(folder, "mav0", "cam0", "data.csv")) if not l.startswith("#")]
    png_sum = int(cv2.imread(os.path.join(folder, "mav0", "cam0", "data", cams[0][1].strip()),
                             cv2.IMREAD_UNCHANGED).astype("int64").sum())
    for comp in ["zstd", "lz4"]:
        out = os.path.join(work, "sim_mcap_" + comp)
        shutil.rmtree(out, ignore_errors=True)
        r = sh([idy, "simulate"] + scene + ["--out", out, "--format", "mcap", "--compression", comp])
        check(r.returncode == 0, "simulate --format mcap --compression %s: %s" % (comp, r.stderr.strip()[-300:]))
        bag = os.path.join(out, "2_mid")
        check(os.path.isfile(os.path.join(bag, "metadata.yaml")) and not os.path.exists(os.path.join(out, "mav0")),
              "%s: a rosbag2 folder named as VIODE's bag (2_mid/metadata.yaml), no EuRoC folder left" % comp)
        r = sh(["node", READER, os.path.join(bag, "2_mid_0.mcap")])
        check(r.returncode == 0, "%s: @mcap/core reads it (indexed and streamed, CRCs checked): %s" % (
            comp, r.stderr.strip()[-300:]))
        if r.returncode != 0:
            continue
        got = json.loads(r.stdout)
        types = {t: v["type"] for t, v in got["topics"].items()}
        check(types == {"/imu0": "sensor_msgs/msg/Imu", "/cam0/image_raw": "sensor_msgs/msg/Image",
                        "/cam1/image_raw": "sensor_msgs/msg/Image", "/odometry": "nav_msgs/msg/Odometry",
                        "/cam0/segmentation": "sensor_msgs/msg/Image"}, "%s: VIODE's topics, ROS 2 types: %s" % (
            comp, types))
        check(all(v["schema_encoding"] == "ros2msg" and v["message_encoding"] == "cdr" for v in got["topics"].values())
              and got["profile"] == "ros2", "%s: ros2 profile, ros2msg schemas, cdr messages" % comp)
        check(got["topics"]["/imu0"]["count"] == len(imu) and got["topics"]["/cam0/image_raw"]["count"] == len(cams),
              "%s: message counts equal the folder's" % comp)
        check(got["statistics"] and got["statistics"]["message_count"] == sum(v["count"] for v in got["topics"].values()),
              "%s: the summary's statistics count every message" % comp)
        first = got["first"]["/imu0"]
        check(first["stamp"] == int(imu[0][0]) and first["gyr"] == [float(v) for v in imu[0][1:4]] and
              first["acc"] == [float(v) for v in imu[0][4:7]], "%s: the first IMU sample is the folder's" % comp)
        img = got["first"]["/cam0/image_raw"]
        check(img["encoding"] == "mono8" and img["width"] == 752 and img["sum"] == png_sum,
              "%s: the first left image has the folder's pixels" % comp)
    cfg = os.path.join(work, "sim_mcap_zstd", "config", "sim_stereo_imu_config.yaml")
    outs = []
    for name, dataset in [("folder", folder), ("mcap", os.path.join(work, "sim_mcap_zstd", "2_mid"))]:
        o = os.path.join(work, "out_sim_" + name)
        r = sh([idy, "run", "-c", cfg, "-d", dataset, "-o", o, "--mode", "seg", "--threads", "1"])
        check(r.returncode == 0, "seg on the simulated %s: %s" % (name, r.stderr.strip()[-300:]))
        outs.append(o)
    if all(os.path.exists(os.path.join(o, "stats.json")) for o in outs):
        a, b = [json.load(open(os.path.join(o, "stats.json")))["summary"] for o in outs]
        check(filecmp.cmp(os.path.join(outs[0], "trajectory.tum"), os.path.join(outs[1], "trajectory.tum"),
                          shallow=False), "simulated ROS 2 bag: trajectory byte-identical to the folder's")
        check(a["classification"] == b["classification"], "simulated ROS 2 bag: the same classification (masks)")


def main():
    cmd, idy, work = sys.argv[1], sys.argv[2], sys.argv[3]
    {"setup": setup, "run": test_run, "info": test_info, "bad": test_bad, "simulate": test_simulate}[cmd](idy, work)
    print("%d failure(s)" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
