"""viser's property casting without rebuilding its type hints on every assignment.

viser (1.1.1) casts every value assigned to a handle's property in
``AssignablePropsBase._cast_value_recursive``, which compares the hint with
``npt.NDArray[np.float16]``, ``[np.float32]``, ``[np.float64]`` and ``[np.uint8]``, building
each of those generic aliases anew on every call (``types.GenericAlias`` subscription is not
cached). A live plot's data (a tuple of four arrays) took 184 µs per assignment, two per push,
24 pushes/s per browser (issue 11). :func:`install_fast_cast` replaces the method with the same
logic against aliases built once: same results, same order of checks.

Private viser API used: ``viser._assignable_props_api.AssignablePropsBase`` and its
``colors_to_uint8`` (checked against viser 1.1.1).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ["install_fast_cast", "installed_cast"]

_F16 = npt.NDArray[np.float16]
_F32 = npt.NDArray[np.float32]
_F64 = npt.NDArray[np.float64]
_U8 = npt.NDArray[np.uint8]


#: (our cast, viser's original) once installed
_INSTALLED: tuple[Any, Any] | None = None


def installed_cast() -> tuple[Any, Any] | None:
    """(the fast cast, viser's original method) once :func:`install_fast_cast` ran, else None."""
    return _INSTALLED


def install_fast_cast() -> None:
    """Patch viser's ``_cast_value_recursive`` (once; idempotent)."""
    global _INSTALLED
    from viser import _assignable_props_api as api

    cls = api.AssignablePropsBase
    if _INSTALLED is not None and cls._cast_value_recursive is _INSTALLED[0]:
        return
    original = cls._cast_value_recursive
    colors_to_uint8 = api.colors_to_uint8

    def cast(self: Any, hint: Any, value: Any, prop_name: str) -> Any:
        if hint == _F16:
            return np.asarray(value).astype(np.float16)
        elif hint == _F32:
            return np.asarray(value).astype(np.float32)
        elif hint == _F64:
            return np.asarray(value).astype(np.float64)
        elif hint == _U8 and "color" in prop_name:
            return colors_to_uint8(value)
        if isinstance(value, np.ndarray):
            return value
        if (
            isinstance(value, tuple)
            and hasattr(hint, "__origin__")
            and hint.__origin__ is tuple
            and hasattr(hint, "__args__")
            and len(hint.__args__) == 2
            and hint.__args__[1] is ...
        ):
            element_type = hint.__args__[0]
            return tuple(cast(self, element_type, item, prop_name) for item in value)
        return value

    _INSTALLED = (cast, original)
    cls._cast_value_recursive = cast  # type: ignore[method-assign]
