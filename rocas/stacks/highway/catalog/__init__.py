"""The highway stack's accident catalog: TOML files read by :mod:`rocas.stacks.highway.accidents`."""
