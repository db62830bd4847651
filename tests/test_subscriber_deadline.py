"""A subscriber actor gives up: a caller waiting longer than its ``wait`` (default
SUBSCRIBER_WAIT) for a message fails with ActorTimeout naming the topic, its type and
whether anything publishes it. The wait bounds each wait for a message, not the stream's
life, and a caller's own deadline replaces it."""

from __future__ import annotations

import pathlib
import threading
import time

import pytest
from std_msgs.msg import String

from bt_engine import ActorTimeout, Failure, Kind, Runtime, SubSystem
from bt_engine.bus.actions import ServerUnavailableError
from bt_engine.errors import ActorbtError
from bt_engine.subsystem import SUBSCRIBER_WAIT
from tests.conftest import run_in_actor

REPO = pathlib.Path(__file__).resolve().parents[1]
TOPIC = "/deadline_test/chat"


class Ear(SubSystem):
    def __init__(self):
        super().__init__()
        self.register_subscriber("heard", String, TOPIC, 5)
        self.register_subscriber("patient", String, TOPIC, 5, wait=None)
        self.register_subscriber("quick", String, TOPIC, 5, wait=2.5)


@pytest.fixture
def ear(rt):
    rt.add_subsystem("ear", Ear)
    return rt


def publish_at(rt, times, topic=TOPIC):
    """Publish "m0", "m1", ... on ``topic`` at runtime-clock ``times`` [s]."""
    pub = rt.bus.publisher(topic, String)
    for i, t in enumerate(times):
        rt.call_later(t, pub.publish, String(data=f"m{i}"))
    return pub


def test_the_default_is_ten_seconds():
    assert SUBSCRIBER_WAIT == 10.0


def test_no_publisher_fails_after_the_default_naming_the_topic(ear):
    t_wall = time.monotonic()
    t0 = ear.now()
    with pytest.raises(ActorTimeout) as e:
        ear.call("heard")
    assert ear.now() - t0 == pytest.approx(SUBSCRIBER_WAIT)
    assert time.monotonic() - t_wall < 2.0  # virtual time: nothing can publish, it jumps
    assert str(e.value) == (
        f"actor ear.heard: no message on {TOPIC} (std_msgs/msg/String) within "
        "10 s: nothing publishes it (is the robot or the simulator running?)"
    )
    assert e.value.path == "ear.heard" and e.value.seconds == SUBSCRIBER_WAIT
    assert isinstance(e.value, ActorbtError)
    assert ear.bus.subscription_count(TOPIC) == 0  # the subscription was closed
    assert ear.transactions() == []


def test_a_silent_publisher_is_named(ear):
    ear.bus.publisher(TOPIC, String)
    with pytest.raises(ActorTimeout, match="within 10 s, though 1 publisher has it"):
        ear.call("heard")


def test_a_late_message_within_the_wait_is_returned(ear):
    publish_at(ear, [9.0])
    t0 = ear.now()
    assert ear.call("heard").data == "m0"
    assert ear.now() - t0 == pytest.approx(9.0)


def test_each_subscriber_has_its_own_wait(ear):
    t0 = ear.now()
    with pytest.raises(ActorTimeout, match="within 2.5 s"):
        ear.call("quick")
    assert ear.now() - t0 == pytest.approx(2.5)


def test_the_callers_own_deadline_replaces_the_wait(ear):
    publish_at(ear, [20.0])
    assert ear.call("heard", timeout=30).data == "m0"  # longer than the wait: still the message
    with pytest.raises(ActorTimeout, match="did not finish within 3 s"):
        ear.call("heard", timeout=3)

    def body():
        t0 = ear.now()
        with ear.run_actor_mode("heard", "timed_iterator", 25.0) as it:
            got = list(it)  # nothing comes: the iteration just ends at its deadline
        return got, ear.now() - t0

    got, took = run_in_actor(ear, body)
    assert got == [] and took == pytest.approx(25.0)


def test_a_stream_goes_on_while_messages_flow_and_fails_when_they_stop(ear):
    publish_at(ear, [1.0 + 2.0 * i for i in range(20)])  # every 2 s for 40 s

    def body():
        t0 = ear.now()
        got = []
        with ear.run_actor_mode("heard", "iterator") as it:
            try:
                for msg in it:
                    got.append(msg.data)
            except ActorTimeout as e:
                return got, ear.now() - t0, str(e)
        return got, ear.now() - t0, None

    got, took, error = run_in_actor(ear, body)
    assert got == [f"m{i}" for i in range(20)]  # 40 s of messages, four waits long
    assert took == pytest.approx(39.0 + SUBSCRIBER_WAIT)  # then 10 s of silence
    assert error is not None and f"no message on {TOPIC}" in error
    assert ear.bus.subscription_count(TOPIC) == 0


