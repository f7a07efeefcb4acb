# An independent NumPy evaluation of glTF 2.0 animation, skinning and morphing, written from
# the specification (3.5 nodes, 3.7.2.2 morph targets, 3.7.3 skins, 3.11 animations,
# Appendix C interpolation) for the tests. It imports nothing of vkpbr's loader or sampler:
# `RefDocument` reads the JSON and buffers itself, and every formula is derived afresh
# (slerp as q0 (q0^-1 q1)^u through axis and angle rather than the spec's sine weights,
# rotation matrices by rotating the basis vectors with q v q*, the Hermite basis from its
# four end conditions). Loops over times and nodes are fine here: it is a reference.
#
# `posed_vertices(scene, node_index, pose)` applies these rules to a loaded vkpbr Scene and a
# vkpbr Pose (the data, not the code): the GPU deformation step's tests compare with it.

from __future__ import annotations

import base64
import bisect
import json
import math
import struct
from pathlib import Path

import numpy as np

__all__ = ["RefDocument", "hermite", "posed_vertices", "quat_to_matrix", "slerp"]

_DTYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


# --- quaternions ------------------------------------------------------------------------------

def qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of quaternions stored (x, y, z, w)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz])


def qconj(q: np.ndarray) -> np.ndarray:
    return np.array([-q[0], -q[1], -q[2], q[3]])


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """3x3 rotation of unit quaternion q: column i is q e_i q*."""
    q = np.asarray(q, np.float64) / np.linalg.norm(q)
    cols = [qmul(qmul(q, np.array([*e, 0.0])), qconj(q))[:3] for e in np.eye(3)]
    return np.stack(cols, axis=1)


def slerp(q0: np.ndarray, q1: np.ndarray, u: float) -> np.ndarray:
    """q0 (q0^-1 q1)^u along the shorter arc, normalised (the power through axis and angle)."""
    q0 = q0 / np.linalg.norm(q0)
    q1 = q1 / np.linalg.norm(q1)
    if np.dot(q0, q1) < 0:
        q1 = -q1
    rel = qmul(qconj(q0), q1)
    half = math.atan2(float(np.linalg.norm(rel[:3])), float(rel[3]))
    if half < 1e-9:
        out = (1 - u) * q0 + u * q1
    else:
        axis = rel[:3] / np.linalg.norm(rel[:3])
        out = qmul(q0, np.array([*(axis * math.sin(u * half)), math.cos(u * half)]))
    return out / np.linalg.norm(out)


def hermite(p0: np.ndarray, m0: np.ndarray, p1: np.ndarray, m1: np.ndarray, s: float) -> np.ndarray:
    """The cubic c(s) with c(0) = p0, c(1) = p1, c'(0) = m0, c'(1) = m1, by solving for its
    coefficients: c = a s^3 + b s^2 + m0 s + p0, a + b = p1 - p0 - m0, 3a + 2b = m1 - m0."""
    a = m1 - m0 - 2 * (p1 - p0 - m0)
    b = (p1 - p0 - m0) - a
    return ((a * s + b) * s + m0) * s + p0


