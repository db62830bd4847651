"""The Foxglove layout shipped as docs/foxglove_layout.json, built with the Foxglove SDK's
layout types (``foxglove.layouts``) so that it stays in the app's format.

It shows a live view (``--foxglove``) and a recorded bag (``--bag``) alike: both carry
the same topic names. A 3D panel with the map, the scan, the robot (its /tf frames and
its body on /actorbt/scene), its path (/actorbt/path), the detections and goals
(/actorbt/scene), following the robot; the camera image; the tree's status as
diagnostics, and the last status change in full. (/actorbt/scene and /actorbt/path
exist only in the live view.)

Regenerate the file after changing it: ``python -m bt_ros.foxglove_layout
docs/foxglove_layout.json`` (a test compares them).
"""

from __future__ import annotations

import json
import sys
from typing import TYPE_CHECKING

from .foxglove_view import PATH_TOPIC, SCENE_TOPIC
from .tree_status import STATUS_TOPIC

if TYPE_CHECKING:
    from foxglove.layouts import Layout

__all__ = ["layout", "layout_json"]

CAMERA = "/camera/color/image_raw/compressed"
CAMERA_INFO = "/camera/camera_info"


def layout() -> Layout:
    """The layout, as a ``foxglove.layouts.Layout``."""
    import foxglove.layouts as fl

    scene = fl.ThreeDeePanel(
        title="map, robot, path, scan, detections and goals",
        config=fl.ThreeDeeConfig(
            follow_tf="base_footprint",
            follow_mode="follow-position",
            topics={
                "/map": fl.BaseRendererRosOccupancyGridTopicSettings(visible=True, color_mode="map"),
                "/scan": fl.BaseRendererLaserScanTopicSettings(
                    visible=True, point_size=4.0, color_mode="flat", flat_color="#ff453aff"
                ),
                SCENE_TOPIC: fl.BaseRendererSceneUpdateTopicSettings(visible=True),
                PATH_TOPIC: fl.BaseRendererPosesTopicSettings(
                    visible=True, type="line", line_width=0.03, gradient=("#2f6fffff", "#2f6fffff")
                ),
            },
        ),
    )
    camera = fl.ImagePanel(
        title="camera",
        config=fl.ImageConfig(image_mode=fl.ImageModeConfig(image_topic=CAMERA, calibration_topic=CAMERA_INFO)),
    )
    status = fl.DiagnosticsSummaryPanel(
        title="tree status", config=fl.DiagnosticsSummaryConfig(topic_to_render=STATUS_TOPIC, sort_by_level=False)
    )
    last = fl.RawMessagesPanel(
        title="last status change", config=fl.RawMessagesConfig(topic_path=f"{STATUS_TOPIC}.status[0]", expansion="all")
    )
    side = fl.SplitContainer(
        direction="column",
        items=[
            fl.SplitItem(proportion=3, content=camera),
            fl.SplitItem(proportion=3, content=status),
            fl.SplitItem(proportion=2, content=last),
        ],
    )
    return fl.Layout(
        content=fl.SplitContainer(
            direction="row", items=[fl.SplitItem(proportion=3, content=scene), fl.SplitItem(proportion=2, content=side)]
        )
    )


def layout_json() -> str:
    """The layout as the JSON text of docs/foxglove_layout.json (indented, sorted keys)."""
    return json.dumps(json.loads(layout().to_json()), indent=2, sort_keys=True) + "\n"


if __name__ == "__main__":
    text = layout_json()
    if len(sys.argv) > 1:
        with open(sys.argv[1], "w", encoding="utf-8") as f:
            f.write(text)
    else:
        sys.stdout.write(text)