def test_an_iterator_bounds_the_callers_wait_not_the_time_between_messages(ear):
    """A consumer busy for longer than the wait finds the message that came meanwhile;
    only its own wait for the next one is bounded."""
    publish_at(ear, [1.0])

    def body():
        with ear.run_actor_mode("heard", "iterator") as it:
            ear.sleep(15.0)  # busy: the message is buffered
            first = next(it).data
            t0 = ear.now()
            try:
                next(it)
            except ActorTimeout:
                return first, ear.now() - t0

    assert run_in_actor(ear, body) == ("m0", pytest.approx(SUBSCRIBER_WAIT))


def test_a_stream_iterated_from_another_thread_gives_up_too(ear):
    with pytest.raises(ActorTimeout, match="nothing publishes it"):
        with ear.stream("heard") as it:
            next(it)


def test_wait_none_waits_until_cancelled(ear):
    def body():
        txn = ear.start("patient")
        ear.sleep(1000.0)
        alive = not txn.done
        txn.cancel("enough")
        ear.sleep(0.0)
        return alive, txn.state.value

    assert run_in_actor(ear, body) == (True, "cancelled")
    assert ear.bus.subscription_count(TOPIC) == 0


def test_wait_none_sync_call_is_cancelled_by_its_caller(ear):
    def waiter():
        return ear.run_actor("patient")

    def body():
        ear.root.add_actor("waiter", waiter, replace=True)
        txn = ear.start("waiter")
        ear.sleep(500.0)
        assert not txn.done
        txn.cancel("enough")
        ear.sleep(0.0)
        return txn.outcome()

    outcome = run_in_actor(ear, body)
    assert isinstance(outcome, Failure) and outcome.cancelled


def test_async_mode_gets_a_failure(ear):
    """A tree leaf starts its actor in async mode: it fails, it does not hang."""
    got = []

    def body():
        ear.start("heard", on_done=got.append)
        ear.sleep(SUBSCRIBER_WAIT + 1)

    run_in_actor(ear, body)
    assert len(got) == 1 and isinstance(got[0], Failure)
    assert isinstance(got[0].exception, ActorTimeout)
    assert "nothing publishes it" in str(got[0].exception)


def test_multi_mode_bounds_the_gap_between_messages(ear):
    publish_at(ear, [5.0, 12.0, 19.0])  # gaps of 7 s, then silence
    got = []

    def body():
        txn = ear.run_actor_mode("heard", "multi", got.append)
        ear.sleep(40.0)
        return txn.state.value

    assert run_in_actor(ear, body) == "failed"
    assert [m.data for m in got[:3]] == ["m0", "m1", "m2"]
    assert len(got) == 4 and isinstance(got[3], Failure)
    assert isinstance(got[3].exception, ActorTimeout)


def test_a_tree_leaf_fails_and_the_trace_says_why(ear, tmp_path):
    from bt_engine.trees import TraceRecorder, TreeFailure, register_tree_folder

    folder = tmp_path / "trees"
    folder.mkdir()
    (folder / "listen.yaml").write_text("name: listen\nroot: {do: ear.heard, out: msg}\n")
    host = register_tree_folder(ear, folder)
    trace = tmp_path / "listen.jsonl"
    with TraceRecorder(trace, host, tree="listen", transactions=True):
        with pytest.raises(ActorbtError) as e:
            ear.call("listen")
    assert isinstance(e.value.root_cause, TreeFailure)
    assert f"ear.heard: no message on {TOPIC}" in str(e.value)
    text = trace.read_text()
    assert f"no message on {TOPIC}" in text and '"actor":"ear.heard","state":"failed"' in text


