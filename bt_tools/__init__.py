"""The mission tools beside the engine: run, check, draw, replay and plot missions and traces.

Each module builds only on ``bt_engine``'s public API:

    cli       the actorbt commands run, check, show, replay, plot
    progress  live progress printing and --arg parsing for ``run``
    replay    headless replay of a trace, its first divergence
    show      ASCII and Graphviz pictures of a mission
    plot      a timeline picture of a trace (matplotlib)

Import from the module that holds a name (``from bt_tools.replay import replay``): the
package imports none of them, so drawing a tree never loads matplotlib.
"""
