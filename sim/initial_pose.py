"""The pose estimate a user gives the localiser (RViz's "2D Pose Estimate" on
``/initialpose``), which the simulator gives in the user's place: it knows where the
robot starts."""

from __future__ import annotations

import math

from geometry_msgs.msg import PoseWithCovarianceStamped

#: [m, rad] how sure the user is of the start pose: a careful look at the robot on the map
INITIAL_STD_XY, INITIAL_STD_YAW = 0.05, 0.03


def initial_pose_msg(
    pose, std_xy: float = INITIAL_STD_XY, std_yaw: float = INITIAL_STD_YAW
) -> PoseWithCovarianceStamped:
    """/initialpose at ``pose`` (x, y, yaw), map frame, with the user's uncertainty."""
    x, y, yaw = pose
    msg = PoseWithCovarianceStamped()
    msg.header.frame_id = "map"
    msg.pose.pose.position.x, msg.pose.pose.position.y = float(x), float(y)
    msg.pose.pose.orientation.z, msg.pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    cov = [0.0] * 36
    cov[0] = cov[7] = std_xy**2
    cov[35] = std_yaw**2
    msg.pose.covariance = cov
    return msg
