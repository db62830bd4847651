"""Positive tests of the mission front end: YAML positions, the model, the validator."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_engine import ActorbtError, UnknownActorError
from bt_engine.trees import (
    REQUIRED,
    Do,
    DuplicateTreeError,
    InputError,
    MissionError,
    ParallelPolicy,
    Ref,
    Retry,
    Sequence,
    SubtreeCycleError,
    Timeout,
    TreeLibrary,
    UnknownBlackboardKeyError,
    UnresolvedActorError,
    ValueType,
    check_files,
    load_mission,
    parse_mission,
    validate_mission,
    walk,
)
from bt_engine.trees._errors import MAX_MESSAGE_LENGTH, LimitError, MissionSyntaxError
from bt_engine.trees._errors import ActorbtError as TreesRoot
from bt_engine.trees._parse import MAX_MISSION_SIZE, read_mission
from bt_engine.trees._yaml import MAX_NUMBER_DIGITS, MAX_SCALAR_LENGTH, MAX_YAML_DEPTH
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
    m = parse_mission(
        """
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
""",
        "all.yaml",
    )
    kinds = [type(c).__name__ for c in m.root.children]
    assert kinds == [
        "ReactiveSequence",
        "Selector",
        "Selector",
        "ReactiveSelector",
        "ReactiveSelector",
        "Parallel",
        "Parallel",
        "Retry",
        "Repeat",
        "Repeat",
        "Timeout",
        "Invert",
        "ForceSuccess",
        "ForceFailure",
        "Do",
        "SetValues",
        "Check",
        "Wait",
        "UseBehaviour",
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
    m = parse_mission(
        """
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
""",
        "refs.yaml",
    )
    values = m.root.values
    assert isinstance(values["whole"], Ref)
    assert isinstance(values["nested"]["a"][0], Ref) and values["nested"]["a"][0].fields == ("x",)
    assert values["literal"] == "{pose}"
    assert values["braces"] == "a {b c} d"
    assert values["number"] == 3


def test_inputs_shorthand_inference_and_signature() -> None:
    m = parse_mission(
        """
name: sig
inputs:
  target: str
  speed: {default: 0.5}
  tries: {type: int, default: 3, doc: attempts}
  extra: {type: any}
outputs:
  result: {type: dict, doc: what happened}
root: {set: {result: {}}}
""",
        "sig.yaml",
    )
    assert [(i.name, i.type) for i in m.inputs] == [
        ("target", ValueType.STR),
        ("speed", ValueType.FLOAT),
        ("tries", ValueType.INT),
        ("extra", ValueType.ANY),
    ]
    assert m.inputs[0].default is REQUIRED and m.inputs[3].required
    assert str(m.signature()) == "(target: str, speed: float = 0.5, tries: int = 3, *, extra) -> dict"
    assert m.bind_inputs("kitchen", extra=None) == {"target": "kitchen", "speed": 0.5, "tries": 3, "extra": None}
    assert m.outputs[0].type is ValueType.DICT and m.outputs[0].doc == "what happened"
    with pytest.raises(InputError, match="input 'tries' is 'x'"):
        m.bind_inputs("kitchen", tries="x", extra=1)
    with pytest.raises(InputError, match="missing a required argument: 'target'"):
        m.bind_inputs(extra=1)


@pytest.mark.parametrize(
    "vtype,text,value",
    [
        (ValueType.STR, "kitchen", "kitchen"),
        (ValueType.INT, "3", 3),
        (ValueType.FLOAT, "0.25", 0.25),
        (ValueType.BOOL, "yes", True),
        (ValueType.BOOL, "false", False),
        (ValueType.LIST, "[1, a]", [1, "a"]),
        (ValueType.DICT, "{x: 1}", {"x": 1}),
        (ValueType.ANY, "3.5", 3.5),
    ],
)
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
    m = parse_mission(
        """
name: t
inputs: {room: {type: int, default: 1}}
root: {do: navigate, with: {target: "{room}"}}
""",
        "t.yaml",
    )
    [error] = validate_mission(m, demo_resolver())
    assert str(error) == ("t.yaml:4:39: argument 'target' of actor 'navigate' expects a str, but {room} holds an int")


def test_validator_collects_all_errors_in_order() -> None:
    m = parse_mission(
        """
