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
    _progress  live progress printing and --arg parsing for the CLI
    _trace     JSON Lines trace recording (TraceRecorder, also rt.recorder)
    _replay    headless replay of a trace, first divergence
    _plot      timeline picture of a trace (matplotlib)
    _show      ASCII and Graphviz pictures of a mission
    cli        the actorbt commands run, check, show, replay, plot
    testing    fake resolver, scripted actors, manual clock for tests
"""

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
from ._expr import evaluate, parse_expression
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
from ._parse import NODE_TYPES, parse_mission, read_mission
from ._plot import plot_trace
from ._progress import ProgressPrinter, parse_inputs
from ._replay import Divergence, ReplayError, ReplayReport, read_trace, replay
from ._run import TreeObserver, TreeRun
from ._show import RenderError, ascii_tree, dot_tree, render
from ._trace import TraceRecorder, to_json
from ._validate import ActorInfo, Resolver, validate_mission

__all__ = [
    "NODE_TYPES",
    "REQUIRED",
    "STANDARD_BEHAVIOURS",
    "ActorInfo",
    "ArgumentMismatchError",
    "BehaviourFactory",
    "BrokenDependencyError",
    "Check",
    "CheckEvaluationError",
    "CheckExpressionError",
    "Composite",
    "Condition",
    "Decorator",
    "Divergence",
    "Do",
    "DuplicateKeyError",
    "DuplicateTreeError",
    "ForceFailure",
    "ForceSuccess",
    "IfThenElse",
    "InputError",
    "InputSpec",
    "InvalidValueError",
    "Invert",
    "LimitError",
    "Mission",
    "MissionError",
    "MissionSyntaxError",
    "Node",
    "OutputSpec",
    "Parallel",
    "ParallelPolicy",
    "PipelineSequence",
    "Pos",
    "ProgressPrinter",
    "RateController",
    "ReactiveSelector",
    "ReactiveSequence",
    "Recovery",
    "Ref",
    "RenderError",
    "Repeat",
    "ReplayError",
    "ReplayReport",
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
    "ascii_tree",
    "check_files",
    "children_of",
    "dot_tree",
    "evaluate",
    "load_mission",
    "parse_expression",
    "parse_inputs",
    "parse_mission",
    "plot_trace",
    "read_mission",
    "read_trace",
    "register_tree_folder",
    "render",
    "replay",
    "resolve_value",
    "to_json",
    "tree_host",
    "validate_mission",
    "walk",
]
