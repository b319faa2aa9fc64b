"""``--steer module:function``: the user's steering function, imported by name (verify, replay).

One owner for naming a steering function on the command line: a module importable from the working
folder (or the path), then a dotted attribute; a class is instantiated without arguments. Anything
that goes wrong is a ``SteerImportError`` naming the spec and the fix (the CLI's exit 2).
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from typing import Any

from fearguard.errors import SteerImportError  # defined in errors.py, importable here


def resolve_steer(steer: Callable[[Any], Any] | str | None) -> tuple[Callable[[Any], Any] | None, str]:
    """A steering function and its name from a callable or ``module:function`` (None stays None: "scripted")."""
    if steer is None:
        return None, "scripted"
    if callable(steer):
        return steer, getattr(steer, "__qualname__", type(steer).__name__)
    module_name, sep, attr = str(steer).partition(":")
    if not sep or not module_name or not attr:
        raise SteerImportError(f"--steer {steer!r}: expected module:function, e.g. my_pilot:steer")
    if "" not in sys.path and "." not in sys.path:
        sys.path.insert(0, "")  # the user's own module in the working folder
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # the user's module: any import failure is a setup error for them to fix
        raise SteerImportError(f"--steer {steer}: cannot import {module_name!r} ({type(exc).__name__}: {exc})") from None
    obj: Any = module
    for part in attr.split("."):
        obj = getattr(obj, part, None)
        if obj is None:
            raise SteerImportError(f"--steer {steer}: {module_name!r} has no {attr!r}")
    if isinstance(obj, type):
        obj = obj()
    if not callable(obj):
        raise SteerImportError(f"--steer {steer}: {attr!r} is not callable (a function frame -> degrees)")
    return obj, str(steer)
