"""sensor_msgs/Image -> sensor_msgs/CompressedImage, as image_transport's ``compressed``
plugin publishes it on ``<topic>/compressed`` (OpenCV encodes: installed with the
``sim`` extra; without it this raises a clear error).

Colour and mono 8-bit images become JPEG (``format``: ``"rgb8; jpeg compressed bgr8"``,
image_transport's spelling, which Foxglove and rqt_image_view read); 16-bit images PNG.
Float images (depth in metres) have no lossless 8/16-bit form here and are refused.
"""

from __future__ import annotations

from types import ModuleType

from bt_engine.bus.messages import RosMessage
from bt_engine.errors import ActorbtError

__all__ = ["CompressionError", "JPEG_QUALITY", "compress_image", "compressed_topic"]

#: JPEG quality (image_transport's default is 80; the camera is small: keep detail)
JPEG_QUALITY = 90
_CHANNELS = {"rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4, "mono8": 1, "8UC1": 1, "8UC3": 3, "mono16": 1, "16UC1": 1}


class CompressionError(ActorbtError, ValueError):
    """An image that cannot be compressed: unknown encoding, or no OpenCV."""


def compressed_topic(topic: str) -> str:
    """Where image_transport publishes ``topic``'s compressed images."""
    return topic.rstrip("/") + "/compressed"


def _cv2() -> ModuleType:
    try:
        import cv2
    except ImportError as exc:
        raise CompressionError(
            "compressing camera images needs OpenCV: pip install opencv-python-headless (the sim extra installs it)"
        ) from exc
    return cv2


def compress_image(msg: RosMessage, quality: int = JPEG_QUALITY) -> RosMessage:
    """``msg`` (sensor_msgs/Image) as a sensor_msgs/CompressedImage with the same header."""
    import numpy as np
    from sensor_msgs.msg import CompressedImage

    enc = msg.encoding
    channels = _CHANNELS.get(enc)
    if channels is None:
        raise CompressionError(f"cannot compress a {enc!r} image; expected one of {', '.join(_CHANNELS)}")
    cv2 = _cv2()
    wide = enc in ("mono16", "16UC1")
    dtype = np.dtype((">u2" if msg.is_bigendian else "<u2") if wide else "u1")
    rows = np.frombuffer(bytes(msg.data), dtype=dtype).reshape(msg.height, msg.step // dtype.itemsize)
    pixels = rows[:, : msg.width * channels].reshape(msg.height, msg.width, channels)
    if channels > 1:  # JPEG keeps no alpha; OpenCV writes BGR
        code = {"rgb8": cv2.COLOR_RGB2BGR, "rgba8": cv2.COLOR_RGBA2BGR, "bgra8": cv2.COLOR_BGRA2BGR}.get(enc)
        if code is not None:
            pixels = cv2.cvtColor(np.ascontiguousarray(pixels), code)
    out = CompressedImage()
    out.header = msg.header
    if wide:
        ok, data = cv2.imencode(".png", pixels.astype("<u2"))
        out.format = f"{enc}; png compressed {enc}"
    else:
        ok, data = cv2.imencode(".jpg", pixels, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
        target = "mono8" if channels == 1 else "bgr8"
        out.format = f"{enc}; jpeg compressed {target}"
    if not ok:
        raise CompressionError(f"OpenCV could not encode a {msg.width}x{msg.height} {enc} image")
    out.data = data.tobytes()
    return out
