#!/usr/bin/python3
"""Writes a ROS1 bag from a EuRoC folder with Debian's python3-rosbag (an
implementation independent of idyvins), for the bag reader's tests.

make_test_bag.py EUROC_DIR OUT.bag [--compression none|bz2|lz4] [--encoding mono8|bgr8|rgb8|png]
                 [--groundtruth odometry|transform|pose|point|none] [--frames N]
                 [--corrupt truncate|unindex|backwards|encoding|empty]

Topics: /imu0 (sensor_msgs/Imu), /cam0/image_raw and /cam1/image_raw
(sensor_msgs/Image, or sensor_msgs/CompressedImage on .../compressed for png),
ground truth as VIODE (/odometry, nav_msgs/Odometry) or EuRoC (/vicon/firefly_sbx/firefly_sbx,
TransformStamped; /leica/position, PointStamped; /pose, PoseStamped).
"""
import argparse
import csv
import io
import os
import sys

import numpy as np
import rosbag
import rospy
from PIL import Image as PilImage
from geometry_msgs.msg import PointStamped, PoseStamped, TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CompressedImage, Image, Imu

GT_TOPICS = {"odometry": "/odometry", "transform": "/vicon/firefly_sbx/firefly_sbx", "pose": "/pose",
             "point": "/leica/position"}


def rows(path):
    with open(path) as f:
        return [r for r in csv.reader(f) if r and not r[0].startswith("#")]


def stamp(ns):
    return rospy.Time(int(ns) // 1_000_000_000, int(ns) % 1_000_000_000)


def image_msg(png_path, t, encoding):
    gray = np.array(PilImage.open(png_path).convert("L"))
    if encoding == "png":
        m = CompressedImage()
        m.header.stamp = t
        m.format = "mono8; png compressed "
        buf = io.BytesIO()
        PilImage.fromarray(gray).save(buf, format="PNG")
        m.data = buf.getvalue()
        return m
    m = Image()
    m.header.stamp = t
    m.height, m.width = gray.shape
    m.encoding = encoding
    if encoding == "mono8":
        m.step = m.width
        m.data = gray.tobytes()
    else:  # colour: the same gray in every channel, so gray conversion gives it back
        rgb = np.repeat(gray[:, :, None], 3, axis=2)
        m.step = 3 * m.width
        m.data = rgb.tobytes()
    return m


def gt_msg(kind, t, r):
    p = [float(x) for x in r[1:4]]
    q = [float(x) for x in r[4:8]]  # w x y z
    if kind == "odometry":
        m = Odometry()
        m.header.stamp = t
        m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z = p
        o = m.pose.pose.orientation
    elif kind == "transform":
        m = TransformStamped()
        m.header.stamp = t
        m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = p
        o = m.transform.rotation
    elif kind == "pose":
        m = PoseStamped()
        m.header.stamp = t
        m.pose.position.x, m.pose.position.y, m.pose.position.z = p
        o = m.pose.orientation
    else:
        m = PointStamped()
        m.header.stamp = t
        m.point.x, m.point.y, m.point.z = p
        return m
    o.w, o.x, o.y, o.z = q
    return m


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("euroc")
    ap.add_argument("out")
    ap.add_argument("--compression", default="none", choices=["none", "bz2", "lz4"])
    ap.add_argument("--encoding", default="mono8", choices=["mono8", "bgr8", "rgb8", "png"])
    ap.add_argument("--groundtruth", default="odometry", choices=list(GT_TOPICS) + ["none"])
    ap.add_argument("--frames", type=int, default=0)
    ap.add_argument("--segmentation", action="store_true",
                    help="also /cam0/segmentation (rgb8) from mav0/cam0/mask, coloured with a table written as "
                         "OUT.rgb_ids.txt / OUT.vehicle_ids.txt in VIODE's formats (mask id k -> vehicle_dynamic_k-1)")
    ap.add_argument("--corrupt", default="", choices=["", "truncate", "unindex", "backwards", "encoding", "empty"])
    a = ap.parse_args()
    mav0 = os.path.join(a.euroc, "mav0")
    msgs = []  # (t_ns, topic, msg)
    suffix = "/compressed" if a.encoding == "png" else ""
    if a.corrupt != "empty":
        cams = {}
        for cam in ("cam0", "cam1"):
            lst = rows(os.path.join(mav0, cam, "data.csv"))
            if a.frames:
                lst = lst[: a.frames]
            cams[cam] = lst
            for k, r in enumerate(lst):
                enc = "yuv422" if (a.corrupt == "encoding" and cam == "cam0" and k == 3) else a.encoding
                m = image_msg(os.path.join(mav0, cam, "data", r[1]), stamp(r[0]), enc)
                msgs.append((int(r[0]), "/%s/image_raw%s" % (cam, suffix), m))
        if a.segmentation:
            colours = np.array([[k, 255 - k, 17] for k in range(256)], dtype=np.uint8)
            with open(a.out + ".rgb_ids.txt", "w") as f:
                f.write("id,r,g,b\n")
                for k in range(256):
                    f.write("%d,%d,%d,%d\n" % (k, *colours[k]))
            with open(a.out + ".vehicle_ids.txt", "w") as f:
                f.write("id, name\n")
                for k in range(1, 256):
                    f.write("%d, vehicle_dynamic_%d\n" % (k, k - 1))
            for r in cams["cam0"]:
                ids = np.array(PilImage.open(os.path.join(mav0, "cam0", "mask", r[1])))
                m = Image()
                m.header.stamp = stamp(r[0])
                m.height, m.width = ids.shape
                m.encoding = "rgb8"
                m.step = 3 * m.width
                m.data = colours[ids].tobytes()
                msgs.append((int(r[0]), "/cam0/segmentation", m))
        t_end = int(cams["cam0"][-1][0])
        imu_rows = [r for r in rows(os.path.join(mav0, "imu0", "data.csv")) if int(r[0]) <= t_end + 10_000_000]
        for k, r in enumerate(imu_rows):
            t_ns = int(r[0])
            if a.corrupt == "backwards" and k == 50:
                t_ns = int(imu_rows[10][0])
            m = Imu()
            m.header.stamp = stamp(t_ns)
            m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = [float(x) for x in r[1:4]]
            m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z = [float(x) for x in r[4:7]]
            m.orientation_covariance[0] = -1
            msgs.append((int(r[0]), "/imu0", m))
        gt_path = os.path.join(mav0, "state_groundtruth_estimate0", "data.csv")
        if a.groundtruth != "none" and os.path.exists(gt_path):
            for r in rows(gt_path):
                if int(r[0]) <= t_end + 10_000_000:
                    msgs.append((int(r[0]), GT_TOPICS[a.groundtruth], gt_msg(a.groundtruth, stamp(r[0]), r)))
    msgs.sort(key=lambda x: x[0])
    bag = rosbag.Bag(a.out, "w", compression=a.compression)
    for t_ns, topic, m in msgs:
        bag.write(topic, m, stamp(t_ns))
    bag.close()
    if a.corrupt == "truncate":
        size = os.path.getsize(a.out)
        with open(a.out, "r+b") as f:
            f.truncate(size // 2)
    elif a.corrupt == "unindex":
        # What an interrupted recording leaves: the header's index position is still 0.
        with open(a.out, "r+b") as f:
            data = f.read(4096)
            key = b"index_pos="
            i = data.find(key)
            f.seek(i + len(key))
            f.write(b"\0" * 8)
    return 0


if __name__ == "__main__":
    sys.exit(main())
