#!/usr/bin/python3
"""idyvins_ros with a real roscore (CTest): a VIODE-style bag played by `rosbag play` into the
node, its outputs recorded by `rosbag record`, compared with `idyvins run` on the same bag.

ros_check.py run IDYVINS NODE WORK   one node per thread mode beside one bag play (the second with
                                     loop closure on): every frame processed, result files
                                     byte-identical to the offline run's, odometry equal to its
                                     trajectory, clouds and image typed, loop topics published
ros_check.py bad IDYVINS NODE WORK   a node without a config, with a missing one, in a seg mode:
                                     exit 1 and one clear line

roscore runs on a free port of 127.0.0.1 with ROS_HOME and logs in WORK, and is stopped at the end,
whatever happens.
"""
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time

failures = []
FRAMES = 81  # a 4 s sequence at 20 Hz
TOPICS = ["/idyvins1/odometry", "/idyvins1/path", "/idyvins1/map_static", "/idyvins1/map_dynamic",
          "/idyvins1/feature_image", "/idyvins1/timing", "/tf", "/idyvins2/odometry_loop", "/idyvins2/path_loop",
          "/idyvins2/map_static_loop"]


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class RosEnv:
    """A roscore of its own on a free local port; every process started here is stopped at exit."""

    def __init__(self, work):
        self.work = work
        self.procs = []
        self.env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % free_port(), ROS_IP="127.0.0.1",
                        ROS_HOME=os.path.join(work, "ros_home"), ROS_LOG_DIR=os.path.join(work, "ros_log"))
        os.environ.update({k: self.env[k] for k in ("ROS_MASTER_URI", "ROS_IP", "ROS_HOME", "ROS_LOG_DIR")})

    def start(self, cmd, log):
        p = subprocess.Popen(cmd, env=self.env, stdout=open(os.path.join(self.work, log), "w"),
                             stderr=subprocess.STDOUT, start_new_session=True)
        self.procs.append(p)
        return p

    def __enter__(self):
        port = int(self.env["ROS_MASTER_URI"].rsplit(":", 1)[1])
        self.start(["roscore", "-p", str(port)], "roscore.log")
        import rosgraph
        deadline = time.time() + 30
        while not rosgraph.is_master_online() and time.time() < deadline:
            time.sleep(0.2)
        check(rosgraph.is_master_online(), "roscore up on port %d" % port)
        return self

    def __exit__(self, *exc):
        for p in reversed(self.procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGINT)
        for p in reversed(self.procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


def stop(p, timeout=90):
    os.killpg(p.pid, signal.SIGINT)
    try:
        return p.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        return None


def simulate(idy, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    r = subprocess.run([idy, "simulate", "--scene", "city", "--level", "high", "--seed", "1", "--duration", "4",
                        "--format", "bag", "--out", os.path.join(work, "seq")], capture_output=True, text=True)
    check(r.returncode == 0, "simulate a VIODE-style bag: " + r.stderr.strip()[-200:])
    return os.path.join(work, "seq", "3_high.bag"), os.path.join(work, "seq", "config", "sim_stereo_imu_config.yaml")


def wait_for(cond, timeout):
    deadline = time.time() + timeout
    while time.time() < deadline:
        if cond():
            return True
        time.sleep(0.2)
    return False


def subscribed(topics, node):
    import rosgraph
    _, subs, _ = rosgraph.Master("/ros_check").getSystemState()
    by_topic = {t: nodes for t, nodes in subs}
    return all(any(n.startswith(node) for n in by_topic.get(t, [])) for t in topics)


class TimingCounter:
    """Counts each node's ~timing messages (one per processed frame) from this process."""

    def __init__(self, nodes):
        import rospy
        from std_msgs.msg import Float64MultiArray
        rospy.init_node("ros_check", anonymous=True, disable_signals=True)
        self.counts = {th: 0 for th in nodes}
        self.subs = [rospy.Subscriber("/idyvins%d/timing" % th, Float64MultiArray, self.count, th, queue_size=1000)
                     for th in nodes]
        check(wait_for(lambda: all(s.get_num_connections() > 0 for s in self.subs), 60),
              "the check subscribed to both nodes' timing topics")

    def count(self, _msg, th):
        self.counts[th] += 1

    def reached(self, expected):
        return all(self.counts[th] >= n for th, n in expected.items())


def loop_config(cfg):
    """The config with loop_closure: 1, beside it."""
    path = os.path.join(os.path.dirname(cfg), "loop.yaml")
    text = "".join(line for line in open(cfg) if not line.startswith("loop_closure:"))
    open(path, "w").write(text + "loop_closure: 1\n")
    return path


def play_into_nodes(ros, bag, cfg, work):
    """Two nodes (threads 1 and 2, the second closing loops), rosbag record on the first and the
    second's loop topics; returns the nodes' exit codes."""
    nodes = {}
    for th in (1, 2):
        nodes[th] = ros.start([NODE, "__name:=idyvins%d" % th, "_config_file:=" + (cfg if th == 1 else loop_config(cfg)),
                               "_mode:=idy",
                               "_threads:=%d" % th, "_body_frame:=body%d" % th, "_out:=" + os.path.join(work, "node%d" % th)],
                               "node%d.log" % th)
    rec = ros.start(["rosbag", "record", "-O", os.path.join(work, "recorded.bag")] + TOPICS, "record.log")
    check(wait_for(lambda: subscribed(TOPICS, "/record"), 60), "rosbag record subscribed to the node's topics")
    inputs = ["/imu0", "/cam0/image_raw", "/cam1/image_raw"]
    check(wait_for(lambda: subscribed(inputs, "/idyvins1") and subscribed(inputs, "/idyvins2"), 60),
          "both nodes subscribed to the config's imu_topic, image0_topic, image1_topic")
    # --wait-for-subscribers waits for one subscriber per topic; -d gives the second node time to
    # connect too after each advertise (under load a connection can take a while). --keep-alive:
    # without it rosbag play exits as soon as it has handed its last message to roscpp, and what
    # is still queued for the sockets can go with it (the likely cause of one run under load where
    # both nodes got 79 of the 81 frames); it is stopped here once every frame has arrived.
    timing = TimingCounter(nodes)
    play = ros.start(["rosbag", "play", "-q", "--keep-alive", "--wait-for-subscribers", "-d", "2", "--topics"] +
                     inputs + ["--", bag], "play.log")
    # The node drains its queue when stopped, but what it publishes while ROS shuts down is less
    # sure to reach the recorder: the stop comes once every frame's timing message has arrived
    # (under load a node can be seconds behind the bag). With two threads the last frame's back
    # end waits for a next frame, so it runs at the stop.
    expected = {1: FRAMES, 2: FRAMES - 1}
    wait_for(lambda: timing.reached(expected) or play.poll() is not None, 300)
    check(timing.reached(expected),
          "timing messages before the stop: %s of %s" % (timing.counts, expected))
    alive = play.poll() is None
    check(alive, "rosbag play kept alive after the bag" + ("" if alive else " (exit %s: %s)" % (
        play.returncode, open(os.path.join(work, "play.log")).read().strip()[-200:])))
    stop(play)
    codes = {}
    for th, p in nodes.items():
        time.sleep(1.0)  # the frame's other messages follow its timing message
        codes[th] = stop(p)
    stop(rec)
    return codes


def compare_files(work, th):
    out, ref = os.path.join(work, "node%d" % th), os.path.join(work, "offline%d" % th)
    loop = ["trajectory_loop.tum", "loops.csv", "map_static_loop.ply"] if th == 2 else []
    for f in ["trajectory.tum", "trajectory.csv", "state.csv", "map_static.ply", "map_dynamic.ply", "map_all.ply"] + loop:
        same = os.path.exists(os.path.join(out, f)) and open(os.path.join(out, f), "rb").read() == \
            open(os.path.join(ref, f), "rb").read()
        check(same, "threads %d: %s byte-identical to `idyvins run --threads %d`'s" % (th, f, th))
    s = json.load(open(os.path.join(out, "stats.json")))["summary"]
    check(s["frames"] == FRAMES and s["ros"]["frames_in"] == FRAMES and s["ros"]["frames_dropped_queue_full"] == 0,
          "threads %d: every frame processed (%d of %d)" % (th, s["frames"], FRAMES))
    manifest = json.load(open(os.path.join(out, "idyvins_manifest.json")))
    check(manifest.get("tool") == "run" and "latency.csv" in manifest.get("entries", []),
          "threads %d: ~out staged and published whole (its manifest lists latency.csv)" % th)
    leftovers = [n for n in os.listdir(work) if n.startswith("node%d.partial-" % th)]
    check(not leftovers, "threads %d: no staging folder left (%s)" % (th, leftovers))
    lat = open(os.path.join(out, "latency.csv")).read().split("\n")[1:]
    check(len([l for l in lat if l]) == FRAMES, "threads %d: latency.csv has one row per frame" % th)
    print("threads %d: latency median %.1f ms, p95 %.1f ms" % (th, s["ros"]["latency_median_ms"],
                                                              s["ros"]["latency_p95_ms"]))


def tum_rows(path):
    return [[float(x) for x in l.split()] for l in open(path) if l.strip() and not l.startswith("#")]


def check_recorded(work):
    import rosbag
    msgs = {}
    with rosbag.Bag(os.path.join(work, "recorded.bag")) as bag:
        for topic, msg, _ in bag.read_messages():
            msgs.setdefault(topic, []).append(msg)
    ref = tum_rows(os.path.join(work, "offline1", "trajectory.tum"))
    odom = msgs.get("/idyvins1/odometry", [])
    check(len(odom) == len(ref), "odometry: %d messages for %d poses" % (len(odom), len(ref)))
    worst = 0.0
    for m, r in zip(odom, ref):
        p, q = m.pose.pose.position, m.pose.pose.orientation
        worst = max(worst, abs(m.header.stamp.to_sec() - r[0]),
                    *[abs(a - b) for a, b in zip([p.x, p.y, p.z, q.x, q.y, q.z, q.w], r[1:])])
    check(bool(odom) and worst < 1e-6 and odom[0]._type == "nav_msgs/Odometry" and odom[0].header.frame_id == "world",
          "odometry equals the offline trajectory (largest difference %.1e, TUM's printed precision)" % worst)
    # The covariance model (publisher.h): diagonal, positive, position sigma 0.02 m + 1 % of the path.
    length, last = 0.0, None
    cov_ok = bool(odom)
    for m in odom:
        p = m.pose.pose.position
        length += 0.0 if last is None else ((p.x - last[0]) ** 2 + (p.y - last[1]) ** 2 + (p.z - last[2]) ** 2) ** 0.5
        last = (p.x, p.y, p.z)
        c = m.pose.covariance
        sp = 0.02 + 0.01 * length
        cov_ok = cov_ok and all(abs(c[7 * k] - sp * sp) < 1e-9 for k in range(3)) and all(
            c[7 * k] > 0 for k in range(6)) and sum(abs(v) for v in c) - sum(c[7 * k] for k in range(6)) == 0 and all(
            m.twist.covariance[7 * k] > 0 for k in range(6))
    check(cov_ok, "odometry covariance: diagonal, never zero, position sigma 0.02 m + 1 %% of the path (%.2f m: "
          "%.3f m at the end)" % (length, 0.02 + 0.01 * length))
    path = msgs.get("/idyvins1/path", [])
    check(bool(path) and path[-1]._type == "nav_msgs/Path" and len(path[-1].poses) == len(ref), "path: every pose")
    for name in ("map_static", "map_dynamic"):
        clouds = msgs.get("/idyvins1/" + name, [])
        fields = [f.name for f in clouds[-1].fields] if clouds else []
        check(bool(clouds) and clouds[-1]._type == "sensor_msgs/PointCloud2" and fields == ["x", "y", "z", "label"]
              and clouds[-1].width > 0, "%s: PointCloud2 x, y, z, label (%d points)" % (name, clouds[-1].width if clouds else 0))
    img = msgs.get("/idyvins1/feature_image", [])
    check(bool(img) and img[-1]._type == "sensor_msgs/Image" and img[-1].encoding == "bgr8" and img[-1].width > 0,
          "feature_image: bgr8 sensor_msgs/Image (%d messages)" % len(img))
    timing = msgs.get("/idyvins1/timing", [])
    check(len(timing) == FRAMES and timing[0]._type == "std_msgs/Float64MultiArray" and len(timing[0].data) == 7,
          "timing: one Float64MultiArray per frame (%d)" % len(timing))
    tf = [t for m in msgs.get("/tf", []) for t in m.transforms if t.child_frame_id == "body1"]
    check(len(tf) == len(ref), "TF world -> body1: one per pose (%d)" % len(tf))
    # Loop closure (node 2): 4 s close no loop, so the live loop odometry is the odometry; the last
    # path_loop is the final pose graph's trajectory (trajectory_loop.tum).
    ref2 = tum_rows(os.path.join(work, "offline2", "trajectory.tum"))
    ref2_loop = tum_rows(os.path.join(work, "offline2", "trajectory_loop.tum"))
    odom = msgs.get("/idyvins2/odometry_loop", [])
    worst = max([abs(a - b) for m, r in zip(odom, ref2) for a, b in zip(
        [m.header.stamp.to_sec(), m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z],
        r[:4])], default=1.0)
    check(len(odom) == len(ref2) and odom[0]._type == "nav_msgs/Odometry" and worst < 1e-6,
          "odometry_loop: %d messages for %d poses, largest difference to the odometry %.1e (no loop)" %
          (len(odom), len(ref2), worst))
    path = msgs.get("/idyvins2/path_loop", [])
    check(bool(path) and path[-1]._type == "nav_msgs/Path" and len(path[-1].poses) == len(ref2_loop),
          "path_loop: the last is trajectory_loop.tum (%d poses)" % (len(path[-1].poses) if path else 0))
    cloud = msgs.get("/idyvins2/map_static_loop", [])
    check(bool(cloud) and cloud[-1]._type == "sensor_msgs/PointCloud2" and cloud[-1].width > 0,
          "map_static_loop: PointCloud2 (%d points)" % (cloud[-1].width if cloud else 0))


def test_run(idy, work):
    bag, cfg = simulate(idy, work)
    for th in (1, 2):
        r = subprocess.run([idy, "run", "-c", cfg if th == 1 else loop_config(cfg), "-d", bag, "-o",
                            os.path.join(work, "offline%d" % th), "--mode",
                            "idy", "--threads", str(th)], capture_output=True, text=True)
        check(r.returncode == 0, "idyvins run --threads %d on the bag" % th)
    with RosEnv(work) as ros:
        codes = play_into_nodes(ros, bag, cfg, work)
    for th in (1, 2):
        check(codes[th] == 0, "node threads %d stopped by SIGINT with exit 0 (%s)" % (th, codes[th]))
        compare_files(work, th)
    check_recorded(work)


def test_bad(idy, work):
    bag, cfg = simulate(idy, work)
    foreign = os.path.join(work, "foreign")  # a folder of the user's: ~out refuses it, before any message
    os.makedirs(foreign, exist_ok=True)
    open(os.path.join(foreign, "notes.txt"), "w").write("mine\n")
    with RosEnv(work) as ros:
        for name, args, expect in [
                ("no config", [], "no config"),
                ("missing config", ["_config_file:=" + os.path.join(work, "nope.yaml")], "nope.yaml"),
                ("seg mode", ["_config_file:=" + cfg, "_mode:=seg"], "needs ground-truth masks"),
                ("threads 3", ["_config_file:=" + cfg, "_threads:=3"], "~threads must be 1 or 2")]:
            r = subprocess.run([NODE, "__name:=bad"] + args, env=ros.env, capture_output=True, text=True, timeout=60)
            lines = [l for l in r.stderr.strip().split("\n") if l]
            check(r.returncode == 1 and len(lines) == 1 and expect in lines[0],
                  "%s: exit %d, %s" % (name, r.returncode, lines))
        # its own name: the parameters above stay on the server under /bad
        r = subprocess.run([NODE, "__name:=bad_out", "_config_file:=" + cfg, "_out:=" + foreign], env=ros.env,
                           capture_output=True, text=True, timeout=60)
        lines = [l for l in r.stderr.strip().split("\n") if l]
        check(r.returncode == 1 and len(lines) == 1 and "file(s) idyvins run did not write" in lines[0],
              "foreign ~out: exit %d, %s" % (r.returncode, lines))
    check(sorted(os.listdir(foreign)) == ["notes.txt"] and open(os.path.join(foreign, "notes.txt")).read() == "mine\n",
          "foreign ~out left as it was")


if __name__ == "__main__":
    part, IDY, NODE, WORK = sys.argv[1:5]
    {"run": test_run, "bad": test_bad}[part](IDY, WORK)
    sys.exit(1 if failures else 0)
