#!/usr/bin/python3
"""idyvins_ros' latency and the fastest playback it sustains (docs/ros.md).

ros_latency.py IDYVINS NODE WORK [--duration 30] [--rates 1,2,3,4] [--threads 1,2] [--queue-frames 10]

Renders a VIODE-style city-high bag once (WORK/seq), starts a roscore of its own on a free local
port, and for each thread mode and playback rate runs the node (mode idy, ~queue_frames as given:
beyond that many waiting frames the oldest is dropped, as a live robot would) beside
`rosbag play -r RATE`. Latency is per frame, from the arrival of its second image to its odometry.
A rate is sustained when no frame was dropped. Prints a Markdown table; writes WORK/latency.json.
"""
import argparse
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
import ros_check  # noqa: E402  (RosEnv: roscore on a free port, stopped at the end)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("idyvins")
    ap.add_argument("node")
    ap.add_argument("work")
    ap.add_argument("--duration", type=float, default=30)
    ap.add_argument("--rates", default="1,2,3,4")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--queue-frames", type=int, default=10)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    seq = os.path.join(a.work, "seq")
    bag, cfg = os.path.join(seq, "3_high.bag"), os.path.join(seq, "config", "sim_stereo_imu_config.yaml")
    if not os.path.exists(bag):
        subprocess.run([a.idyvins, "simulate", "--scene", "city", "--level", "high", "--seed", "1", "--duration",
                        str(a.duration), "--format", "bag", "--out", seq], check=True, capture_output=True)
    rows = []
    with ros_check.RosEnv(a.work) as ros:
        for th in [int(t) for t in a.threads.split(",")]:
            for rate in [float(r) for r in a.rates.split(",")]:
                out = os.path.join(a.work, "t%d_r%g" % (th, rate))
                node = ros.start([a.node, "__name:=idyvins", "_config_file:=" + cfg, "_mode:=idy", "_threads:=%d" % th,
                                  "_queue_frames:=%d" % a.queue_frames, "_out:=" + out], "node_t%d_r%g.log" % (th, rate))
                inputs = ["/imu0", "/cam0/image_raw", "/cam1/image_raw"]
                ros_check.wait_for(lambda: ros_check.subscribed(inputs, "/idyvins"), 60)
                t0 = time.time()
                subprocess.run(["rosbag", "play", "-q", "--wait-for-subscribers", "-r", str(rate), "--topics"] + inputs +
                               ["--", bag], env=ros.env, capture_output=True, check=True)
                play_s = time.time() - t0
                ros_check.stop(node)
                s = json.load(open(os.path.join(out, "stats.json")))["summary"]
                r = s["ros"]
                rows.append({"threads": th, "rate": rate, "play_s": play_s, "frames_in": r["frames_in"],
                             "dropped": r["frames_dropped_queue_full"], "processed": s["frames"],
                             "median_ms": r["latency_median_ms"], "p95_ms": r["latency_p95_ms"],
                             "max_ms": r["latency_max_ms"]})
                print(rows[-1], flush=True)
    json.dump(rows, open(os.path.join(a.work, "latency.json"), "w"), indent=1)
    print("| threads | rate | frames in | dropped | latency median | p95 | max | sustained |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        print("| %d | %g× | %d | %d | %.1f ms | %.1f ms | %.1f ms | %s |" % (
            r["threads"], r["rate"], r["frames_in"], r["dropped"], r["median_ms"], r["p95_ms"], r["max_ms"],
            "yes" if r["dropped"] == 0 else "no"))


if __name__ == "__main__":
    main()
