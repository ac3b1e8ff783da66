"""A toy accident with a known cause, for the search tests (importable by spawned workers).

The accident is avoided iff the truck drives slower than 8 m/s (original 12 m/s) or the
cone is removed; every other property is irrelevant.
"""

from rocas.search.space import Mutation, MutationSpace, Variable

SPACE = MutationSpace((
    Variable("truck.speed", "truck", "real", 12.0, low=0.0, high=20.0, unit="m/s"),
    Variable("truck.model", "truck", "enum", "truck", choices=("sedan", "suv", "truck", "bus")),
    Variable("car.speed", "car", "real", 5.0, low=0.0, high=20.0, unit="m/s"),
    Variable("car.x", "car", "real", 30.0, low=0.0, high=60.0, unit="m"),
    Variable("cone.enabled", "cone", "bool", True),
    Variable("weather.fog", "weather", "real", 0.0, low=0.0, high=100.0),
    Variable("ped.speed", "ped", "real", 1.2, low=0.0, high=3.0, unit="m/s"),
))


def simulate(mutation: Mutation) -> tuple[tuple[float, ...], float]:
    """(objectives, constraint) of one 'simulation': constraint <= 0 when no accident."""
    values = {v.name: v.original for v in SPACE.variables} | dict(mutation.values)
    margin = 8.0 - float(values["truck.speed"])  # > 0: slow enough
    if not values["cone.enabled"]:
        margin = max(margin, 0.5)
    return (SPACE.distance(mutation), float(len(mutation.values))), -margin


def batch(mutations):
    return [simulate(m) for m in mutations]


def avoided(mutation: Mutation) -> bool:
    return simulate(mutation)[1] <= 0
