#!/usr/bin/python3
"""ROS1 bags against EuRoC folders, through the idyvins command (CTest).

bag_check.py setup IDYVINS WORK   simulate a short sequence, write bags of it with python3-rosbag
bag_check.py run IDYVINS WORK     run on the folder, on each bag and on a converted bag: byte-identical
                                  outputs, same ATE
bag_check.py seg IDYVINS WORK     masks from a segmentation topic: seg and idy identical to the folder's
bag_check.py viode IDYVINS WORK   simulate --format both: VIODE's topics and types; bag and folder alike
bag_check.py viode_bench IDYVINS WORK  bench --suite viode on a VIODE-like tree of simulated bags
bag_check.py info IDYVINS WORK    info on the folder and on a bag: same counts, rates and gaps
bag_check.py bad IDYVINS WORK     bad bags and configs: exit code 1 and one clear line each
"""
import filecmp
import json
import os
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
MAKE_BAG = os.path.join(HERE, "make_test_bag.py")
# (file, compression, encoding, ground truth kind, its topic)
VARIANTS = [
    ("plain_mono8_odometry.bag", "none", "mono8", "odometry", "/odometry"),
    ("bz2_bgr8_transform.bag", "bz2", "bgr8", "transform", "/vicon/firefly_sbx/firefly_sbx"),
    ("lz4_rgb8_pose.bag", "lz4", "rgb8", "pose", "/pose"),
    ("lz4_png_point.bag", "lz4", "png", "point", "/leica/position"),
]
SEG_BAG = "viode_like_segmentation.bag"
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def sh(cmd):
    return subprocess.run(cmd, capture_output=True, text=True)


def config(work):
    return os.path.join(work, "seq", "config", "sim_stereo_imu_config.yaml")


