"""Tolerant loading of a trees folder: what loads is registered, what does not (and
every tree that calls it) is skipped with its located reason; strict loading stays
all or nothing."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from bt_engine import ActorError, Runtime
from bt_engine.trees import (
    DuplicateTreeError,
    MissionError,
    SubtreeCycleError,
    TreeHost,
    TreeLibrary,
    UnresolvedActorError,
    register_tree_folder,
)
from bt_engine.trees._library import BrokenDependencyError, SkippedTreeError


def write(folder: Path, **files: str) -> Path:
    for name, body in files.items():
        (folder / f"{name}.yaml").write_text(textwrap.dedent(body).lstrip())
    return folder


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    return write(
        tmp_path,
        good="""
            name: good
            root: {do: sleep, with: {seconds: 1}}
        """,
        broken="""
            name: broken
            root:
              sequence:
                - do: nope
        """,
        caller="""
            name: caller
            root: {do: broken}
        """,
        grand="""
            name: grand
            root: {sequence: [{do: good}, {do: caller}]}
        """,
        uses_good="""
            name: uses_good
            outputs: [r]
            root: {do: good, out: r}
        """,
    )


def test_tolerant_loading_registers_what_is_valid(rt: Runtime, folder: Path) -> None:
    host = register_tree_folder(rt, folder, strict=False)
    assert sorted(host.library.names) == ["good", "uses_good"]
    assert rt.call("uses_good") == {"r": {}}
    assert sorted(host.library.broken) == ["broken", "caller", "grand"]
    error = host.library.broken["broken"]
    assert isinstance(error, UnresolvedActorError)
    assert str(error).startswith(f"{folder / 'broken.yaml'}:4:11: unknown actor 'nope'")


def test_trees_calling_a_broken_tree_are_skipped_and_say_which(rt: Runtime, folder: Path) -> None:
    host = register_tree_folder(rt, folder, strict=False)
    root = host.library.broken["broken"]
    caller = host.library.broken["caller"]
    assert isinstance(caller, BrokenDependencyError)
    assert caller.chain == ["broken"] and caller.root is root
    assert str(caller) == f"{folder / 'caller.yaml'}:2:12: calls tree 'broken', which does not load: {root}"
    grand = host.library.broken["grand"]
    assert grand.chain == ["caller", "broken"] and grand.root is root
    assert grand.pos.line == 2 and "calls tree 'caller', which calls 'broken', which does not load" in str(grand)


def test_calling_a_skipped_tree_gives_the_reason(rt: Runtime, folder: Path) -> None:
    host = register_tree_folder(rt, folder, strict=False)
    with pytest.raises(ActorError) as info:
        rt.call("grand")
    cause = info.value.__cause__
    assert isinstance(cause, SkippedTreeError) and cause.name == "grand"
    assert not str(info.value).startswith("unknown actor")
    assert str(cause).startswith("tree 'grand' was skipped: ")
    assert str(host.library.broken["broken"]) in str(cause)
    assert not rt.resolve("grand").is_tree
    # by name in the library too (what `actorbt run NAME` asks)
    assert "grand" in host.library
    with pytest.raises(SkippedTreeError, match="tree 'broken' was skipped: .*unknown actor 'nope'"):
        host.library["broken"]
    with pytest.raises(SkippedTreeError):
        host.run("caller")
    with pytest.raises(KeyError):
        host.library["no_such_tree"]


def test_strict_loading_is_all_or_nothing(rt: Runtime, folder: Path) -> None:
    with pytest.raises(UnresolvedActorError, match="unknown actor 'nope'"):
        register_tree_folder(rt, folder)
    assert not rt.check_actor("good")
    lib = TreeLibrary(rt.root.resolve)
    lib.load_folder(folder)
    with pytest.raises(MissionError):
        lib.check()
    assert lib.broken == {}


def test_a_file_that_does_not_parse_is_skipped_under_its_declared_name(rt: Runtime, tmp_path: Path) -> None:
    (tmp_path / "syn.yaml").write_text("name: syn\nroot: {do: [\n")
    (tmp_path / "anon.yaml").write_text("root: [\n")
    write(
        tmp_path,
        user="""
        name: user
        root: {do: syn}
    """,
        fine="""
        name: fine
        root: {wait: 1}
    """,
    )
    host = TreeHost(rt)
    assert [m.name for m in host.load_folder(tmp_path, strict=False)] == ["fine"]
    broken = host.library.broken
    assert set(broken) == {"syn", str(tmp_path / "anon.yaml"), "user"}
    assert str(broken["syn"]).startswith(f"{tmp_path / 'syn.yaml'}:3:1: YAML syntax error")
    assert isinstance(broken["user"], BrokenDependencyError)  # not "unknown actor 'syn'"
    assert str(tmp_path / "anon.yaml") not in host.library  # a file is not a tree name
    with pytest.raises(ActorError, match="tree 'syn' was skipped"):
        rt.call("syn")


def test_two_files_with_one_name_skip_that_name(rt: Runtime, tmp_path: Path) -> None:
    write(
        tmp_path,
        a="name: same\nroot: {wait: 1}\n",
        b="name: same\nroot: {wait: 2}\n",
        c="name: other\nroot: {wait: 1}\n",
    )
    host = register_tree_folder(rt, tmp_path, strict=False)
    assert host.library.names == ["other"]
    assert isinstance(host.library.broken["same"], DuplicateTreeError)
    with pytest.raises(ActorError, match="already used by"):
        rt.call("same")


def test_a_tree_named_like_an_actor_is_skipped_but_the_actor_stays(rt: Runtime, tmp_path: Path) -> None:
    write(tmp_path, sleep="name: sleep\nroot: {wait: 1}\n", nap="name: nap\nroot: {do: sleep, with: {seconds: 2}}\n")
    host = register_tree_folder(rt, tmp_path, strict=False)
    assert host.library.names == ["nap"]
    assert list(host.library.broken) == [str(tmp_path / "sleep.yaml")]
    assert "already the actor sleep" in str(host.library.broken[str(tmp_path / "sleep.yaml")])
    assert not rt.resolve("sleep").is_tree
    rt.call("nap")
    assert rt.now() == pytest.approx(2.0)


def test_trees_in_a_cycle_are_skipped(rt: Runtime, tmp_path: Path) -> None:
    write(tmp_path, a="name: ta\nroot: {do: tb}\n", b="name: tb\nroot: {do: ta}\n", c="name: tc\nroot: {wait: 1}\n")
    host = register_tree_folder(rt, tmp_path, strict=False)
    assert host.library.names == ["tc"]
    assert all(isinstance(host.library.broken[n], (SubtreeCycleError, BrokenDependencyError)) for n in ("ta", "tb"))


def test_a_tree_loaded_later_that_calls_a_skipped_tree_gives_the_reason(
    rt: Runtime, folder: Path, tmp_path_factory
) -> None:
    host = register_tree_folder(rt, folder, strict=False)
    extra = write(tmp_path_factory.mktemp("extra"), late="name: late\nroot: {do: broken}\n")
    with pytest.raises(MissionError, match="tree 'broken' was skipped"):
        host.load_file(extra / "late.yaml")
