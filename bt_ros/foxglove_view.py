"""A live view for Foxglove (``--foxglove [PORT]``): a Foxglove SDK WebSocket server,
bound to 127.0.0.1 unless told otherwise, that the Foxglove app connects to
(``ws://127.0.0.1:8765``; docs/foxglove_layout.json arranges the panels).

Channels:

- The robot's topics, as a ROS bridge offers them: the topics a bag records
  (:data:`bt_ros.bag.DEFAULT_TOPICS`: /map, /tf, /tf_static, /odom, /scan,
  /joint_states and the tree's status on /actorbt/status, and those ``robot: topics:``
  adds in actorbt.yaml, such as a camera's), with their ROS types (``ros2msg`` schemas) and CDR bytes.
  So the layout that shows a live run shows its bag too. A topic is subscribed on the
  bus only while a Foxglove client subscribes to its channel: the simulator renders the
  camera only while someone watches it.
- ``/actorbt/scene`` (foxglove.SceneUpdate): the robot's body (``robot: body:``), the detections and the
  navigation goals (:mod:`.foxglove_scene` says where they come from).
- ``/actorbt/path`` (foxglove.PosesInFrame): the robot's path, from its odometry.

Messages are stamped with the runtime clock (as their headers), and the server
broadcasts that clock (the ``time`` capability), so Foxglove's time is the robot's
even under the virtual clock. The view watches actor calls through ``rt.recorder``
(it chains to the hooks that were there), on the hub.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING, Callable, Protocol

from bt_engine.bus.messages import RosMessage, message_class
from bt_engine.errors import RuntimeClosedError
from .bag import DEFAULT_TOPICS, BagTopic
from .cdr import message_definition, serialize
from .compressed import CompressionError, compress_image
from .foxglove_scene import Body, Scene, detections_in, goal_of

if TYPE_CHECKING:
    from foxglove.websocket import ChannelView, Client, ServerListener

    from bt_engine import Runtime, Transaction
    from bt_engine.bus.transport import Subscription
    from bt_engine.hub import TimerHandle
from .live_options import FOXGLOVE_PORT, FoxgloveError
from .rostypes import Json

__all__ = ["DEFAULT_PORT", "FoxgloveError", "FoxgloveView", "PATH_TOPIC", "SCENE_TOPIC"]

log = logging.getLogger("actorbt.foxglove")

DEFAULT_PORT = FOXGLOVE_PORT
SCENE_TOPIC = "/actorbt/scene"
PATH_TOPIC = "/actorbt/path"
#: [s] of the runtime clock between two sendings of the whole scene (late clients) and
#: of the path, and between two broadcasts of the server's time
SCENE_PERIOD, PATH_PERIOD, TIME_PERIOD = 1.0, 0.5, 0.05


def _listener(view: FoxgloveView) -> ServerListener:
    """The SDK's ServerListener: which channels clients want (called on its threads).
    Made here, as the SDK is imported only when a view starts; the callbacks it does not
    define keep the SDK's defaults."""
    from foxglove.websocket import ServerListener

    class _Listener(ServerListener):
        def on_subscribe(self, client: Client, channel: ChannelView) -> None:
            view._demand(channel.topic, +1)

        def on_unsubscribe(self, client: Client, channel: ChannelView) -> None:
            view._demand(channel.topic, -1)

    return _Listener()


class CallHooks(Protocol):
    """What ``rt.recorder`` hears of every actor call (:mod:`bt_engine.transaction`)."""

    def call_started(self, txn: Transaction) -> None: ...

    def call_finished(self, txn: Transaction) -> None: ...


class _Hooks:
    """``rt.recorder`` while the view is open: every actor call, then the previous hooks."""

    def __init__(self, view: FoxgloveView, previous: CallHooks | None) -> None:
        self.view = view
        self.previous = previous

    def call_started(self, txn: Transaction) -> None:
        if not self.view.closed:
            self.view._call_started(txn)
        if self.previous is not None:
            self.previous.call_started(txn)

    def call_finished(self, txn: Transaction) -> None:
        if not self.view.closed:
            self.view._call_finished(txn)
        if self.previous is not None:
            self.previous.call_finished(txn)

    def emit(self, event: dict[str, Json]) -> None:
        if self.previous is not None and hasattr(self.previous, "emit"):
            self.previous.emit(event)


