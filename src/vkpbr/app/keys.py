"""The viewer's key bindings: one table, from which the input handlers dispatch
(app/viewer_input.py), the help panel prints its lines (HELP) and docs/viewer.md's key table
is generated (`python -m vkpbr.app.keys --markdown`, or `--update docs/viewer.md`; a test
fails when the file is stale). No window code here: keys are GLFW names ("w", "1",
"left_bracket", "page_up", "f12"), turned into codes by the handlers.

Each `Binding` is one line of the help panel and one row of the docs: a label naming the
input, the panel's short text, the docs' longer text, and the chords it covers. A `Chord`
is a key with optional "shift+" / "ctrl+" prefix, the action it triggers and its argument.
Actions are of three kinds:

- press actions (`PRESS_ACTIONS`): run when the key goes down (and on auto-repeat when
  `repeat`); `InputHandlers` has a method `_act_<action>(arg)` for each;
- held actions ("fly", "move_light", "speed"): read every frame from the keys held down;
- mouse rows, with no chords: documented here, handled by the mouse callbacks.

A key with modified chords in the table (the digits, V) answers exactly those combinations;
every other key ignores Shift and Ctrl (so Shift+= still raises the exposure).
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from vkpbr.app.controls import FAST, FOV_RANGE, FOV_STEP, SLOW
from vkpbr.render import layouts as L
from vkpbr.render.options import ENUM_FIELDS, RenderOptions

__all__ = ["Chord", "Binding", "BINDINGS", "HELP", "PRESS_ACTIONS", "HELD_ACTIONS",
           "EXPOSURE_STEP", "EXPOSURE_RANGE", "ENV_ROTATION_STEP", "env_choices", "next_env",
           "turn_env", "chords", "markdown_table", "update_markdown",
           "cycle", "toggle", "with_view", "view_at"]

EXPOSURE_STEP = 0.5  # EV per = / - press
EXPOSURE_RANGE = (-16.0, 16.0)
ENV_ROTATION_STEP = 15.0  # degrees per , / . press

PRESS_ACTIONS = ("quit", "view", "cycle", "toggle", "exposure", "fov", "animate_light",
                 "light_to_camera", "reset", "print_camera", "screenshot", "toggle_help",
                 "toggle_hud", "environment", "env_rotation", "play", "next_animation",
                 "animation_speed")
HELD_ACTIONS = ("fly", "move_light", "speed")


@dataclass(frozen=True)
class Chord:
    """A key (GLFW name, optionally "shift+" / "ctrl+" first) and what it does."""

    key: str
    action: str
    arg: Any = None
    repeat: bool = True  # act again on auto-repeat (mode switches); False for toggles

    @property
    def name(self) -> str:
        return self.key.rsplit("+", 1)[-1]

    @property
    def shift(self) -> bool:
        return "shift+" in self.key

    @property
    def ctrl(self) -> bool:
        return "ctrl+" in self.key


@dataclass(frozen=True)
class Binding:
    """One help-panel line and docs row: `label` names the input, `help` is the panel's
    text, `doc` the docs' (default: `help`)."""

    label: str
    help: str
    chords: tuple[Chord, ...] = ()
    doc: str = ""

    @property
    def text(self) -> str:
        return self.doc or self.help


def _press(key: str, action: str, arg: Any = None) -> Chord:
    return Chord(key, action, arg)


def _once(key: str, action: str, arg: Any = None) -> Chord:
    return Chord(key, action, arg, repeat=False)


_DIGITS = "1234567890"  # keys 1..9, 0 select views 0..9 (Shift: 10..19, Ctrl: 20..29)
_VIEWS = list(L.View)


def _view_chords(prefix: str, first: int) -> tuple[Chord, ...]:
    return tuple(_press(prefix + d, "view", first + i) for i, d in enumerate(_DIGITS)
                 if first + i < len(_VIEWS))


