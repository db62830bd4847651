"""The hub watchdog names the actor that blocked the hub and where."""

from __future__ import annotations

import logging
import time

from bt_engine import Runtime, SubSystem, actor


class Careless(SubSystem):
    @actor
    def naps(self) -> str:
        time.sleep(0.3)  # blocks the hub: the watchdog should say so
        return "woke"


def test_blocking_call_is_reported_with_actor_and_line(caplog):
    with caplog.at_level(logging.WARNING, logger="actorbt.watchdog"):
        with Runtime(watchdog=0.1) as rt:
            rt.add_subsystem("c", Careless)
            assert rt.call("naps") == "woke"
            warnings = list(rt._watchdog.warnings)
    assert len(warnings) == 1
    assert "actor c.naps" in warnings[0]
    assert "test_watchdog.py" in warnings[0] and "time.sleep(0.3)" in warnings[0]
    assert any("hub blocked" in r.getMessage() for r in caplog.records)


def test_well_behaved_actors_raise_no_warning():
    with Runtime(watchdog=0.1) as rt:
        rt.call("sleep", 100)
        assert rt._watchdog.warnings == []
