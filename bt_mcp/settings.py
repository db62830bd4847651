"""What an ``actorbt mcp`` server allows: read from actorbt.yaml's ``mcp:`` section and
the command line (the command line wins).

    mcp:
      allow_motion: false   # default: actors that move the robot are refused
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from bt_cli import ConfigError

__all__ = ["McpSettings", "MOTION_HOW_TO"]

#: how a user allows motion, quoted in every refusal and in the tool descriptions
MOTION_HOW_TO = "start the server with `actorbt mcp --allow-motion`, or set `mcp: {allow_motion: true}` in actorbt.yaml"

_KEYS = {"allow_motion"}


@dataclass(frozen=True)
class McpSettings:
    """Attributes:
    allow_motion: run actors and trees that move the robot (off by default: a
        language model should not drive a robot nobody is watching).
    """

    allow_motion: bool = False

    @classmethod
    def of(cls, section: Mapping[str, Any] | None, allow_motion: bool | None = None) -> "McpSettings":
        """From the ``mcp:`` mapping; ``allow_motion`` (``--allow-motion``) overrides it."""
        section = dict(section or {})
        unknown = set(section) - _KEYS
        if unknown:
            raise ConfigError(f"actorbt.yaml: mcp: unknown settings {sorted(unknown)}; expected {sorted(_KEYS)}")
        value = section.get("allow_motion", False)
        if not isinstance(value, bool):
            raise ConfigError(f"actorbt.yaml: mcp: allow_motion must be true or false, not {value!r}")
        return cls(allow_motion=value if allow_motion is None else allow_motion)
