# The glTF node hierarchy flattened into world matrices, and what hangs off nodes: mesh
# instances (primitives decoded on first use, gltf_meshes), perspective cameras and
# KHR_lights_punctual lights; EXT_mesh_gpu_instancing's per-instance transforms (Node.instances,
# the mesh kept once). Reference: glTF 2.0 spec 3.5 (nodes and hierarchy), 3.10 (cameras);
# KHR_lights_punctual; EXT_mesh_gpu_instancing.

from __future__ import annotations

import math
import warnings

import numpy as np

from vkpbr.errors import SceneError
from vkpbr.scene.gltf_document import GltfDocument, check_index, ext, floats, get, scalar
from vkpbr.scene.gltf_meshes import primitive
from vkpbr.scene.tree import NodeTree
from vkpbr.scene.types import Camera, Light, Node, Scene

__all__ = ["NodeLinks", "build_nodes_cameras_lights", "instance_matrices", "trs_matrix"]


class NodeLinks:
    """Which file objects the walk made scene objects from (what animation pointers need):
    `lights[k]` the KHR_lights_punctual index of scene.lights[k], `cameras[k]` the glTF camera
    index of scene.cameras[k], `mesh_nodes[m]` the tree nodes showing glTF mesh m."""

    def __init__(self) -> None:
        self.lights: list[int] = []
        self.cameras: list[int] = []
        self.mesh_nodes: dict[int, list[int]] = {}


def trs_matrix(t: tuple, r: tuple, s: tuple) -> np.ndarray:
    """T * R * S as a (4, 4) float64 matrix; r is a quaternion (x, y, z, w), renormalised."""
    x, y, z, w = r
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = (x / norm, y / norm, z / norm, w / norm) if norm > 1e-12 else (0, 0, 0, 1)
    rot = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    m = np.eye(4)
    m[:3, :3] = rot * np.asarray(s)  # scales columns: R @ diag(s)
    m[:3, 3] = t
    return m


def instance_matrices(ld: GltfDocument, i: int, node: object) -> np.ndarray | None:
    """A node's EXT_mesh_gpu_instancing transforms as (K, 4, 4) float32 T * R * S matrices
    (relative to the node's world matrix), None without the extension.

    TRANSLATION, ROTATION (a quaternion x, y, z, w; renormalised) and SCALE are each optional
    accessors of one common count; integer ones are dequantised as their `normalized` flag says
    (KHR_mesh_quantization).
    """
    info = ext(node, "EXT_mesh_gpu_instancing")
    attrs = get(info, "attributes")
    if not info:
        return None
    if not isinstance(attrs, dict):
        raise SceneError(ld.path, f"node {i}: EXT_mesh_gpu_instancing has no attributes object")
    what = f"node {i} EXT_mesh_gpu_instancing"
    parts = {key: ld.attribute(attrs[key], (n,), f"{what} {key}") for key, n in
             (("TRANSLATION", 3), ("ROTATION", 4), ("SCALE", 3)) if attrs.get(key) is not None}
    if not parts:
        return None  # only custom (_ID...) attributes: nothing that moves an instance
    counts = {key: len(a) for key, a in parts.items()}
    if len(set(counts.values())) != 1:
        raise SceneError(ld.path, f"{what}: attribute counts differ ({counts})")
    k = next(iter(counts.values()))
    t = parts.get("TRANSLATION", np.zeros((k, 3), np.float32)).astype(np.float64)
    q = parts.get("ROTATION", np.tile(np.float32([0, 0, 0, 1]), (k, 1))).astype(np.float64)
    sc = parts.get("SCALE", np.ones((k, 3), np.float32)).astype(np.float64)
    norm = np.linalg.norm(q, axis=1, keepdims=True)
    q = np.where(norm > 1e-12, q / np.maximum(norm, 1e-300), np.float64([0, 0, 0, 1]))
    x, y, z, w = q.T
    rot = np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], axis=1)  # (k, 3 rows, 3 columns), the same matrix as trs_matrix
    out = np.zeros((k, 4, 4))
    out[:, :3, :3] = rot * sc[:, None, :]  # R @ diag(s): scales columns
    out[:, :3, 3] = t
    out[:, 3, 3] = 1.0
    out = out.astype(np.float32)
    if not np.isfinite(out).all():
        raise SceneError(ld.path, f"{what}: non-finite instance transform")
    out.setflags(write=False)
    return out


