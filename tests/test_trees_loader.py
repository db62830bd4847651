"""Positive tests of the mission front end: YAML positions, the model, the validator."""

from __future__ import annotations

import inspect
from pathlib import Path

import pytest

from bt_engine import ActorbtError, UnknownActorError
from bt_engine.trees import (
    REQUIRED,
    Check,
    Do,
    DuplicateTreeError,
    InputError,
    MissionError,
    Parallel,
    ParallelPolicy,
    ReactiveSelector,
    ReactiveSequence,
    Ref,
    Repeat,
    Retry,
    Selector,
    Sequence,
    SetValues,
    SubtreeCycleError,
    Timeout,
    TreeLibrary,
    UnresolvedActorError,
    UseBehaviour,
    ValueType,
    Wait,
    check_files,
    load_mission,
    parse_mission,
    validate_mission,
    walk,
)
from bt_engine.trees._errors import ActorbtError as TreesRoot
from bt_engine.trees.testing import demo_resolver

DESIGN_EXAMPLE = """\
name: bt_catch
doc: Approach the found object with its category's strategy and pick it.
inputs:                       # parameters of the tree as an actor and as a ROS goal
  category: {type: str, default: can}
outputs: [grasp]
root:
  sequence:
    - do: watch               # actor call, result stored on the blackboard
      out: found
    - do: navigate
      with: {target: "{found.room}"}
    - retry:
        times: 3
        child:
          sequence:
            - do: open_gripper
            - do: pick
              with: {target: "{found}", category: "{category}"}
              out: grasp
    - timeout: {seconds: 20, child: {do: sleep, with: {seconds: 1}}}
"""


def test_errors_derive_from_the_engine_root() -> None:
    assert TreesRoot is ActorbtError
    assert issubclass(MissionError, ActorbtError)


def test_design_example_parses_with_positions() -> None:
    m = parse_mission(DESIGN_EXAMPLE, "bt_catch.yaml")
    assert m.name == "bt_catch"
    assert m.doc.startswith("Approach")
    assert [(i.name, i.type, i.default) for i in m.inputs] == [("category", ValueType.STR, "can")]
    assert [o.name for o in m.outputs] == ["grasp"]
    assert isinstance(m.root, Sequence)
    watch, navigate, retry, timeout = m.root.children
    assert isinstance(watch, Do) and watch.actor == "watch" and watch.out == "found"
    assert (watch.pos.line, watch.pos.column) == (8, 7)
    assert (watch.at("do").line, watch.at("do").column) == (8, 11)
    target = navigate.kwargs["target"]
    assert isinstance(target, Ref) and target.key == "found" and target.fields == ("room",)
    assert (target.pos.line, target.pos.column) == (11, 24)
    assert isinstance(retry, Retry) and retry.times == 3
    assert isinstance(timeout, Timeout) and timeout.seconds == 20
    assert validate_mission(m, demo_resolver()) == []


def test_every_node_type_parses() -> None:
    m = parse_mission("""
name: all_nodes
inputs:
  n: {type: int, default: 2}
root:
  sequence:
    - reactive_sequence: [{check: "true"}]
    - selector: [{check: "true"}]
    - fallback: [{check: "true"}]
    - reactive_selector: [{check: "true"}]
    - reactive_fallback: [{check: "true"}]
    - parallel: [{wait: 0}]
    - parallel:
        policy: success_on_selected
        selected: [a]
        children: [{name: a, wait: 0}, {name: b, wait: 1}]
    - retry: {times: "{n}", child: {wait: 0}}
    - repeat: {child: {wait: 0}}
    - repeat: {times: forever, child: {wait: 0}}
    - timeout: {seconds: 1.5, child: {wait: 0}}
    - invert: {check: "false"}
    - force_success: {child: {check: "false"}}
    - force_failure: {wait: 0}
    - {name: hello, do: say, with: [hi]}
    - set: {x: 1}
    - check: x == 1
    - wait: "{n}"
    - behaviour: Blinker
      with: {period: "{n}"}
      writes: [blinked]
""", "all.yaml")
    kinds = [type(c).__name__ for c in m.root.children]
    assert kinds == [
        "ReactiveSequence", "Selector", "Selector", "ReactiveSelector", "ReactiveSelector", "Parallel",
        "Parallel", "Retry", "Repeat", "Repeat", "Timeout", "Invert", "ForceSuccess", "ForceFailure",
        "Do", "SetValues", "Check", "Wait", "UseBehaviour",
    ]
    c = m.root.children
    assert c[6].policy is ParallelPolicy.SUCCESS_ON_SELECTED and c[6].selected == ("a",)
    assert c[5].policy is ParallelPolicy.SUCCESS_ON_ALL
    assert isinstance(c[7].times, Ref)
    assert c[8].times is None and c[9].times is None
    assert c[14].name == "hello" and c[14].args == ("hi",) and c[14].label == "hello"
    assert c[18].writes == ("blinked",)
    assert validate_mission(m, demo_resolver(), behaviours={"Blinker"}) == []


