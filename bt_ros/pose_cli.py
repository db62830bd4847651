"""``actorbt pose init X Y YAW``: give the robot's localisation (AMCL, or navstack in the
simulator) its initial pose, as RViz's "2D Pose Estimate" tool does.

    actorbt --config actorbt.real.yaml pose init 1.0 2.0 1.57
    actorbt pose init 1 2 0 --bus ros [--std-xy M] [--std-yaw RAD] [--frame map] [--wait S]

One geometry_msgs/PoseWithCovarianceStamped goes out on ``/initialpose``, reliable and
volatile as RViz sends it, stamped with the wall clock, its covariance diagonal x and y
``std_xy``², yaw ``std_yaw``² (RViz's defaults: 0.5 m and π/12 rad). A node waits until
a subscriber of /initialpose is matched (a message published before that is lost: the
topic is volatile), publishes, and lives on for half a second while the message goes out.

Only over ROS (``--bus ros``, or ``transport: ros`` in actorbt.yaml): on the local bus the
message would reach this command's own runtime only, so the command refuses and says
where to give the pose instead (the ``set_initial_pose`` actor of the navigation, from
``actorbt shell``, a mission or ``actorbt rcall``).

Exit status: 0 published to a subscriber; 1 no subscriber within ``--wait``; 2 on
the local bus or a bad option; 130 on Ctrl-C. Nothing here imports rclpy or geometry_msgs
until the command runs.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from typing import TYPE_CHECKING, Callable

from bt_engine.errors import ActorbtError

if TYPE_CHECKING:
    from rclpy.node import Node

    from bt_engine.bus.messages import RosMessage
    from .command_app import CommandApp
    from .host import RosHost

TOPIC = "/initialpose"
#: RViz's "2D Pose Estimate" defaults (rviz_default_plugins SetInitialPose: "X std
#: deviation" and "Y std deviation" 0.5 m, "Theta std deviation" π/12 rad)
RVIZ_STD_XY = 0.5
RVIZ_STD_YAW = math.pi / 12
#: how long the node lives on after publishing [s] (``ros2 topic pub --once``: 0.1 s). Not
#: until every subscriber acknowledges: Fast DDS acknowledges on its heartbeat, every 3 s,
#: long after the message arrived
KEEP_ALIVE = 0.5


def register(sub: argparse._SubParsersAction, common: Callable[[argparse.ArgumentParser], None]) -> None:
    p = sub.add_parser(
        "pose",
        help="the robot's pose: init X Y YAW (like RViz's 2D Pose Estimate)",
        description="Tell the robot's localisation where the robot is, as RViz's \"2D Pose Estimate\" does.",
    )
    psub = p.add_subparsers(dest="pose_command", metavar="POSE_COMMAND")
    psub.required = True

    i = psub.add_parser(
        "init",
        help="publish an initial pose on /initialpose: X Y YAW",
        description="Publish one geometry_msgs/PoseWithCovarianceStamped on /initialpose, as "
        "RViz's \"2D Pose Estimate\" does, for AMCL (or the simulator's navstack) "
        "to start localising from. Over ROS only (--bus ros, or transport: ros in "
        "actorbt.yaml); in a runtime on the local bus, call the navigation's "
        "set_initial_pose actor instead. Exit status 1 when nothing subscribes to "
        "/initialpose within --wait.",
    )
    i.add_argument("x", type=float, help="The robot's x in the frame, in metres.")
    i.add_argument("y", type=float, help="The robot's y in the frame, in metres.")
    i.add_argument(
        "yaw",
        type=float,
        help="The robot's heading in radians, counter-clockwise from the frame's x "
        "axis (a negative one is fine: pose init 1 2 -1.57).",
    )
    i.add_argument(
        "--std-xy",
        type=_non_negative,
        default=RVIZ_STD_XY,
        metavar="M",
        help='The standard deviation of x and of y, in metres (default 0.5, RViz\'s "2D Pose Estimate" default).',
    )
    i.add_argument(
        "--std-yaw",
        type=_non_negative,
        default=RVIZ_STD_YAW,
        metavar="RAD",
        help="The standard deviation of the heading, in radians (default π/12 = "
        '0.2618, RViz\'s "2D Pose Estimate" default).',
    )
    i.add_argument(
        "--frame",
        default="map",
        help="The frame of the pose (default map: AMCL ignores an initial pose outside its global frame).",
    )
    i.add_argument(
        "--wait",
        type=float,
        default=5.0,
        metavar="S",
        help="Wait up to S seconds for a subscriber of /initialpose to be discovered "
        "before giving up with exit status 1 (default 5).",
    )
    i.add_argument(
        "--bus",
        choices=["local", "ros"],
        help="Where the robot is: 'ros' over ROS 2 (DDS), a robot or an `actorbt sim "
        "run --bus ros`; 'local' is refused, as the pose would reach only this "
        "command's own runtime. Overrides 'transport:' in actorbt.yaml.",
    )
    i.set_defaults(func=cmd_init)


def _non_negative(text: str) -> float:
    value = float(text)
    if not value >= 0.0:
        raise argparse.ArgumentTypeError(f"expected a standard deviation >= 0, got {text}")
    return value


def initial_pose_msg(
    x: float, y: float, yaw: float, std_xy: float = RVIZ_STD_XY, std_yaw: float = RVIZ_STD_YAW, frame: str = "map"
) -> RosMessage:
    """The PoseWithCovarianceStamped RViz's "2D Pose Estimate" sends (unstamped): pose
    (x, y, yaw) in ``frame``; covariance (row-major 6x6 over x, y, z, roll, pitch, yaw)
    ``std_xy``² for x and y, ``std_yaw``² for yaw, zero elsewhere."""
    from geometry_msgs.msg import PoseWithCovarianceStamped

    msg = PoseWithCovarianceStamped()
    msg.header.frame_id = frame
    msg.pose.pose.position.x, msg.pose.pose.position.y = float(x), float(y)
    msg.pose.pose.orientation.z = math.sin(yaw / 2)
    msg.pose.pose.orientation.w = math.cos(yaw / 2)
    cov = [0.0] * 36
    cov[0] = cov[7] = float(std_xy) ** 2
    cov[35] = float(std_yaw) ** 2
    msg.pose.covariance = cov
    return msg


def cmd_init(args: argparse.Namespace, app: CommandApp) -> int:
    if (args.bus or app.cfg.transport) != "ros":
        raise ActorbtError(
            f"pose init publishes {TOPIC} over ROS 2, and the bus here is local: the pose "
            "would reach only this command's own runtime (its own simulated robot, gone when "
            "the command ends). Give it in the process that runs the robot: in `actorbt "
            f"shell`, `set_initial_pose {args.x:g} {args.y:g} {args.yaw:g}`; to a running "
            f"`actorbt serve`, `actorbt rcall set_initial_pose {args.x:g} {args.y:g} "
            f"{args.yaw:g}`; or as a step of a mission. For a robot on ROS 2: --bus ros (or "
            "transport: ros in actorbt.yaml)."
        )
    return publish_over_ros(args)


def publish_over_ros(args: argparse.Namespace) -> int:
    """Publish the pose ``args`` give on /initialpose once a subscriber is matched, and
    keep the node alive while it goes out."""
    from .host import RosHost
    from .qos import qos_profile

    msg = initial_pose_msg(args.x, args.y, args.yaw, args.std_xy, args.std_yaw, args.frame)
    with RosHost("pose") as host:
        node = host.create_node(f"actorbt_pose_{os.getpid()}_{host.id}", lean=True)
        pub = host.call(node.create_publisher, type(msg), TOPIC, qos_profile("reliable"))
        # matched, not merely discovered: a message published before the match is lost
        deadline = time.monotonic() + args.wait
        while pub.get_subscription_count() == 0:
            if time.monotonic() >= deadline:
                domain = os.environ.get("ROS_DOMAIN_ID", "0")
                scope = os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
                print(
                    f"actorbt pose init: nobody subscribes to {TOPIC} after {args.wait:g} s: "
                    f"is AMCL / the navstack running? (ROS_DOMAIN_ID {domain}, discovery "
                    f"range {scope})",
                    file=sys.stderr,
                )
                return 1
            time.sleep(0.05)
        msg.header.stamp = node.get_clock().now().to_msg()  # as RViz stamps it
        pub.publish(msg)
        end = time.monotonic() + KEEP_ALIVE
        listeners = _listeners(host, node, KEEP_ALIVE)
        # the writer sends from its own thread: the node lives on until it has
        time.sleep(max(0.0, end - time.monotonic()))
    print(
        f"{TOPIC}: x {args.x:.3f} m, y {args.y:.3f} m, yaw {args.yaw:.3f} rad "
        f"({math.degrees(args.yaw):.1f} deg) in {args.frame}; std {args.std_xy:g} m, "
        f"{args.std_yaw:.4g} rad; to {listeners}"
    )
    return 0


def _listeners(host: RosHost, node: Node, wait: float = 1.0) -> str:
    """The nodes subscribed to /initialpose, for the user to see who heard it. A node's
    name arrives after its endpoints (the graph says _NODE_NAME_UNKNOWN_ meanwhile), so
    wait up to ``wait`` seconds for the names; else count the subscribers."""
    deadline = time.monotonic() + wait
    while True:
        infos = host.call(node.get_subscriptions_info_by_topic, TOPIC)
        names = sorted({f"{i.node_namespace.rstrip('/')}/{i.node_name}" for i in infos})
        if names and not any("_UNKNOWN_" in n for n in names):
            return ", ".join(names)
        if time.monotonic() >= deadline:
            return f"{len(infos)} subscriber{'s' if len(infos) != 1 else ''}"
        time.sleep(0.05)
