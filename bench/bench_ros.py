"""ROS 2 benchmarks (issue [ros]): real rclpy over Fast DDS, on this machine only.

    .venv/bin/python bench/bench_ros.py

- goal -> result latency of a trivial tree (``/actorbt/tree/trivial``), client and server
  in one process, and across two processes after discovery (targets <= 5 ms, <= 15 ms);
- the same from a plain rclpy ActionClient in a third process (target <= 5 ms), beside
  the floor: that client against a plain rclpy ActionServer that succeeds at once, with
  the same feedback and result retention;
- cancel latency: from the cancel request to (a) every transaction of the goal cancelled
  in the server and (b) the client holding the CANCELED result (target <= 50 ms);
- topic throughput: 320x240 rgb8 Images from another process through a subscriber
  stream actor (sensor QoS), in frames/s, and the latency the actor path adds over a
  plain rclpy callback in the same process.

All figures are medians. A private ROS domain keeps other processes out.
"""

from __future__ import annotations

import json
import os
import pathlib
import random
import statistics
import subprocess
import sys
import tempfile
import textwrap
import threading
import time

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(120, 200)))

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bt_engine import Kind, Runtime  # noqa: E402
from bt_engine.bus.qos import qos_depth  # noqa: E402
from bt_ros.host import RosHost  # noqa: E402
from bt_ros.qos import qos_profile  # noqa: E402
from bt_ros.remote import Remote  # noqa: E402
from bt_ros.server import serve  # noqa: E402
from bt_ros.transport import RosTransport  # noqa: E402

GOALS = 200
CANCELS = 20
IMAGE_SECONDS = 3.0

TREES = {
    "trivial.yaml": """\
        name: trivial
        doc: Does nothing but set its output.
        inputs: {x: {type: int, default: 0}}
        outputs: [y]
        root:
          sequence:
            - set: {y: 1}
        """,
    "hold.yaml": """\
        name: hold
        doc: Sleeps (an actor transaction) until cancelled.
        root:
          sequence:
            - name: holding
              do: sleep
              with: {seconds: 1000}
        """,
}


def write_trees(folder: pathlib.Path) -> pathlib.Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in TREES.items():
        (folder / name).write_text(textwrap.dedent(text))
    return folder


def ms(seconds: float) -> str:
    return f"{seconds * 1e3:7.2f} ms"


def verdict(value: float, target: float) -> str:
    return "ok" if value <= target else f"OVER the {target * 1e3:g} ms target"


def goal_latencies(remote: Remote, n: int) -> list[float]:
    out = []
    for i in range(n):
        t0 = time.perf_counter()
        g = remote.tree_goal("trivial", {"x": i})
        g.done.wait(10.0)
        out.append(time.perf_counter() - t0)
        assert g.status == "succeeded", (g.status, g.error)
    return out


def call_latencies(remote: Remote, n: int) -> list[float]:
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        remote.call("sleep", 0)
        out.append(time.perf_counter() - t0)
    return out


def cancel_latencies(remote: Remote, rt: Runtime | None, n: int) -> tuple[list[float], list[float]]:
    """(to every transaction cancelled in the server, to the CANCELED result at the client)"""
    server_side, client_side = [], []
    for _ in range(n):
        started = threading.Event()
        g = remote.tree_goal("hold", on_feedback=lambda fb: "holding" in fb.active_node and started.set())
        assert started.wait(10.0), g.status
        t0 = time.perf_counter()
        g.cancel()
        if rt is not None:
            while rt.transactions():
                time.sleep(0.0002)
            server_side.append(time.perf_counter() - t0)
        g.done.wait(10.0)
        client_side.append(time.perf_counter() - t0)
        assert g.status == "canceled", g.status
    return server_side, client_side


def bench_in_process(tmp: pathlib.Path) -> None:
    print("\n-- one process: server runtime + client (two rclpy contexts) --")
    rt = Runtime(clock="wall", bus=RosTransport)
    from bt_engine.trees import register_tree_folder

    register_tree_folder(rt, write_trees(tmp / "trees"))
    server = serve(rt)
    remote = Remote()
    try:
        goal_latencies(remote, 20)  # warm-up, discovery
        lat = statistics.median(goal_latencies(remote, GOALS))
        print(f"goal -> result, trivial tree      {ms(lat)}   ({GOALS} goals; {verdict(lat, 0.005)})")
        call = statistics.median(call_latencies(remote, GOALS))
        print(f"/actorbt/call sleep(0) round trip {ms(call)}")
        sustained = goal_latencies(remote, 3 * GOALS)
        print(
            f"goal -> result, sustained         {ms(statistics.median(sustained[-GOALS:]))}"
            f"   (back to back for {sum(sustained):.1f} s: every kept result is in each"
            " status message)"
        )
        srv, cli = cancel_latencies(remote, rt, CANCELS)
        s, c = statistics.median(srv), statistics.median(cli)
        print(f"cancel -> all transactions ended  {ms(s)}   ({CANCELS} cancels; {verdict(s, 0.05)})")
        print(f"cancel -> CANCELED at the client  {ms(c)}   ({verdict(c, 0.05)})")
    finally:
        remote.close()
        server.close()
        rt.close()


