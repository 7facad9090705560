#!/usr/bin/python3
"""Writes an fgcal dataset folder as a ROS 1 bag with ROS 1's own Python
writer (Debian's python3-rosbag + python3-sensor-msgs), so that calibrating
from a bag is measured on a bag fgcal did not write.

    /usr/bin/python3 benchmarks/apps/make_bag_from_dataset.py DATASET OUT.bag
        [--images mixed|raw|png] [--compression none|lz4|bz2] [--rig-out RIG.yaml]
        [--latency-ms 2]

Run it with /usr/bin/python3: the pyenv python3 does not see Debian's ROS
packages. Reads DATASET/rig.yaml (cameras), DATASET/joints.csv and
DATASET/<camera>/<stamp_ns>.png|jpg and writes, in record-time order
(record time = header stamp + --latency-ms):

  /joint_states                 sensor_msgs/JointState, one per joints.csv row
                                (names from its header, positions in radians)
  /<camera>/image_raw           sensor_msgs/Image mono8 (the decoded image), or
  /<camera>/image_raw/compressed sensor_msgs/CompressedImage holding the image
                                file's own bytes, format "mono8; png compressed "
                                (as ROS's compressed_image_transport writes it)
  /<camera>/camera_info         sensor_msgs/CameraInfo per image, from rig.yaml
                                (radtan -> plumb_bob [k1 k2 p1 p2 0],
                                equidistant -> equidistant, none -> plumb_bob 0)

--images: raw = every camera as Image; png = every camera as CompressedImage;
mixed (default) = the first camera as Image, the others as CompressedImage.
Header stamps are the image file names and the joints.csv stamps, exactly.

--rig-out (default OUT.bag with .rig.yaml for .bag) receives the dataset's
rig.yaml with the bag fields added (joint_states_topic, per camera topic and
camera_info_topic) and the URDF path made absolute, for
`fgcal calibrate OUT.bag --rig RIG.yaml`.
"""
import argparse
import csv
import os
import sys

import genpy
import rosbag
import yaml
from PIL import Image as PilImage
from sensor_msgs.msg import CameraInfo, CompressedImage, Image, JointState