def _view_names(first: int) -> str:
    short = {"specular": "spec", "diffuse": "diff", "ambient": "amb", "geometric-normal": "geoN",
             "mapped-normal": "mapN", "view-dir": "viewdir", "light-dir": "lightdir",
             "base-color": "base", "metallic": "metal", "roughness": "rough", "occlusion": "occl",
             "texcoords": "uv", "depth": "depth", "emissive": "emis", "final": "final"}
    names = [short.get(v.label, v.label.upper() if len(v.label) == 1 else v.label)
             for v in _VIEWS[first:first + 10]]
    return " ".join(names)


def _view_doc(first: int) -> str:
    return ", ".join(v.label for v in _VIEWS[first:first + 10])


_LO, _HI = FOV_RANGE
BINDINGS: tuple[Binding, ...] = (
    Binding("W/S A/D E/Q", "fly forward/back, strafe, up/down", (
        Chord("w", "fly", (0, 1)), Chord("s", "fly", (0, -1)),
        Chord("d", "fly", (1, 1)), Chord("a", "fly", (1, -1)),
        Chord("e", "fly", (2, 1)), Chord("q", "fly", (2, -1))),
        doc="fly forward/back, strafe right/left, up/down while held (course scheme)"),
    Binding("Shift / Ctrl", f"x{FAST:g} / x{SLOW:g} speed (keys, scroll)", (
        Chord("left_shift", "speed", FAST), Chord("right_shift", "speed", FAST),
        Chord("left_control", "speed", SLOW), Chord("right_control", "speed", SLOW)),
        doc=f"held: x{FAST:g} / x{SLOW:g} speed for the fly keys, the light keys and scroll"),
    Binding("left drag", "look (yaw/pitch)",
            doc="look: yaw and pitch, 0.01 rad per pixel (report scheme)"),
    Binding("right drag", "pan in the view plane",
            doc="pan in the view plane (the point at the focus distance follows the cursor)"),
    Binding("scroll", "move forward/back"),
    Binding("middle click", "hide/show cursor (hidden: mouse looks)",
            doc="hide and capture the cursor (mouse moves then look) / show it again"),
    Binding("1..9, 0", "view: " + _view_names(0), _view_chords("", 0),
            doc="view: " + _view_doc(0)),
    Binding("Shift+1..0", "view: " + _view_names(10), _view_chords("shift+", 10),
            doc="view: " + _view_doc(10)),
    Binding("Ctrl+1..0", "view: " + _view_names(20), _view_chords("ctrl+", 20),
            doc="view: " + _view_doc(20)),
    Binding("V / Shift+V", "next / previous debug view",
            (_press("v", "cycle", ("view", 1)), _press("shift+v", "cycle", ("view", -1)))),
    Binding("G", "lighting: pbr <-> course", (_press("g", "cycle", ("lighting", 1)),)),
    Binding("I / Shift+I", "environment: sky -> none -> --env file", (
        _press("i", "environment", 1), _press("shift+i", "environment", -1)),
        doc="next / previous environment of the pbr lighting: sky, none and the `--env` file "
            "if one was given (each pre-filtered on first use, then kept)"),
    Binding(", / .", f"turn the environment -/+ {ENV_ROTATION_STEP:g} degrees", (
        _press("comma", "env_rotation", -ENV_ROTATION_STEP),
        _press("period", "env_rotation", ENV_ROTATION_STEP)),
        doc=f"turn the environment about +Y by -/+ {ENV_ROTATION_STEP:g} degrees "
            "(`--env-rotation`); the automatic sun turns with it"),
    Binding("B", "BRDF: GGX -> Blinn-Phong -> glTF", (_press("b", "cycle", ("brdf", 1)),)),
    Binding("T", "TBN path: vectors -> quat -> packed", (_press("t", "cycle", ("tbn", 1)),)),
    Binding("U", "frame path: auto -> forward -> compute", (_press("u", "cycle", ("pipeline", 1)),),
            doc="frame path (`--pipeline`): auto -> forward -> compute; compute needs an "
                "offscreen viewer (`--offscreen`) and skips back to auto in a window"),
    Binding("M  N  O", "alpha masking, normal maps, occlusion on/off", (
        _press("m", "toggle", "alpha_mask"), _press("n", "toggle", "normal_mapping"),
        _press("o", "toggle", "occlusion"))),
    Binding("K", "shadows on/off", (_press("k", "toggle", "shadows"),),
            doc="shadow maps on/off (the physically based lighting mode's; the HUD shows it)"),
    Binding("X  = / -", f"tone map cycle, exposure +/- {EXPOSURE_STEP:g} EV", (
        _press("x", "cycle", ("tonemap", 1)),
        _press("equal", "exposure", EXPOSURE_STEP), _press("kp_add", "exposure", EXPOSURE_STEP),
        _press("minus", "exposure", -EXPOSURE_STEP),
        _press("kp_subtract", "exposure", -EXPOSURE_STEP)),
        doc=f"tone map: none -> reinhard -> aces -> aces-hill -> pbr-neutral; exposure +/- {EXPOSURE_STEP:g} EV (keypad + / - "
            f"too), within {EXPOSURE_RANGE[0]:g}..{EXPOSURE_RANGE[1]:g}"),
    Binding("[ / ]", f"field of view -/+ {FOV_STEP:g} degrees ({_LO:g}..{_HI:g})", (
        _press("left_bracket", "fov", -FOV_STEP), _press("right_bracket", "fov", FOV_STEP)),
        doc=f"field of view -/+ {FOV_STEP:g} degrees, within {_LO:g}..{_HI:g} (shown in the "
            "HUD; `C` prints it as `--fov`)"),
    Binding("Space", "light animation on/off", (_once("space", "animate_light"),),
            doc="light animation (orbit about the scene centre's vertical axis) on/off"),
    Binding("J", "play / pause the animation", (_once("j", "play"),),
            doc="play / pause the scene's glTF animation (the HUD shows its time)"),
    Binding("Y / Shift+Y", "next / previous animation (all, then each)", (
        _press("y", "next_animation", 1), _press("shift+y", "next_animation", -1)),
        doc="next / previous animation: all of them at once, then each by name"),
    Binding("; / '", "animation speed / 2, x 2", (
        _press("semicolon", "animation_speed", -1), _press("apostrophe", "animation_speed", 1)),
        doc="animation speed halved / doubled (x0.125 .. x4)"),
    Binding("arrows PgUp/PgDn", "move the light (camera-relative), up/down", (
        Chord("up", "move_light", (0, 1)), Chord("down", "move_light", (0, -1)),
        Chord("right", "move_light", (1, 1)), Chord("left", "move_light", (1, -1)),
        Chord("page_up", "move_light", (2, 1)), Chord("page_down", "move_light", (2, -1))),
        doc="move the light forward/back/right/left relative to the camera, up/down, while held"),
    Binding("L", "light to the camera position", (_once("l", "light_to_camera"),)),
    Binding("R", "reset camera and light", (_once("r", "reset"),)),
    Binding("C", "print the camera as a `vkpbr render` command", (_once("c", "print_camera"),),
            doc="print the current view as a `vkpbr render` command (`--camera` format)"),
    Binding("P / F12", "screenshot (PNG, without the HUD)",
            (_once("p", "screenshot"), _once("f12", "screenshot")),
            doc="screenshot `vkpbr-DATE-TIME-FRAME.png` in the current folder (no HUD)"),
    Binding("H / F1   F2", "help panel on/off, HUD on/off", (
        _once("h", "toggle_help"), _once("f1", "toggle_help"), _once("f2", "toggle_hud")),
        doc="key-help panel on/off, whole HUD on/off"),
    Binding("Esc", "quit", (_press("escape", "quit"),)),
)

