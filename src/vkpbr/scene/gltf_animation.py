# glTF skins, animations and KHR_animation_pointer -> Scene.skins / Scene.animations, after
# the node walk (gltf_nodes) has made the tree: joints and channel targets become tree indices.
# The rules, fallbacks and limits are in docs/animation.md; sampling is vkpbr.scene.animation.
# Reference: glTF 2.0 spec 3.7.3 (skins), 3.11 (animations), Appendix on interpolation;
# KHR_animation_pointer.

from __future__ import annotations

import re
import warnings

import numpy as np

from vkpbr.errors import SceneError
from vkpbr.scene.gltf_document import GltfDocument, check_index, ext, get, to_float
from vkpbr.scene.gltf_nodes import NodeLinks
from vkpbr.scene.types import Animation, AnimationChannel, AnimationSampler, Scene, Skin

__all__ = ["POINTER_TARGETS", "build_skins", "build_animations"]

_INTERPOLATIONS = ("STEP", "LINEAR", "CUBICSPLINE")
_NODE_PATHS = {"translation": 3, "rotation": 4, "scale": 3, "weights": 0}  # 0: the target count

# KHR_animation_pointer targets vkpbr animates: pattern -> (kind, member, components).
POINTER_TARGETS: tuple[tuple[re.Pattern[str], str, str, int], ...] = tuple(
    (re.compile(pattern), kind, member, n) for pattern, kind, member, n in (
        (r"/materials/(\d+)/pbrMetallicRoughness/baseColorFactor", "material", "base_color_factor", 4),
        (r"/materials/(\d+)/pbrMetallicRoughness/metallicFactor", "material", "metallic_factor", 1),
        (r"/materials/(\d+)/pbrMetallicRoughness/roughnessFactor", "material", "roughness_factor", 1),
        (r"/materials/(\d+)/emissiveFactor", "material", "emissive_factor", 3),
        (r"/materials/(\d+)/extensions/KHR_materials_emissive_strength/emissiveStrength",
         "material", "emissive_strength", 1),
        (r"/extensions/KHR_lights_punctual/lights/(\d+)/color", "light", "color", 3),
        (r"/extensions/KHR_lights_punctual/lights/(\d+)/intensity", "light", "intensity", 1),
        (r"/extensions/KHR_lights_punctual/lights/(\d+)/range", "light", "range", 1),
        (r"/extensions/KHR_lights_punctual/lights/(\d+)/spot/innerConeAngle", "light", "inner_cone", 1),
        (r"/extensions/KHR_lights_punctual/lights/(\d+)/spot/outerConeAngle", "light", "outer_cone", 1),
        (r"/cameras/(\d+)/perspective/yfov", "camera", "yfov", 1),
        (r"/meshes/(\d+)/weights", "mesh", "weights", 0),
    ))
# glTF's defaults of the animatable properties a file may leave out (range: infinite, as 0).
_POINTER_DEFAULTS = {"base_color_factor": 1.0, "metallic_factor": 1.0, "roughness_factor": 1.0,
                     "emissive_factor": 0.0, "emissive_strength": 1.0, "color": 1.0,
                     "intensity": 1.0, "range": 0.0, "inner_cone": 0.0,
                     "outer_cone": float(np.pi / 4), "weights": 0.0}
_NODE_POINTER = re.compile(r"/nodes/(\d+)/(translation|rotation|scale|weights)")


def _target_counts(ld: GltfDocument, links: NodeLinks) -> dict[int, int]:
    """Morph target count of each displayed glTF mesh that has targets; every primitive of a
    mesh must have the same count (the spec's rule)."""
    out: dict[int, int] = {}
    for m in links.mesh_nodes:
        counts = {len(get(p, "targets") or []) for p in get(ld.gltf.meshes[m], "primitives", [])}
        if len(counts) > 1:
            raise SceneError(ld.path, f"mesh {m}: its primitives have different numbers of "
                                      f"morph targets ({sorted(counts)})")
        if counts and (t := counts.pop()):
            out[m] = t
    return out


def _row_of(ld: GltfDocument, scene: Scene) -> dict[int, int]:
    """glTF node index -> tree index, for the displayed scene's nodes."""
    assert scene.tree is not None
    return {int(s): r for r, s in enumerate(scene.tree.source)}


