"""The last check every loaded scene passes: the Scene is what types.py says it is.

Loaders decode files; this checks their product in one place, whatever the format (a baked
file's checksum proves the file is intact, not that its contents are valid). A scene that
passes is safe to hand to the renderer: every index in range, every array of the declared
shape and dtype, every number finite and of a magnitude that float32 uniforms and the
camera maths can hold. A failure is one SceneError naming the file and the field:
"scene.vkpbr: materials[3].roughness_factor: expected a finite number, got 'rough'".
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from vkpbr.errors import SceneError, UsageError
from vkpbr.scene.camera import MAX_COORDINATE, Camera, validate_camera
from vkpbr.scene.limits import MAX_MORPH_TARGETS, limits
from vkpbr.scene.material_table import PARAMS
from vkpbr.scene.types import (
    TEXTURE_SLOTS,
    Image,
    Light,
    Material,
    Mesh,
    Node,
    Sampler,
    Scene,
    TextureRef,
)
from vkpbr.shading import MAX_LIGHTS

__all__ = ["validate_scene", "validate_lights", "MAX_COORDINATE"]

_TEXTURE_SLOTS = TEXTURE_SLOTS


class _Bad(Exception):
    """A problem at a field path; turned into SceneError by validate_scene."""


def _fail(where: str, problem: str, value: Any = None) -> None:
    shown = "" if value is None else f", got {_short(value)}"
    raise _Bad(f"{where}: {problem}{shown}")


def _short(value: Any) -> str:
    if isinstance(value, np.ndarray):
        return f"array of shape {value.shape} and dtype {value.dtype}"
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _number(value: Any, where: str, lo: float = -MAX_COORDINATE, hi: float = MAX_COORDINATE) -> None:
    if type(value) is not float and (isinstance(value, bool) or not isinstance(value, numbers.Real)):
        _fail(where, "expected a number", value)  # (the type() test first: ABCs are slow)
    if not (math.isfinite(float(value)) and lo <= float(value) <= hi):
        _fail(where, f"expected a finite number in [{lo:g}, {hi:g}]", value)


def _integer(value: Any, where: str, lo: int, hi: int) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not lo <= value <= hi:
        _fail(where, f"expected an integer in [{lo}, {hi}]", value)


def _vector(value: Any, n: int, where: str, lo: float = -MAX_COORDINATE,
            hi: float = MAX_COORDINATE) -> None:
    if isinstance(value, str | bytes) or not isinstance(value, Sequence | np.ndarray) or len(value) != n:
        _fail(where, f"expected {n} numbers", value)
    for i, x in enumerate(value):
        _number(x, f"{where}[{i}]", lo, hi)


def _choice(value: Any, choices: Sequence[Any], where: str) -> None:
    if not isinstance(value, str | bool) or value not in choices:
        _fail(where, f"expected one of {', '.join(map(str, choices))}", value)


def _array(value: Any, where: str, dtype: Any, shape: tuple[int | None, ...],
           finite_bound: float | None = None) -> None:
    if not isinstance(value, np.ndarray) or value.dtype != dtype or value.ndim != len(shape) or any(
            want is not None and got != want for got, want in zip(value.shape, shape, strict=True)):
        want = "x".join("N" if s is None else str(s) for s in shape)
        _fail(where, f"expected a ({want}) {np.dtype(dtype).name} array", value)
    if finite_bound is not None and value.size:
        if not np.isfinite(value).all():
            _fail(where, "holds non-finite values")
        if np.abs(value).max() > finite_bound:
            _fail(where, f"holds values beyond +-{finite_bound:g}")


# --- parts ---------------------------------------------------------------------------------
def _check_mesh(m: Mesh, where: str, n_materials: int) -> None:
    if not isinstance(m, Mesh):
        _fail(where, "expected a Mesh", m)
    _array(m.positions, f"{where}.positions", np.float32, (None, 3), MAX_COORDINATE)
    n = m.positions.shape[0]
    _array(m.indices, f"{where}.indices", np.uint32, (None,))
    if m.indices.size % 3:
        _fail(f"{where}.indices", f"count {m.indices.size} is not a multiple of 3")
    if m.indices.size and int(m.indices.max()) >= n:
        _fail(f"{where}.indices", f"index {int(m.indices.max())} is beyond the {n} vertices")
    for name, width, dtype, bound in (("normals", 3, np.float32, 1e6), ("texcoords", 2, np.float32, 1e9),
                                      ("texcoords1", 2, np.float32, 1e9), ("tangents", 4, np.float32, 1e6),
                                      ("colors", 4, np.float32, 1e6), ("qtangents", 4, np.float32, 1e6)):
        value = getattr(m, name)
        if value is not None:
            _array(value, f"{where}.{name}", dtype, (n, width), bound)
    if m.packed_frames is not None:
        _array(m.packed_frames, f"{where}.packed_frames", np.uint32, (n,))
    _integer(m.material, f"{where}.material", -1, n_materials - 1)
    _check_deformation(m, where, n)


def _check_deformation(m: Mesh, where: str, n: int) -> None:
    """Skin attributes and morph targets (docs/animation.md): shapes, dtypes, the budget."""
    if (m.joints is None) != (m.weights is None):
        _fail(f"{where}.joints", "joints and weights come together")
    if m.joints is not None:
        _array(m.joints, f"{where}.joints", np.uint16, (n, 8))
        _array(m.weights, f"{where}.weights", np.float32, (n, 8), 1e6)
    if not isinstance(m.morph_targets, dict):
        _fail(f"{where}.morph_targets", "expected a dict", m.morph_targets)
    counts = set()
    for key, d in m.morph_targets.items():
        _choice(key, ("POSITION", "NORMAL", "TANGENT"), f"{where}.morph_targets key")
        _array(d, f"{where}.morph_targets[{key!r}]", np.float32, (None, n, 3), MAX_COORDINATE)
        counts.add(d.shape[0])
    if m.morph_targets or m.morph_weights is not None:
        t = counts.pop() if len(counts) == 1 else -1
        if t < 0 or t > MAX_MORPH_TARGETS:
            _fail(f"{where}.morph_targets", f"expected 0..{MAX_MORPH_TARGETS} targets, the same "
                  "number for every attribute")
        _array(m.morph_weights, f"{where}.morph_weights", np.float64, (t,), 1e9)


def _check_skins(scene: Scene) -> None:
    k = len(scene.tree) if scene.tree is not None else 0
    for i, skin in enumerate(scene.skins):
        where = f"skins[{i}]"
        _array(skin.joints, f"{where}.joints", np.int64, (None,))
        j = len(skin.joints)
        if j and (skin.joints.min() < 0 or skin.joints.max() >= k):
            _fail(f"{where}.joints", f"expected tree node indices in [0, {k - 1}]")
        _array(skin.inverse_bind, f"{where}.inverse_bind", np.float64, (j, 4, 4), 1e12)


def _check_texture(t: TextureRef | None, where: str, n_images: int) -> None:
    if t is None:
        return
    if not isinstance(t, TextureRef):
        _fail(where, "expected a texture reference", t)
    _integer(t.image, f"{where}.image", 0, n_images - 1)
    _integer(t.channel, f"{where}.channel", 0, 3)
    _integer(t.texcoord, f"{where}.texcoord", 0, 1)
    _vector(t.offset, 2, f"{where}.offset", -1e9, 1e9)
    _number(t.rotation, f"{where}.rotation", -1e9, 1e9)
    _vector(t.scale, 2, f"{where}.scale", -1e9, 1e9)
    s = t.sampler
    if not isinstance(s, Sampler):
        _fail(f"{where}.sampler", "expected a sampler", s)
    _choice(s.wrap_s, ("repeat", "clamp", "mirror"), f"{where}.sampler.wrap_s")
    _choice(s.wrap_t, ("repeat", "clamp", "mirror"), f"{where}.sampler.wrap_t")
    _choice(s.mag_filter, ("linear", "nearest"), f"{where}.sampler.mag_filter")
    _choice(s.min_filter, ("linear", "nearest"), f"{where}.sampler.min_filter")
    _choice(s.mipmaps, (True, False), f"{where}.sampler.mipmaps")


def _check_material(m: Material, where: str, n_images: int) -> None:
    if not isinstance(m, Material):
        _fail(where, "expected a Material", m)
    if not isinstance(m.name, str):
        _fail(f"{where}.name", "expected a string", m.name)
    for p in PARAMS:  # every numeric parameter within its row's range (material_table.py)
        if p.size == 1:
            _number(getattr(m, p.name), f"{where}.{p.name}", p.lo, p.hi)
        else:
            _vector(getattr(m, p.name), p.size, f"{where}.{p.name}", p.lo, p.hi)
    _choice(m.unlit, (True, False), f"{where}.unlit")
    _choice(m.glossiness, (True, False), f"{where}.glossiness")
    _choice(m.alpha_mode, ("opaque", "mask", "blend"), f"{where}.alpha_mode")
    _choice(m.double_sided, (True, False), f"{where}.double_sided")
    _choice(m.casts_shadows, (True, False), f"{where}.casts_shadows")
    for slot in _TEXTURE_SLOTS:
        _check_texture(getattr(m, f"{slot}_texture"), f"{where}.{slot}_texture", n_images)


def _check_image(img: Image, where: str) -> None:
    if not isinstance(img, Image):
        _fail(where, "expected an Image", img)
    if not isinstance(img.name, str):
        _fail(f"{where}.name", "expected a string", img.name)
    sources = [s for s in (img.pixels, img.data, img.path) if s is not None]
    if len(sources) > 1:
        _fail(where, "has more than one source (pixels, data, path)")
    if img.pixels is not None:
        _array(img.pixels, f"{where}.pixels", np.uint8, (None, None, 4))
    if img.data is not None and not isinstance(img.data, bytes | bytearray | memoryview):
        _fail(f"{where}.data", "expected bytes", img.data)
    if img.path is not None and not isinstance(img.path, Path):
        _fail(f"{where}.path", "expected a path", img.path)


def _check_node(node: Node, where: str, n_meshes: int) -> None:
    if not isinstance(node, Node):
        _fail(where, "expected a Node", node)
    _integer(node.mesh, f"{where}.mesh", 0, n_meshes - 1)
    m = node.matrix
    if not isinstance(m, np.ndarray) or m.shape != (4, 4) or m.dtype not in (np.float32, np.float64):
        _fail(f"{where}.matrix", "expected a (4x4) float array", m)
    if not np.isfinite(m).all() or np.abs(m).max() > MAX_COORDINATE:
        _fail(f"{where}.matrix", f"holds non-finite values or values beyond +-{MAX_COORDINATE:g}")
    inst = node.instances
    if inst is not None:
        if not isinstance(inst, np.ndarray) or inst.ndim != 3 or inst.shape[1:] != (4, 4):
            _fail(f"{where}.instances", "expected a (K, 4, 4) float array", inst)
        if inst.size and (not np.isfinite(inst).all() or np.abs(inst).max() > MAX_COORDINATE):
            _fail(f"{where}.instances",
                  f"holds non-finite values or values beyond +-{MAX_COORDINATE:g}")


def _check_light(li: Light, where: str) -> None:
    if not isinstance(li, Light):
        _fail(where, "expected a Light", li)
    _vector(li.position, 3, f"{where}.position")
    _vector(li.color, 3, f"{where}.color", 0.0, 1e9)
    _number(li.intensity, f"{where}.intensity", 0.0, 1e15)
    _choice(li.falloff, ("none", "inverse_square"), f"{where}.falloff")
    _number(li.range, f"{where}.range", 0.0, MAX_COORDINATE)
    _choice(li.kind, ("point", "spot", "directional"), f"{where}.kind")
    _vector(li.direction, 3, f"{where}.direction")
    if li.kind != "point" and not math.hypot(*li.direction) > 1e-12:
        _fail(f"{where}.direction", "must not be zero for a spot or directional light")
    _number(li.inner_cone, f"{where}.inner_cone", 0.0, math.pi / 2)
    _number(li.outer_cone, f"{where}.outer_cone", 0.0, math.pi / 2)
    if li.kind == "spot" and not li.inner_cone < li.outer_cone:
        _fail(f"{where}.outer_cone", f"must be greater than inner_cone ({li.inner_cone:g}) "
              "and above 0: a spot light needs a cone")
    if not isinstance(li.shadows, bool):
        _fail(f"{where}.shadows", "expected true or false", li.shadows)


def _check_lights(lights: Sequence[Light], where: str) -> None:
    if len(lights) > MAX_LIGHTS:
        _fail(where, f"{len(lights)} punctual lights; vkpbr renders at most {MAX_LIGHTS} at once")
    for i, li in enumerate(lights):
        _check_light(li, f"{where}[{i}]")


def validate_lights(lights: Sequence[Light], where: str = "lights") -> None:
    """Raise UsageError("lights[1].outer_cone: ...") unless every light given through the API
    or the command line is a well-formed Light (scene files' lights: validate_scene)."""
    try:
        _check_lights(list(lights), where)
    except _Bad as exc:
        raise UsageError(str(exc)) from None


def _check_camera(c: Camera, where: str) -> None:
    if not isinstance(c, Camera):
        _fail(where, "expected a Camera", c)
    _vector(c.eye, 3, f"{where}.eye")
    _vector(c.target, 3, f"{where}.target")
    _vector(c.up, 3, f"{where}.up")
    try:
        validate_camera(c)
    except UsageError as exc:
        _fail(where, str(exc).removeprefix("camera: "))


def _check_bounds(scene: Scene) -> None:
    """World positions (node transforms applied) stay within MAX_COORDINATE."""
    lo, hi = scene.bounds()
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))) or max(
            np.abs(lo).max(initial=0), np.abs(hi).max(initial=0)) > MAX_COORDINATE:
        _fail("bounds", f"the geometry reaches beyond +-{MAX_COORDINATE:g} in world space")