def _local_transform(ld: GltfDocument, i: int, node: object
                     ) -> tuple[np.ndarray, tuple, tuple, tuple, bool]:
    """A node's local matrix, its TRS (identity for a matrix node) and whether it gives a
    matrix (glTF: a node gives TRS or a matrix; only TRS nodes are animated)."""
    matrix = get(node, "matrix")
    if matrix is not None and len(matrix) and list(matrix) != [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]:  # fmt: skip
        # glTF stores matrices column-major; numpy reshape is row-major, hence .T
        m = np.asarray(floats(matrix, 16, (), f"node {i} matrix", ld.path)).reshape(4, 4).T
        return m, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), (1.0, 1.0, 1.0), True
    t = floats(get(node, "translation"), 3, (0.0, 0.0, 0.0), f"node {i} translation", ld.path)
    r = floats(get(node, "rotation"), 4, (0.0, 0.0, 0.0, 1.0), f"node {i} rotation", ld.path)
    s = floats(get(node, "scale"), 3, (1.0, 1.0, 1.0), f"node {i} scale", ld.path)
    return trs_matrix(t, r, s), t, r, s, False


def _root_nodes(ld: GltfDocument, n_nodes: int) -> list[object]:
    scenes = ld.gltf.scenes or []
    if scenes:
        chosen = get(ld.doc, "scene", 0)
        return list(get(scenes[check_index(ld.path, chosen, len(scenes), "scene")], "nodes", []))
    children = {c for n in ld.gltf.nodes or [] for c in (get(n, "children", []) or [])}
    return [i for i in range(n_nodes) if i not in children]


def build_nodes_cameras_lights(ld: GltfDocument, scene: Scene) -> NodeLinks:
    """Walk the displayed scene's node tree: fill scene.meshes/nodes/cameras/lights and
    scene.tree (with the nodes' morph weights and skin indices)."""
    nodes = ld.gltf.nodes or []
    meshes = ld.gltf.meshes or []
    cameras = ld.gltf.cameras or []
    light_defs = ext(ld.doc, "KHR_lights_punctual").get("lights") or []
    mesh_prims: dict[int, list[int]] = {}  # glTF mesh -> indices of its primitives in scene.meshes
    pending_lights: list[tuple[int, np.ndarray]] = []
    links = NodeLinks()
    stack = [
        (check_index(ld.path, r, len(nodes), "root node"), np.eye(4), -1)
        for r in _root_nodes(ld, len(nodes))
    ][::-1]  # reversed: the stack pops them in document order (nodes, lights keep file order)
    seen: set[int] = set()
    tree = _TreeRows()
    while stack:
        i, parent, parent_row = stack.pop()
        if i in seen:
            raise SceneError(ld.path, f"node {i} is reached twice (cycle or shared child)")
        seen.add(i)
        node = nodes[i]
        local, *trs = _local_transform(ld, i, node)
        world = parent @ local
        name = str(get(node, "name", f"node {i}"))
        row = tree.add(name, parent_row, local, trs, i)
        _morph_and_skin(ld, i, node, row, tree)
        for c in list(get(node, "children", []) or [])[::-1]:
            stack.append((check_index(ld.path, c, len(nodes), f"node {i} child"), world, row))
        if get(node, "mesh") is not None:
            m = check_index(ld.path, get(node, "mesh"), len(meshes), f"node {i} mesh")
            links.mesh_nodes.setdefault(m, []).append(row)
            if m not in mesh_prims:
                mesh_prims[m] = []
                for k, prim in enumerate(get(meshes[m], "primitives", [])):
                    mesh_prims[m].append(len(scene.meshes))
                    scene.meshes.append(primitive(ld, m, k, prim))
            w32 = world.astype(np.float32)
            inst = instance_matrices(ld, i, node)
            label = _semantic_extra(node)
            label = _semantic_extra(meshes[m]) if label is None else label
            scene.nodes += [Node(mesh=j, matrix=w32.copy(), name=name, instances=inst,
                                 semantic=label, tree=row)
                            for j in mesh_prims[m]]  # primitives share the read-only array
        if get(node, "camera") is not None:
            c = check_index(ld.path, get(node, "camera"), len(cameras), "camera")
            if _add_camera(ld, scene, cameras[c], world, name):
                links.cameras.append(c)
        ext_light = ext(node, "KHR_lights_punctual").get("light")
        if ext_light is not None:
            pending_lights.append((check_index(ld.path, ext_light, len(light_defs), "light"), world))
    for light, world in pending_lights:  # after the meshes, in file order
        scene.lights.append(_light(ld, scene, light_defs[light], world))
        links.lights.append(light)
    scene.tree = tree.tree()
    return links


