"""The names of the variant families (:mod:`rocas.catalog.variants`), importable without
numpy so that the command line can offer them as choices."""

#: family name -> what a variant of it changes
FAMILIES: dict[str, str] = {
    "jitter": "the entry's own small position, speed, timing and weather ranges",
    "rotate": "the whole world turned by any angle about any point (also a translation)",
    "mirror": "the whole world mirrored in any line (left-hand traffic)",
    "speed": "the ego's speed and each actor's speed profile",
    "actors": "vehicle models and colours (the trigger's documented property kept)",
    "position": "the ego's and each actor's start along its route",
    "mixed": "a rotation or mirror plus half-range speed, actors and position changes",
}