def time_of(ns):
    return genpy.Time(ns // 1000000000, ns % 1000000000)


def camera_info(cam, stamp_ns, frame_id):
    fx, fy, cx, cy = [float(v) for v in cam["intrinsics"]]
    w, h = [int(v) for v in cam["resolution"]]
    model = cam.get("distortion_model", "none")
    coeffs = [float(v) for v in (cam.get("distortion_coeffs") or [])]
    info = CameraInfo()
    info.header.stamp = time_of(stamp_ns)
    info.header.frame_id = frame_id
    info.width, info.height = w, h
    if model == "radtan":
        info.distortion_model, info.D = "plumb_bob", coeffs + [0.0]
    elif model == "equidistant":
        info.distortion_model, info.D = "equidistant", coeffs
    else:
        info.distortion_model, info.D = "plumb_bob", [0.0] * 5
    info.K = [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]
    info.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    info.P = [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0]
    return info


def list_images(folder):
    out = []
    for name in os.listdir(folder):
        stem, ext = os.path.splitext(name)
        if stem.isdigit() and ext.lower() in (".png", ".jpg", ".jpeg"):
            out.append((int(stem), os.path.join(folder, name)))
    out.sort()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dataset")
    ap.add_argument("out")
    ap.add_argument("--images", choices=["mixed", "raw", "png"], default="mixed")
    ap.add_argument("--compression", choices=["none", "lz4", "bz2"], default="none")
    ap.add_argument("--rig-out")
    ap.add_argument("--latency-ms", type=float, default=2.0)
    a = ap.parse_args()

    with open(os.path.join(a.dataset, "rig.yaml")) as f:
        rig = yaml.safe_load(f)
    cameras = rig["cameras"]
    latency = int(round(a.latency_ms * 1e6))

    # Events (record_ns, order, kind, payload); images are read when written.
    events = []
    with open(os.path.join(a.dataset, "joints.csv"), newline="") as f:
        rows = csv.reader(f)
        header = next(rows)
        joint_names = header[1:]
        for row in rows:
            if not row:
                continue
            stamp = int(row[0])
            events.append((stamp + latency, 0, "joints", (stamp, [float(v) for v in row[1:]])))
    counts = {}
    for ci, cam in enumerate(cameras):
        name = cam["name"]
        raw = a.images == "raw" or (a.images == "mixed" and ci == 0)
        cam["_raw"] = raw
        cam["topic"] = "/%s/image_raw" % name + ("" if raw else "/compressed")
        cam["camera_info_topic"] = "/%s/camera_info" % name
        images = list_images(os.path.join(a.dataset, name))
        counts[name] = len(images)
        for stamp, path in images:
            events.append((stamp + latency, 1 + ci, "image", (ci, stamp, path)))
    events.sort(key=lambda e: (e[0], e[1]))

    compression = {"none": rosbag.Compression.NONE, "lz4": rosbag.Compression.LZ4,
                   "bz2": rosbag.Compression.BZ2}[a.compression]
    tmp = a.out + ".part"
    decoded = {}  # (inode, device) -> mono8 image: hard-linked repeats are decoded once
    with rosbag.Bag(tmp, "w", compression=compression) as bag:
        for n, (record_ns, _, kind, payload) in enumerate(events):
            t = time_of(record_ns)
            if kind == "joints":
                stamp, position = payload
                m = JointState()
                m.header.seq = n
                m.header.stamp = time_of(stamp)
                m.name = joint_names
                m.position = position
                bag.write("/joint_states", m, t)
                continue
            ci, stamp, path = payload
            cam = cameras[ci]
            frame = cam["name"] + "_optical_frame"
            if cam["_raw"]:
                st = os.stat(path)
                key = (st.st_ino, st.st_dev)
                if key in decoded:
                    w, h, data = decoded[key]
                else:
                    pil = PilImage.open(path).convert("L")
                    w, h, data = pil.width, pil.height, pil.tobytes()
                    if st.st_nlink > 1 and len(decoded) < 1024:
                        decoded[key] = (w, h, data)
                m = Image()
                m.header.stamp = time_of(stamp)
                m.header.frame_id = frame
                m.height, m.width, m.encoding, m.is_bigendian, m.step = h, w, "mono8", 0, w
                m.data = data
            else:
                m = CompressedImage()
                m.header.stamp = time_of(stamp)
                m.header.frame_id = frame
                m.format = "mono8; png compressed " if path.lower().endswith(".png") else "mono8; jpeg compressed "
                with open(path, "rb") as f:
                    m.data = f.read()
            bag.write(cam["topic"], m, t)
            bag.write(cam["camera_info_topic"], camera_info(cam, stamp, frame), t)
            if n % 5000 == 0:
                print("  %d/%d messages" % (n, len(events)), file=sys.stderr, end="\r")
    os.replace(tmp, a.out)

    rig_out = a.rig_out or (os.path.splitext(a.out)[0] + ".rig.yaml")
    urdf = rig["robot"]["urdf"]
    if not os.path.isabs(urdf):
        rig["robot"]["urdf"] = os.path.abspath(os.path.join(a.dataset, urdf))
    rig["joint_states_topic"] = "/joint_states"
    for cam in cameras:
        del cam["_raw"]
    with open(rig_out, "w") as f:
        f.write("# %s as a bag: written by make_bag_from_dataset.py\n" % os.path.abspath(a.dataset))
        yaml.safe_dump(rig, f, sort_keys=False, default_flow_style=None)
    print("%s: %d joint samples, %s; rig %s" % (
        a.out, sum(1 for e in events if e[2] == "joints"),
        ", ".join("%s %d %s" % (c["name"], counts[c["name"]], c["topic"]) for c in cameras), rig_out))


if __name__ == "__main__":
    main()
