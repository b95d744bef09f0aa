"""``--op scenario``: a test case is a short script of calls on one live ``MoveGroup``.

A scenario is a small bag of ROS messages on named topics (``fuzzer.scenario.steps``), run
in order on a new group of each target (``fuzzer.scenario.execute``). docs/engine.md,
"Scenarios (``--op scenario``)", documents the mapping, the execution and the compared values.
"""

from fuzzer.scenario.steps import MAX_STEPS, MSG_TYPE, TOPICS, ScenarioCall, Step, to_call, validate

__all__ = ["MAX_STEPS", "MSG_TYPE", "TOPICS", "ScenarioCall", "Step", "to_call", "validate"]
