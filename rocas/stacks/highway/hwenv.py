"""The one place that imports highway-env (an optional extra)."""

from __future__ import annotations

from types import ModuleType

from rocas.errors import UsageError

INSTALL_HINT = "pip install 'rocas[highway]'"


def require() -> ModuleType:
    """``highway_env``, imported; a clear error when the extra is not installed.

    Raises:
        UsageError: highway-env is not installed.
    """
    try:
        import highway_env
    except ImportError as exc:
        raise UsageError(f"the highway stack needs highway-env, which is not installed ({exc})",
                         INSTALL_HINT) from None
    return highway_env