def _check_material_count(scene: Scene) -> None:
    cap = limits().max_materials  # (the glTF reader checks it before reading them too)
    if len(scene.materials) > cap:
        _fail("materials", f"{len(scene.materials):,} materials are over the limit of {cap:,} "
                           "(VKPBR_MAX_MATERIALS)")


def _check_limits(scene: Scene) -> None:
    cap = limits()
    vertices = sum(m.vertex_count for m in scene.meshes)
    if vertices > cap.max_vertices:
        _fail("meshes", f"{vertices:,} vertices are over the limit of {cap.max_vertices:,} "
                        "(VKPBR_MAX_VERTICES)")
    if scene.triangle_count > cap.max_triangles:
        _fail("nodes", f"{scene.triangle_count:,} triangles are over the limit of "
                       f"{cap.max_triangles:,} (VKPBR_MAX_TRIANGLES)")


# --- the scene -----------------------------------------------------------------------------
def validate_scene(scene: Scene, path: str | Path) -> None:
    """Raise SceneError(path, "field: problem") unless `scene` is a well-formed Scene."""
    try:
        if not isinstance(scene.name, str):
            _fail("name", "expected a string", scene.name)
        for name in ("meshes", "materials", "images", "nodes", "lights", "cameras"):
            if not isinstance(getattr(scene, name), list):
                _fail(name, "expected a list", getattr(scene, name))
        _check_material_count(scene)  # before checking each of them
        for i, img in enumerate(scene.images):
            _check_image(img, f"images[{i}]")
        for i, mat in enumerate(scene.materials):
            _check_material(mat, f"materials[{i}]", len(scene.images))
        for i, mesh in enumerate(scene.meshes):
            _check_mesh(mesh, f"meshes[{i}]", len(scene.materials))
        for i, node in enumerate(scene.nodes):
            _check_node(node, f"nodes[{i}]", len(scene.meshes))
        _check_skins(scene)
        _check_lights(scene.lights, "lights")
        for i, cam in enumerate(scene.cameras):
            _check_camera(cam, f"cameras[{i}]")
        _check_bounds(scene)
        _check_limits(scene)
    except _Bad as exc:
        raise SceneError(path, str(exc)) from None
