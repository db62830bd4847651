"""pybullet without its build banner: importing it prints "pybullet build time: ..." from
C to the process's stderr, a line a user would see before every command's own output.
Import ``pybullet`` from here (``from common.quiet_pybullet import pybullet``)."""

from __future__ import annotations

import ctypes
import os
import sys


def _import_quietly():
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr to keep clean
        import pybullet

        return pybullet
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
            import pybullet

            ctypes.CDLL(None).fflush(None)  # C's buffers, while they still go nowhere
    finally:
        os.dup2(saved, 2)
        os.close(saved)
    return pybullet


pybullet = _import_quietly()
