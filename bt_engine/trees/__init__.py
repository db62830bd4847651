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
    _plugins   controls and decorators written in Python: ports, specs, registration
    _plugin_nodes  their base classes (ControlNode, DecoratorNode): ticking, ports, actor calls
    _poses     positions read from poses and paths of any shape (for the Nav2 nodes)
    nav2_nodes Nav2's RoundRobin, DistanceController, SpeedController, GoalUpdater... as plugins
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

from ._behaviours import CallSite
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
from ._expr import And, Compare, Expr, ExprSyntaxError, Key, Literal, Neg, Not, Or, evaluate, keys_of, parse_expression
from ._host import STANDARD_BEHAVIOURS, BehaviourFactory, TreeHost, register_tree_folder, tree_host
from ._library import BrokenDependencyError, SkippedTreeError, TreeInfo, TreeLibrary, check_files, load_mission
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
    PluginControl,
    PluginDecorator,
    PluginNode,
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
from ._plugin_nodes import ActorCall, ControlNode, DecoratorNode, PluginCallError
from ._plugins import (
    UNSET,
    InputPort,
    OutputPort,
    PluginSpec,
    PortUnsetError,
    control_node,
    decorator_node,
    node_plugins,
    plugin_spec,
    register_node,
)
from ._run import TreeObserver, TreeRun, node_path
from ._safety import mission_safety
from ._trace import TRACE_FORMAT, TRACE_VERSION, EventBuilder, TraceRecorder, to_json
from ._validate import ActorInfo, Resolver, annotation_text, annotation_type, validate_mission

# imported here so that Nav2's controls and decorators are registered whenever missions load
from .nav2_nodes import (
    DistanceController,
    GoalUpdatedController,
    GoalUpdater,
    PathLongerOnApproach,
    RoundRobin,
    SpeedController,
)

__all__ = [
    "ActorCall",
    "ActorInfo",
    "And",
    "ArgumentMismatchError",
    "BehaviourFactory",
    "BrokenDependencyError",
    "CallSite",
    "Check",
    "CheckEvaluationError",
    "CheckExpressionError",
    "Compare",
    "Composite",
    "Condition",
    "ControlNode",
    "Decorator",
    "DecoratorNode",
    "DistanceController",
    "Do",
    "DuplicateKeyError",
    "DuplicateTreeError",
    "EventBuilder",
    "Expr",
    "ExprSyntaxError",
    "ForceFailure",
    "ForceSuccess",
    "GoalUpdatedController",
    "GoalUpdater",
    "IfThenElse",
    "InputError",
    "InputPort",
    "InputSpec",
    "InvalidValueError",
    "Invert",
    "Key",
    "LimitError",
    "Literal",
    "Mission",
    "MissionError",
    "MissionSyntaxError",
    "NODE_TYPES",
    "Neg",
    "Node",
    "Not",
    "Or",
    "OutputPort",
    "OutputSpec",
    "Parallel",
    "ParallelPolicy",
    "PathLongerOnApproach",
    "PipelineSequence",
    "PluginCallError",
    "PluginControl",
    "PluginDecorator",
    "PluginNode",
    "PluginSpec",
    "PortUnsetError",
    "Pos",
    "REQUIRED",
    "RateController",
    "ReactiveSelector",
    "ReactiveSequence",
    "Recovery",
    "Ref",
    "Repeat",
    "Resolver",
    "ResumeSequence",
    "Retry",
    "RoundRobin",
    "RunOnce",
    "RunOnceThen",
    "STANDARD_BEHAVIOURS",
    "Selector",
    "Sequence",
    "SetValues",
    "SkippedTreeError",
    "SpeedController",
    "SubtreeCycleError",
    "TRACE_FORMAT",
    "TRACE_VERSION",
    "Timeout",
    "TraceRecorder",
    "TreeFailure",
    "TreeHost",
    "TreeInfo",
    "TreeLibrary",
    "TreeObserver",
    "TreeRun",
    "UNSET",
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
    "control_node",
    "decorator_node",
    "evaluate",
    "keys_of",
    "load_mission",
    "mission_safety",
    "node_path",
    "node_plugins",
    "parse_expression",
    "parse_mission",
    "plugin_spec",
    "read_mission",
    "register_node",
    "register_tree_folder",
    "resolve_value",
    "suggest",
    "to_json",
    "tree_host",
    "validate_mission",
    "walk",
]