# (keys, what they do): the help panel prints these lines as they are.
HELP: tuple[tuple[str, str], ...] = tuple((b.label, b.help) for b in BINDINGS)


def chords(kind: Sequence[str] = PRESS_ACTIONS) -> list[Chord]:
    """Every chord of the table whose action is in `kind` (press or held actions)."""
    return [c for b in BINDINGS for c in b.chords if c.action in kind]


# --- option changes the actions make ----------------------------------------------------------
def view_at(index: int) -> L.View | None:
    """The view with number `index`, or None past the last one."""
    return _VIEWS[index] if 0 <= index < len(_VIEWS) else None


def with_view(options: RenderOptions, view: L.View) -> RenderOptions:
    return dataclasses.replace(options, view=view)


def cycle(options: RenderOptions, field: str, step: int = 1) -> RenderOptions:
    """Next (or previous) value of an enum option: view, lighting, brdf, tbn or tonemap (from
    the lighting mode's choice where the option leaves it to the mode)."""
    members = list(ENUM_FIELDS[field])
    current = getattr(options, field)
    if current is None:
        current = getattr(options, f"shading_{field}")
    nxt = members[(members.index(current) + step) % len(members)]
    return dataclasses.replace(options, **{field: nxt})


def toggle(options: RenderOptions, field: str) -> RenderOptions:
    """Flip a boolean option: alpha_mask, normal_mapping, occlusion or shadows."""
    return dataclasses.replace(options, **{field: not getattr(options, field)})


