"""Phase IV: cyber mutation over the stack's parameters (section 5.3)."""

from __future__ import annotations

from collections.abc import Mapping

from rocas.errors import UsageError
from rocas.scenarios.model import DEFAULT_STACK
from rocas.search.space import MutationSpace, Variable
from rocas.stacks.registry import get_stack


def cyber_space(module: str | None, current: Mapping[str, float],
                stack: str = DEFAULT_STACK) -> MutationSpace:
    """The parameters of ``module`` (all modules when None) as a mutation space, without the
    stack's declared ``braking_limits`` (a "fix" that caps braking only hides the accident),
    with its ``sensing_limits`` free to grow only (from their current value to their upper
    bound: a "fix" that senses less hides the accident too), and its ``pace_limits`` free to
    fall only (a "fix" that drives faster wins a race instead of removing the cause).

    Args:
        module: the initial deviating module, or None for ``--scope all``.
        current: the values in force in the accident run (defaults plus overrides).
        stack: the registered stack whose parameters are searched.
    """
    st = get_stack(stack)
    modules = st.modules
    specs = tuple(p for p in st.parameters if module is None or p.module == module)
    braking = frozenset(getattr(st, "braking_limits", ()))
    sensing = frozenset(getattr(st, "sensing_limits", ()))
    pace = frozenset(getattr(st, "pace_limits", ()))
    if module is not None and module not in modules:
        raise UsageError(f"no parameters for module {module!r}", f"modules: {', '.join(modules)}")
    out = []
    for p in specs:
        if p.full_name in braking:
            continue
        value = float(current.get(p.full_name, p.default))
        kind = "int" if p.is_integer else "real"
        low = max(p.low, value) if p.full_name in sensing else p.low
        high = min(p.high, value) if p.full_name in pace else p.high
        out.append(Variable(p.full_name, p.module, kind, int(value) if kind == "int" else value,
                            low=low, high=high, unit=p.unit if p.unit not in ("bool", "enum") else ""))
    return MutationSpace(tuple(out))
