"""The local bus: real ROS message classes, publisher and subscriber actors."""

from __future__ import annotations

import pytest
from geometry_msgs.msg import Twist
from std_msgs.msg import String

from bt_engine import ActorError, SubSystem, actor
from bt_engine.bus.local import TopicTypeError
from tests.conftest import run_in_actor


class Talker(SubSystem):
    def __init__(self):
        super().__init__()
        self.register_publisher("motor", Twist, "cmd_vel", 10)
        self.register_subscriber("motor_echo", Twist, "/cmd_vel", 3)

    @actor
    def drive(self, speed: float, n: int) -> None:
        for _ in range(n):
            msg = Twist()
            msg.linear.x = speed
            self.run_actor("motor", msg)
            self.run_actor("sleep", 0.1)


def test_publisher_actor_and_subscriber_stream(rt):
    rt.add_subsystem("t", Talker)

    def body():
        rt.start("drive", 0.2, 5)
        with rt.run_actor_mode("motor_echo", "timed_iterator", 1.0) as it:
            return [m.linear.x for m in it]

    assert run_in_actor(rt, body) == [0.2] * 5
    assert rt.bus.subscription_count("/cmd_vel") == 0  # the stream unsubscribed on close


def test_stream_buffer_keeps_the_latest_values(rt):
    rt.add_subsystem("t", Talker)
    pub = rt.bus.publisher("/cmd_vel", Twist)

    def body():
        with rt.run_actor_mode("motor_echo", "iterator") as it:
            for i in range(6):  # 6 messages arrive while the consumer is busy
                m = Twist()
                m.linear.x = float(i)
                pub.publish(m)
            rt.sleep(0.1)
            return [next(it).linear.x for _ in range(3)]

    assert run_in_actor(rt, body) == [3.0, 4.0, 5.0]  # depth 3: the oldest were dropped


def test_publisher_rejects_the_wrong_message_type(rt):
    rt.add_subsystem("t", Talker)
    with pytest.raises(ActorError) as e:
        rt.call("motor", String(data="fast"))
    assert "Twist" in str(e.value)


def test_topic_type_is_fixed(rt):
    rt.bus.publisher("/chatter", String)
    with pytest.raises(TopicTypeError):
        rt.bus.publisher("/chatter", Twist)


def test_delivery_is_on_the_hub_in_publish_order(rt):
    got = []
    rt.bus.subscribe("/chatter", String, lambda m: got.append(m.data))
    pub = rt.bus.publisher("/chatter", String)
    for word in "one two three".split():
        pub.publish(String(data=word))  # from this (non-hub) thread
    rt.call("sleep", 0.1)
    assert got == ["one", "two", "three"]


def test_a_latched_topic_reaches_a_late_latched_subscriber_only(rt):
    """Transient local as in DDS: the last message waits for latched subscribers."""
    got: dict[str, list] = {"latched": [], "volatile": []}
    pub = rt.bus.publisher("/map_name", String, "latched")
    pub.publish(String(data="first"))
    pub.publish(String(data="house"))

    def body():
        subs = [
            rt.bus.subscribe("/map_name", String, got["latched"].append, "latched"),
            rt.bus.subscribe("/map_name", String, got["volatile"].append, 10),
        ]
        rt.sleep(0.1)
        pub.publish(String(data="flat"))
        rt.sleep(0.1)
        for s in subs:
            s.close()

    run_in_actor(rt, body)
    assert [m.data for m in got["latched"]] == ["house", "flat"]
    assert [m.data for m in got["volatile"]] == ["flat"]


def test_a_volatile_topic_keeps_nothing(rt):
    got: list = []
    rt.bus.publisher("/chatter", String).publish(String(data="lost"))

    def body():
        sub = rt.bus.subscribe("/chatter", String, got.append, "latched")
        rt.sleep(0.1)
        sub.close()

    run_in_actor(rt, body)
    assert got == []
