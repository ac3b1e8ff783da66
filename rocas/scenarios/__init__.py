"""Scenario files: the format (load, validate, write back) and the shipped examples."""

from rocas.scenarios.loader import (
    example_names,
    load_example,
    load_scenario,
    resolve_scenario,
    scenario_from_dict,
    scenario_to_dict,
    world_to_dict,
)
from rocas.scenarios.model import (
    Actor,
    Area,
    Ego,
    Lane,
    LightPolicy,
    Scenario,
    StaticObject,
    TrafficLight,
    Weather,
)

__all__ = ["Actor", "Area", "Ego", "Lane", "LightPolicy", "Scenario", "StaticObject",
           "TrafficLight", "Weather", "example_names", "load_example", "load_scenario",
           "resolve_scenario", "scenario_from_dict", "scenario_to_dict", "world_to_dict"]