# A plain rclpy client, as a robot's own code would write it: send the goal, wait for the
# acceptance, ask for the result, wait for it. It spins with spin_once: rclpy 7.1's
# spin_until_future_complete adds a wake-up callback to the future on every turn, they
# pile up over hundreds of goals and the client ends up spinning flat out (the "tutorial"
# line shows what that costs).
PLAIN_CLIENT = """
import json, sys, time
import rclpy
from rclpy.action import ActionClient
from rclpy.executors import SingleThreadedExecutor
from actorbt_interfaces.action import RunTree
name, goals, warm, way = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
rclpy.init(args=[])
node = rclpy.create_node("bench_plain_client")
client = ActionClient(node, RunTree, name)
ex = SingleThreadedExecutor()
ex.add_node(node)
assert client.wait_for_server(timeout_sec=15.0), "no server"

def wait(fut):
    if way == "tutorial":
        ex.spin_until_future_complete(fut, 10.0)
    end = time.monotonic() + 10.0
    while not fut.done() and time.monotonic() < end:
        ex.spin_once(timeout_sec=1.0)
    return fut.result()

def one(i):
    t0 = time.perf_counter()
    handle = wait(client.send_goal_async(RunTree.Goal(inputs_yaml=f"{{x: {i}}}")))
    assert handle is not None and handle.accepted
    res = wait(handle.get_result_async())
    assert res is not None and res.result.success, res
    return time.perf_counter() - t0
for i in range(warm):
    one(i)
print(json.dumps([one(i) for i in range(goals)]), flush=True)
"""

# The floor: a plain rclpy server of the same action, succeeding at once, with the two
# feedback messages and the result retention of ``actorbt serve``.
FLOOR_SERVER = """
import sys
import rclpy
from rclpy.action import ActionServer
from rclpy.executors import SingleThreadedExecutor
from actorbt_interfaces.action import RunTree
from bt_ros.server import RESULT_TIMEOUT
rclpy.init(args=[])
node = rclpy.create_node("bench_floor_server")

def execute(handle):
    handle.publish_feedback(RunTree.Feedback(status="running", active_node="trivial"))
    handle.publish_feedback(RunTree.Feedback(status="success", active_node="trivial"))
    handle.succeed()
    return RunTree.Result(success=True, status="succeeded", outputs_yaml="y: 1\\n")
ActionServer(node, RunTree, sys.argv[1], execute, result_timeout=RESULT_TIMEOUT)
ex = SingleThreadedExecutor()
ex.add_node(node)
print("ready", flush=True)
ex.spin()
"""