def test_references_are_typed_and_escapable() -> None:
    m = parse_mission("""
name: refs
inputs:
  pose: {type: dict, default: {x: 1}}
root:
  set:
    whole: "{pose}"
    nested: {a: ["{pose.x}", 3]}
    literal: "{{pose}}"
    braces: "a {b c} d"
    number: 3
""", "refs.yaml")
    values = m.root.values
    assert isinstance(values["whole"], Ref)
    assert isinstance(values["nested"]["a"][0], Ref) and values["nested"]["a"][0].fields == ("x",)
    assert values["literal"] == "{pose}"
    assert values["braces"] == "a {b c} d"
    assert values["number"] == 3


def test_inputs_shorthand_inference_and_signature() -> None:
    m = parse_mission("""
name: sig
inputs:
  target: str
  speed: {default: 0.5}
  tries: {type: int, default: 3, doc: attempts}
  extra: {type: any}
outputs:
  result: {type: dict, doc: what happened}
root: {set: {result: {}}}
""", "sig.yaml")
    assert [(i.name, i.type) for i in m.inputs] == [
        ("target", ValueType.STR), ("speed", ValueType.FLOAT), ("tries", ValueType.INT), ("extra", ValueType.ANY)]
    assert m.inputs[0].default is REQUIRED and m.inputs[3].required
    assert str(m.signature()) == "(target: str, speed: float = 0.5, tries: int = 3, *, extra) -> dict"
    assert m.bind_inputs("kitchen", extra=None) == {"target": "kitchen", "speed": 0.5, "tries": 3, "extra": None}
    assert m.outputs[0].type is ValueType.DICT and m.outputs[0].doc == "what happened"
    with pytest.raises(InputError, match="input 'tries' is 'x'"):
        m.bind_inputs("kitchen", tries="x", extra=1)
    with pytest.raises(InputError, match="missing a required argument: 'target'"):
        m.bind_inputs(extra=1)


@pytest.mark.parametrize("vtype,text,value", [
    (ValueType.STR, "kitchen", "kitchen"),
    (ValueType.INT, "3", 3),
    (ValueType.FLOAT, "0.25", 0.25),
    (ValueType.BOOL, "yes", True),
    (ValueType.BOOL, "false", False),
    (ValueType.LIST, "[1, a]", [1, "a"]),
    (ValueType.DICT, "{x: 1}", {"x": 1}),
    (ValueType.ANY, "3.5", 3.5),
])
def test_command_line_values_coerce(vtype: ValueType, text: str, value: object) -> None:
    assert vtype.coerce(text) == value


def test_coerce_rejects_bad_text() -> None:
    with pytest.raises(ValueError):
        ValueType.INT.coerce("1.5")
    with pytest.raises(ValueError):
        ValueType.DICT.coerce("[1]")


def test_validator_checks_literal_types_against_annotations() -> None:
    m = parse_mission("name: t\nroot: {do: navigate, with: {target: kitchen, speed: 1}}\n", "t.yaml")
    assert validate_mission(m, demo_resolver()) == []  # int is fine for float
    m = parse_mission("name: t\nroot: {do: navigate, with: {target: 3}}\n", "t.yaml")
    [error] = validate_mission(m, demo_resolver())
    assert "argument 'target' of actor 'navigate' expects a str, got int 3" in str(error)


def test_validator_checks_reference_types_against_annotations() -> None:
    m = parse_mission("""
name: t
inputs: {room: {type: int, default: 1}}
root: {do: navigate, with: {target: "{room}"}}
""", "t.yaml")
    [error] = validate_mission(m, demo_resolver())
    assert str(error) == ("t.yaml:4:39: argument 'target' of actor 'navigate' expects a str, "
                          "but {room} holds an int")


def test_validator_collects_all_errors_in_order() -> None:
    m = parse_mission("""
name: many
root:
  sequence:
    - do: navgate
    - check: missing > 1
    - do: navigate
      with: {target: "{nothing}"}
""", "many.yaml")
    errors = validate_mission(m, demo_resolver())
    assert [type(e).__name__ for e in errors] == [
        "UnresolvedActorError", "UnknownBlackboardKeyError", "UnknownBlackboardKeyError"]
    assert [e.pos.line for e in errors] == [5, 6, 8]