def trs(t: np.ndarray, r: np.ndarray, s: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = quat_to_matrix(r) @ np.diag(s)
    m[:3, 3] = t
    return m


# --- the document -----------------------------------------------------------------------------

class RefDocument:
    """A .gltf (buffers as files or data URIs) or .glb read with json and struct alone."""

    def __init__(self, path: Path) -> None:
        raw = Path(path).read_bytes()
        self.bin = b""
        if raw[:4] == b"glTF":
            n = struct.unpack_from("<I", raw, 12)[0]
            self.doc = json.loads(raw[20:20 + n])
            rest = 20 + n
            if rest + 8 <= len(raw):
                m = struct.unpack_from("<I", raw, rest)[0]
                self.bin = raw[rest + 8:rest + 8 + m]
        else:
            self.doc = json.loads(raw)
        self.buffers = []
        for buf in self.doc.get("buffers", []):
            uri = buf.get("uri")
            if uri is None:
                self.buffers.append(self.bin)
            elif uri.startswith("data:"):
                self.buffers.append(base64.b64decode(uri.split(",", 1)[1]))
            else:
                self.buffers.append((Path(path).parent / uri).read_bytes())
        self.nodes = self.doc.get("nodes", [])
        self._accessors: dict[int, np.ndarray] = {}

    def accessor(self, i: int) -> np.ndarray:
        """(count, ncomp) float64, normalized integers scaled (no sparse support: not needed)."""
        if i not in self._accessors:
            self._accessors[i] = self._read(i)
        return self._accessors[i]

    def _read(self, i: int) -> np.ndarray:
        acc = self.doc["accessors"][i]
        dtype, n = np.dtype(_DTYPES[acc["componentType"]]), _NCOMP[acc["type"]]
        view = self.doc["bufferViews"][acc["bufferView"]]
        stride = view.get("byteStride") or dtype.itemsize * n
        data = self.buffers[view["buffer"]]
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        rows = [np.frombuffer(data, dtype, n, start + k * stride) for k in range(acc["count"])]
        out = np.array(rows, np.float64).reshape(acc["count"], n)
        if acc.get("normalized") and dtype.kind in "iu":
            out = np.maximum(out / np.iinfo(dtype).max, -1.0)
        return out

    # -- nodes ---------------------------------------------------------------------------------
    def rest_trs(self, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        node = self.nodes[i]
        if "matrix" in node:
            return None
        return (np.array(node.get("translation", [0, 0, 0]), float),
                np.array(node.get("rotation", [0, 0, 0, 1]), float),
                np.array(node.get("scale", [1, 1, 1]), float))

    def roots(self) -> list[int]:
        scenes = self.doc.get("scenes")
        if scenes:
            return list(scenes[self.doc.get("scene", 0)]["nodes"])
        children = {c for n in self.nodes for c in n.get("children", [])}
        return [i for i in range(len(self.nodes)) if i not in children]

    def world(self, locals_: dict[int, np.ndarray]) -> dict[int, np.ndarray]:
        """World matrices of the displayed nodes, by a recursive walk from the roots."""
        out: dict[int, np.ndarray] = {}

        def walk(i: int, parent: np.ndarray) -> None:
            out[i] = parent @ locals_[i]
            for c in self.nodes[i].get("children", []):
                walk(c, out[i])

        for r in self.roots():
            walk(r, np.eye(4))
        return out

    def morph_count(self, node: int) -> int:
        mesh = self.nodes[node].get("mesh")
        if mesh is None:
            return 0
        return len(self.doc["meshes"][mesh]["primitives"][0].get("targets", []))

    def rest_weights(self, node: int) -> np.ndarray:
        n = self.morph_count(node)
        given = self.nodes[node].get("weights")
        if given is None:
            given = self.doc["meshes"][self.nodes[node]["mesh"]].get("weights", [0.0] * n)
        return np.array(given, float)

    # -- animation -----------------------------------------------------------------------------
    def channel_value(self, anim: dict, ch: dict, t: float) -> np.ndarray:
        """Channel `ch` of `anim` at time t, per the spec's interpolation rules."""
        smp = anim["samplers"][ch["sampler"]]
        times = self.accessor(smp["input"])[:, 0]
        interp = smp.get("interpolation", "LINEAR")
        path = ch["target"]["path"]
        n = {"translation": 3, "rotation": 4, "scale": 3}.get(path)
        if n is None:
            n = self.morph_count(ch["target"]["node"])
        values = self.accessor(smp["output"]).reshape(len(times), -1, n)  # (k, 1 or 3, n)
        rotation = path == "rotation"
        key = values[:, 1] if interp == "CUBICSPLINE" else values[:, 0]
        if t <= times[0] or len(times) == 1:
            out = key[0]
        elif t >= times[-1]:
            out = key[-1]
        else:
            k = bisect.bisect_right(list(times), t) - 1
            if interp == "STEP":
                out = key[k]
            else:
                td = times[k + 1] - times[k]
                s = (t - times[k]) / td
                if interp == "CUBICSPLINE":
                    out = hermite(key[k], td * values[k, 2], key[k + 1], td * values[k + 1, 0], s)
                elif rotation:
                    out = slerp(key[k], key[k + 1], s)
                else:
                    out = (1 - s) * key[k] + s * key[k + 1]
        return out / np.linalg.norm(out) if rotation else np.array(out, float)

    def pose(self, t: float, animations: list[int] | None = None
             ) -> tuple[dict[int, np.ndarray], dict[int, tuple], dict[int, np.ndarray]]:
        """(local matrices, TRS, morph weights) of every node at time t."""
        trs_now = {i: self.rest_trs(i) for i in range(len(self.nodes))}
        trs_now = {i: None if v is None else list(v) for i, v in trs_now.items()}
        weights = {i: self.rest_weights(i) for i in range(len(self.nodes)) if self.morph_count(i)}
        anims = self.doc.get("animations", [])
        for a in range(len(anims)) if animations is None else animations:
            for ch in anims[a]["channels"]:
                node, path = ch["target"].get("node"), ch["target"]["path"]
                if node is None or path not in ("translation", "rotation", "scale", "weights"):
                    continue
                value = self.channel_value(anims[a], ch, t)
                if path == "weights":
                    weights[node] = value
                else:
                    trs_now[node][("translation", "rotation", "scale").index(path)] = value
        local = {}
        for i, v in trs_now.items():
            if v is None:
                local[i] = np.array(self.nodes[i]["matrix"], float).reshape(4, 4).T
            else:
                local[i] = trs(*v)
        return local, trs_now, weights

    def joint_matrices(self, skin: int, world: dict[int, np.ndarray]) -> np.ndarray:
        s = self.doc["skins"][skin]
        n = len(s["joints"])
        ibm = (self.accessor(s["inverseBindMatrices"]).reshape(-1, 4, 4).transpose(0, 2, 1)[:n]
               if "inverseBindMatrices" in s else np.tile(np.eye(4), (n, 1, 1)))
        return np.array([world[j] @ ibm[k] for k, j in enumerate(s["joints"])])

    def posed_primitive(self, node: int, prim: int, t: float) -> tuple[np.ndarray, np.ndarray | None]:
        """World positions and unit normals of primitive `prim` of node's mesh at time t, in
        the file's vertex order."""
        local, _, weights = self.pose(t)
        world = self.world(local)
        p = self.doc["meshes"][self.nodes[node]["mesh"]]["primitives"][prim]
        attrs = p["attributes"]
        pos = self.accessor(attrs["POSITION"])
        nrm = self.accessor(attrs["NORMAL"]) if "NORMAL" in attrs else None
        for w, target in zip(weights.get(node, []), p.get("targets", []), strict=False):
            pos = pos + w * self.accessor(target["POSITION"]) if "POSITION" in target else pos
            if nrm is not None and "NORMAL" in target:
                nrm = nrm + w * self.accessor(target["NORMAL"])
        if "skin" in self.nodes[node]:
            joints = self.joint_matrices(self.nodes[node]["skin"], world)
            ids = np.concatenate([self.accessor(attrs[k]) for k in ("JOINTS_0", "JOINTS_1")
                                  if k in attrs], 1).astype(int)
            ws = np.concatenate([self.accessor(attrs[k]) for k in ("WEIGHTS_0", "WEIGHTS_1")
                                 if k in attrs], 1)
            ws = ws / ws.sum(1, keepdims=True)
            mats = np.einsum("vk,vkij->vij", ws, joints[ids])  # sum_k w_k J_k per vertex
        else:
            mats = np.broadcast_to(world[node], (len(pos), 4, 4))
        return _apply(mats, pos, nrm)


def _apply(mats: np.ndarray, pos: np.ndarray, nrm: np.ndarray | None
           ) -> tuple[np.ndarray, np.ndarray | None]:
    """Per-vertex 4x4 matrices applied to positions (w = 1) and normals (inverse transpose)."""
    out = np.einsum("vij,vj->vi", mats[:, :3, :3], pos) + mats[:, :3, 3]
    if nrm is None:
        return out, None
    normal_mats = np.linalg.inv(mats[:, :3, :3]).transpose(0, 2, 1)
    n = np.einsum("vij,vj->vi", normal_mats, nrm)
    return out, n / np.linalg.norm(n, axis=1, keepdims=True)


# --- the reference applied to a vkpbr Scene and Pose --------------------------------------------

def _world_of(parents: np.ndarray, local: np.ndarray) -> np.ndarray:
    world = np.empty_like(local)
    for i, p in enumerate(parents):  # parents come first (NodeTree's order)
        world[i] = local[i] if p < 0 else world[p] @ local[i]
    return world


def posed_vertices(scene: object, node_index: int, pose: object) -> tuple[np.ndarray, np.ndarray]:
    """World-space posed positions and unit normals of scene.nodes[node_index] (one mesh
    primitive instance) under a vkpbr Pose of one time: morph displacements p + sum w_i d_i
    (the node's weights in pose.weights), then skinning sum_k w_k J_k p with J = world[joint]
    @ inverse_bind (the node's own transform ignored), else the node's world matrix. Returns
    ((N, 3), (N, 3)) float64 in the Mesh's vertex order. A pose of several times is refused:
    `pose.at(b)` is time b's."""
    tree = scene.node_tree()
    local = np.asarray(pose.local, np.float64)
    if local.ndim != 3:
        raise ValueError("posed_vertices takes the Pose of one time (pose.at(b) picks one)")
    node = scene.nodes[node_index]
    mesh = scene.meshes[node.mesh]
    world = _world_of(np.asarray(tree.parents), local)
    pos = mesh.positions.astype(np.float64)
    nrm = mesh.normals.astype(np.float64)
    w = pose.weights.get(node.tree)
    if w is not None:
        for i, wi in enumerate(np.asarray(w, np.float64)):
            if "POSITION" in mesh.morph_targets:
                pos = pos + wi * mesh.morph_targets["POSITION"][i]
            if "NORMAL" in mesh.morph_targets:
                nrm = nrm + wi * mesh.morph_targets["NORMAL"][i]
    skin_index = tree.skin.get(node.tree)
    if skin_index is not None and mesh.joints is not None:
        skin = scene.skins[skin_index]
        joints = np.array([world[j] @ skin.inverse_bind[k] for k, j in enumerate(skin.joints)])
        weights = mesh.weights.astype(np.float64)
        mats = np.einsum("vk,vkij->vij", weights / weights.sum(1, keepdims=True),
                         joints[mesh.joints.astype(int)])
    else:  # EXT_mesh_gpu_instancing's per-instance matrices are not applied here
        mats = np.broadcast_to(world[node.tree], (len(pos), 4, 4))
    return _apply(mats, pos, nrm)
