#!/usr/bin/python3
"""Writes a ROS 1 bag from the content `timeopt export --format rosbag` prepares.

    timeopt_rosbag.py CONTENT.json OUT.bag

CONTENT.json is RosbagContentJson (timeopt/io/trajectory_io.h): samples t, x, y, z, vx, vy, vz,
ax, ay, az, yaw, yaw_rate (ENU, frame "map"), start, goal, the largest speed and optionally the
occupied voxels near the path. The bag holds, every header in frame "map", times from 0:
- /timeopt/path (nav_msgs/Path): one pose per sample, stamped with its time;
- /timeopt/trajectory (trajectory_msgs/MultiDOFJointTrajectory): one point per sample with the
  transform (position, heading), velocity (linear, yaw rate) and acceleration;
- /timeopt/markers (visualization_msgs/MarkerArray): the path as a line strip coloured by speed
  (blue slow, red fast), start (green) and goal (red) spheres, and the voxels as a cube list.
Written with Debian's python3-rosbag and message packages. Exit 0 when written; 3 when a package
is missing; 2 for a content file that is not what is expected.
"""

import json
import math
import sys


def main(argv):
    if len(argv) != 3:
        sys.stderr.write("usage: timeopt_rosbag.py CONTENT.json OUT.bag\n")
        return 2
    try:
        import genpy
        import rosbag
        from geometry_msgs.msg import Point, PoseStamped, Quaternion, Transform, Twist, Vector3
        from nav_msgs.msg import Path
        from std_msgs.msg import ColorRGBA
        from trajectory_msgs.msg import MultiDOFJointTrajectory, MultiDOFJointTrajectoryPoint
        from visualization_msgs.msg import Marker, MarkerArray
    except ImportError as error:
        sys.stderr.write("the bag needs Debian's python3-rosbag, python3-nav-msgs, python3-trajectory-msgs and "
                         "python3-visualization-msgs (scripts/install_deps.sh main): %s\n" % error)
        return 3
    try:
        with open(argv[1]) as f:
            content = json.load(f)
        samples = content["samples"]
        frame = content["frame"]
        fastest = float(content["max_speed"])
    except (OSError, ValueError, KeyError) as error:
        sys.stderr.write("cannot read the bag's content %s: %s\n" % (argv[1], error))
        return 2

    def stamp(t):
        return genpy.Time.from_sec(t)

    def heading(yaw):
        return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))

    path = Path()
    path.header.frame_id = frame
    trajectory = MultiDOFJointTrajectory()
    trajectory.header.frame_id = frame
    trajectory.joint_names = ["base_link"]
    for t, x, y, z, vx, vy, vz, ax, ay, az, yaw, rate in samples:
        pose = PoseStamped()
        pose.header.frame_id = frame
        pose.header.stamp = stamp(t)
        pose.pose.position = Point(x=x, y=y, z=z)
        pose.pose.orientation = heading(yaw)
        path.poses.append(pose)
        point = MultiDOFJointTrajectoryPoint()
        point.transforms = [Transform(translation=Vector3(x=x, y=y, z=z), rotation=heading(yaw))]
        point.velocities = [Twist(linear=Vector3(x=vx, y=vy, z=vz), angular=Vector3(x=0.0, y=0.0, z=rate))]
        point.accelerations = [Twist(linear=Vector3(x=ax, y=ay, z=az), angular=Vector3())]
        point.time_from_start = genpy.Duration.from_sec(t)
        trajectory.points.append(point)

    def marker(marker_id, kind):
        m = Marker()
        m.header.frame_id = frame
        m.ns = "timeopt"
        m.id = marker_id
        m.type = kind
        m.action = Marker.ADD
        m.pose.orientation.w = 1.0
        return m

    markers = MarkerArray()
    line = marker(0, Marker.LINE_STRIP)
    line.scale.x = 0.05
    line.color = ColorRGBA(r=1.0, g=1.0, b=1.0, a=1.0)
    for row in samples:
        x, y, z, vx, vy, vz = row[1:7]
        line.points.append(Point(x=x, y=y, z=z))
        share = math.sqrt(vx * vx + vy * vy + vz * vz) / fastest if fastest > 0.0 else 0.0
        line.colors.append(ColorRGBA(r=share, g=0.2, b=1.0 - share, a=1.0))
    markers.markers.append(line)
    for marker_id, where, color in ((1, content["start"], (0.0, 0.8, 0.0)), (2, content["goal"], (0.9, 0.0, 0.0))):
        sphere = marker(marker_id, Marker.SPHERE)
        sphere.pose.position = Point(x=where[0], y=where[1], z=where[2])
        sphere.scale = Vector3(x=0.3, y=0.3, z=0.3)
        sphere.color = ColorRGBA(r=color[0], g=color[1], b=color[2], a=1.0)
        markers.markers.append(sphere)
    if "voxels" in content:
        cubes = marker(3, Marker.CUBE_LIST)
        size = float(content["voxels"]["size"])
        cubes.scale = Vector3(x=size, y=size, z=size)
        cubes.color = ColorRGBA(r=0.5, g=0.5, b=0.5, a=0.6)
        for x, y, z in content["voxels"]["centers"]:
            cubes.points.append(Point(x=x, y=y, z=z))
        markers.markers.append(cubes)

    try:
        bag = rosbag.Bag(argv[2], "w")
        try:
            bag.write("/timeopt/path", path, stamp(0.0))
            bag.write("/timeopt/trajectory", trajectory, stamp(0.0))
            bag.write("/timeopt/markers", markers, stamp(0.0))
        finally:
            bag.close()
    except (OSError, rosbag.ROSBagException) as error:
        sys.stderr.write("cannot write the bag %s: %s\n" % (argv[2], error))
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