name: many
root:
  sequence:
    - do: navgate
    - check: missing > 1
    - do: navigate
      with: {target: "{nothing}"}
""",
        "many.yaml",
    )
    errors = validate_mission(m, demo_resolver())
    assert [type(e).__name__ for e in errors] == [
        "UnresolvedActorError",
        "UnknownBlackboardKeyError",
        "UnknownBlackboardKeyError",
    ]
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
    (tmp_path / "a.yaml").write_text(
        "name: tree_a\nroot: {sequence: [{do: sleep, with: {seconds: 1}}, {do: tree_b}]}\n"
    )
    (tmp_path / "b.yaml").write_text("name: tree_b\nroot: {do: tree_c}\n")
    (tmp_path / "c.yaml").write_text("name: tree_c\nroot: {do: tree_a}\n")
    lib = TreeLibrary(demo_resolver())
    lib.load_folder(tmp_path)
    errors = lib.validate()
    assert len(errors) == 3 and all(isinstance(e, SubtreeCycleError) for e in errors)
    assert str(errors[0]) == (
        f"{tmp_path / 'a.yaml'}:2:57: subtree cycle tree_a -> tree_b -> tree_c -> tree_a, "
        "expected trees that do not call themselves directly or through other trees"
    )


def test_library_trees_call_each_other_with_signature_checks(tmp_path: Path) -> None:
    (tmp_path / "inner.yaml").write_text('name: inner\ninputs: {n: int}\noutputs: [m]\nroot: {set: {m: "{n}"}}\n')
    (tmp_path / "outer.yaml").write_text(
        "name: outer\nroot: {sequence: [{do: inner, with: {n: 2}, out: r}, {check: r.m == 2}]}\n"
    )
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


def test_walk_visits_in_source_order() -> None:
    m = parse_mission(DESIGN_EXAMPLE, "x.yaml")
    labels = [n.label for n in walk(m.root)]
    assert labels == [
        "sequence",
        "watch",
        "navigate",
        "retry x3",
        "sequence",
        "open_gripper",
        "pick",
        "timeout 20s",
        "sleep",
    ]


def test_repo_trees_validate_against_the_runtime(rt) -> None:
    folder = Path(__file__).parent.parent / "trees"
    lib = TreeLibrary(rt.root.resolve)
    names = [m.name for m in lib.load_folder(folder)]
    assert "demo_patrol" in names
    errors = [e for e in lib.validate(["demo_patrol"])]
    assert errors == []


# ---------------------------------------------------------------- hostile input (issue core-2)
# Each crash class of the external fuzz: a located one-line MissionError, never a traceback.


def error_of(text: str, file: str = "m.yaml") -> MissionError:
    with pytest.raises(MissionError) as info:
        parse_mission(text, file)
    assert len(str(info.value).splitlines()) == 1
    return info.value


def where(error: MissionError) -> tuple[int, int]:
    return error.pos.line, error.pos.column


@pytest.mark.parametrize("char", ["\x00", "\x08", "\x0b", "\x0c", "\x1b", "\x7f", "\ufffe", "\uffff"])
def test_control_characters_are_located_errors(char: str) -> None:
    error = error_of(f"name: a\nroot: {{wait: 1}}\n# ab{char}\n")
    assert isinstance(error, MissionSyntaxError)
    assert where(error) == (3, 5)
    assert f"non-printable character U+{ord(char):04X} is not allowed in YAML" in error.message


def test_the_issue_repro_is_one_line_from_the_file(tmp_path: Path) -> None:
    path = tmp_path / "a.yaml"
    path.write_bytes(b"name: a\nroot: {wait: 1}\n# \x7f\n")
    [error] = check_files([path])
    assert str(error) == (
        f"{path}:3:3: non-printable character U+007F is not allowed in YAML, expected printable text "
        "(write it as an escape in a double-quoted string)"
    )


def test_invalid_utf8_points_at_the_byte(tmp_path: Path) -> None:
    path = tmp_path / "latin1.yaml"
    path.write_bytes("name: a\ndoc: d\u00e9j\u00e0 \n".encode() + b"root: {wait: 1} # caf\xe9\n")
    with pytest.raises(MissionSyntaxError, match=r"latin1\.yaml:3:22: file is not UTF-8 text \(byte 0xE9\)"):
        read_mission(path)


def test_a_utf8_bom_is_skipped_and_utf16_is_named(tmp_path: Path) -> None:
    path = tmp_path / "bom.yaml"
    path.write_bytes(b"\xef\xbb\xbfname: bom\nroot: {wait: 1}\n")
    assert read_mission(path).pos.column == 1
    path.write_bytes(b"\xef\xbb\xbfname: bom\nroot: {wait: 1}\nname: again\n")
    with pytest.raises(MissionError, match=r"bom\.yaml:3:1: duplicate key 'name' \(first at line 1, column 1\)"):
        read_mission(path)
    path.write_bytes("name: a\nroot: {wait: 1}\n".encode("utf-16"))
    with pytest.raises(MissionSyntaxError, match=r"bom\.yaml:1:1: file is UTF-16 text, expected UTF-8"):
        read_mission(path)


@pytest.mark.parametrize("text", ["", "\n", "  \n\n", "# only a comment\n", "\ufeff"])
def test_empty_files_are_one_error(text: str) -> None:
    error = error_of(text)
    assert where(error) == (1, 1) and "empty mission file" in error.message


@pytest.mark.parametrize(
    "number",
    [
        "9" * 5000,
        "-" + "9" * 4301,
        "0x" + "f" * 5000,
        "0b" + "1" * 9000,
        "1_" * 3000 + "1",
        ":".join(["59"] * 2000),
        "1" * 5000 + ".5",
    ],
)
def test_huge_yaml_numbers_name_the_limit(number: str) -> None:
    error = error_of(f"name: a\nroot:\n  sequence:\n    - wait: {number}\n")
    assert isinstance(error, LimitError)
    assert where(error) == (4, 13)
    assert error.message.startswith(f"number longer than {MAX_NUMBER_DIGITS} digits")


def test_numbers_up_to_the_limit_load_and_quoted_ones_are_text() -> None:
    m = parse_mission(f"name: a\nroot: {{set: {{n: {'9' * MAX_NUMBER_DIGITS}, s: '{'9' * 5000}'}}}}\n", "m.yaml")
    assert m.root.values["n"] == int("9" * MAX_NUMBER_DIGITS)
    assert len(m.root.values["s"]) == 5000


def test_long_values_name_the_limit() -> None:
    error = error_of(f"name: a\nroot: {{do: say, with: [{'x' * (MAX_SCALAR_LENGTH + 1)}]}}\n")
    assert isinstance(error, LimitError) and where(error) == (2, 24)
    assert error.message == f"YAML value longer than {MAX_SCALAR_LENGTH} characters, expected a shorter value"


def deep_flow(levels: int) -> str:
    """A mission whose YAML is ``levels`` deep, the innermost list on line 3."""
    inner = levels - 3  # the top mapping, the sequence node's mapping, its list
    return "name: deep\nroot:\n  sequence: [" + "[" * inner + "]" * inner + "]\n"


def deep_block(levels: int) -> str:
    """``levels`` deep in block style: the mapping on line k is level k - 1."""
    lines = [" " * (2 * k) + "invert:" for k in range(1, levels - 1)]
    return "name: deep\nroot:\n" + "\n".join(lines) + "\n" + " " * (2 * (levels - 1)) + "wait: 0\n"


def test_yaml_nesting_up_to_the_limit_loads() -> None:
    parse_mission(deep_block(MAX_YAML_DEPTH), "deep.yaml")
    error = error_of(deep_flow(MAX_YAML_DEPTH))  # loads as YAML, then lists are not nodes
    assert "expected a node mapping" in error.message


@pytest.mark.parametrize("levels", [MAX_YAML_DEPTH + 1, 3000])
def test_deep_flow_nesting_points_at_the_first_level_past_the_limit(levels: int) -> None:
    error = error_of(deep_flow(levels))
    assert isinstance(error, LimitError)
    assert error.message.startswith(f"YAML nested deeper than {MAX_YAML_DEPTH} levels")
    # line 3, column 13 holds level 3; level MAX + 1 is MAX - 2 further along
    assert where(error) == (3, 13 + MAX_YAML_DEPTH - 2)


@pytest.mark.parametrize("levels", [MAX_YAML_DEPTH + 1, 300])
def test_deep_block_nesting_points_at_the_line_past_the_limit(levels: int) -> None:
    error = error_of(deep_block(levels))
    assert isinstance(error, LimitError) and "nested deeper than" in error.message
    assert where(error) == (MAX_YAML_DEPTH + 2, 2 * MAX_YAML_DEPTH + 1)


def test_deep_invert_chains_are_an_error_at_the_limit_not_a_crash() -> None:
    text = "name: deep\nroot: " + "{invert: " * 3000 + "{wait: 0}" + "}" * 3000 + "\n"
    error = error_of(text, "deep.yaml")
    assert isinstance(error, LimitError)
    assert where(error) == (2, 7 + 9 * (MAX_YAML_DEPTH - 1))  # the brace of level MAX + 1


def test_aliases_are_rejected_where_they_are_so_no_alias_bomb_expands() -> None:
    lines = ["name: laughs", "lol0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    lines += [f"lol{i}: &l{i} [{', '.join([f'*l{i - 1}'] * 9)}]" for i in range(1, 10)]
    lines += ["root: {set: {bomb: *l9}}"]
    error = error_of("\n".join(lines) + "\n")
    assert where(error) == (3, 12)
    assert error.message == "YAML alias *l0 is not supported, expected the value written out"


def test_recursive_aliases_are_rejected() -> None:
    assert "YAML alias *r is not supported" in error_of("name: a\nroot: &r {invert: *r}\n").message


@pytest.mark.parametrize(
    "value,message",
    [
        (
            "!!python/object/apply:os.system [echo]",
            "unsupported YAML tag 'tag:yaml.org,2002:python/object/apply:os.system'",
        ),
        ("!!python/name:os.system", "unsupported YAML tag 'tag:yaml.org,2002:python/name:os.system'"),
        ("!!bool maybe", "'maybe' is not a valid bool, expected a bool or no tag"),
        ("!!int 1e3", "'1e3' is not a valid int"),
        ("!!float abc", "'abc' is not a valid float"),
        ("!!timestamp today", "'today' is not a valid timestamp"),
        ("2001-02-30", "invalid timestamp '2001-02-30': day is out of range for month"),
        ("2001-01-01 00:00:00 +99:00", "invalid timestamp"),
        ("0b_", "invalid int '0b_'"),
        ("!!set {a}", "unsupported YAML tag 'tag:yaml.org,2002:set'"),
        ("!local x", "unsupported YAML tag '!local'"),
    ],
)
def test_tags_and_impossible_values_are_located(value: str, message: str) -> None:
    error = error_of(f"name: a\nroot:\n  set:\n    x: {value}\n")
    assert where(error) == (4, 8)
    assert message in error.message


def test_explicit_tags_that_agree_with_the_text_are_fine() -> None:
    m = parse_mission("name: a\nroot: {set: {f: !!float 1, i: !!int '7', s: !!str 3, e: =}}\n", "m.yaml")
    assert m.root.values == {"f": 1.0, "i": 7, "s": "3", "e": "="}


@pytest.mark.parametrize(
    "text,pos,message",
    [
        ("name: a\nroot: {wait: 1}\n1: x\n", (3, 1), "unknown field '1' in the mission"),
        ("name: a\nroot: {set: {1: x}}\n", (2, 14), "blackboard key must be a string, got int '1'"),
        ("name: a\nroot: {set: {~: x}}\n", (2, 14), "blackboard key must be a string, got nothing"),
        ("name: a\nroot: {set: {? [k]: x}}\n", (2, 16), "complex mapping key, expected a plain string key"),
        ("name: a\nroot: {do: say, with: {true: x}}\n", (2, 24), "argument name must be a string, got bool 'true'"),
    ],
)
def test_non_string_keys_are_located_errors(text: str, pos: tuple[int, int], message: str) -> None:
    error = error_of(text)
    assert (where(error), message in error.message) == (pos, True), str(error)


def test_tabs_in_indentation_are_located() -> None:
    error = error_of("name: a\nroot:\n  sequence:\n\t- wait: 1\n")
    assert where(error) == (4, 1) and "a tab character" in error.message


def test_python_keywords_cannot_be_input_names() -> None:
    error = error_of("name: a\ninputs:\n  speed: float\n  class: int\nroot: {wait: 1}\n")
    assert where(error) == (4, 3)
    assert error.message == "input name 'class' is a Python keyword, expected a name a parameter can have"


def test_huge_text_and_endless_files_name_the_size_limit(tmp_path: Path) -> None:
    error = error_of("name: a\nroot: {wait: 1}\n" + "#" * MAX_MISSION_SIZE)
    assert isinstance(error, LimitError) and where(error) == (1, 1)
    assert f"longer than {MAX_MISSION_SIZE} characters" in error.message
    if Path("/dev/zero").exists():  # read at most one byte past the limit
        with pytest.raises(LimitError, match=f"/dev/zero:1:1: file larger than {MAX_MISSION_SIZE} bytes"):
            read_mission("/dev/zero")


def test_folders_and_bad_paths_give_located_errors(tmp_path: Path) -> None:
    (tmp_path / "sub.yaml").mkdir()
    with pytest.raises(MissionError, match=r"sub\.yaml:1:1: cannot read mission file: Is a directory"):
        read_mission(tmp_path / "sub.yaml")
    with pytest.raises(MissionError, match="cannot read mission file: embedded null byte"):
        read_mission(tmp_path / "a\x00.yaml")
    with pytest.raises(MissionError, match=r"missing:1:1: cannot read trees folder"):
        TreeLibrary().load_folder(tmp_path / "missing")


def test_file_names_with_control_characters_stay_on_one_line() -> None:
    error = error_of("name: a\n", "odd\nname.yaml")
    assert str(error).startswith("odd\\nname.yaml:1:1: the mission has no 'root'")


def test_long_values_are_shortened_in_messages() -> None:
    error = error_of(f"name: a\nroot: {{do: {'x' * 5000}!}}\n")
    assert "do 'xxxx" in error.message and "...' is not an actor name" in error.message
    assert len(error.message) < 200
    # the net for any other message: its middle goes, what is wrong and what was expected stay
    long_message = MissionError(error.pos, "wrong " + "x" * 5000 + " expected y")
    assert len(long_message.message) <= MAX_MESSAGE_LENGTH + 5
    assert long_message.message.startswith("wrong xx") and long_message.message.endswith("xx expected y")


def test_long_chains_of_tree_calls_do_not_recurse() -> None:
    # More trees in one call chain than Python may recurse: the cycle check walks a stack.
    n = 1200
    lib = TreeLibrary()
    for i in range(n):
        lib.add(parse_mission(f"name: t{i}\nroot: {{do: t{(i + 1) % n}}}\n", f"t{i}.yaml"))
    [error] = lib.validate(["t0"])
    assert isinstance(error, SubtreeCycleError)
    assert error.message.startswith("subtree cycle t0 -> t1 -> t2 -> ") and " -> t1199 -> t0, expected" in error.message


def test_validation_of_a_file_full_of_problems_stops_after_max_errors() -> None:
    # Unknown keys among many written ones: every error would search the written keys for
    # a close match, quadratic in the file size. Bounded twice: errors and choices searched.
    from bt_engine.trees._parse import MAX_SUGGESTION_CHOICES
    from bt_engine.trees._validate import MAX_ERRORS

    n = MAX_SUGGESTION_CHOICES + 100
    text = (
        "name: many\nroot:\n  sequence:\n"
        + "".join(f"    - set: {{key_{i}: 1}}\n" for i in range(n))
        + "".join(f"    - check: kez_{i} > 1\n" for i in range(n))
    )
    errors = validate_mission(parse_mission(text, "many.yaml"))
    assert len(errors) == MAX_ERRORS + 1
    assert all(isinstance(e, UnknownBlackboardKeyError) for e in errors[:-1])
    assert isinstance(errors[-1], LimitError) and where(errors[-1]) == where(errors[-2])
    assert errors[-1].message.startswith(f"more than {MAX_ERRORS} problems in this mission, stopped checking")
