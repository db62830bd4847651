"""The protocol's stdout, kept apart from everything else the process prints.

The simulator's C libraries write to C's stdout (pybullet's EGL loader prints "Loaded
EGL ..." when the world starts, buffered until the process exits), and any such line on
the wire is a broken JSON-RPC message for the client. The SDK diverts fd 1 only
while it serves, so the command holds the wire for its whole life instead: from before
the world starts until after it has closed, fd 1 points at stderr and only the protocol
writes to a private duplicate of the original stdout. C's own stdout buffer is flushed
before fd 1 is given back.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
from typing import BinaryIO, Iterator

__all__ = ["held_wire"]


@contextlib.contextmanager
def held_wire() -> Iterator[BinaryIO]:
    """Yield the original stdout as a binary file; meanwhile fd 1 (and ``sys.stdout``)
    go to stderr. Both are restored on exit."""
    sys.stdout.flush()
    wire_fd = os.dup(1)
    saved_stdout = sys.stdout
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    # closefd=False: the text layer the server wraps around it may close this file
    wire = os.fdopen(wire_fd, "wb", buffering=0, closefd=False)
    try:
        yield wire
    finally:
        sys.stdout = saved_stdout
        _flush_c_stdio()  # what C code buffered meanwhile belongs on stderr, not the wire
        os.dup2(wire_fd, 1)
        os.close(wire_fd)


def _flush_c_stdio() -> None:
    """fflush(NULL): C's stdout is block-buffered on a pipe, and a buffer flushed at exit
    would land on whatever fd 1 is then."""
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):  # no C library to ask: nothing of it is buffered
        pass
