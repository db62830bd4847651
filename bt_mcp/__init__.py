"""``actorbt mcp``: the catalog as a Model Context Protocol server over stdio, so a
language model can read the robot's skills as tools, call them and write missions.

    settings       the ``mcp:`` section of actorbt.yaml and ``--allow-motion``
    tools          catalog entries -> MCP tools (schema, annotations), the mission tools
    validate       a call's arguments against the tool's JSON Schema, then as call arguments
    progress       tree runs of one call -> progress events and the trace of the last run
    calls          one call on the runtime: started, reported, cancelled, summarised
    mission_tools  validate_mission, run_mission, show_tree, get_trace
    server         the SDK's low-level server wired to the above
    cli            the ``mcp`` sub-command (argparse only; the rest is imported when it runs)

Only ``server`` and ``cli`` know the SDK's session; the other modules are plain Python
and tested without it. Like the rest of ``bt_engine`` it knows no robot: which actors
move the robot is what they declare (``@actor(moves=True)``, see docs/mcp.md).
"""
