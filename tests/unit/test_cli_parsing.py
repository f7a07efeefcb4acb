"""The command line's parsing, without a GPU: negative values, enum choices from the one
options table, -q/-v, one-line errors and warnings."""

from __future__ import annotations

import dataclasses
import logging
import warnings

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vkpbr.app import log as app_log
from vkpbr.app.cli import _verbosity, build_parser, main
from vkpbr.app.options import SHARED_OPTIONS, option_flags, render_options_from_args, shared_options
from vkpbr.render.layouts import Brdf, Lighting, TbnMode, Tonemap, View
from vkpbr.render.options import RenderOptions

COMMANDS = ("render", "view")


def parse(*argv: str):  # noqa: ANN201
    return build_parser().parse_args(list(argv))


# --- negative values ------------------------------------------------------------------------
@pytest.mark.parametrize("command", COMMANDS)
def test_negative_vectors_and_numbers_are_values(command: str) -> None:
    args = parse(command, "--light", "-5,0.6,-0.9", "--camera", "-1,2,-3,0,-0.5,0",
                 "--exposure", "-2", "--light-color", "-.5,0,1", "--fov", "45")
    assert args.light == [(-5.0, 0.6, -0.9)]
    assert args.light_color == (-0.5, 0.0, 1.0)
    assert args.camera == "-1,2,-3,0,-0.5,0"
    assert args.exposure == -2.0 and args.fov == 45.0


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("text, value", [("-2.5", -2.5), ("-.5", -0.5), ("-1e-1", -0.1),
                                         ("-3", -3.0)])
def test_negative_number_forms(command: str, text: str, value: float) -> None:
    assert parse(command, "--exposure", text).exposure == value
    assert parse(command, "--light-intensity", text).light_intensity == value


@pytest.mark.parametrize("command", COMMANDS)
def test_negative_value_then_scene_and_options(command: str) -> None:
    """A negative value does not swallow what follows it, nor get taken for the scene."""
    args = parse(command, "--light", "-1,-2,-3", "scene.gltf", "--exposure", "-1", "--view", "d")
    assert args.light == [(-1.0, -2.0, -3.0)] and args.scene == "scene.gltf"
    assert args.exposure == -1.0 and args.view == "d"


@given(st.tuples(*[st.floats(-1e6, 1e6, allow_nan=False)] * 3))
@settings(max_examples=50, deadline=None)
def test_any_vector_round_trips(v: tuple[float, float, float]) -> None:
    text = ",".join(repr(x) for x in v)
    assert parse("render", "--light", text).light == [v]
    assert parse("view", f"--light={text}").light == [v]


@pytest.mark.parametrize("argv, message", [
    (["render", "--light", "-5,0.6"], "argument --light: '-5,0.6': expected three comma-separated"),
    (["render", "--light"], "argument --light: expected one argument"),
    (["view", "--light-color", "-1,x,2"], "argument --light-color: '-1,x,2': expected three"),
    (["render", "--exposure", "-x"], "argument --exposure: expected one argument"),
    (["render", "-5"], None),  # a negative "scene" name is a positional, failing later
    (["render", "--size", "-3x10"], "argument --size: '-3x10': width and height must be positive"),
    (["view", "--view", "nope"], "argument --view: invalid choice: 'nope'"),
    (["render", "--bogus"], "unrecognized arguments: --bogus"),
])
def test_parse_errors_are_one_line_exit_2(capsys, argv: list[str], message: str | None) -> None:  # noqa: ANN001
    if message is None:
        assert parse(*argv).scene == "-5"
        return
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("vkpbr: error: ") and err.count("\n") == 1, err
    assert message in err and "usage:" not in err, err


# --- the options table ------------------------------------------------------------------------
def test_enum_choices_come_from_the_enums(capsys) -> None:  # noqa: ANN001
    parser = build_parser()
    render = parser._subparsers._group_actions[0].choices["render"]  # noqa: SLF001
    render.format_help()  # deferred arguments are added on first use
    by_dest = {a.dest: a for a in render._actions}  # noqa: SLF001
    for dest, enum in (("view", View), ("lighting", Lighting), ("brdf", Brdf), ("tbn", TbnMode),
                       ("tonemap", Tonemap)):
        assert tuple(by_dest[dest].choices) == enum.labels()
    assert main(["render", "--help"]) == 0
    text = capsys.readouterr().out
    assert "geometric-normal" in text and "{ggx,blinn-phong,gltf}" in text and "examples:" in text


@pytest.mark.parametrize("command", COMMANDS)
def test_defaults_are_render_options_defaults(command: str) -> None:
    assert render_options_from_args(parse(command)) == RenderOptions()


def test_enum_names_are_normalised() -> None:
    args = parse("render", "--view", "MAPPED_NORMAL", "--brdf", "Blinn-Phong")
    o = render_options_from_args(args)
    assert (o.view, o.brdf) == (View.MAPPED_NORMAL, Brdf.BLINN_PHONG)


@given(view=st.sampled_from(View), brdf=st.sampled_from(Brdf), tbn=st.sampled_from(TbnMode),
       tonemap=st.sampled_from(Tonemap), exposure=st.floats(-64, 64).map(lambda x: round(x, 2)),
       flags=st.tuples(st.booleans(), st.booleans(), st.booleans()))
@settings(max_examples=60, deadline=None)
def test_option_flags_reproduce_the_options(view, brdf, tbn, tonemap, exposure, flags) -> None:  # noqa: ANN001
    """What the viewer's C key prints, parsed again, is the same RenderOptions."""
    o = RenderOptions(view=view, brdf=brdf, tbn=tbn, tonemap=tonemap, exposure=exposure,
                      alpha_mask=flags[0], normal_mapping=flags[1], occlusion=flags[2])
    for command in COMMANDS:
        assert render_options_from_args(parse(command, *option_flags(o))) == o