def build_skins(ld: GltfDocument, scene: Scene, links: NodeLinks) -> None:
    """scene.skins: the skins displayed nodes use, in file order; tree.skin is renumbered to
    index them. Checks each skin's joints (in range, in the displayed scene), its inverse bind
    matrices (MAT4, enough of them, finite) and every skinned mesh's joint indices."""
    tree = scene.tree
    assert tree is not None
    counts = _target_counts(ld, links)
    for row, w in tree.weights.items():
        m = get(ld.gltf.nodes[int(tree.source[row])], "mesh")
        if m in counts and len(w) != counts[m]:
            raise SceneError(ld.path, f"node {int(tree.source[row])}: {len(w)} weights for mesh "
                                      f"{m}'s {counts[m]} morph targets")
    if not tree.skin:
        return
    row_of = _row_of(ld, scene)
    skins = ld.gltf.skins or []
    used = sorted(set(tree.skin.values()))
    renumber = {s: k for k, s in enumerate(used)}
    for s in used:
        scene.skins.append(_skin(ld, s, skins[s], row_of))
    tree.skin = {row: renumber[s] for row, s in tree.skin.items()}
    for node in scene.nodes:
        k = tree.skin.get(node.tree)
        mesh = scene.meshes[node.mesh]
        if k is None or mesh.joints is None:
            continue
        n_joints = len(scene.skins[k].joints)
        top = int(mesh.joints.max(initial=0))
        if top >= n_joints:
            raise SceneError(ld.path, f"mesh {mesh.name}: joint index {top} is beyond skin "
                                      f"{scene.skins[k].name!r}'s {n_joints} joints")


def _skin(ld: GltfDocument, s: int, skin: object, row_of: dict[int, int]) -> Skin:
    name = str(get(skin, "name", f"skin {s}"))
    what = f"skin {name!r}"
    n_nodes = len(ld.gltf.nodes or [])
    joints = get(skin, "joints")
    if not isinstance(joints, list) or not joints:
        raise SceneError(ld.path, f"{what}: joints must be a non-empty list of node indices")
    rows = []
    for j in joints:
        j = check_index(ld.path, j, n_nodes, f"{what} joint")
        if j not in row_of:
            raise SceneError(ld.path, f"{what}: joint node {j} is not in the displayed scene")
        rows.append(row_of[j])
    inverse = np.tile(np.eye(4), (len(rows), 1, 1))
    if get(skin, "inverseBindMatrices") is not None:
        arr, _ = ld.accessor(get(skin, "inverseBindMatrices"))
        if arr.dtype != np.float32 or arr.shape[1] != 16 or len(arr) < len(rows):
            raise SceneError(ld.path, f"{what}: inverseBindMatrices must be {len(rows)} float "
                                      f"MAT4, got {len(arr)} of {arr.shape[1]} {arr.dtype}")
        # Column-major in the file: reshape row-major, then transpose each matrix.
        inverse = arr[:len(rows)].astype(np.float64).reshape(-1, 4, 4).transpose(0, 2, 1)
        if not np.isfinite(inverse).all():
            raise SceneError(ld.path, f"{what}: inverseBindMatrices has non-finite values")
    skeleton = get(skin, "skeleton")
    if skeleton is not None:
        skeleton = row_of.get(check_index(ld.path, skeleton, n_nodes, f"{what} skeleton"))
    return Skin(name, np.asarray(rows, np.int64), np.ascontiguousarray(inverse), skeleton)


def build_animations(ld: GltfDocument, scene: Scene, links: NodeLinks) -> None:
    """scene.animations, every animation of the file in order (even one whose channels all
    target nodes outside the displayed scene: its names and indices stay the file's)."""
    unsupported: list[str] = []
    animations = ld.doc.get("animations") or []
    if not isinstance(animations, list):
        raise SceneError(ld.path, "animations must be a list")
    shared = (_row_of(ld, scene), _target_counts(ld, links))
    for a, anim in enumerate(animations):
        if not isinstance(anim, dict):
            raise SceneError(ld.path, f"animation {a} is not an object")
        scene.animations.append(_Reader(ld, scene, links, shared, a, anim, unsupported).animation())
    if unsupported:
        shown = ", ".join(sorted(set(unsupported))[:4])
        more = len(set(unsupported)) - 4
        warnings.warn(f"{ld.path}: animation pointers vkpbr does not animate are ignored: "
                      f"{shown}{f' and {more} more' if more > 0 else ''}", stacklevel=4)


