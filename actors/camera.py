"""The RGB-D camera as actors: raw topics, numpy images, and synchronised posed frames.

Everything comes from topics, as on a real robot:

==================  =================================  ==========================================
actor               kind                               what it gives
==================  =================================  ==========================================
``color_raw``       stream (subscriber)                ``sensor_msgs/Image`` from the colour topic
``depth_raw``       stream (subscriber)                ``sensor_msgs/Image`` from the depth topic
``camera_info``     stream (subscriber)                ``sensor_msgs/CameraInfo``
``camera_base_pose`` stream (subscriber)               ``geometry_msgs/PoseStamped`` map -> base
``pic``             stream                             BGR ``uint8`` array (H, W, 3), OpenCV order
``depth``           stream                             ``float32`` array (H, W), metres, NaN = none
``rgbd``            stream                             :class:`RGBDFrame`: colour + depth with the
                                                       same header stamp, intrinsics, camera pose
``intrinsics``      sync                               fx, fy, cx, cy, width, height, frame_id
==================  =================================  ==========================================

The camera pose of a frame is the base pose at the frame's stamp (interpolated between the
two pose messages around it) times the fixed base -> optical-frame transform, read from the
robot URDF (``planning.read_urdf``) for the frame id the image carries. Nothing here imports
the simulator.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Iterator

import numpy as np
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import CameraInfo, Image

from bt_engine import ActorbtError, SubSystem, actor
from planning import read_urdf
from planning.urdf import origin_transform

COLOR_TOPIC = "/camera/color/image_raw"
DEPTH_TOPIC = "/camera/depth/image_raw"
INFO_TOPIC = "/camera/camera_info"
POSE_TOPIC = "/ground_truth/pose"       # map -> base_footprint; remap to AMCL's pose on a robot
BASE_FRAME = "base_footprint"
MAX_POSE_GAP = 0.25                     # [s] a frame further than this from any pose is dropped


class CameraError(ActorbtError):
    """An image could not be decoded, or the camera frame is not in the robot model."""


# ----------------------------------------------------------------------------- conversions
def stamp_seconds(header) -> float:
    """A ROS header's stamp in seconds."""
    return header.stamp.sec + header.stamp.nanosec * 1e-9


def image_to_array(msg: Image) -> np.ndarray:
    """A sensor_msgs/Image as a numpy array, as ``cv_bridge`` would give it.

    Colour becomes BGR ``uint8`` (H, W, 3) (OpenCV's order); depth becomes ``float32``
    metres (``16UC1`` millimetres are converted, zero becomes NaN); ``mono8`` stays (H, W).
    """
    h, w, enc = msg.height, msg.width, msg.encoding
    buf = np.frombuffer(msg.data, np.uint8)
    if enc in ("rgb8", "bgr8", "rgba8", "bgra8"):
        ch = 4 if enc.endswith("a8") else 3
        img = buf.reshape(h, msg.step)[:, :w * ch].reshape(h, w, ch)
        if enc == "rgb8":
            return np.ascontiguousarray(img[:, :, ::-1])
        if enc == "rgba8":
            return np.ascontiguousarray(img[:, :, 2::-1])
        if enc == "bgra8":
            return np.ascontiguousarray(img[:, :, :3])
        return img.copy()
    if enc == "mono8":
        return buf.reshape(h, msg.step)[:, :w].copy()
    if enc == "32FC1":
        dt = np.dtype(">f4" if msg.is_bigendian else "<f4")
        return buf.reshape(h, msg.step)[:, :w * 4].copy().view(dt).reshape(h, w).astype(np.float32)
    if enc == "16UC1":
        dt = np.dtype(">u2" if msg.is_bigendian else "<u2")
        mm = buf.reshape(h, msg.step)[:, :w * 2].copy().view(dt).reshape(h, w)
        out = mm.astype(np.float32) / 1000.0
        out[mm == 0] = np.nan
        return out
    raise CameraError(f"unsupported image encoding {enc!r}")