def test_the_runtime_resolver_works_as_validator_resolver(rt) -> None:
    m = parse_mission("name: t\nroot: {sequence: [{do: sleep, with: {seconds: 1}}, {do: slep}]}\n", "t.yaml")
    [error] = validate_mission(m, rt.root.resolve)
    assert isinstance(error, UnresolvedActorError)
    assert "unknown actor 'slep' (did you mean 'sleep'?)" in str(error)


def test_structure_only_validation_without_resolver(tmp_path: Path) -> None:
    path = tmp_path / "free.yaml"
    path.write_text("name: free\nroot: {do: anything_goes, with: {x: 1}}\n")
    assert load_mission(path).name == "free"


def test_library_detects_cycles_across_files(tmp_path: Path) -> None:
    (tmp_path / "a.yaml").write_text("name: tree_a\nroot: {sequence: [{do: sleep, with: {seconds: 1}}, {do: tree_b}]}\n")
    (tmp_path / "b.yaml").write_text("name: tree_b\nroot: {do: tree_c}\n")
    (tmp_path / "c.yaml").write_text("name: tree_c\nroot: {do: tree_a}\n")
    lib = TreeLibrary(demo_resolver())
    lib.load_folder(tmp_path)
    errors = lib.validate()
    assert len(errors) == 3 and all(isinstance(e, SubtreeCycleError) for e in errors)
    assert str(errors[0]) == (f"{tmp_path / 'a.yaml'}:2:57: subtree cycle tree_a -> tree_b -> tree_c -> tree_a, "
                              "expected trees that do not call themselves directly or through other trees")


def test_library_trees_call_each_other_with_signature_checks(tmp_path: Path) -> None:
    (tmp_path / "inner.yaml").write_text(
        "name: inner\ninputs: {n: int}\noutputs: [m]\nroot: {set: {m: \"{n}\"}}\n")
    (tmp_path / "outer.yaml").write_text(
        "name: outer\nroot: {sequence: [{do: inner, with: {n: 2}, out: r}, {check: r.m == 2}]}\n")
    (tmp_path / "bad.yaml").write_text("name: bad\nroot: {do: inner, with: {n: two}}\n")
    (tmp_path / "typo.yaml").write_text("name: typo\nroot: {do: iner}\n")
    errors = check_files(sorted(tmp_path.glob("*.yaml")), demo_resolver())
    assert [Path(e.pos.file).name for e in errors] == ["bad.yaml", "typo.yaml"]
    assert "argument 'n' of actor 'inner' expects an int, got str 'two'" in errors[0].message
    assert "unknown actor 'iner' (did you mean 'inner'?)" in errors[1].message


def test_library_rejects_two_files_with_one_name(tmp_path: Path) -> None:
    (tmp_path / "a.yaml").write_text("name: same\nroot: {wait: 1}\n")
    (tmp_path / "b.yaml").write_text("name: same\nroot: {wait: 2}\n")
    with pytest.raises(DuplicateTreeError, match="already used by"):
        TreeLibrary().load_folder(tmp_path)


def test_library_merges_suggestions_from_trees_and_actors(tmp_path: Path) -> None:
    (tmp_path / "a.yaml").write_text("name: patrol\nroot: {wait: 1}\n")
    lib = TreeLibrary(demo_resolver())
    lib.load_folder(tmp_path)
    with pytest.raises(UnknownActorError) as info:
        lib.resolve("patro")
    assert "patrol" in info.value.suggestions


def test_unreadable_and_binary_files_give_positioned_errors(tmp_path: Path) -> None:
    missing = tmp_path / "missing.yaml"
    with pytest.raises(MissionError, match=r"missing\.yaml:1:1: cannot read mission file"):
        load_mission(missing)
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"name: x\n\xff\xfe\n")
    with pytest.raises(MissionError, match=r"binary\.yaml:2:1: file is not UTF-8 text"):
        load_mission(binary)


def test_deep_nesting_is_an_error_not_a_crash() -> None:
    text = "name: deep\nroot: " + "{invert: " * 3000 + "{wait: 0}" + "}" * 3000 + "\n"
    with pytest.raises(MissionError):
        parse_mission(text, "deep.yaml")


def test_walk_visits_in_source_order() -> None:
    m = parse_mission(DESIGN_EXAMPLE, "x.yaml")
    labels = [n.label for n in walk(m.root)]
    assert labels == ["sequence", "watch", "navigate", "retry x3", "sequence", "open_gripper", "pick",
                      "timeout 20s", "sleep"]


def test_repo_trees_validate_against_the_runtime(rt) -> None:
    folder = Path(__file__).parent.parent / "trees"
    lib = TreeLibrary(rt.root.resolve)
    names = [m.name for m in lib.load_folder(folder)]
    assert "demo_patrol" in names
    errors = [e for e in lib.validate(["demo_patrol"])]
    assert errors == []