def test_a_message_from_another_thread_is_waited_for_at_wall_pace():
    """Under the virtual clock, a stream fed by another thread (a ROS subscriber is not
    hub_only) gets its wait in wall time: the message 0.5 s later (wall) is not lost to
    a jump of virtual time."""
    rt = Runtime(clock="virtual")
    try:

        def feed(emit):
            timer = threading.Timer(0.5, emit, args=("late",))
            timer.start()
            return timer.cancel

        rt.run_on_hub(
            lambda: rt.root.add_actor(
                "driver", feed, Kind.STREAM, wait=1.0, wait_detail=lambda s: f"no frame in {s:g} s"
            )
        )
        t0 = time.monotonic()
        assert rt.call("driver") == "late"
        assert time.monotonic() - t0 >= 0.45

        def silent(emit):
            return lambda: None

        rt.run_on_hub(lambda: rt.root.add_actor("silent", silent, Kind.STREAM, wait=0.3))
        t0 = time.monotonic()
        with pytest.raises(ActorTimeout, match=r"^actor silent: no value within 0.3 s$"):
            rt.call("silent")
        assert time.monotonic() - t0 >= 0.25  # paced: another thread might still emit
    finally:
        rt.close()


def test_wait_is_checked_where_it_is_declared(rt):
    with pytest.raises(ActorbtError, match="emit-style stream"):
        rt.run_on_hub(lambda: rt.root.add_actor("f", lambda: 1, wait=1.0))
    with pytest.raises(ActorbtError, match="positive number of seconds"):
        rt.run_on_hub(lambda: rt.root.add_actor("g", lambda emit: None, Kind.STREAM, wait=0))


def test_the_catalog_says_how_long_a_subscriber_waits(ear):
    assert "Waiting more than 10 s for one fails" in ear.resolve("ear.heard").doc
    assert "Waiting" not in ear.resolve("ear.patient").doc


def test_a_local_action_without_a_server_fails_at_once_naming_it(rt):
    from control_msgs.action import GripperCommand

    class Arm(SubSystem):
        def __init__(self):
            super().__init__()
            self.register_action("grip", GripperCommand, "/gripper_controller/gripper_cmd")

    rt.add_subsystem("arm", Arm)
    t0 = rt.now()
    with pytest.raises(ActorbtError) as e:
        rt.call("grip")
    assert rt.now() == t0
    assert isinstance(e.value.root_cause, ServerUnavailableError)
    assert "no server for /gripper_controller/gripper_cmd (nothing serves it on the local bus)" in str(e.value)


# -- the actorbt command ---------------------------------------------------------------------
def test_actorbt_call_of_a_silent_topic_ends_with_the_reason(capsys):
    from bt_cli.main import main

    config = str(REPO / "actorbt.yaml")
    t0 = time.monotonic()
    rc = main(["--config", config, "call", "robot.navigation.odom", "--world", "none"])
    took = time.monotonic() - t0
    err = capsys.readouterr().err
    assert rc != 0
    assert (
        "actor robot.navigation.odom: no message on /odom (nav_msgs/msg/Odometry) within "
        "10 s: nothing publishes it (is the robot or the simulator running?)"
    ) in err
    assert took < 30.0  # virtual clock: no wall-time wait at all (about 1 s in all)
    # with the simulated world, the message comes at once
    assert main(["--config", config, "call", "robot.navigation.odom"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("nav_msgs.msg.Odometry(") and "child_frame_id='base_footprint'" in out


# -- over ROS 2 ------------------------------------------------------------------------------
def test_ros_subscriber_waits_in_wall_time_under_the_virtual_clock():
    pytest.importorskip("rclpy")
    from bt_ros.transport import RosTransport

    class RosEar(SubSystem):
        def __init__(self):
            super().__init__()
            self.register_subscriber("heard", String, "/deadline_test/ros_chat", 5, wait=4.0)
            self.register_subscriber("nobody", String, "/deadline_test/nobody", 5, wait=1.5)

    listener = Runtime(clock="virtual", bus=RosTransport)
    talker = Runtime(clock="wall", bus=RosTransport)
    stop = threading.Event()
    try:
        listener.add_subsystem("ear", RosEar)
        t0 = time.monotonic()
        with pytest.raises(ActorTimeout) as e:
            listener.call("nobody")
        assert time.monotonic() - t0 >= 1.4  # wall pace, though the clock is virtual
        assert "no message on /deadline_test/nobody (std_msgs/msg/String) within 1.5 s: nothing publishes it" in str(
            e.value
        )
        assert "ROS_DOMAIN_ID" in str(e.value)

        pub = talker.bus.publisher("/deadline_test/ros_chat", String)

        def talk():  # starts 1 s (wall) after the call, then every 0.1 s
            time.sleep(1.0)
            while not stop.is_set():
                pub.publish(String(data="hi"))
                time.sleep(0.1)

        t = threading.Thread(target=talk)
        t.start()
        try:
            assert listener.call("heard").data == "hi"  # discovery and all, within 4 s of wall
        finally:
            stop.set()
            t.join()
    finally:
        listener.close()
        talker.close()
