"""A minimal Foxglove WebSocket client for the tests (standard library only: no websocket
package is installed, and the tests need only a few frames).

It speaks RFC 6455 with the ``foxglove.sdk.v1`` subprotocol: JSON control messages in
text frames (``serverInfo``, ``advertise``; ``subscribe``/``unsubscribe`` sent masked,
as a client must) and the binary frames the server sends (opcode byte 1: message data
``subscription id u32, log time u64, payload``; 2: the server's time ``u64``).
"""

from __future__ import annotations

import base64
import json
import os
import socket
import struct
import time
from typing import Any

PROTOCOL = "foxglove.sdk.v1"


class FoxgloveClient:
    def __init__(self, port: int, host: str = "127.0.0.1", timeout: float = 10.0) -> None:
        self.sock = socket.create_connection((host, port), timeout=timeout)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall(
            (
                f"GET / HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
                f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                f"Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: {PROTOCOL}\r\n\r\n"
            ).encode()
        )
        head = b""
        while b"\r\n\r\n" not in head:
            head += self._read(1)
        self.response = head.decode()
        self.channels: dict[str, dict] = {}  # topic -> advertised channel
        self.server_info: dict | None = None

    def close(self) -> None:
        self.sock.close()

    def _read(self, n: int) -> bytes:
        buf = b""
        while len(buf) < n:
            chunk = self.sock.recv(n - len(buf))
            if not chunk:
                raise EOFError("the server closed the connection")
            buf += chunk
        return buf

    def recv(self) -> Any:
        """The next text (as JSON) or binary frame (bytes); control frames are skipped."""
        while True:
            b0, b1 = self._read(2)
            n = b1 & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._read(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._read(8))[0]
            data = self._read(n)
            op = b0 & 0x0F
            if op == 1:
                msg = json.loads(data)
                if msg.get("op") == "serverInfo":
                    self.server_info = msg
                elif msg.get("op") == "advertise":
                    self.channels.update({c["topic"]: c for c in msg["channels"]})
                return msg
            if op == 2:
                return data

    def send(self, obj: dict) -> None:
        data = json.dumps(obj).encode()
        mask = os.urandom(4)
        n = len(data)
        head = bytes([0x81]) + (bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + struct.pack(">H", n))
        self.sock.sendall(head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(data)))

    def wait_for_channels(self, topics: set[str], timeout: float = 10.0) -> None:
        end = time.monotonic() + timeout
        while not topics <= set(self.channels):
            if time.monotonic() > end:
                raise TimeoutError(f"channels not advertised: {sorted(topics - set(self.channels))}")
            self.recv()

    def subscribe(self, sub_id: int, topic: str) -> None:
        self.send({"op": "subscribe", "subscriptions": [{"id": sub_id, "channelId": self.channels[topic]["id"]}]})

    def unsubscribe(self, sub_id: int) -> None:
        self.send({"op": "unsubscribe", "subscriptionIds": [sub_id]})

    def message(self, sub_id: int, timeout: float = 10.0) -> tuple[int, bytes]:
        """The next message data of subscription ``sub_id``: (log time [ns], payload)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            frame = self.recv()
            if isinstance(frame, bytes) and frame[0] == 1:
                sub, log_time = struct.unpack_from("<IQ", frame, 1)
                if sub == sub_id:
                    return log_time, frame[13:]
        raise TimeoutError(f"no message on subscription {sub_id}")