def test_every_render_option_field_has_one_flag() -> None:
    table = shared_options()  # SHARED_OPTIONS and the post steps' (render/options.py)
    fields = [s.field for s in table if s.field]
    assert sorted(fields) == sorted(f.name for f in dataclasses.fields(RenderOptions))
    flags = [s.flag for s in table]
    assert len(set(flags)) == len(flags)


# Every command that loads a user's scene file (issue 11): the same scene-loading options,
# each defined once in SHARED_OPTIONS (the same help text wherever it appears).
SCENE_COMMANDS = {"render": ["scene.gltf"], "view": ["scene.gltf"],
                  "bake": ["scene.gltf", "-o", "x.vkpbr"], "bench": ["--sponza", "scene.gltf"]}


@pytest.mark.parametrize("command", sorted(SCENE_COMMANDS))
def test_every_scene_loading_command_takes_the_loading_options(command: str) -> None:
    from vkpbr.app.options import SCENE_LOADING_FLAGS

    rest = SCENE_COMMANDS[command]
    plain = parse(command, *rest)
    assert plain.allow_outside_paths is False and plain.strict is False
    flagged = parse(command, *rest, "--allow-outside-paths", "--strict")
    assert flagged.allow_outside_paths is True and flagged.strict is True
    sub = build_parser()._subparsers._group_actions[0].choices[command]
    sub.format_help()  # runs deferred additions
    by_flag = {a.option_strings[0]: a.help for a in sub._actions if a.option_strings}
    for spec in SHARED_OPTIONS:
        if spec.flag in SCENE_LOADING_FLAGS:
            assert by_flag[spec.flag] == spec.help, (command, spec.flag)


def test_bench_passes_allow_outside_paths_to_the_loader(tmp_path) -> None:  # noqa: ANN001
    """`vkpbr bench --sponza` loads a user's file: the path policy applies, the flag lifts it."""
    from vkpbr.app import bench_cmd
    from vkpbr.scene.resources import ResourceRefused

    (tmp_path / "x.mtl").write_text("newmtl m\nKd 1 0 0\n")
    (tmp_path / "in").mkdir()
    obj = tmp_path / "in" / "s.obj"
    obj.write_text("mtllib ../x.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(ResourceRefused, match=r"s\.obj: material library refers to \.\./x\.mtl "
                                              "outside the scene's folder; pass --allow-outside"):
        bench_cmd._sponza(parse("bench", "--sponza", str(obj)))
    scene = bench_cmd._sponza(parse("bench", "--sponza", str(obj), "--allow-outside-paths"))
    assert [m.base_color_factor for m in scene.materials] == [(1.0, 0.0, 0.0, 1.0)]


def test_help_does_not_import_numpy() -> None:
    """The shared options are added when a command is used, so `vkpbr --help` stays fast."""
    import subprocess
    import sys

    code = ("import sys; from vkpbr.app.cli import main; main(['--help']); "
            "sys.stdout.flush(); print('numpy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout
    assert out.strip().splitlines()[-1] == "False"


# --- -q / -v, logging and warnings ------------------------------------------------------------
@pytest.mark.parametrize("argv, verbosity", [
    (["render"], 0), (["-q", "render"], -1), (["render", "-q"], -1), (["-v", "render"], 1),
    (["render", "-vv"], 2), (["-v", "view", "-v"], 2), (["--quiet", "info"], -1),
])
def test_verbosity_before_or_after_the_command(argv: list[str], verbosity: int) -> None:
    assert _verbosity(parse(*argv)) == verbosity


def test_warnings_are_one_line(capsys) -> None:  # noqa: ANN001
    with app_log.cli_logging(0):
        warnings.warn("scene.gltf: 3 of 3 textures\nnot found", stacklevel=1)
        warnings.warn("old API", DeprecationWarning, stacklevel=1)
        logging.getLogger("vkpbr.app.test").info("hidden at the default verbosity")
    err = capsys.readouterr().err
    assert err == "vkpbr: scene.gltf: 3 of 3 textures not found\nvkpbr: DeprecationWarning: old API\n"


def test_quiet_and_verbose_levels(capsys) -> None:  # noqa: ANN001
    child = logging.getLogger("vkpbr.scene.test")
    with app_log.cli_logging(-1):
        warnings.warn("a warning", stacklevel=1)
        child.error("error: broken")
        app_log.say("wrote x.png")
    out, err = capsys.readouterr()
    assert out == "" and err == "vkpbr: error: broken\n"
    with app_log.cli_logging(2):
        child.info("scene cache: x")
        child.debug("details")
        warnings.warn("where from", stacklevel=1)
        app_log.say("wrote x.png")
    out, err = capsys.readouterr()
    lines = err.splitlines()
    assert out == "wrote x.png\n"
    assert lines[:2] == ["vkpbr: info: scene cache: x", "vkpbr: debug: details"]
    assert lines[2].startswith("vkpbr: where from (") and __file__ in lines[2]  # -vv: the source


def test_cli_logging_restores_state() -> None:
    before = (warnings.showwarning, app_log.LOGGER.level, app_log.LOGGER.propagate,
              list(app_log.LOGGER.handlers))
    with app_log.cli_logging(1):
        assert app_log.LOGGER.handlers and not app_log.LOGGER.propagate
    after = (warnings.showwarning, app_log.LOGGER.level, app_log.LOGGER.propagate,
             list(app_log.LOGGER.handlers))
    assert before == after and not app_log.is_quiet()
