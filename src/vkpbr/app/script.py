"""Timed input scripts for `vkpbr view --script FILE` (tests and demos; docs/viewer.md).

A script is JSON: either a list of events, or {"fixed_dt": seconds, "events": [...]}. With
`fixed_dt` the viewer's clock advances exactly that much per loop iteration (frames and
minimised waits alike), so camera motion and light animation are reproducible; without it,
event times are wall-clock seconds since the window opened. Each event has a time "t" and a
"type"; events are replayed through the same handlers as real GLFW input.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from vkpbr.errors import JsonError, UsageError
from vkpbr.json_input import read_json

__all__ = ["Event", "Script", "load_script", "parse_script", "EVENT_FIELDS"]

# type -> required fields (beyond "t"); optional: key "mods", key/mouse_button "action"
EVENT_FIELDS: dict[str, tuple[str, ...]] = {
    "key": ("key",),  # action: press | release | tap (default tap); mods: ["shift", ...]
    "mouse_move": ("x", "y"),  # cursor position in window pixels
    "mouse_button": ("button",),  # left | middle | right; action: press | release
    "scroll": ("dy",),  # notches, positive = away from the user (forward)
    "resize": ("width", "height"),  # window size in pixels
    "minimize": (),
    "restore": (),
    "screenshot": ("path",),  # write the current frame as PNG
    "print_camera": (),
    "time": ("seconds",),  # the animation's time; "play": true/false plays or pauses it
    "quit": (),
}
_ACTIONS = ("press", "release", "tap")
_MODS = ("shift", "ctrl", "alt", "super")


@dataclass(frozen=True)
class Event:
    t: float
    type: str
    data: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Script:
    events: tuple[Event, ...]
    fixed_dt: float | None = None


def parse_script(obj: Any, source: str = "script") -> Script:
    """Validate a decoded JSON script; raises UsageError naming the bad event."""
    fixed_dt = None
    if isinstance(obj, dict):
        fixed_dt = obj.get("fixed_dt")
        if fixed_dt is not None and (not isinstance(fixed_dt, int | float) or not 0 < fixed_dt <= 1):
            raise UsageError(f"{source}: fixed_dt must be a number of seconds in (0, 1]")
        obj = obj.get("events")
    if not isinstance(obj, list):
        raise UsageError(f"{source}: expected a list of events or {{\"events\": [...]}}")
    events = []
    for i, raw in enumerate(obj):
        where = f"{source}: event {i}"
        if not isinstance(raw, dict):
            raise UsageError(f"{where}: expected an object")
        kind, t = raw.get("type"), raw.get("t", 0.0)
        if kind not in EVENT_FIELDS:
            raise UsageError(f"{where}: unknown type {kind!r}; choose one of: {', '.join(EVENT_FIELDS)}")
        if not isinstance(t, int | float) or t < 0 or t != t:
            raise UsageError(f"{where}: \"t\" must be a time in seconds >= 0")
        missing = [f for f in EVENT_FIELDS[kind] if f not in raw]
        if missing:
            raise UsageError(f"{where} ({kind}): missing {', '.join(missing)}")
        action = raw.get("action", "tap" if kind == "key" else "press")
        if action not in _ACTIONS or (kind == "mouse_button" and action == "tap"):
            raise UsageError(f"{where}: action {action!r} must be press, release or tap (keys)")
        mods = raw.get("mods", [])
        if not isinstance(mods, list) or any(m not in _MODS for m in mods):
            raise UsageError(f"{where}: mods must be a list of {', '.join(_MODS)}")
        if kind == "key":
            key_code(raw["key"], where)
        if kind == "mouse_button" and raw["button"] not in ("left", "middle", "right"):
            raise UsageError(f"{where}: button must be left, middle or right")
        if kind == "time" and not (isinstance(raw["seconds"], int | float) and raw["seconds"] >= 0
                                   and raw["seconds"] == raw["seconds"]
                                   and raw["seconds"] != float("inf")):
            raise UsageError(f"{where}: \"seconds\" must be a time in seconds >= 0")
        if kind == "resize" and not all(isinstance(raw[k], int) and 0 < raw[k] <= 16384
                                        for k in ("width", "height")):
            raise UsageError(f"{where}: width and height must be positive integers")
        data = {k: v for k, v in raw.items() if k not in ("t", "type")}
        data["action"], data["mods"] = action, mods
        events.append(Event(float(t), kind, data))
    events.sort(key=lambda e: e.t)  # stable: equal times keep file order
    return Script(tuple(events), None if fixed_dt is None else float(fixed_dt))


def load_script(path: str | Path) -> Script:
    path = Path(path)
    try:
        obj = read_json(path)
    except OSError as exc:
        raise UsageError(f"--script {path}: {exc.strerror or exc}") from None
    except JsonError as exc:
        raise UsageError(f"--script {path}: not valid JSON ({exc.problem})") from None
    return parse_script(obj, f"--script {path}")


def key_code(name: Any, where: str = "key") -> int:
    """GLFW key code for a name: "w", "1", "space", "escape", "left_shift", "page_up", "f1"."""
    import glfw

    code = getattr(glfw, f"KEY_{str(name).upper()}", None) if isinstance(name, str) else None
    if not isinstance(code, int) or code < 0:
        raise UsageError(f"{where}: unknown key {name!r} (GLFW names: w, 1, space, escape, "
                         "left_shift, page_up, f1, ...)")
    return code


def mods_bits(mods: list[str]) -> int:
    import glfw

    bits = {"shift": glfw.MOD_SHIFT, "ctrl": glfw.MOD_CONTROL, "alt": glfw.MOD_ALT,
            "super": glfw.MOD_SUPER}
    out = 0
    for m in mods:
        out |= bits[m]
    return out
