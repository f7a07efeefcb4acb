"""--shadows on|off and --shadow-resolution N: parsed into RenderOptions, reproduced by
option_flags, bad values refused in one line."""

from __future__ import annotations

import pytest

from vkpbr.app.cli import build_parser
from vkpbr.app.options import option_flags, render_options_from_args
from vkpbr.errors import UsageError
from vkpbr.render.options import RenderOptions


@pytest.mark.parametrize("command", ["render", "view"])
def test_shadow_flags_round_trip(command: str) -> None:
    parser = build_parser()
    assert render_options_from_args(parser.parse_args([command])).shadows is True
    o = render_options_from_args(parser.parse_args(
        [command, "--shadows", "off", "--shadow-resolution", "512"]))
    assert (o.shadows, o.shadow_resolution) == (False, 512)
    assert render_options_from_args(parser.parse_args([command, *option_flags(o)])) == o


@pytest.mark.parametrize("res", [0, 15, 16385, 2.5, True, "1024"])
def test_bad_shadow_resolution_is_one_line(res) -> None:  # noqa: ANN001
    with pytest.raises(UsageError, match="shadow resolution") as e:
        RenderOptions(shadow_resolution=res)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("command", ["render", "view"])
def test_shadow_raster_flag_round_trip(command: str) -> None:
    """--shadow-raster auto|hardware|compute (render/shadow_raster.py): auto by default, the
    other two parsed and reproduced by option_flags; another value is refused."""
    parser = build_parser()
    assert render_options_from_args(parser.parse_args([command])).shadow_raster.name == "AUTO"
    for value in ("hardware", "compute"):
        o = render_options_from_args(parser.parse_args([command, "--shadow-raster", value]))
        assert o.shadow_raster.name.lower() == value
        assert render_options_from_args(parser.parse_args([command, *option_flags(o)])) == o
    with pytest.raises(UsageError):
        RenderOptions(shadow_raster="fast")