def _morph_and_skin(ld: GltfDocument, i: int, node: object, row: int, tree: _TreeRows) -> None:
    """A node's own morph weights (glTF node `weights`) and skin index, on its tree row."""
    weights = get(ld.doc["nodes"][i], "weights")  # pygltflib's Node drops `weights`
    if weights is not None:
        if not isinstance(weights, list):
            raise SceneError(ld.path, f"node {i}: weights must be a list of numbers")
        tree.weights[row] = np.asarray(floats(weights, len(weights), (), f"node {i} weights",
                                              ld.path), np.float64)
    if get(node, "skin") is not None:
        tree.skin[row] = check_index(ld.path, get(node, "skin"), len(ld.gltf.skins or []),
                                     f"node {i} skin")


class _TreeRows:
    """The displayed scene's nodes as the walk meets them (parents first): NodeTree rows."""

    def __init__(self) -> None:
        self.names: list[str] = []
        self.parents: list[int] = []
        self.local: list[np.ndarray] = []
        self.trs: list[tuple] = []
        self.source: list[int] = []
        self.weights: dict[int, np.ndarray] = {}
        self.skin: dict[int, int] = {}

    def add(self, name: str, parent: int, local: np.ndarray, trs: list, source: int) -> int:
        self.names.append(name)
        self.parents.append(parent)
        self.local.append(local)
        self.trs.append(trs)
        self.source.append(source)
        return len(self.names) - 1

    def tree(self) -> NodeTree:
        k = len(self.names)
        t, r, s, m = ([row[j] for row in self.trs] for j in range(4))
        return NodeTree(self.names, np.asarray(self.parents, np.int64),
                        np.asarray(self.local, np.float64).reshape(k, 4, 4),
                        np.asarray(t, np.float64).reshape(k, 3), np.asarray(r, np.float64).reshape(k, 4),
                        np.asarray(s, np.float64).reshape(k, 3), np.asarray(m, bool).reshape(k),
                        np.asarray(self.source, np.int64).reshape(k), self.weights, self.skin)