def quat_matrix(x: float, y: float, z: float, w: float) -> np.ndarray:
    """Rotation matrix (3, 3) of a unit quaternion."""
    n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def pose_matrix(pose) -> np.ndarray:
    """Homogeneous transform (4, 4) of a geometry_msgs Pose."""
    t = np.eye(4)
    q = pose.orientation
    t[:3, :3] = quat_matrix(q.x, q.y, q.z, q.w)
    t[:3, 3] = (pose.position.x, pose.position.y, pose.position.z)
    return t


def _interpolate(ta: float, Ta: np.ndarray, tb: float, Tb: np.ndarray, t: float) -> np.ndarray:
    """Pose at ``t`` between two poses (linear position, yaw-plane-safe rotation blend)."""
    if tb <= ta:
        return Tb
    f = min(1.0, max(0.0, (t - ta) / (tb - ta)))
    out = np.eye(4)
    out[:3, 3] = (1 - f) * Ta[:3, 3] + f * Tb[:3, 3]
    # rotation: R_a * exp(f * log(R_a^T R_b)), by the axis-angle of the relative rotation
    Rr = Ta[:3, :3].T @ Tb[:3, :3]
    angle = math.acos(max(-1.0, min(1.0, (np.trace(Rr) - 1) / 2)))
    if angle < 1e-9:
        out[:3, :3] = Tb[:3, :3]
        return out
    axis = np.array([Rr[2, 1] - Rr[1, 2], Rr[0, 2] - Rr[2, 0], Rr[1, 0] - Rr[0, 1]]) / (2 * math.sin(angle))
    a = f * angle
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    out[:3, :3] = Ta[:3, :3] @ (np.eye(3) + math.sin(a) * k + (1 - math.cos(a)) * (k @ k))
    return out


