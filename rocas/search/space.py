"""Mutation spaces: the properties a search may change, and how a genome encodes them.

A genome has two genes per variable, both in [0, 1]: a *mask* gene (the variable is mutated
when it is >= 0.5) and a *value* gene (mapped onto the variable's range or choices). With the
mask the genetic search can leave most properties at their original values, so counting
"how many properties were mutated" (f3 / h2) is meaningful, and an initial population of
single-property mutants is easy to write down.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from rocas.errors import UsageError

Kind = Literal["real", "int", "enum", "bool"]
Value = float | int | str | bool


@dataclass(frozen=True)
class Variable:
    """One mutable property.

    Attributes:
        name: unique name, e.g. ``"actor.truck_1.speed"`` or ``"planning.yield_distance_m"``.
        entity: the entity (or module) it belongs to, e.g. ``"truck_1"``.
        kind: ``"real"``, ``"int"``, ``"enum"`` or ``"bool"``.
        original: the value in the original execution.
        low: lower bound (real, int).
        high: upper bound (real, int).
        choices: allowed values (enum).
        unit: unit of a numeric value, for reports.
    """

    name: str
    entity: str
    kind: Kind
    original: Value
    low: float | None = None
    high: float | None = None
    choices: tuple[Value, ...] = ()
    unit: str = ""

    def __post_init__(self) -> None:
        if self.kind in ("real", "int"):
            if self.low is None or self.high is None or not self.low <= self.high:
                raise UsageError(f"variable {self.name}: needs low <= high")
        elif self.kind == "enum":
            if self.original not in self.choices or len(self.choices) < 2:
                raise UsageError(f"variable {self.name}: original must be one of >= 2 choices")
        elif self.kind != "bool":
            raise UsageError(f"variable {self.name}: unknown kind {self.kind!r}")

    def decode(self, u: float) -> Value:
        """Map a value gene ``u`` in [0, 1] to a value of this variable."""
        u = min(max(float(u), 0.0), 1.0)
        if self.kind == "real":
            return self.low + u * (self.high - self.low)  # type: ignore[operator]
        if self.kind == "int":
            lo, hi = int(math.ceil(self.low)), int(math.floor(self.high))  # type: ignore[arg-type]
            return min(hi, lo + int(u * (hi - lo + 1)))
        if self.kind == "bool":
            return u >= 0.5
        return self.choices[min(len(self.choices) - 1, int(u * len(self.choices)))]

    def encode(self, value: Value) -> float:
        """A value gene that decodes to ``value``."""
        if self.kind == "real":
            span = self.high - self.low  # type: ignore[operator]
            return 0.5 if span == 0 else (float(value) - self.low) / span  # type: ignore[operator]
        if self.kind == "int":
            lo, hi = int(math.ceil(self.low)), int(math.floor(self.high))  # type: ignore[arg-type]
            return (int(value) - lo + 0.5) / (hi - lo + 1)
        if self.kind == "bool":
            return 0.75 if value else 0.25
        return (self.choices.index(value) + 0.5) / len(self.choices)

    def change(self, value: Value) -> float:
        """Size of a change from the original: 1 for a different enum choice or bool (enums
        are nominal: a red truck is not "closer" to orange than to blue), |v - v0| for ints,
        |v - v0| / range for reals."""
        if self.kind == "real":
            span = (self.high - self.low) or 1.0  # type: ignore[operator]
            return abs(float(value) - float(self.original)) / span  # type: ignore[arg-type]
        if self.kind == "int":
            return float(abs(int(value) - int(self.original)))  # type: ignore[arg-type]
        if self.kind == "bool":
            return 0.0 if bool(value) == bool(self.original) else 1.0
        return 0.0 if value == self.original else 1.0

    @property
    def is_enum_like(self) -> bool:
        """Counted with L1 in f3/h2 (enum, bool, int) rather than L2 (real)."""
        return self.kind != "real"


@dataclass(frozen=True)
class Mutation:
    """A decoded candidate: the variables it changes and their new values.

    Attributes:
        values: variable name -> mutated value (only variables that differ from the original).
    """

    values: Mapping[str, Value] = field(default_factory=dict)

    def __hash__(self) -> int:
        return hash(tuple(sorted(self.values.items(), key=lambda kv: kv[0])))

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(sorted(self.values))

    def without(self, name: str) -> Mutation:
        return Mutation({k: v for k, v in self.values.items() if k != name})

    def with_value(self, name: str, value: Value) -> Mutation:
        return Mutation({**self.values, name: value})


@dataclass(frozen=True)
class MutationSpace:
    """An ordered set of variables and the genome encoding over them."""

    variables: tuple[Variable, ...]

    def __post_init__(self) -> None:
        names = [v.name for v in self.variables]
        if len(set(names)) != len(names):
            raise UsageError("mutation space has duplicate variable names")
        if not names:
            raise UsageError("mutation space is empty")

    @property
    def n_genes(self) -> int:
        return 2 * len(self.variables)

    def variable(self, name: str) -> Variable:
        for v in self.variables:
            if v.name == name:
                return v
        raise KeyError(name)

    def decode(self, genome: np.ndarray) -> Mutation:
        """Genome of shape (2 * n_vars,) -> Mutation (unchanged values are dropped)."""
        values: dict[str, Value] = {}
        for i, var in enumerate(self.variables):
            if genome[2 * i] >= 0.5:
                value = var.decode(genome[2 * i + 1])
                if var.change(value) > 0:
                    values[var.name] = value
        return Mutation(values)

    def encode(self, mutation: Mutation) -> np.ndarray:
        """Mutation -> genome of shape (2 * n_vars,)."""
        genome = np.zeros(self.n_genes)
        for i, var in enumerate(self.variables):
            if var.name in mutation.values:
                genome[2 * i] = 0.75
                genome[2 * i + 1] = var.encode(mutation.values[var.name])
            else:
                genome[2 * i] = 0.25
                genome[2 * i + 1] = var.encode(var.original)
        return genome

    def distance(self, mutation: Mutation) -> float:
        """f3 / h2: number of mutated properties + L1 over enum-like changes + L2 over the
        normalised real changes."""
        l1 = 0.0
        l2 = 0.0
        for name, value in mutation.values.items():
            var = self.variable(name)
            if var.is_enum_like:
                l1 += var.change(value)
            else:
                l2 += var.change(value) ** 2
        return len(mutation.values) + l1 + math.sqrt(l2)

    def single_property_seeds(self, count: int, rng: np.random.Generator) -> np.ndarray:
        """``count`` genomes (shape (count, n_genes)) that each mutate one variable.

        Variables are taken in order, cycling; values are drawn uniformly in their range.
        """
        seeds = np.empty((count, self.n_genes))
        base = self.encode(Mutation())
        for k in range(count):
            g = base.copy()
            i = k % len(self.variables)
            g[2 * i] = 0.75
            g[2 * i + 1] = rng.random()
            seeds[k] = g
        return seeds

    def sample(self, count: int, rng: np.random.Generator, mutate_prob: float = 0.2
               ) -> np.ndarray:
        """Random genomes (shape (count, n_genes)), each variable mutated with ``mutate_prob``."""
        genomes = rng.random((count, self.n_genes))
        masks = rng.random((count, len(self.variables))) < mutate_prob
        genomes[:, 0::2] = np.where(masks, 0.75, 0.25)
        return genomes