def _add_camera(ld: GltfDocument, scene: Scene, cam: object, world: np.ndarray, name: str) -> bool:
    """A perspective camera node -> Camera (True), other kinds ignored with a warning (False).
    The file's znear is kept; a camera without zfar (glTF's infinite projection) gets zfar
    None, as the renderer's far plane is infinite."""
    if get(cam, "type") != "perspective" or get(cam, "perspective") is None:
        warnings.warn(f"{ld.path}: {get(cam, 'type')} camera {name!r} ignored", stacklevel=5)
        return False
    persp = get(cam, "perspective")
    yfov = scalar(get(persp, "yfov"), 0.8, "camera yfov", ld.path)
    znear = None if get(persp, "znear") is None else scalar(get(persp, "znear"), 0.0, "camera znear", ld.path)
    zfar = None if get(persp, "zfar") is None else scalar(get(persp, "zfar"), 0.0, "camera zfar", ld.path)
    if not 0 < yfov < math.pi:
        raise SceneError(ld.path, f"camera {name!r}: yfov {yfov} is not in (0, pi)")
    if znear is not None and znear <= 0:
        raise SceneError(ld.path, f"camera {name!r}: znear {znear} must be > 0")
    if zfar is not None and not zfar > (znear or 0.0):
        # The spec requires zfar > znear. Nothing is clipped at zfar any more (it only scales
        # the depth view), so an invalid one is dropped rather than failing the whole scene.
        zfar = None
    eye = world[:3, 3]
    forward = -world[:3, 2] / max(np.linalg.norm(world[:3, 2]), 1e-12)  # cameras look down -Z
    up = world[:3, 1] / max(np.linalg.norm(world[:3, 1]), 1e-12)
    scene.cameras.append(
        Camera(
            eye=tuple(map(float, eye)),
            target=tuple(map(float, eye + forward)),
            up=tuple(map(float, up)),
            yfov_deg=math.degrees(yfov),
            znear=znear,
            zfar=zfar,
            name=name,
        )
    )
    return True


def _light(ld: GltfDocument, scene: Scene, light: dict, world: np.ndarray) -> Light:
    """KHR_lights_punctual light at a node's world transform: the light shines along the
    node's -Z; spot cones and range as the extension defines them."""
    kind = get(light, "type", "point")
    if kind not in ("point", "spot", "directional"):
        raise SceneError(ld.path, f"unknown light type {kind!r}")
    color = floats(get(light, "color"), 3, (1.0, 1.0, 1.0), "light color", ld.path)
    intensity = scalar(get(light, "intensity"), 1.0, "light intensity", ld.path)
    light_range = scalar(get(light, "range"), 0.0, "light range", ld.path)
    axis = -world[:3, 2]
    norm = float(np.linalg.norm(axis))
    direction = tuple(map(float, axis / norm)) if norm > 1e-12 else (0.0, 0.0, -1.0)
    inner, outer = 0.0, math.pi / 4
    if kind == "spot":
        spot = get(light, "spot", {})
        if not isinstance(spot, dict):
            raise SceneError(ld.path, f"light 'spot' must be an object, got {spot!r}")
        inner = scalar(get(spot, "innerConeAngle"), 0.0, "spot innerConeAngle", ld.path)
        outer = scalar(get(spot, "outerConeAngle"), math.pi / 4, "spot outerConeAngle", ld.path)
        if not 0.0 <= inner < outer <= math.pi / 2:
            raise SceneError(ld.path, f"spot light cone: need 0 <= innerConeAngle ({inner:g}) < "
                             f"outerConeAngle ({outer:g}) <= pi/2")
    return Light(
        position=tuple(map(float, world[:3, 3])),
        color=color,
        intensity=intensity,
        falloff="inverse_square",
        range=0.0 if kind == "directional" else light_range,
        kind=kind,
        direction=direction,
        inner_cone=inner,
        outer_cone=outer,
    )


def _semantic_extra(obj: object) -> int | str | None:
    """`extras: {"semantic": ...}` of a glTF node or mesh: a non-negative integer or a
    non-empty label; anything else is ignored (extras are free-form application data)."""
    extras = get(obj, "extras")
    value = extras.get("semantic") if isinstance(extras, dict) else None
    if isinstance(value, bool):
        return None
    if isinstance(value, int) and 0 <= value < 2**32:
        return value
    if isinstance(value, str) and value.strip():
        return value.strip()
    return None
