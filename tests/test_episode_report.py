"""What an episode reports (demo/episode.py, demo/first_failure.py): the first step that
went wrong, not only where the tree gave up, and where its object ended, not where it
started."""

from __future__ import annotations

import io
import math

import pybullet as p
import pytest

from bt_engine import SubSystem, actor
from bt_engine.errors import ActorError
from bt_engine.trees import register_tree_folder, tree_host
from demo.episode import Episode, _end_state, print_outcome
from demo.first_failure import FirstFailure
from sim import SimWorld


class Steps(SubSystem):
    @actor
    def grasp(self) -> None:
        """A grasp that misses."""
        raise RuntimeError("fingers closed at 0 mm")

    @actor
    def search(self) -> None:
        """A search that finds nothing."""
        raise LookupError("visited 8 search locations and saw nothing")

    @actor
    def fine(self) -> None:
        """Succeeds."""

    @actor
    def watch(self) -> dict:
        """Sees a cup."""
        return {"category": "cup", "x": 1.0, "y": 2.0}


TREE = """name: fetch_test
root:
  sequence:
    - fallback:
        - do: steps.grasp
        - do: steps.fine
    - name: look again
      do: steps.search
"""


def test_the_first_step_that_went_wrong_is_kept_beside_where_the_tree_gave_up(rt, tmp_path):
    rt.add_subsystem("steps", Steps)
    (tmp_path / "fetch_test.yaml").write_text(TREE)
    register_tree_folder(rt, tmp_path)
    first = FirstFailure()
    tree_host(rt).observers.append(first)
    with pytest.raises(ActorError, match="look again"):
        rt.call("fetch_test")
    assert first.node == "fetch_test:sequence/selector/steps.grasp"
    assert first.reason == "steps.grasp: RuntimeError: fingers closed at 0 mm"


def test_the_printout_names_both_and_the_end_state():
    ep = Episode(
        "bt_pick_place",
        "house",
        2,
        "cup",
        tree_status="FAILURE",
        failed_node="bt_catch:catch/attempts/attempt/grasp",
        reason="pick: GraspError: cup grasp missed: fingers closed at 0 mm",
        tree_failure="tree bt_pick_place failed at pick_place/fetch/attempt/search: SearchExhausted",
        target="cup_1",
        pose="upright",
        support="floor",
        end_pose="lying",
        end_support="the floor",
    )
    out = io.StringIO()
    print_outcome(ep, out)
    text = out.getvalue()
    assert text.startswith("FAILURE at bt_catch:catch/attempts/attempt/grasp: pick: GraspError: cup grasp missed")
    assert "  then the tree gave up: tree bt_pick_place failed at pick_place/fetch/attempt/search" in text
    assert "the last pick went for cup_1: it stood upright on the floor, it ended lying on the floor" in text


def test_the_end_state_is_read_from_the_world():
    sim = SimWorld(None, "house", seed=0, camera=False)
    try:
        name = next(n for n in sim.object_names() if sim.object_category(n) == "can")
        sim.set_object_pose(name, 2.0, 2.0)
        sim.advance(0.5)
        assert _end_state(sim, name) == ("upright", "the floor")
        pl = sim.place_location
        sim.set_object_pose(name, pl.x, pl.y, z=pl.sz + 0.062)
        sim.advance(0.5)
        assert _end_state(sim, name) == ("upright", "the place location")
        body = sim.scene.objects[name]
        p.resetBasePositionAndOrientation(
            body, [2.0, 2.0, 0.034], p.getQuaternionFromEuler([math.pi / 2, 0, 0]), physicsClientId=sim.cid
        )
        sim.advance(0.5)
        assert _end_state(sim, name) == ("lying", "the floor")
    finally:
        sim.close()


def test_a_long_step_is_told_every_heartbeat(rt, tmp_path, monkeypatch):
    """The demo is not silent through a long step: the running node is told."""
    from demo.episode import DemoProgress

    (tmp_path / "patrol_test.yaml").write_text(
        "name: patrol_test\nroot:\n  sequence:\n    - name: long drive\n      wait: 5\n"
    )
    register_tree_folder(rt, tmp_path)
    monkeypatch.setattr(DemoProgress, "HEARTBEAT", 0.0)
    out = io.StringIO()
    tree_host(rt).observers.append(DemoProgress(out, rt))
    rt.call("patrol_test")
    assert "  ... patrol_test: sequence/long drive" in out.getvalue()


def test_the_evaluation_tells_what_its_running_episodes_do(tmp_path, monkeypatch):
    import time as _time
    from demo.evaluate import PROGRESS_LOG, Progress

    monkeypatch.setattr(Progress, "HEARTBEAT", 0.2)
    folder = tmp_path / "can_seed3"
    folder.mkdir()
    (folder / PROGRESS_LOG).write_text(
        "[   12.0s] bt_search: search/patrol\n[   80.0s]   ... bt_catch: catch/attempts/attempt\n"
    )
    out = io.StringIO()
    bar = Progress(out, 2)
    bar.start(2, "", [])
    jobs = [("bt_pick_place", "house", seed, "can", tmp_path / f"can_seed{seed}") for seed in (3, 4)]
    bar.watch(jobs, [])
    _time.sleep(1.5)
    bar.end()
    assert "[0/2] 0 succeeded, " in out.getvalue()
    assert "running: seed 3 can: [   80.0s]   ... bt_catch: catch/attempts/attempt\n" in out.getvalue()


def test_what_the_robot_saw_is_kept_for_the_top_view_also_when_the_run_fails(rt, tmp_path):
    from demo.episode import Sightings

    rt.add_subsystem("steps", Steps)
    (tmp_path / "saw_test.yaml").write_text(
        "name: saw_test\nroot:\n  sequence:\n    - do: watch\n    - do: steps.search\n"
    )
    register_tree_folder(rt, tmp_path)
    seen: list = []
    tree_host(rt).observers.append(Sightings(seen))
    with pytest.raises(ActorError):
        rt.call("saw_test")
    assert seen == [{"category": "cup", "x": 1.0, "y": 2.0}]


def test_an_object_on_a_turned_pallet_is_on_it_only_within_its_turned_outline():
    from demo.episode import _on_surface
    from sim.world_spec import Box

    pallet = Box("pallet", 2.0, 1.0, 0.6, 0.4, 0.12, math.radians(90))  # long side along y
    assert _on_surface((2.0, 1.25, 0.2), pallet)  # inside: 0.25 m along its long side
    assert not _on_surface((2.25, 1.0, 0.2), pallet)  # inside were it not turned
    assert not _on_surface((2.0, 1.25, 0.05), pallet)  # beside it on the floor