def plain_client_latency(action: str, way: str = "spin_once") -> float:
    """Median goal -> result latency [s] of a plain rclpy client in its own process."""
    out = subprocess.run(
        [sys.executable, "-c", PLAIN_CLIENT, action, str(GOALS), "30", way],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    if out.returncode != 0:
        raise RuntimeError(f"plain client failed: {out.stderr[-2000:]}")
    return statistics.median(json.loads(out.stdout.strip().splitlines()[-1]))


def drain(stream) -> None:
    """Read a server's output to its end, so it never blocks on a full pipe."""
    threading.Thread(target=lambda: stream.read(), daemon=True).start()


def bench_floor() -> None:
    print("\n-- the floor: a plain rclpy server that succeeds at once + the plain client --")
    action = "/bench/floor/trivial"
    proc = subprocess.Popen(
        [sys.executable, "-c", FLOOR_SERVER, action],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        for line in proc.stdout:
            if "ready" in line:
                break
        drain(proc.stdout)
        lat = plain_client_latency(action)
        print(f"goal -> result, plain rclpy client {ms(lat)}   ({GOALS} goals, another process)")
    finally:
        proc.terminate()
        proc.wait(15)


def bench_two_processes(tmp: pathlib.Path) -> None:
    print("\n-- two processes: `actorbt serve` on the ROS bus + client --")
    cfg = tmp / "actorbt.yaml"
    cfg.write_text(f"trees: {write_trees(tmp / 'trees2')}\nworld: null\ntransport: ros\nclock: wall\n")
    proc = subprocess.Popen(
        [sys.executable, "-m", "bt_cli.main", "--config", str(cfg), "serve", "--no-record"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        for line in proc.stdout:
            if "ready" in line:
                break
        drain(proc.stdout)  # a line per goal
        from actorbt_interfaces.action import RunTree

        remote = Remote()
        try:
            t0 = time.perf_counter()
            assert remote.wait_for(RunTree, "/actorbt/tree/trivial", 15.0), "no server"
            print(f"discovery of the server           {ms(time.perf_counter() - t0)}")
            goal_latencies(remote, 20)
            lat = statistics.median(goal_latencies(remote, GOALS))
            print(f"goal -> result, trivial tree      {ms(lat)}   ({GOALS} goals; {verdict(lat, 0.015)})")
            call = statistics.median(call_latencies(remote, GOALS))
            print(f"/actorbt/call sleep(0) round trip {ms(call)}")
            _, cli = cancel_latencies(remote, None, CANCELS)
            c = statistics.median(cli)
            print(f"cancel -> CANCELED at the client  {ms(c)}   ({CANCELS} cancels; {verdict(c, 0.05)})")
        finally:
            remote.close()
        lat = plain_client_latency("/actorbt/tree/trivial")
        print(
            f"goal -> result, plain rclpy client {ms(lat)}   ({GOALS} goals from a third process;"
            f" {verdict(lat, 0.005)})"
        )
        lat = plain_client_latency("/actorbt/tree/trivial", "tutorial")
        print(f"  the same, spin_until_future_complete {ms(lat)}   (rclpy 7.1: the client spins flat out)")
    finally:
        proc.send_signal(2)
        proc.wait(15)


PUBLISHER = """
import sys, time, os
from rclpy.context import Context
import rclpy
from sensor_msgs.msg import Image
from bt_ros.qos import qos_profile
rate, seconds, readers = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
ctx = Context(); ctx.init(args=[])
node = rclpy.create_node("bench_image_pub", context=ctx)
pub = node.create_publisher(Image, "/bench/image", qos_profile("sensor"))
img = Image(height=240, width=320, encoding="rgb8", step=960)
img.data = bytes(320 * 240 * 3)
end = time.monotonic() + 15
while pub.get_subscription_count() < readers and time.monotonic() < end:
    time.sleep(0.01)
time.sleep(0.3)
n, t0 = 0, time.monotonic()
while time.monotonic() - t0 < seconds:
    ns = time.time_ns()
    img.header.stamp.sec, img.header.stamp.nanosec = ns // 10**9, ns % 10**9
    pub.publish(img)
    n += 1
    if rate > 0:
        time.sleep(max(0.0, t0 + n / rate - time.monotonic()))
elapsed = time.monotonic() - t0
img.header.frame_id = "end"
for _ in range(20):
    pub.publish(img)
    time.sleep(0.01)
print(n, elapsed, flush=True)
node.destroy_node(); ctx.shutdown()
"""


def bench_images(rate: float) -> None:
    """Frames from another process: a stream actor and a plain rclpy callback."""
    from sensor_msgs.msg import Image

    rt = Runtime(clock="wall", bus=RosTransport)
    raw_host = RosHost("bench-raw")
    raw_lat: list[float] = []

    def raw_cb(msg):
        if msg.header.frame_id != "end":
            raw_lat.append(time.time_ns() - (msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec))

    node = raw_host.create_node("bench_raw_sub")
    raw_host.call(node.create_subscription, Image, "/bench/image", raw_cb, qos_profile("sensor"))
    bus = rt.bus

    def frames(emit):
        return bus.subscribe("/bench/image", Image, emit, "sensor").close

    rt.run_on_hub(rt.root.add_actor, "frames", frames, Kind.STREAM, buffer=qos_depth("sensor"))

    def consume() -> tuple[list[float], float]:
        lat, first, last = [], None, None
        with rt.run_actor_mode("frames", "timed_iterator", IMAGE_SECONDS + 20.0) as it:
            for msg in it:
                if msg.header.frame_id == "end":
                    break
                now = time.time_ns()
                first = first or time.perf_counter()
                last = time.perf_counter()
                lat.append(now - (msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec))
        return lat, (last - first) if first and last else 0.0

    rt.run_on_hub(rt.root.add_actor, "consume", consume)
    pub = subprocess.Popen(
        [sys.executable, "-c", PUBLISHER, str(rate), str(IMAGE_SECONDS), "2"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        lat, span = rt.call("consume")
        out, _ = pub.communicate(timeout=30)
    finally:
        if pub.poll() is None:
            pub.kill()
        raw_host.close()
        rt.close()
    sent, seconds = out.split()
    sent_fps = int(sent) / float(seconds)
    got_fps = len(lat) / span if span else 0.0
    actor_ms = statistics.median(lat) / 1e6
    raw_ms = statistics.median(raw_lat) / 1e6 if raw_lat else float("nan")
    label = f"{rate:g} Hz" if rate > 0 else "max rate"
    print(
        f"{label:>8}: published {sent_fps:6.1f} fps, stream actor {got_fps:6.1f} fps "
        f"({len(lat)} frames), rclpy callback {len(raw_lat) / max(span, 1e-9):6.1f} fps; "
        f"latency actor {actor_ms:6.2f} ms, rclpy {raw_ms:6.2f} ms, added {actor_ms - raw_ms:+.2f} ms"
    )


def main() -> int:
    print(
        f"ROS_DOMAIN_ID={os.environ['ROS_DOMAIN_ID']} "
        f"ROS_AUTOMATIC_DISCOVERY_RANGE={os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE']}"
    )
    with tempfile.TemporaryDirectory() as d:
        tmp = pathlib.Path(d)
        bench_in_process(tmp)
        bench_two_processes(tmp)
    bench_floor()
    print("\n-- 320x240 rgb8 images from another process, sensor QoS (best effort, depth 5) --")
    bench_images(30.0)
    bench_images(0.0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
