"""The ROS transport of the bus, real rclpy over Fast DDS on loopback: topics as actors
(subscriber streams with timed iterators, sensor QoS for images), action and service
clients as async actors, and a clean shutdown."""

from __future__ import annotations

import threading
import time

import pytest

pytest.importorskip("rclpy")
from actorbt_interfaces.action import CallActor  # noqa: E402
from sensor_msgs.msg import Image  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from std_srvs.srv import SetBool  # noqa: E402

from bt_engine import ActorError, Kind, Runtime, SubSystem  # noqa: E402
from bt_engine.bus.qos import QosError, qos_depth  # noqa: E402
from bt_ros.host import RosHost  # noqa: E402
from bt_ros.qos import qos_profile  # noqa: E402
from bt_ros.server import serve  # noqa: E402
from bt_ros.transport import RosTransport  # noqa: E402
from tests.test_ros_common import (
    Work,
    os_threads,
    python_threads,
    shm_leaks,  # noqa: E402
    shm_mapped,
    wait_until,
)


class Talker(SubSystem):
    def __init__(self):
        super().__init__()
        self.register_publisher("say", String, "/ros_test/chat")


class Listener(SubSystem):
    def __init__(self):
        super().__init__()
        self.register_subscriber("heard", String, "/ros_test/chat", 50)
        bus = self.runtime.bus

        def frames(emit):  # a sensor stream: best effort, keep the latest 5
            return bus.subscribe("/ros_test/image", Image, emit, "sensor").close

        self.add_actor("frames", frames, Kind.STREAM, buffer=qos_depth("sensor"))


@pytest.fixture(scope="module")
def pair():
    """Two wall-clock runtimes, each with its own rclpy context and node."""
    a = Runtime(clock="wall", bus=RosTransport)
    b = Runtime(clock="wall", bus=RosTransport)
    try:
        a.add_subsystem("talk", Talker)
        b.add_subsystem("listen", Listener)
        yield a, b
    finally:
        a.close()
        b.close()


def _publish_while(rt, stop, make, topic, qos, period):
    pub = rt.bus.publisher(topic, type(make(0)), qos)
    i = 0
    while not stop.is_set():
        pub.publish(make(i))
        i += 1
        time.sleep(period)


def test_qos_settings():
    from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

    assert qos_profile(7).depth == 7 and qos_profile(7).reliability == ReliabilityPolicy.RELIABLE
    assert qos_profile("sensor").reliability == ReliabilityPolicy.BEST_EFFORT
    assert qos_profile("latched").durability == DurabilityPolicy.TRANSIENT_LOCAL
    assert qos_depth(3) == 3 and qos_depth("sensor") == 5 and qos_depth(qos_profile(4)) == 4
    for bad in ("fast", True, 1.5):
        with pytest.raises(QosError):
            qos_depth(bad)


def test_subscriber_stream_with_a_timed_iterator_on_a_real_topic(pair):
    a, b = pair
    stop = threading.Event()

    def talk():
        i = 0
        while not stop.is_set():
            a.call("say", String(data=f"m{i}"))
            i += 1
            time.sleep(0.01)

    with b.stream("heard", timeout=0.8) as it:
        assert wait_until(lambda: a.bus.subscription_count("/ros_test/chat") >= 1, 5.0)
        t = threading.Thread(target=talk)
        t.start()
        t0 = time.monotonic()
        try:
            got = [m.data for m in it]
        finally:
            stop.set()
            t.join()
    elapsed = time.monotonic() - t0
    assert len(got) >= 10, got
    numbers = [int(s[1:]) for s in got]
    assert numbers == sorted(numbers)  # in order; the stream kept up (depth 50)
    assert elapsed < 1.5  # it ended at its deadline (0.8 s after it started)
    assert not b.bus._subs  # leaving the block closed the subscription


def test_images_with_sensor_qos(pair):
    a, b = pair
    stop = threading.Event()

    def make(i):
        img = Image(height=240, width=320, encoding="rgb8", step=320 * 3)
        img.data = bytes([i % 256]) * (320 * 240 * 3)
        return img

    t = threading.Thread(target=_publish_while, args=(a, stop, make, "/ros_test/image", "sensor", 0.02))
    t.start()
    try:
        with b.stream("frames", timeout=0.8) as it:
            frames = list(it)
    finally:
        stop.set()
        t.join()
    assert len(frames) >= 5
    f = frames[-1]
    assert (f.width, f.height, f.encoding, len(f.data)) == (320, 240, "rgb8", 320 * 240 * 3)


def test_service_client_actor():
    srv_host = RosHost("test-service")
    rt = Runtime(clock="wall", bus=RosTransport)
    try:
        node = srv_host.create_node("setbool_server")

        def handle(req, resp):
            resp.success = req.data
            resp.message = f"set to {req.data}"
            return resp

        srv_host.call(node.create_service, SetBool, "/ros_test/set", handle)
        rt.run_on_hub(rt.bus.register_service, rt.root, "set_flag", SetBool, "/ros_test/set")
        resp = rt.call("set_flag", data=True)
        assert resp.success and resp.message == "set to True"
        resp = rt.call("set_flag", SetBool.Request(data=False))
        assert not resp.success
        assert rt.call("set_flag", request=SetBool.Request(data=True)).success  # by keyword
        with pytest.raises(Exception) as e:
            rt.call("set_flag", colour="red")
        assert "colour" in str(e.value)
    finally:
        rt.close()
        srv_host.close()