def setup(idy, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    r = sh([idy, "simulate", "--scene", "city", "--level", "high", "--seed", "1", "--duration", "4", "--out",
            os.path.join(work, "seq")])
    check(r.returncode == 0, "simulate: " + r.stderr.strip()[-200:])
    for name, comp, enc, gt, _ in VARIANTS:
        r = sh(["/usr/bin/python3", MAKE_BAG, os.path.join(work, "seq"), os.path.join(work, name), "--compression",
                comp, "--encoding", enc, "--groundtruth", gt])
        check(r.returncode == 0, "write %s %s" % (name, r.stderr.strip()[-300:]))
    r = sh(["/usr/bin/python3", MAKE_BAG, os.path.join(work, "seq"), os.path.join(work, SEG_BAG), "--compression",
            "lz4", "--segmentation"])
    check(r.returncode == 0, "write %s %s" % (SEG_BAG, r.stderr.strip()[-300:]))
    for c in ["truncate", "unindex", "backwards", "encoding", "empty"]:
        r = sh(["/usr/bin/python3", MAKE_BAG, os.path.join(work, "seq"), os.path.join(work, "bad_%s.bag" % c),
                "--frames", "12", "--corrupt", c])
        check(r.returncode == 0, "write bad_%s.bag %s" % (c, r.stderr.strip()[-300:]))


def run(idy, work, dataset, out, extra=(), cfg=None):
    r = sh([idy, "run", "-c", cfg or config(work), "-d", dataset, "-o", out, "--mode", "idy", "--threads", "1"] + list(extra))
    return r, (json.load(open(os.path.join(out, "stats.json")))["summary"] if r.returncode == 0 else None)


def test_run(idy, work):
    ref_out = os.path.join(work, "out_folder")
    r, ref = run(idy, work, os.path.join(work, "seq"), ref_out)
    check(r.returncode == 0 and ref is not None and "ate_rmse_m" in ref, "run on the folder")
    for name, _, _, _, topic in VARIANTS:
        out = os.path.join(work, "out_" + name)
        cfg = None
        if "png" in name:  # image_transport's names for compressed images
            cfg = edited_config(work, "compressed", r"^image0_topic:.*$", 'image0_topic: "/cam0/image_raw/compressed"')
            edit(cfg, r"^image1_topic:.*$", 'image1_topic: "/cam1/image_raw/compressed"')
        r, s = run(idy, work, os.path.join(work, name), out, ["--groundtruth-topic", topic], cfg)
        check(r.returncode == 0, "run on %s: %s" % (name, r.stderr.strip()[-300:]))
        if r.returncode != 0:
            continue
        for f in ["trajectory.tum", "trajectory.csv", "state.csv", "map_static.ply", "map_dynamic.ply"]:
            check(filecmp.cmp(os.path.join(ref_out, f), os.path.join(out, f), shallow=False),
                  "%s: %s byte-identical to the folder's" % (name, f))
        check(s.get("ate_rmse_m") == ref["ate_rmse_m"], "%s: ATE %s == folder's %s" % (
            name, s.get("ate_rmse_m"), ref["ate_rmse_m"]))
    # convert, then run on the folder it wrote: identical again.
    conv = os.path.join(work, "converted")
    shutil.rmtree(conv, ignore_errors=True)
    r = sh([idy, "convert", os.path.join(work, VARIANTS[1][0]), conv, "-c", config(work), "--groundtruth-topic",
            VARIANTS[1][4]])
    check(r.returncode == 0, "convert %s: %s" % (VARIANTS[1][0], r.stderr.strip()[-300:]))
    r, s = run(idy, work, conv, os.path.join(work, "out_converted"))
    check(r.returncode == 0 and filecmp.cmp(os.path.join(ref_out, "trajectory.tum"),
                                            os.path.join(work, "out_converted", "trajectory.tum"), shallow=False),
          "convert then run: trajectory byte-identical to the original folder's")
    check(s is not None and s.get("ate_rmse_m") == ref["ate_rmse_m"], "convert then run: same ATE")
    # track (the front end alone) on a bag: the same figures as on the folder.
    figures = []
    for dataset in (os.path.join(work, "seq"), os.path.join(work, VARIANTS[0][0])):
        js = os.path.join(work, "track_%s.json" % os.path.basename(dataset))
        r = sh([idy, "track", "-c", config(work), "-d", dataset, "--json", js])
        check(r.returncode == 0, "track on %s: %s" % (os.path.basename(dataset), r.stderr.strip()[-300:]))
        figures.append({k: v for k, v in json.load(open(js)).items() if k != "tracking_ms"} if r.returncode == 0 else None)
    check(figures[0] is not None and figures[0] == figures[1], "track: bag and folder give the same figures")


def test_seg(idy, work):
    """Masks from a VIODE-style segmentation topic: seg and idy as on the folder's masks."""
    bag = os.path.join(work, SEG_BAG)
    cfg = edited_config(work, "segmentation", r"^segmentation_topic:.*$", 'segmentation_topic: "/cam0/segmentation"')
    edit(cfg, r"^segmentation_rgb_ids:.*$", "segmentation_rgb_ids: " + bag + ".rgb_ids.txt")
    edit(cfg, r"^segmentation_vehicle_ids:.*$", "segmentation_vehicle_ids: " + bag + ".vehicle_ids.txt")
    for mode in ["seg", "idy"]:
        outs = []
        for name, dataset, c in [("folder", os.path.join(work, "seq"), config(work)), ("bag", bag, cfg)]:
            out = os.path.join(work, "out_%s_%s" % (mode, name))
            r = sh([idy, "run", "-c", c, "-d", dataset, "-o", out, "--mode", mode, "--threads", "1",
                    "--groundtruth-topic", "/odometry"] if name == "bag" else
                   [idy, "run", "-c", c, "-d", dataset, "-o", out, "--mode", mode, "--threads", "1"])
            check(r.returncode == 0, "%s on the %s: %s" % (mode, name, r.stderr.strip()[-300:]))
            outs.append(out)
        if not all(os.path.exists(os.path.join(o, "stats.json")) for o in outs):
            continue
        a, b = [json.load(open(os.path.join(o, "stats.json")))["summary"] for o in outs]
        check(filecmp.cmp(os.path.join(outs[0], "trajectory.tum"), os.path.join(outs[1], "trajectory.tum"),
                          shallow=False), "%s: trajectory byte-identical between bag and folder" % mode)
        check(a["classification"] is not None and a["classification"] == b["classification"],
              "%s: classification figures identical (%s)" % (mode, json.dumps(b["classification"])[:120]))
    # convert writes the masks too: seg on the converted folder, identical again.
    conv = os.path.join(work, "converted_seg")
    shutil.rmtree(conv, ignore_errors=True)
    r = sh([idy, "convert", bag, conv, "-c", cfg, "--groundtruth-topic", "/odometry"])
    check(r.returncode == 0 and os.path.isdir(os.path.join(conv, "mav0", "cam0", "mask")),
          "convert writes cam0/mask from the segmentation topic")
    r = sh([idy, "run", "-c", config(work), "-d", conv, "-o", os.path.join(work, "out_seg_converted"), "--mode", "seg",
            "--threads", "1"])
    check(r.returncode == 0 and filecmp.cmp(os.path.join(work, "out_seg_folder", "trajectory.tum"),
                                            os.path.join(work, "out_seg_converted", "trajectory.tum"), shallow=False),
          "seg on the converted folder: trajectory byte-identical to the original folder's")


def test_viode(idy, work):
    """simulate --format both: VIODE's topics and types (read back by python3-rosbag), and
    run on the bag as on the folder, seg mode included."""
    import rosbag
    import numpy as np
    out = os.path.join(work, "viode_sim")
    shutil.rmtree(out, ignore_errors=True)
    r = sh([idy, "simulate", "--scene", "parking_lot", "--level", "mid", "--seed", "2", "--duration", "3", "--out", out,
            "--format", "both", "--compression", "lz4"])
    check(r.returncode == 0, "simulate --format both: " + r.stderr.strip()[-300:])
    bag_path = os.path.join(out, "2_mid.bag")
    check(os.path.exists(bag_path), "the bag is named as VIODE's (2_mid.bag)")
    if not os.path.exists(bag_path):
        return
    bag = rosbag.Bag(bag_path)
    types = {t: i.msg_type for t, i in bag.get_type_and_topic_info().topics.items()}
    check(types == {"/imu0": "sensor_msgs/Imu", "/cam0/image_raw": "sensor_msgs/Image",
                    "/cam1/image_raw": "sensor_msgs/Image", "/odometry": "nav_msgs/Odometry",
                    "/cam0/segmentation": "sensor_msgs/Image"}, "VIODE's topics and types: %s" % types)
    table = {}
    for row in open(os.path.join(out, "config", "rgb_ids.txt")).read().splitlines()[1:]:
        i, rr, gg, bb = [int(x) for x in row.split(",")]
        table[(rr, gg, bb)] = i
    seen = set()
    for _, m, _ in bag.read_messages(topics=["/cam0/segmentation"]):
        check(m.encoding == "rgb8", "segmentation encoding rgb8") if not seen else None
        px = np.frombuffer(m.data, dtype=np.uint8).reshape(m.height, m.width, 3)
        seen |= {tuple(int(v) for v in c) for c in np.unique(px.reshape(-1, 3), axis=0)}
    bag.close()
    check(seen and all(c in table for c in seen), "every segmentation colour is in VIODE's rgb_ids.txt")
    moving = [int(l.split(",")[0]) for l in open(os.path.join(out, "config", "vehicle_ids_parking_lot.txt"))
              .read().splitlines()[1:] if "dynamic" in l]
    check(any(table[c] in moving for c in seen), "moving vehicles coloured as VIODE's dynamic vehicles")
    cfg = os.path.join(out, "config", "sim_stereo_imu_config.yaml")
    outs = []
    for name, dataset in [("folder", out), ("bag", bag_path)]:
        o = os.path.join(work, "out_viode_" + name)
        r = sh([idy, "run", "-c", cfg, "-d", dataset, "-o", o, "--mode", "seg", "--threads", "1"])
        check(r.returncode == 0, "seg on the simulated %s: %s" % (name, r.stderr.strip()[-300:]))
        outs.append(o)
    if all(os.path.exists(os.path.join(o, "stats.json")) for o in outs):
        a, b = [json.load(open(os.path.join(o, "stats.json")))["summary"] for o in outs]
        check(filecmp.cmp(os.path.join(outs[0], "trajectory.tum"), os.path.join(outs[1], "trajectory.tum"),
                          shallow=False), "simulated bag: trajectory byte-identical to the folder's")
        check(a.get("ate_rmse_m") == b.get("ate_rmse_m") and a["classification"] == b["classification"],
              "simulated bag: same ATE and classification as the folder")


def test_viode_bench(idy, work):
    """bench --suite viode on a VIODE-like tree written by simulate --format bag."""
    tree = os.path.join(work, "viode_tree")
    shutil.rmtree(tree, ignore_errors=True)
    for env, scene, level, name in [("city_day", "city", "high", "3_high"), ("parking_lot", "parking_lot", "mid", "2_mid")]:
        sim = os.path.join(work, "viode_sim_" + env)
        shutil.rmtree(sim, ignore_errors=True)
        r = sh([idy, "simulate", "--scene", scene, "--level", level, "--seed", "3", "--duration", "3", "--out", sim,
                "--format", "bag"])
        check(r.returncode == 0 and not os.path.exists(os.path.join(sim, "mav0")),
              "simulate --format bag %s (no EuRoC folder left)" % env)
        os.makedirs(os.path.join(tree, env), exist_ok=True)
        shutil.move(os.path.join(sim, name + ".bag"), os.path.join(tree, env, name + ".bag"))
    cfg_dir = os.path.join(work, "viode_sim_city_day", "config")
    for f in os.listdir(os.path.join(HERE, "..", "config", "viode")):
        if f.startswith("vehicle_ids_"):
            shutil.copy(os.path.join(HERE, "..", "config", "viode", f), cfg_dir)
    out = os.path.join(work, "viode_bench")
    shutil.rmtree(out, ignore_errors=True)
    r = sh([idy, "bench", "--suite", "viode", "--data", tree, "--out", out, "--modes", "baseline,seg,idy", "--config",
            os.path.join(cfg_dir, "sim_stereo_imu_config.yaml")])
    check(r.returncode == 0, "bench --suite viode: " + r.stderr.strip()[-300:])
    t1 = open(os.path.join(out, "table1.md")).read() if r.returncode == 0 else ""
    header = [l for l in t1.splitlines() if l.startswith("| mode |")]
    check(bool(header) and "city_day_high" in header[0] and "parking_lot_mid" in header[0],
          "table1 has the VIODE columns: %s" % (header[0] if header else None))
    rows = [l for l in t1.splitlines() if l.startswith("| baseline |") or l.startswith("| seg |") or l.startswith("| idy |")]
    # The SE3 table, then the same runs after a similarity alignment with their scale errors.
    check(len(rows) == 6 and all(" x " not in l for l in rows) and all(l.count(" %)") == 2 for l in rows[3:]),
          "every mode has an ATE, a sim3 ATE and a scale error in every column: %s" % rows)
    dyn = open(os.path.join(out, "dynamic.md")).read() if r.returncode == 0 else ""
    check("| city_day_high | seg |" in dyn and "| parking_lot_mid | idy |" in dyn,
          "classification against the segmentation masks for every bag")


def info_json(idy, args):
    r = sh([idy, "info", "--json"] + args)
    return r, (json.loads(r.stdout) if r.returncode == 0 else None)


def test_info(idy, work):
    r, folder = info_json(idy, [os.path.join(work, "seq")])
    check(r.returncode == 0, "info on the folder")
    for name, _, _, _, topic in VARIANTS[:2]:
        r, bag = info_json(idy, [os.path.join(work, name), "--groundtruth-topic", topic, "-c", config(work)])
        check(r.returncode == 0, "info on %s: %s" % (name, r.stderr.strip()[-300:]))
        if r.returncode != 0:
            continue
        for stream in ["imu", "cam0", "cam1", "stereo_pairs", "groundtruth"]:
            check(bag[stream] == folder[stream], "%s: %s stats equal the folder's" % (name, stream))
        for k in ["unmatched_cam0", "unmatched_cam1", "image_width", "image_height"]:
            check(bag[k] == folder[k], "%s: %s equal" % (name, k))
        topics = {t["topic"]: (t["type"], t["count"]) for t in bag["topics"]}
        check(topics.get("/imu0") == ("sensor_msgs/Imu", folder["imu"]["count"]), "%s: /imu0 listed" % name)
        check(topics.get("/cam0/image_raw") == ("sensor_msgs/Image", folder["cam0"]["count"]),
              "%s: /cam0/image_raw listed" % name)


def edit(path, pattern, replacement):
    """Replaces the line matching `pattern` (or appends `replacement`)."""
    text = open(path).read()
    if re.search(pattern, text, flags=re.M):
        text = re.sub(pattern, replacement, text, flags=re.M)
    else:
        text += "\n" + replacement + "\n"
    open(path, "w").write(text)


def edited_config(work, name, pattern, replacement, all_files=False):
    """A copy of the sequence's config folder with one edit (in every YAML file with all_files)."""
    src = os.path.dirname(config(work))
    dst = os.path.join(work, "config_" + name)
    shutil.rmtree(dst, ignore_errors=True)
    shutil.copytree(src, dst)
    path = os.path.join(dst, os.path.basename(config(work)))
    for f in sorted(os.listdir(dst)) if all_files else [os.path.basename(path)]:
        if f.endswith(".yaml"):
            edit(os.path.join(dst, f), pattern, replacement)
    return path


def test_bad(idy, work):
    cases = [
        ("bad_truncate.bag", None, "truncated"),
        ("bad_unindex.bag", None, "rosbag reindex"),
        ("bad_backwards.bag", None, "topic '/imu0' message 51"),
        ("bad_encoding.bag", None, "unsupported image encoding 'yuv422'"),
        ("bad_empty.bag", None, "holds no messages"),
        ("plain_mono8_odometry.bag", edited_config(work, "topic", r"^image0_topic:.*$", 'image0_topic: "/cam0/missing"'),
         "topic '/cam0/missing' (config key image0_topic) is not in the bag; its image topics: /cam0/image_raw"),
        ("plain_mono8_odometry.bag", edited_config(work, "size", r"^image_width:.*$", "image_width: 640", True),
         "image is 752x480, the config says 640x480"),
        ("plain_mono8_odometry.bag", None, "topic '/nothing' (config key groundtruth_topic) is not in the bag"),
    ]
    for i, (bag, cfg, expected) in enumerate(cases):
        args = [idy, "run", "-c", cfg or config(work), "-d", os.path.join(work, bag), "-o",
                os.path.join(work, "out_bad%d" % i)]
        if i == len(cases) - 1:
            args += ["--groundtruth-topic", "/nothing"]
        r = sh(args)
        lines = [l for l in r.stderr.splitlines() if l.strip()]
        check(r.returncode == 1, "%s: exit code %d (1 expected)" % (bag, r.returncode))
        check(len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0],
              "%s: one clear line containing '%s', got %r" % (bag, expected, lines))


def main():
    cmd, idy, work = sys.argv[1], sys.argv[2], sys.argv[3]
    {"setup": setup, "run": test_run, "seg": test_seg, "viode": test_viode, "viode_bench": test_viode_bench,
     "info": test_info,
     "bad": test_bad}[cmd](idy, work)
    print("%d failure(s)" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
