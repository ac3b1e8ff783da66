"""Systems under test behind one small interface, registered by name.

- :mod:`rocas.stacks.base`: the protocol (what a stack receives each step, what it returns,
  its parameter inventory, its channels and topology).
- :mod:`rocas.stacks.registry`: ``get_stack("lav")``, :func:`~rocas.stacks.registry.register`.
- :mod:`rocas.rollout`: the loop that joins a world and a stack (batch and recording).
- :mod:`rocas.stacks.lav`: a second stack, written independently of the built-in ADS.
- :mod:`rocas.stacks.external`: a stack run as an external process per simulation.
"""
