"""The perception plug-in registry: plug-ins are found by entry point (group `auv.perception`) and named by
missions. A missing or broken plug-in is an error that names what is installed.

`load_plugin` also takes an import path, `module:Class` (the form of an entry point's value), so that tests and
tools name a plug-in class that no installed package registers; plug-in workers load theirs by the same spec.
"""

from __future__ import annotations

import importlib
from importlib.metadata import EntryPoint, entry_points
from typing import Any

from mission.errors import PluginError

GROUP = "auv.perception"


def installed_plugins() -> dict[str, EntryPoint]:
    """Installed perception plug-ins by entry-point name. A duplicate name is an error (it would be ambiguous)."""
    found: dict[str, EntryPoint] = {}
    for ep in entry_points(group=GROUP):
        if ep.name in found and found[ep.name].value != ep.value:
            raise PluginError(f"two installed plug-ins share the name '{ep.name}': "
                              f"{found[ep.name].value} and {ep.value}")
        found[ep.name] = ep
    return found


def describe_installed() -> str:
    names = sorted(installed_plugins())
    return ", ".join(names) if names else "none"


def load_plugin(name: str) -> Any:
    """The object an installed plug-in's entry point names, or the object a `module:attr` path names (raises
    PluginError, naming what is installed)."""
    if ":" in name:
        return _import_path(name)
    plugins = installed_plugins()
    if name not in plugins:
        raise PluginError(f"perception plug-in '{name}' is not installed (installed: {describe_installed()})")
    try:
        return plugins[name].load()
    except Exception as exc:  # a broken plug-in must not crash the caller
        raise PluginError(f"perception plug-in '{name}' failed to load: {type(exc).__name__}: {exc}") from exc


def _import_path(spec: str) -> Any:
    """`package.module:Class` (or `module:Outer.Inner`) → that object, as entry points resolve their values."""
    module_name, _, attr = spec.partition(":")
    try:
        obj: Any = importlib.import_module(module_name)
        for part in attr.split("."):
            obj = getattr(obj, part)
    except Exception as exc:  # a broken plug-in must not crash the caller
        raise PluginError(f"perception plug-in '{spec}' failed to load: {type(exc).__name__}: {exc}") from exc
    return obj