@functools.lru_cache(maxsize=16)
def camera_extrinsics(frame_id: str, base_frame: str = BASE_FRAME, urdf: str | None = None) -> np.ndarray:
    """Fixed transform (4, 4) from ``base_frame`` to the camera frame ``frame_id``, composed
    from the robot URDF's joint origins (every joint on the chain must be fixed)."""
    robot = read_urdf(urdf)
    try:
        chain = robot.chain(base_frame, frame_id)
    except Exception as e:  # ModelError: unknown link or not below the base
        raise CameraError(f"camera frame {frame_id!r} is not below {base_frame!r} in the URDF: {e}") from e
    T = np.eye(4)
    for j in chain:
        if j.movable:
            raise CameraError(f"camera frame {frame_id!r} moves with joint {j.name!r}; "
                              "only a fixed camera mount is supported")
        T = T @ origin_transform(j)
    return T


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics [px] of a CameraInfo (no distortion is modelled)."""
    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int
    frame_id: str

    @classmethod
    def from_msg(cls, msg: CameraInfo) -> "Intrinsics":
        k = msg.k
        return cls(float(k[0]), float(k[4]), float(k[2]), float(k[5]), int(msg.width), int(msg.height),
                   msg.header.frame_id)

    def as_dict(self) -> dict:
        return {"fx": self.fx, "fy": self.fy, "cx": self.cx, "cy": self.cy,
                "width": self.width, "height": self.height, "frame_id": self.frame_id}


@dataclass(frozen=True)
class RGBDFrame:
    """One colour + depth pair with the same header stamp, and where the camera was.

    ``bgr``: uint8 (H, W, 3); ``depth``: float32 (H, W) [m], NaN = no return;
    ``T_map_cam``: camera optical frame (z forward, x right, y down) in the map frame;
    ``T_map_base``: the robot base (``base_footprint``) in the map frame; ``stamp`` [s].
    """
    stamp: float
    bgr: np.ndarray
    depth: np.ndarray
    intrinsics: Intrinsics
    T_map_cam: np.ndarray
    T_map_base: np.ndarray
    frame_id: str


# ----------------------------------------------------------------------------- subsystem
class Camera(SubSystem):
    """An RGB-D camera reached through its ROS topics, posed by the robot's localisation."""

    def __init__(self, color_topic: str = COLOR_TOPIC, depth_topic: str = DEPTH_TOPIC,
                 info_topic: str = INFO_TOPIC, pose_topic: str = POSE_TOPIC,
                 base_frame: str = BASE_FRAME, urdf: str | None = None) -> None:
        super().__init__()
        self.register_subscriber("color_raw", Image, color_topic, 2)
        self.register_subscriber("depth_raw", Image, depth_topic, 2)
        self.register_subscriber("camera_info", CameraInfo, info_topic, 1)
        self.register_subscriber("camera_base_pose", PoseStamped, pose_topic, 60)
        self.set_value("camera_base_frame", base_frame)
        self.set_value("camera_urdf", urdf)

    @actor
    def pic(self) -> Iterator[np.ndarray]:
        """Colour images as BGR uint8 arrays (H, W, 3), as OpenCV expects them."""
        with self.run_actor_mode("color_raw", "iterator") as msgs:
            for msg in msgs:
                yield image_to_array(msg)

    @actor
    def depth(self) -> Iterator[np.ndarray]:
        """Depth images as float32 arrays (H, W) in metres; NaN where there is no return."""
        with self.run_actor_mode("depth_raw", "iterator") as msgs:
            for msg in msgs:
                yield image_to_array(msg)

    @actor
    def intrinsics(self) -> dict:
        """The camera's pinhole intrinsics: fx, fy, cx, cy [px], width, height, frame_id."""
        return Intrinsics.from_msg(self.run_actor_mode("camera_info", "timed", 5.0)).as_dict()

    @actor
    def rgbd(self) -> Iterator[RGBDFrame]:
        """Synchronised RGB-D frames: colour and depth with the same header stamp, the
        intrinsics, and the camera pose in the map frame at that stamp."""
        base_frame = self.get_value("camera_base_frame")
        urdf = self.get_value("camera_urdf")
        info: Intrinsics | None = None
        with self.run_actor_mode("camera_info", "iterator") as infos, \
                self.run_actor_mode("color_raw", "iterator") as colors, \
                self.run_actor_mode("depth_raw", "iterator") as depths, \
                self.run_actor_mode("camera_base_pose", "iterator") as poses:
            dmsg = None
            before: tuple[float, np.ndarray] | None = None
            after: tuple[float, np.ndarray] | None = None
            for cmsg in colors:
                t = stamp_seconds(cmsg.header)
                while dmsg is None or stamp_seconds(dmsg.header) < t - 1e-6:
                    dmsg = next(depths)
                if stamp_seconds(dmsg.header) > t + 1e-6:
                    continue                      # this colour frame has no depth twin
                while after is None or after[0] < t - 1e-6:
                    before = after
                    pmsg = next(poses)
                    after = (stamp_seconds(pmsg.header), pose_matrix(pmsg.pose))
                if before is not None and before[0] <= t <= after[0]:
                    T_map_base = _interpolate(before[0], before[1], after[0], after[1], t)
                elif abs(after[0] - t) <= MAX_POSE_GAP:
                    T_map_base = after[1]
                else:
                    continue                      # no pose near this frame
                if info is None or (info.width, info.height) != (cmsg.width, cmsg.height):
                    info = Intrinsics.from_msg(next(infos))   # sent with the images
                frame_id = cmsg.header.frame_id or info.frame_id
                T_base_cam = camera_extrinsics(frame_id, base_frame, urdf)
                yield RGBDFrame(stamp=t, bgr=image_to_array(cmsg), depth=image_to_array(dmsg),
                                intrinsics=info, T_map_cam=T_map_base @ T_base_cam,
                                T_map_base=T_map_base, frame_id=frame_id)
