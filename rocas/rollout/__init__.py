"""The rollout: a world (:mod:`rocas.sim`) joined with a registered stack (:mod:`rocas.stacks`).

One simulate path for every stack, the built-in ADS included:

- :func:`simulate` runs one scenario with the stack it names (``scenario.ego.stack``),
  optionally recording every channel to MCAP; :func:`simulate_batch` runs N variants of one
  scenario structure together (recording the rows asked for).
- :func:`rollout` / :func:`rollout_batch` do the same with a stack object in hand (a stack
  process simulating itself, a test's toy stack).
- :func:`resolve` merges a scenario's parameter overrides with the caller's and validates them
  against the stack's inventory (:class:`rocas.stacks.base.StackParams`); :func:`check_params`
  does it for a scenario just loaded, so a bad parameter is refused at load time.

The results are the simulator's two types, :class:`~rocas.sim.engine.RunResult` (one run) and
:class:`~rocas.sim.engine.BatchResult` (N variants), whatever the stack.
"""

from rocas.rollout.run import (
    BatchResult,
    ParamsLike,
    RunResult,
    check_params,
    drive_with,
    load_scenario,
    resolve,
    rollout,
    rollout_batch,
    simulate,
    simulate_batch,
    with_stack,
)

__all__ = ["BatchResult", "ParamsLike", "RunResult", "check_params", "drive_with", "load_scenario",
           "resolve",
           "rollout",
           "rollout_batch", "simulate", "simulate_batch", "with_stack"]