class FoxgloveView:
    """Serves ``rt``'s robot topics, scene and path to Foxglove until :meth:`close`.

    Args:
        rt: the runtime whose bus and actor calls are shown.
        port: the TCP port (0: any free one; :attr:`port` says which).
        host: the address to bind (default 127.0.0.1: this machine only).
        topics: the robot topics to offer.
        body: the robot's box to draw at base_footprint (None: none).

    Raises:
        FoxgloveError: the server cannot bind ``host:port``.
    """

    def __init__(
        self,
        rt: Runtime,
        *,
        port: int = DEFAULT_PORT,
        host: str = "127.0.0.1",
        topics: tuple[BagTopic, ...] = DEFAULT_TOPICS,
        body: Body | None = None,
    ) -> None:
        import foxglove
        from foxglove.channels import PosesInFrameChannel, SceneUpdateChannel

        self.rt = rt
        self.closed = False
        self.scene = Scene(body)
        self.ctx = foxglove.Context()
        self._topics = {t.bag_name: t for t in topics}
        self._channels = {
            t.bag_name: foxglove.Channel(
                t.bag_name,
                message_encoding="cdr",
                context=self.ctx,
                schema=foxglove.Schema(
                    name=t.bag_type, encoding="ros2msg", data=message_definition(t.bag_type).encode()
                ),
            )
            for t in topics
        }
        self._scene_channel = SceneUpdateChannel(SCENE_TOPIC, context=self.ctx)
        self._path_channel = PosesInFrameChannel(PATH_TOPIC, context=self.ctx)
        self._demanded: dict[str, int] = {}
        self._subs: dict[str, Subscription] = {}
        self._odom: Subscription | None = None
        self._timer: TimerHandle | None = None
        self._hooks: _Hooks | None = None
        self._sent = {"path": -1.0, "time": -1.0}
        try:
            self.server = foxglove.start_server(
                name="actorbt",
                host=host,
                port=port,
                context=self.ctx,
                server_listener=_listener(self),
                capabilities=[foxglove.Capability.Time],
            )
        except RuntimeError as exc:
            reason = str(exc).split("FoxgloveError:", 1)[-1].strip()
            raise FoxgloveError(f"--foxglove: cannot serve on {host}:{port}: {reason}") from None
        self.host = host
        self.port = self.server.port
        try:
            rt.run_on_hub(self._start)
        except BaseException:
            self.server.stop()
            raise

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    # -- on the hub ------------------------------------------------------------------------
    def _start(self) -> None:
        from nav_msgs.msg import Odometry

        self._odom = self.rt.bus.subscribe("/odom", Odometry, self._on_odom, 50)
        self._hooks = _Hooks(self, self.rt.recorder)
        self.rt.recorder = self._hooks
        self._timer = self.rt.call_every(SCENE_PERIOD, self._send_scene)

    def _stop(self) -> None:
        for sub in [*self._subs.values(), self._odom]:
            if sub is not None:
                sub.close()
        self._subs.clear()
        self._odom = None
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self._hooks is not None and self.rt.recorder is self._hooks:
            self.rt.recorder = self._hooks.previous
        # else hooks opened later keep ours in their chain: closed, it only forwards

    def _now_ns(self) -> int:
        return int(round(self.rt.now() * 1e9))

    def _demand(self, topic: str, delta: int) -> None:
        if topic in self._topics:
            try:
                self.rt.call_soon_threadsafe(self._set_demand, topic, delta)
            except RuntimeClosedError:
                pass

    def _set_demand(self, topic: str, delta: int) -> None:
        n = self._demanded[topic] = max(0, self._demanded.get(topic, 0) + delta)
        if self.closed:
            return
        if n and topic not in self._subs:
            t = self._topics[topic]
            self._subs[topic] = self.rt.bus.subscribe(t.name, message_class(t.type), self._forwarder(t), t.qos)
        elif not n and topic in self._subs:
            self._subs.pop(topic).close()

    def _forwarder(self, topic: BagTopic) -> Callable[[RosMessage], None]:
        channel = self._channels[topic.bag_name]

        def forward(msg: RosMessage) -> None:
            if topic.compress:
                try:
                    msg = compress_image(msg)
                except CompressionError as exc:
                    log.warning("not showing %s: %s", topic.bag_name, exc)
                    self._subs.pop(topic.bag_name).close()
                    return
            channel.log(serialize(msg), log_time=self._now_ns())
            self._tell_time()

        return forward

    def _tell_time(self) -> None:
        now = self.rt.now()
        if now - self._sent["time"] >= TIME_PERIOD or now < self._sent["time"]:
            self._sent["time"] = now
            self.server.broadcast_time(self._now_ns())

    def _on_odom(self, msg: RosMessage) -> None:
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        self.scene.add_odometry(p.x, p.y, yaw, msg.header.frame_id or "odom")
        now = self.rt.now()
        if now - self._sent["path"] >= PATH_PERIOD:
            self._sent["path"] = now
            self._path_channel.log(self.scene.path_message(now), log_time=self._now_ns())
        self._tell_time()

    def _send_scene(self) -> None:
        self._scene_channel.log(self.scene.update(self.rt.now()), log_time=self._now_ns())

    def _call_started(self, txn: Transaction) -> None:
        goal = goal_of(txn.args)
        if goal is not None:
            self.scene.add_goal(goal)
            self._send_scene()

    def _call_finished(self, txn: Transaction) -> None:
        if txn.result is None or txn.error is not None:
            return
        changed = False
        for d in detections_in(txn.result):
            changed = self.scene.add_detection(d) or changed
        if changed:
            self._send_scene()

    # -- from any thread -------------------------------------------------------------------
    def close(self) -> None:
        """Stop serving: unsubscribe, unhook, stop the server."""
        if self.closed:
            return
        self.closed = True
        try:
            self.rt.run_on_hub(self._stop)
        except RuntimeClosedError:
            pass
        self.server.stop()

    def __enter__(self) -> FoxgloveView:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
