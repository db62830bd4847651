"""Missions: YAML behaviour trees, their loader and validator.

Layering (see docs/architecture.md, "The layers"): this package is part of ``bt_engine``
and imports none of ``actors``, ``planning`` or ``sim``. It reaches actors only through
a resolver (``rt.root.resolve``) handed to it. Inside the package::

    _errors    MissionError and friends, Pos
    _yaml      position-keeping safe YAML
    _expr      the check: language (tokenizer, parser, evaluator; never eval)
    _model     the typed mission model
    _parse     YAML -> model, local checks
    _validate  model vs. actors, behaviours and trees
    _library   a folder of trees validated together
    _blackboard  one run's namespace on py_trees' global blackboard
    _behaviours  the py_trees behaviours (actor leaf, set, check, wait, decorators)
    _controls  control nodes for BehaviorTree.CPP and Nav2 trees (pipeline, recovery...)
    _run       one run: build, event-driven tick loop, halt, observers
    _host      trees as actors of a runtime (register_tree_folder)
    _trace     JSON Lines trace recording (TraceRecorder, also rt.recorder)
    testing    fake resolver, scripted actors, manual clock for tests

Everything other packages use is imported from here (``__all__``), never from a
``_module``: the front-ends beside the engine (``bt_tools``, ``bt_xml``, ``bt_mcp``,
``bt_cli``, ``bt_ros``) build on the mission model, the check: language's syntax tree, the
trace events and the safety of a mission. Replaying, drawing and plotting a mission or its
trace, and the tree commands, are ``bt_tools``.
"""

from ._behaviours import ActorLeaf
from ._errors import (
    ArgumentMismatchError,
    CheckEvaluationError,
    CheckExpressionError,
    DuplicateKeyError,
    DuplicateTreeError,
    InputError,
    InvalidValueError,
    LimitError,
    MissionError,
    MissionSyntaxError,
    Pos,
    SubtreeCycleError,
    UnknownBehaviourError,
    UnknownBlackboardKeyError,
    UnknownFieldError,
    UnknownNodeError,
    TreeFailure,
    UnresolvedActorError,
)
from ._expr import (And, Compare, Expr, ExprSyntaxError, Key, Literal, Neg, Not, Or, evaluate, keys_of,
                    parse_expression)
from ._host import STANDARD_BEHAVIOURS, BehaviourFactory, TreeHost, register_tree_folder, tree_host
from ._library import (BrokenDependencyError, SkippedTreeError, TreeInfo, TreeLibrary, check_files,
                       load_mission)
from ._model import (
    REQUIRED,
    Check,
    Composite,
    Condition,
    Decorator,
    Do,
    ForceFailure,
    ForceSuccess,
    IfThenElse,
    InputSpec,
    Invert,
    Mission,
    Node,
    OutputSpec,
    Parallel,
    ParallelPolicy,
    PipelineSequence,
    RateController,
    ReactiveSelector,
    ReactiveSequence,
    Recovery,
    Ref,
    Repeat,
    ResumeSequence,
    Retry,
    RunOnce,
    RunOnceThen,
    Selector,
    Sequence,
    SetValues,
    Timeout,
    UseBehaviour,
    ValueType,
    Wait,
    WhileDoElse,
    children_of,
    resolve_value,
    walk,
)
from ._parse import NODE_TYPES, parse_mission, read_mission, suggest
from ._run import TreeObserver, TreeRun, node_path
from ._safety import mission_safety
from ._trace import TRACE_FORMAT, TRACE_VERSION, EventBuilder, TraceRecorder, to_json
from ._validate import ActorInfo, Resolver, annotation_text, annotation_type, validate_mission

__all__ = [
    "NODE_TYPES",
    "TRACE_FORMAT",
    "TRACE_VERSION",
    "REQUIRED",
    "STANDARD_BEHAVIOURS",
    "ActorInfo",
    "ActorLeaf",
    "And",
    "ArgumentMismatchError",
    "BehaviourFactory",
    "BrokenDependencyError",
    "Check",
    "CheckEvaluationError",
    "CheckExpressionError",
    "Compare",
    "Composite",
    "Condition",
    "Decorator",
    "Do",
    "DuplicateKeyError",
    "DuplicateTreeError",
    "EventBuilder",
    "Expr",
    "ExprSyntaxError",
    "ForceFailure",
    "ForceSuccess",
    "IfThenElse",
    "InputError",
    "InputSpec",
    "InvalidValueError",
    "Invert",
    "Key",
    "LimitError",
    "Literal",
    "Mission",
    "MissionError",
    "MissionSyntaxError",
    "Neg",
    "Node",
    "Not",
    "Or",
    "OutputSpec",
    "Parallel",
    "ParallelPolicy",
    "PipelineSequence",
    "Pos",
    "RateController",
    "ReactiveSelector",
    "ReactiveSequence",
    "Recovery",
    "Ref",
    "Repeat",
    "Resolver",
    "ResumeSequence",
    "Retry",
    "RunOnce",
    "RunOnceThen",
    "Selector",
    "Sequence",
    "SetValues",
    "SkippedTreeError",
    "SubtreeCycleError",
    "Timeout",
    "TraceRecorder",
    "TreeFailure",
    "TreeHost",
    "TreeInfo",
    "TreeLibrary",
    "TreeObserver",
    "TreeRun",
    "UnknownBehaviourError",
    "UnknownBlackboardKeyError",
    "UnknownFieldError",
    "UnknownNodeError",
    "UnresolvedActorError",
    "UseBehaviour",
    "ValueType",
    "Wait",
    "WhileDoElse",
    "annotation_text",
    "annotation_type",
    "check_files",
    "children_of",
    "evaluate",
    "keys_of",
    "load_mission",
    "mission_safety",
    "node_path",
    "parse_expression",
    "parse_mission",
    "read_mission",
    "register_tree_folder",
    "resolve_value",
    "suggest",
    "to_json",
    "tree_host",
    "validate_mission",
    "walk",
]
