"""The viewer's key map and mode switching: one table, read by the viewer, the HUD's help
panel and docs/viewer.md, so the three cannot disagree. No window code here.
"""

from __future__ import annotations

import dataclasses

from vkpbr.render import layouts as L
from vkpbr.render.options import ENUM_FIELDS, RenderOptions

__all__ = ["HELP", "cycle", "view_for_digit", "with_view", "toggle"]

# (keys, what they do): the help panel prints these lines as they are.
HELP: tuple[tuple[str, str], ...] = (
    ("W/S A/D E/Q", "fly forward/back, strafe, up/down"),
    ("Shift / Ctrl", "x5 / x0.05 speed (keys, scroll)"),
    ("left drag", "look (yaw/pitch)"),
    ("right drag", "pan in the view plane"),
    ("scroll", "move forward/back"),
    ("middle click", "hide/show cursor (hidden: mouse looks)"),
    ("1..9, 0", "view: final D F G spec diff amb geoN mapN viewdir"),
    ("Shift+1..0", "view: lightdir base metal rough occl alpha uv depth emis tangent"),
    ("Ctrl+1", "view: bitangent"),
    ("V / Shift+V", "next / previous debug view"),
    ("B", "D model: GGX <-> Blinn-Phong"),
    ("T", "TBN path: vectors -> quat -> packed"),
    ("M  N  O", "alpha masking, normal maps, occlusion on/off"),
    ("X  = / -", "tone map cycle, exposure +/- 0.5 EV"),
    ("[ / ]", "field of view -/+ 5 degrees (10..120)"),
    ("Space", "light animation on/off"),
    ("arrows PgUp/PgDn", "move the light (camera-relative), up/down"),
    ("L", "light to the camera position"),
    ("R", "reset camera and light"),
    ("C", "print the camera as a `vkpbr render` command"),
    ("P / F12", "screenshot (PNG, without the HUD)"),
    ("H / F1   F2", "help panel on/off, HUD on/off"),
    ("Esc", "quit"),
)

_VIEWS = list(L.View)


def view_for_digit(digit: int, shift: bool, ctrl: bool) -> L.View | None:
    """Digit keys 1..9, 0 select views 0..9; with Shift 10..19; with Ctrl 20..29."""
    index = (digit - 1) % 10 + (20 if ctrl else 10 if shift else 0)
    return _VIEWS[index] if index < len(_VIEWS) else None


def with_view(options: RenderOptions, view: L.View) -> RenderOptions:
    return dataclasses.replace(options, view=view)


def cycle(options: RenderOptions, field: str, step: int = 1) -> RenderOptions:
    """Next (or previous) value of an enum option: view, brdf, tbn or tonemap."""
    members = list(ENUM_FIELDS[field])
    current = getattr(options, field)
    nxt = members[(members.index(current) + step) % len(members)]
    return dataclasses.replace(options, **{field: nxt})


def toggle(options: RenderOptions, field: str) -> RenderOptions:
    """Flip a boolean option: alpha_mask, normal_mapping or occlusion."""
    return dataclasses.replace(options, **{field: not getattr(options, field)})
