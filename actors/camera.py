"""The RGB-D camera as actors: raw topics, numpy images, and synchronised posed frames.

Everything comes from topics, as on a real robot:

==================  =================================  ==========================================
actor               kind                               what it gives
==================  =================================  ==========================================
``color_raw``       stream (subscriber)                ``sensor_msgs/Image`` from the colour topic
``depth_raw``       stream (subscriber)                ``sensor_msgs/Image`` from the depth topic
``camera_info``     stream (subscriber)                ``sensor_msgs/CameraInfo``
``pic``             stream                             BGR ``uint8`` array (H, W, 3), OpenCV order
``depth``           stream                             ``float32`` array (H, W), metres, NaN = none
``rgbd``            stream                             :class:`RGBDFrame`: colour + depth with the
                                                       same header stamp, intrinsics, camera pose
``intrinsics``      sync                               fx, fy, cx, cy, width, height, frame_id
==================  =================================  ==========================================

The camera pose of a frame is looked up on the robot's transform tree (``/tf`` and
``/tf_static``, :mod:`actors.tf_listener`) at the frame's stamp, from the frame id the image
carries: map -> odom (the localiser) -> base_footprint (the odometry, interpolated to the
stamp) -> base_link -> camera_link -> camera_optical_frame (the robot description). A frame
whose pose tf cannot give within ``MAX_POSE_GAP`` of its stamp (the robot is not localised
yet) is dropped. Nothing here imports the simulator.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

import numpy as np
from sensor_msgs.msg import CameraInfo, Image

from bt_engine import ActorbtError, SubSystem, actor

from .tf_listener import TransformError, tf_listener

COLOR_TOPIC = "/camera/color/image_raw"
DEPTH_TOPIC = "/camera/depth/image_raw"
INFO_TOPIC = "/camera/camera_info"
MAP_FRAME = "map"
BASE_FRAME = "base_footprint"
MAX_POSE_GAP = 0.25  # [s] how long a frame may wait for tf to pose it
TF_POLL = 0.02  # [s] between two tries meanwhile
#: [s] frames that tf cannot pose for this long end the stream with the reason: the
#: robot is not localised (a look's own deadline, 3 s, would only say "timed out")
UNPOSED_LIMIT = 2.0


class CameraError(ActorbtError):
    """An image could not be decoded."""


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
        img = buf.reshape(h, msg.step)[:, : w * ch].reshape(h, w, ch)
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
        dt: np.dtype = np.dtype(">f4" if msg.is_bigendian else "<f4")
        return buf.reshape(h, msg.step)[:, : w * 4].copy().view(dt).reshape(h, w).astype(np.float32)
    if enc == "16UC1":
        dt = np.dtype(">u2" if msg.is_bigendian else "<u2")
        mm = buf.reshape(h, msg.step)[:, : w * 2].copy().view(dt).reshape(h, w)
        out = mm.astype(np.float32) / 1000.0
        out[mm == 0] = np.nan
        return out
    raise CameraError(f"unsupported image encoding {enc!r}")


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
        return cls(
            float(k[0]), float(k[4]), float(k[2]), float(k[5]), int(msg.width), int(msg.height), msg.header.frame_id
        )

    def as_dict(self) -> dict:
        return {
            "fx": self.fx,
            "fy": self.fy,
            "cx": self.cx,
            "cy": self.cy,
            "width": self.width,
            "height": self.height,
            "frame_id": self.frame_id,
        }


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
    """An RGB-D camera reached through its ROS topics, posed by the robot's transform tree
    (the localisation's map frame)."""

    def __init__(
        self,
        color_topic: str = COLOR_TOPIC,
        depth_topic: str = DEPTH_TOPIC,
        info_topic: str = INFO_TOPIC,
        map_frame: str = MAP_FRAME,
        base_frame: str = BASE_FRAME,
    ) -> None:
        super().__init__()
        self.register_subscriber("color_raw", Image, color_topic, 2)
        self.register_subscriber("depth_raw", Image, depth_topic, 2)
        self.register_subscriber("camera_info", CameraInfo, info_topic, 1)
        self.tf = tf_listener(self)
        self.set_value("camera_map_frame", map_frame)
        self.set_value("camera_base_frame", base_frame)

    def _poses(self, frame_id: str, t: float) -> tuple[np.ndarray, np.ndarray] | TransformError:
        """(T_map_cam, T_map_base) at stamp ``t`` from tf, waiting up to MAX_POSE_GAP for
        the transforms to reach it; the lookup's error when they do not."""
        map_frame, base_frame = self.get_value("camera_map_frame"), self.get_value("camera_base_frame")
        end = self.runtime.now() + MAX_POSE_GAP
        while True:
            try:
                return (self.tf.lookup(map_frame, frame_id, t), self.tf.lookup(map_frame, base_frame, t))
            except TransformError as e:
                if self.runtime.now() >= end:
                    return e
            self.run_actor("sleep", TF_POLL)

    @actor(read_only=True)
    def pic(self) -> Iterator[np.ndarray]:
        """Colour images as BGR uint8 arrays (H, W, 3), as OpenCV expects them."""
        with self.run_actor_mode("color_raw", "iterator") as msgs:
            for msg in msgs:
                yield image_to_array(msg)

    @actor(read_only=True)
    def depth(self) -> Iterator[np.ndarray]:
        """Depth images as float32 arrays (H, W) in metres; NaN where there is no return."""
        with self.run_actor_mode("depth_raw", "iterator") as msgs:
            for msg in msgs:
                yield image_to_array(msg)

    @actor(read_only=True)
    def intrinsics(self) -> dict:
        """The camera's pinhole intrinsics: fx, fy, cx, cy [px], width, height, frame_id."""
        return Intrinsics.from_msg(self.run_actor_mode("camera_info", "timed", 5.0)).as_dict()

    @actor(read_only=True)
    def rgbd(self) -> Iterator[RGBDFrame]:
        """Synchronised RGB-D frames: colour and depth with the same header stamp, the
        intrinsics, and the camera pose in the map frame at that stamp (from tf)."""
        info: Intrinsics | None = None
        with (
            self.run_actor_mode("camera_info", "iterator") as infos,
            self.run_actor_mode("color_raw", "iterator") as colors,
            self.run_actor_mode("depth_raw", "iterator") as depths,
        ):
            dmsg = None
            unposed_since = None
            for cmsg in colors:
                t = stamp_seconds(cmsg.header)
                while dmsg is None or stamp_seconds(dmsg.header) < t - 1e-6:
                    dmsg = next(depths)
                if stamp_seconds(dmsg.header) > t + 1e-6:
                    continue  # this colour frame has no depth twin
                if info is None or (info.width, info.height) != (cmsg.width, cmsg.height):
                    info = Intrinsics.from_msg(next(infos))  # sent with the images
                frame_id = cmsg.header.frame_id or info.frame_id
                poses = self._poses(frame_id, t)
                if isinstance(poses, TransformError):  # tf cannot pose it: not localised
                    now = self.runtime.now()
                    unposed_since = now if unposed_since is None else unposed_since
                    if now - unposed_since >= UNPOSED_LIMIT:
                        raise CameraError(
                            f"no camera pose for {now - unposed_since:.1f} s of frames: "
                            f"{poses} (is the robot localised? the localiser publishes "
                            "map -> odom on /tf)"
                        )
                    continue
                unposed_since = None
                T_map_cam, T_map_base = poses
                yield RGBDFrame(
                    stamp=t,
                    bgr=image_to_array(cmsg),
                    depth=image_to_array(dmsg),
                    intrinsics=info,
                    T_map_cam=T_map_cam,
                    T_map_base=T_map_base,
                    frame_id=frame_id,
                )
