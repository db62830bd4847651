"""The ``actorbt`` command line.

    main         the parser, the core and tree commands, ``main()``
    config       actorbt.yaml: Config, find_config, load_config
    actor_index  the actors of the configured subsystems, without a runtime
    app          App: the runtime a command builds from actorbt.yaml and its options
    shell        ``actorbt shell``
    topic        ``actorbt topic list | echo | hz``
    action       ``actorbt action list``

Other packages (``demo``, ``mcp``) use the names exported here. Each is imported on first
use (PEP 562), so declaring the commands stays quick.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .app import App
    from .config import Config, ConfigError, find_config, load_config

__all__ = ["App", "Config", "ConfigError", "find_config", "load_config"]

#: name -> the module that defines it
_HOMES = {"App": "app", "Config": "config", "ConfigError": "config", "find_config": "config", "load_config": "config"}


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{home}"), name)