def test_action_client_actor_against_another_runtime_and_cancel():
    server_rt = Runtime(clock="wall", bus=RosTransport)
    client = Runtime(clock="wall", bus=RosTransport)
    server = None
    try:
        server_rt.add_subsystem("work", Work)
        server = serve(server_rt)
        client.run_on_hub(client.bus.register_action, client.root, "remote", CallActor, "/actorbt/call")
        assert "goal" in str(client.resolve("remote").signature)
        res = client.call("remote", actor="work.echo", args_yaml="[1, two]")
        assert res.success and res.result_yaml.startswith("args:")
        # a failed goal is an ActorError with the server's reason
        with pytest.raises(ActorError) as e:
            client.call("remote", {"actor": "work.boom"})
        assert "aborted" in str(e.value) and "kaput" in str(e.value)
        # cancelling the client's transaction cancels the goal and the remote work
        txn = client.start("remote", actor="work.slow", args_yaml="{steps: 500, period: 0.01}")
        assert wait_until(lambda: server_rt.call("work.stats")["started"] == 1, 5.0)
        txn.cancel("test cancels")
        assert wait_until(lambda: server_rt.call("work.stats")["cancelled"] == 1, 5.0)
        assert wait_until(lambda: not server_rt.call("work.stats")["live"], 2.0)
        assert txn.cancelled
    finally:
        if server is not None:
            server.close()
        client.close()
        server_rt.close()


def test_unavailable_server_fails_after_the_wait():
    rt = Runtime(clock="wall", bus=lambda r: RosTransport(r, server_timeout=0.3))
    try:
        rt.run_on_hub(rt.bus.register_action, rt.root, "nobody", CallActor, "/ros_test/nobody")
        t0 = time.monotonic()
        with pytest.raises(ActorError) as e:
            rt.call("nobody", actor="x")
        assert "no server for /ros_test/nobody" in str(e.value)
        assert 0.25 < time.monotonic() - t0 < 3.0
    finally:
        rt.close()


def test_shutdown_leaves_no_threads_and_no_shared_memory():
    RosHost("warm-up").close()  # Fast DDS starts a few process-wide threads once
    threads, os_before, shm_before = python_threads(), os_threads(), shm_mapped()
    server_rt = Runtime(clock="wall", bus=RosTransport)
    client = Runtime(clock="wall", bus=RosTransport)
    server_rt.add_subsystem("work", Work)
    server = serve(server_rt)
    client.run_on_hub(client.bus.register_action, client.root, "remote", CallActor, "/actorbt/call")
    assert client.call("remote", actor="work.echo").success
    segments = shm_mapped() - shm_before  # our new participants' segments
    assert segments, "Fast DDS uses shared memory between participants here"
    server.close()
    server_rt.close()
    client.close()
    assert wait_until(lambda: python_threads() <= threads, 2.0), python_threads() - threads
    assert wait_until(lambda: os_threads() <= os_before, 2.0), (os_threads(), os_before)
    assert shm_mapped() & segments == set()
    assert shm_leaks(segments) == set()


def test_a_goal_whose_server_dies_fails_instead_of_waiting_for_ever():
    """The server's process dies while it runs our goal (a robot-side restart): no result
    will ever come, so the goal fails once the server has been gone for LOST_GRACE."""
    import rclpy
    from rclpy.action import ActionServer
    from rclpy.executors import SingleThreadedExecutor

    from bt_ros.client import LOST_GRACE

    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    node = rclpy.create_node("doomed_server", context=ctx)
    started, release = threading.Event(), threading.Event()

    def execute(goal):  # accepts, then never finishes until released
        started.set()
        release.wait(30)
        goal.abort()
        return CallActor.Result()

    server = ActionServer(node, CallActor, "/ros_test/doomed", execute)
    executor = SingleThreadedExecutor(context=ctx)
    executor.add_node(node)
    spin = threading.Thread(target=executor.spin, daemon=True)
    spin.start()
    client = Runtime(clock="wall", bus=RosTransport)
    try:
        client.run_on_hub(client.bus.register_action, client.root, "doomed", CallActor, "/ros_test/doomed")
        txn = client.start("doomed", actor="x")
        assert started.wait(10), "the goal never reached the server"
        server.destroy()  # the server goes away with the goal under way
        node.destroy_node()
        t0 = time.monotonic()
        assert wait_until(lambda: txn.done, LOST_GRACE + 5.0), "the goal still waits for its server"
        assert LOST_GRACE - 0.6 <= time.monotonic() - t0 <= LOST_GRACE + 3.0
        assert "went away while it ran the goal" in str(txn.error)
    finally:
        release.set()
        client.close()
        executor.shutdown()
        rclpy.shutdown(context=ctx)