class _Reader:
    """One animation's channels and the samplers they use (renumbered in file order)."""

    def __init__(self, ld: GltfDocument, scene: Scene, links: NodeLinks,
                 shared: tuple[dict[int, int], dict[int, int]], a: int, anim: dict,
                 unsupported: list[str]) -> None:
        self.ld, self.scene, self.links, self.anim = ld, scene, links, anim
        self.name = str(anim.get("name") or f"animation {a}")
        self.what = f"animation {self.name!r}"
        self.unsupported = unsupported
        self.row_of, self.counts = shared  # glTF node -> tree row; mesh -> target count
        self.samplers = anim.get("samplers") or []
        if not isinstance(self.samplers, list):
            raise SceneError(ld.path, f"{self.what}: samplers must be a list")
        self.used: dict[int, tuple[int, AnimationSampler]] = {}  # file sampler -> (new, parsed)

    def fail(self, problem: str) -> SceneError:
        return SceneError(self.ld.path, f"{self.what}: {problem}")

    def animation(self) -> Animation:
        channels = self.anim.get("channels") or []
        if not isinstance(channels, list):
            raise self.fail("channels must be a list")
        out = [c for k, ch in enumerate(channels) if (c := self.channel(k, ch)) is not None]
        samplers = [s for _, s in sorted(self.used.values(), key=lambda v: v[0])]
        return Animation(self.name, out, samplers)

    def channel(self, k: int, ch: object) -> AnimationChannel | None:
        target = get(ch, "target")
        if not isinstance(ch, dict) or not isinstance(target, dict):
            raise self.fail(f"channel {k} has no target object")
        path = target.get("path")
        if path == "pointer":
            pointer = ext(target, "KHR_animation_pointer").get("pointer")
            if not isinstance(pointer, str):
                raise self.fail(f"channel {k}: path 'pointer' without a KHR_animation_pointer "
                                "pointer string")
            return self.pointer_channel(k, ch, pointer)
        if path not in _NODE_PATHS:
            self.unsupported.append(f"path {path!r}")
            return None
        if target.get("node") is None:
            return None  # the spec: no node, the channel is ignored (an extension may use it)
        return self.node_channel(k, ch, target.get("node"), path, None)

    def node_channel(self, k: int, ch: dict, node: object, path: str,
                     pointer: str | None) -> AnimationChannel | None:
        i = check_index(self.ld.path, node, len(self.ld.gltf.nodes or []),
                        f"{self.what} channel {k} target node")
        row = self.row_of.get(i)
        if row is None:
            return None  # animates a node of another scene: nothing shown moves
        assert self.scene.tree is not None
        if self.scene.tree.uses_matrix[row]:
            raise self.fail(f"channel {k} animates node {i}, which gives a matrix (the spec "
                            "allows only TRS nodes as targets)")
        n = _NODE_PATHS[path]
        if path == "weights":
            n = self.counts.get(get(self.ld.gltf.nodes[i], "mesh"), 0)
            if not n:
                raise self.fail(f"channel {k} animates the weights of node {i}, whose mesh has "
                                "no morph targets")
        sampler = self.sampler(k, ch, n)
        return AnimationChannel(sampler, path, node=row, pointer=pointer)

    def pointer_channel(self, k: int, ch: dict, pointer: str) -> AnimationChannel | None:
        if m := _NODE_POINTER.fullmatch(pointer):
            return self.node_channel(k, ch, int(m.group(1)), m.group(2), pointer)
        for pattern, kind, member, n in POINTER_TARGETS:
            if m := pattern.fullmatch(pointer):
                index = int(m.group(1))
                targets = self.pointer_targets(k, kind, index)
                if kind == "mesh":
                    n = self.counts.get(index, 0)
                    if not n:
                        return None  # a mesh not shown (or without targets): nothing moves
                sampler = self.sampler(k, ch, n)
                return AnimationChannel(sampler, "pointer", pointer=pointer, kind=kind,
                                        index=index, member=member, targets=targets,
                                        rest=self.rest_value(pointer, member, n))
        self.unsupported.append(pointer)
        return None

    def rest_value(self, pointer: str, member: str, n: int) -> np.ndarray:
        """(n,) the file's value at `pointer` (a JSON pointer into the document), else the
        property's glTF default: what the property holds when no animation plays."""
        value: object = self.ld.doc
        for part in pointer.split("/")[1:]:
            part = part.replace("~1", "/").replace("~0", "~")
            if isinstance(value, list) and part.isdigit() and int(part) < len(value):
                value = value[int(part)]
            elif isinstance(value, dict) and part in value:
                value = value[part]
            else:
                value = _POINTER_DEFAULTS.get(member, 0.0)
                break
        try:
            out = np.broadcast_to(np.asarray(value, np.float64).reshape(-1), (n,)).copy()
        except (TypeError, ValueError):
            raise self.fail(f"{pointer}: the file's value {value!r} is not {n} numbers") from None
        if not np.isfinite(out).all():
            raise self.fail(f"{pointer}: the file's value is not finite")
        return out

    def pointer_targets(self, k: int, kind: str, index: int) -> tuple[int, ...]:
        """The scene objects made from file object `index` of `kind`; SceneError when the
        file has no such object."""
        ld, links = self.ld, self.links
        count = {"material": len(ld.gltf.materials or []), "camera": len(ld.gltf.cameras or []),
                 "mesh": len(ld.gltf.meshes or []),
                 "light": len(ext(ld.doc, "KHR_lights_punctual").get("lights") or [])}[kind]
        check_index(ld.path, index, count, f"{self.what} channel {k} pointer {kind}")
        if kind == "material":
            return (index,)
        made = {"light": links.lights, "camera": links.cameras}.get(kind)
        if made is not None:
            return tuple(j for j, src in enumerate(made) if src == index)
        return tuple(links.mesh_nodes.get(index, ()))

    def sampler(self, k: int, ch: dict, n: int) -> int:
        """The new index of channel k's sampler, parsed with `n` components a keyframe."""
        s = check_index(self.ld.path, ch.get("sampler"), len(self.samplers),
                        f"{self.what} channel {k} sampler")
        if s in self.used:
            new, parsed = self.used[s]
            if parsed.output.shape[-1] != n:
                raise self.fail(f"sampler {s} drives channels of {parsed.output.shape[-1]} and "
                                f"{n} components")
            return new
        parsed = self.parse_sampler(s, n)
        self.used[s] = (len(self.used), parsed)
        return len(self.used) - 1

    def parse_sampler(self, s: int, n: int) -> AnimationSampler:
        """Sampler s: times strictly increasing, finite, >= 0; output count = input count x
        (3 for CUBICSPLINE) x n values, finite."""
        smp = self.samplers[s]
        what = f"sampler {s}"
        if not isinstance(smp, dict):
            raise self.fail(f"{what} is not an object")
        interp = smp.get("interpolation", "LINEAR")
        if interp not in _INTERPOLATIONS:
            raise self.fail(f"{what}: unknown interpolation {interp!r}")
        arr, normalized = self.ld.accessor(smp.get("input"))
        if arr.shape[1] != 1 or not len(arr):
            raise self.fail(f"{what}: input must be a non-empty SCALAR accessor")
        times = to_float(arr, normalized).astype(np.float64).reshape(-1)
        if not np.isfinite(times).all() or times[0] < 0:
            raise self.fail(f"{what}: keyframe times must be finite and >= 0")
        step = np.diff(times)
        if (step <= 0).any():
            j = int(np.argmax(step <= 0))
            raise self.fail(f"{what}: keyframe times are not increasing (time {j + 1} is "
                            f"{times[j + 1]:g} after {times[j]:g})")
        arr, normalized = self.ld.accessor(smp.get("output"))
        values = to_float(arr, normalized).astype(np.float64).reshape(-1)
        per = 3 if interp == "CUBICSPLINE" else 1
        if values.size != len(times) * per * n:
            raise self.fail(f"{what}: output has {values.size} values, expected {len(times)} "
                            f"keyframes x {per} x {n}")
        if not np.isfinite(values).all():
            raise self.fail(f"{what}: output has non-finite values")
        shape = (len(times), 3, n) if per == 3 else (len(times), n)
        return AnimationSampler(times, values.reshape(shape), interp)
