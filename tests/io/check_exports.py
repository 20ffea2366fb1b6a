#!/usr/bin/python3
"""`timeopt export` read back independently of timeopt (ctest io.exports_read_back).

    check_exports.py TIMEOPT_CLI SOURCE_DIR

Plans on the shipped map with --trajectory, exports every format, and checks:
- the bag with Debian's python3-rosbag: the three topics and their standard types, frame "map",
  one pose and one trajectory point per sample of the csv export, times from 0, the same positions;
- the px4 rows against the csv rows under the stated NED conversion, to 1e-6;
- the polynomial segments evaluated at 1 kHz against the trajectory's csv export at 1 kHz, within
  1 mm and 1 cm/s (and within the bounds the file states);
- the yaw rate of the csv export against finite differences, and within --max-yaw-rate.
Exits 77 (skipped, saying why) without python3-rosbag.
"""

import csv
import json
import math
import os
import subprocess
import sys
import tempfile


def rows(path):
    with open(path) as f:
        reader = csv.reader(f)
        header = next(reader)
        return header, [[float(v) for v in row] for row in reader]


def main(cli, source):
    try:
        import rosbag  # noqa: F401
    except ImportError:
        print("SKIP: Debian's python3-rosbag is not installed (scripts/install_deps.sh)")
        return 77
    import rosbag

    failures = []

    def check(condition, message):
        if not condition:
            failures.append(message)

    with tempfile.TemporaryDirectory() as tmp:
        traj = os.path.join(tmp, "t.json")
        subprocess.run([cli, "plan", "-q", "--trajectory", traj, "-o", os.path.join(tmp, "p.csv")], check=True,
                       cwd=source)
        out = {}
        for fmt, ext in (("csv", "csv"), ("px4", "csv"), ("polynomial", "json"), ("rosbag", "bag")):
            out[fmt] = os.path.join(tmp, fmt + "." + ext)
            extra = ["--map", os.path.join(source, "maps", "forest_20x20.bt")] if fmt == "rosbag" else []
            subprocess.run([cli, "export", traj, "--format", fmt, "-o", out[fmt], "--max-yaw-rate", "0.8"] + extra,
                           check=True)
        header, enu = rows(out["csv"])
        check(header == "t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz,yaw,yaw_rate".split(","), "csv header %s" % header)
        # Yaw: its rate is the finite difference to the next row, within the limit.
        for a, b in zip(enu, enu[1:]):
            difference = (b[13] - a[13]) / (b[0] - a[0])
            check(abs(difference - a[14]) < 1e-6, "yaw rate %g against its difference %g at t %g" % (a[14], difference, a[0]))
            check(abs(difference) <= 0.8 + 1e-6, "yaw rate %g above 0.8 at t %g" % (difference, a[0]))
        # PX4: NED of the same rows.
        header, ned = rows(out["px4"])
        check(header == "timestamp_us,x,y,z,vx,vy,vz,ax,ay,az,yaw,yawspeed".split(","), "px4 header %s" % header)
        check(len(ned) == len(enu), "px4 rows %d, csv rows %d" % (len(ned), len(enu)))
        for e, n in zip(enu, ned):
            check(n[0] == round(e[0] * 1e6), "timestamp %g at t %g" % (n[0], e[0]))
            expected = [e[2], e[1], -e[3], e[5], e[4], -e[6], e[8], e[7], -e[9], math.pi / 2 - e[13], -e[14]]
            worst = max(abs(a - b) for a, b in zip(n[1:], expected))
            check(worst <= 1e-6, "px4 row at t %g off by %g" % (e[0], worst))
        # Polynomial segments against the trajectory at 1 kHz (its csv export at --rate 1000).
        fine = os.path.join(tmp, "fine.csv")
        subprocess.run([cli, "export", traj, "--format", "csv", "--rate", "1000", "-o", fine], check=True)
        _, dense = rows(fine)
        with open(out["polynomial"]) as f:
            poly = json.load(f)
        segments = poly["segments"]
        check(poly["frame"] == "ENU", "polynomial frame")
        worst_p = worst_v = worst_a = 0.0
        index = 0
        for r in dense:
            t = r[0]
            while index + 1 < len(segments) and segments[index + 1]["start"] <= t:
                index += 1
            s = segments[index]
            tau = t - s["start"]
            for axis in range(3):
                c = s["coefficients"][axis]
                p = sum(c[j] * tau ** j for j in range(len(c)))
                v = sum(j * c[j] * tau ** (j - 1) for j in range(1, len(c)))
                a = sum(j * (j - 1) * c[j] * tau ** (j - 2) for j in range(2, len(c)))
                worst_p = max(worst_p, abs(p - r[1 + axis]))
                worst_v = max(worst_v, abs(v - r[4 + axis]))
                worst_a = max(worst_a, abs(a - r[7 + axis]))
        check(worst_p <= 1e-3, "polynomial position error %g m above 1 mm" % worst_p)
        check(worst_v <= 1e-2, "polynomial velocity error %g m/s above 1 cm/s" % worst_v)
        check(worst_a <= 2e-2, "polynomial acceleration error %g m/s^2 above 0.02" % worst_a)
        check(worst_p <= poly["max_error"]["position"] and worst_v <= poly["max_error"]["velocity"] and
              worst_a <= poly["max_error"]["acceleration"],
              "errors %g / %g / %g above the stated bounds %s" % (worst_p, worst_v, worst_a, poly["max_error"]))
        # The bag: standard types, one frame, times from 0, the samples' positions.
        bag = rosbag.Bag(out["rosbag"])
        info = bag.get_type_and_topic_info()
        types = {topic: value.msg_type for topic, value in info.topics.items()}
        check(types == {"/timeopt/path": "nav_msgs/Path",
                        "/timeopt/trajectory": "trajectory_msgs/MultiDOFJointTrajectory",
                        "/timeopt/markers": "visualization_msgs/MarkerArray"}, "bag topics %s" % types)
        for topic, msg, stamp in bag.read_messages():
            check(stamp.to_sec() == 0.0, "%s recorded at %s" % (topic, stamp.to_sec()))
            if topic == "/timeopt/path":
                check(msg.header.frame_id == "map", "path frame %s" % msg.header.frame_id)
                check(len(msg.poses) == len(enu), "path poses %d, samples %d" % (len(msg.poses), len(enu)))
                for pose, e in zip(msg.poses, enu):
                    check(abs(pose.header.stamp.to_sec() - e[0]) < 2e-9, "pose stamp")  # ROS time: nanoseconds
                    position = pose.pose.position
                    check(max(abs(position.x - e[1]), abs(position.y - e[2]), abs(position.z - e[3])) < 1e-12,
                          "pose at t %g" % e[0])
                    q = pose.pose.orientation
                    yaw = 2 * math.atan2(q.z, q.w)
                    check(abs(math.remainder(yaw - e[13], 2 * math.pi)) < 1e-9, "pose heading at t %g" % e[0])
            elif topic == "/timeopt/trajectory":
                check(msg.header.frame_id == "map", "trajectory frame")
                check(len(msg.points) == len(enu), "trajectory points %d" % len(msg.points))
                check(msg.points[0].time_from_start.to_sec() == 0.0, "trajectory starts at 0")
                last = msg.points[-1]
                check(abs(last.time_from_start.to_sec() - enu[-1][0]) < 2e-9, "trajectory ends at T")
                check(abs(last.velocities[0].linear.x - enu[-1][4]) < 1e-12, "trajectory velocity")
            else:
                ids = sorted((m.id, m.type, m.header.frame_id) for m in msg.markers)
                check([i for i, _, _ in ids] == [0, 1, 2, 3], "marker ids %s" % ids)
                check(all(frame == "map" for _, _, frame in ids), "marker frames")
                cubes = [m for m in msg.markers if m.id == 3][0]
                check(len(cubes.points) > 0, "no voxels near the path on the forest map")
        bag.close()
    for message in failures[:20]:
        print("FAIL:", message)
    if failures:
        print("%d checks failed" % len(failures))
        return 1
    print("every export read back: %d samples, %d segments (degree %d), bounds %.3g m / %.3g m/s / %.3g m/s^2, "
          "measured at 1 kHz %.3g / %.3g / %.3g"
          % (len(enu), len(segments), poly["degree"], poly["max_error"]["position"], poly["max_error"]["velocity"],
             poly["max_error"]["acceleration"], worst_p, worst_v, worst_a))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