# --- docs/viewer.md ---------------------------------------------------------------------------
BEGIN = "<!-- keys: generated from src/vkpbr/app/keys.py by `python -m vkpbr.app.keys --update docs/viewer.md`; do not edit -->"
END = "<!-- keys: end -->"


def markdown_table() -> str:
    """The key table as Markdown (without the markers)."""
    esc = lambda s: s.replace("|", "\\|")  # noqa: E731
    rows = [f"| {esc(b.label)} | {esc(b.text)} |" for b in BINDINGS]
    return "\n".join(["| Input | Action |", "|---|---|", *rows])


def update_markdown(text: str) -> str:
    """`text` with the block between BEGIN and END replaced by the current table."""
    try:
        head, rest = text.split(BEGIN, 1)
        _, tail = rest.split(END, 1)
    except ValueError:
        raise ValueError(f"no generated key block ({BEGIN} ... {END})") from None
    return f"{head}{BEGIN}\n{markdown_table()}\n{END}{tail}"


def main(argv: Sequence[str] | None = None) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="python -m vkpbr.app.keys",
                                description="The viewer's key table as Markdown.")
    p.add_argument("--markdown", action="store_true", help="print the table")
    p.add_argument("--update", metavar="FILE.md", help="rewrite the generated block in FILE")
    args = p.parse_args(argv)
    if args.update:
        path = Path(args.update)
        old = path.read_text()
        new = update_markdown(old)
        if new != old:
            path.write_text(new)
            print(f"updated {path}")
    if args.markdown or not args.update:
        print(markdown_table())
    return 0


if __name__ == "__main__":
    sys.exit(main())


def env_choices(options: RenderOptions) -> tuple[str, ...]:
    """The environments the K key cycles through: sky, none, and the start's file if any."""
    return ("sky", "none") + ((options.env,) if options.env not in ("sky", "none") else ())


def next_env(options: RenderOptions, choices: Sequence[str], step: int = 1) -> RenderOptions:
    """The next (or previous) environment of `choices` after `options.env`."""
    i = choices.index(options.env) if options.env in choices else -1
    return dataclasses.replace(options, env=choices[(i + step) % len(choices)])


def turn_env(options: RenderOptions, degrees: float) -> RenderOptions:
    """The environment turned by `degrees` more, kept in [-180, 180)."""
    angle = (options.env_rotation + degrees + 180.0) % 360.0 - 180.0
    return dataclasses.replace(options, env_rotation=angle)
