# The COMP5822M baked mesh file (*.comp5822mesh), renderer-spec section 5, little-endian:
#   16 B magic "\0\0COMP5822Mmesh" | 16 B variant ("default", NUL padded)
#   u32 T, T x (u32 len incl. NUL, path bytes + NUL (relative to the file's folder), u8 channels)
#   u32 M, M x 5 u32 texture ids (base colour, roughness, metalness, alpha mask, normal; ~0 none)
#   u32 N, N x (u32 material, u32 V, u32 I, V x vec3 pos, V x vec3 normal, V x vec2 uv, I x u32)
# Texture coordinates are stored as vkpbr holds them (glTF top-left origin), so a round trip is
# bit-exact. The reader checks every length against the bytes left before allocating anything.

from __future__ import annotations

import os
import struct
from pathlib import Path

import numpy as np

from vkpbr.atomic import atomic_writer
from vkpbr.errors import SceneError
from vkpbr.scene.geometry import ensure_normals
from vkpbr.scene.resources import ResourcePolicy, policy_image, read_resource
from vkpbr.scene.types import Image, Material, Mesh, Node, Scene, TextureRef

__all__ = ["MAGIC", "VARIANT", "read_comp5822mesh", "write_comp5822mesh"]

# "\0\0COMP5822Mmesh" is 15 characters; the 16th byte is the C string literal's own NUL.
MAGIC = b"\0\0COMP5822Mmesh\0"
VARIANT = b"default".ljust(16, b"\0")
_NONE = 0xFFFFFFFF


class _Reader:
    """A cursor over the file's bytes that refuses to read past the end."""

    def __init__(self, path: Path, data: bytes) -> None:
        self.path, self.data, self.pos = path, data, 0

    def take(self, n: int, what: str) -> bytes:
        if n < 0 or self.pos + n > len(self.data):
            raise SceneError(
                self.path, f"truncated file: {what} at byte {self.pos} needs {n} bytes"
            )
        self.pos += n
        return self.data[self.pos - n : self.pos]

    def u32(self, what: str) -> int:
        return struct.unpack("<I", self.take(4, what))[0]

    def array(self, dtype: str, shape: tuple[int, ...], what: str) -> np.ndarray:
        n = int(np.prod(shape))
        raw = self.take(n * np.dtype(dtype).itemsize, what)
        return np.frombuffer(raw, dtype).reshape(shape).astype(dtype[1:])  # native, writable copy


def read_comp5822mesh(path: str | Path, policy: ResourcePolicy | None = None) -> Scene:
    """Read a .comp5822mesh file. `policy`: where its texture files may lie (default: the
    file's folder tree; a texture outside it is reported and replaced like a missing one).

    Returns
    -------
    Scene with one Mesh per stored mesh (positions/normals (V, 3), texcoords (V, 2) float32,
    indices (I,) uint32) and one identity Node each; materials reference scalar maps through
    channel 0 and masked materials (alpha-mask id set) use `Material.alpha_texture`.

    Raises
    ------
    SceneError : bad magic or variant, truncation, out-of-range ids or indices.
    """
    path = Path(path)
    try:
        r = _Reader(path, read_resource(path))
    except OSError as exc:
        raise SceneError(path, f"cannot read: {exc.strerror or exc}") from exc
    if r.take(16, "magic") != MAGIC:
        raise SceneError(path, "not a .comp5822mesh file (bad magic)")
    variant = r.take(16, "variant")
    if variant != VARIANT:
        shown = variant.split(b"\0", 1)[0].decode("ascii", "replace")
        raise SceneError(path, f"unsupported variant {shown!r} (expected 'default')")
    scene = Scene(name=path.stem, source=path)
    policy = policy or ResourcePolicy(path)
    n_tex = r.u32("texture count")
    if n_tex * 6 > len(r.data) - r.pos:  # each texture needs >= 6 bytes: fail before looping
        raise SceneError(path, f"truncated file: texture count {n_tex} is too large")
    for t in range(n_tex):
        length = r.u32(f"texture {t} path length")
        raw = r.take(length, f"texture {t} path")
        if length == 0 or raw[-1:] != b"\0" or b"\0" in raw[:-1]:
            raise SceneError(path, f"texture {t}: path is not a NUL-terminated string")
        channels = r.take(1, f"texture {t} channels")[0]
        if not 1 <= channels <= 4:
            raise SceneError(path, f"texture {t}: channel count {channels} not in 1..4")
        try:
            rel = raw[:-1].decode("utf-8")
        except UnicodeDecodeError as exc:
            raise SceneError(path, f"texture {t}: path is not UTF-8") from exc
        # A missing file: load_scene reports all of them in one line.
        scene.images.append(policy_image(policy, rel))

    n_mat = r.u32("material count")
    if n_mat * 20 > len(r.data) - r.pos:
        raise SceneError(path, f"truncated file: material count {n_mat} is too large")
    ids = r.array("<u4", (n_mat, 5), "material table")
    bad = (ids != _NONE) & (ids >= n_tex)
    if bad.any():
        raise SceneError(path, f"material {int(np.argwhere(bad)[0][0])}: texture id out of range")
    for m, row in enumerate(ids.tolist()):
        scene.materials.append(_material(m, row))

    n_mesh = r.u32("mesh count")
    if n_mesh * 12 > len(r.data) - r.pos:
        raise SceneError(path, f"truncated file: mesh count {n_mesh} is too large")
    for k in range(n_mesh):
        material, nv, ni = (r.u32(f"mesh {k} header") for _ in range(3))
        if material != _NONE and material >= n_mat:
            raise SceneError(path, f"mesh {k}: material {material} out of range")
        if nv * 32 + ni * 4 > len(r.data) - r.pos:  # before allocating: absurd counts fail here
            raise SceneError(path, f"truncated file: mesh {k} needs {nv} vertices, {ni} indices")
        positions = r.array("<f4", (nv, 3), f"mesh {k} positions")
        normals = r.array("<f4", (nv, 3), f"mesh {k} normals")
        texcoords = r.array("<f4", (nv, 2), f"mesh {k} texcoords")
        indices = r.array("<u4", (ni,), f"mesh {k} indices")
        if ni % 3:
            raise SceneError(path, f"mesh {k}: index count {ni} is not a multiple of 3")
        if ni and int(indices.max()) >= nv:
            raise SceneError(path, f"mesh {k}: index {int(indices.max())} >= vertex count {nv}")
        scene.nodes.append(Node(mesh=len(scene.meshes), name=f"mesh {k}"))
        scene.meshes.append(
            Mesh(
                f"mesh {k}",
                positions,
                indices,
                normals,
                texcoords,
                material=-1 if material == _NONE else material,
            )  # fmt: skip
        )
    if r.pos != len(r.data):
        raise SceneError(path, f"{len(r.data) - r.pos} unexpected trailing bytes")
    return scene


def _material(m: int, ids: list[int]) -> Material:
    """Five texture ids -> Material. Factors are not stored: textures carry the values, and a
    material without a metalness map is a dielectric (metallic 0)."""

    def ref(i: int) -> TextureRef | None:
        return None if i == _NONE else TextureRef(image=i, channel=0)

    base, rough, metal, alpha, normal = ids
    mat = Material(
        name=f"material {m}",
        metallic_factor=1.0 if metal != _NONE else 0.0,
        base_color_texture=ref(base),
        roughness_texture=ref(rough),
        metallic_texture=ref(metal),
        normal_texture=ref(normal),
        alpha_texture=ref(alpha),
    )
    if alpha != _NONE:
        mat.alpha_mode, mat.alpha_cutoff, mat.double_sided = "mask", 0.5, True
    return mat


def _channels(image: Image) -> int:
    """Channel count of an image for the texture table (read from the header, not decoded)."""
    if image.pixels is not None:
        return int(image.pixels.shape[2]) if image.pixels.ndim == 3 else 1
    if image.refused or image.path is None:
        return 4  # the path policy refused it: never opened
    try:
        import io

        from PIL import Image as PILImage

        # read_resource: regular files only (a FIFO named as a texture must not block).
        with PILImage.open(io.BytesIO(read_resource(image.path))) as img:
            return max(1, min(4, len(img.getbands())))
    except (OSError, ValueError):
        return 4


def write_comp5822mesh(scene: Scene, path: str | Path) -> None:
    """Write `scene` as a .comp5822mesh file, atomically (temp file + os.replace).

    Every node becomes one stored mesh; a non-identity node matrix is baked into positions and
    normals. Missing normals are generated (flat), missing texcoords written as zeros.

    Raises
    ------
    SceneError : the scene cannot be expressed in the format (an image without a file path, a
        scalar map read from a channel other than 0, such as glTF's packed metal-roughness).
    """
    path = Path(path)
    folder = path.parent.resolve()
    out = [MAGIC, VARIANT, struct.pack("<I", len(scene.images))]
    for i, img in enumerate(scene.images):
        if img.path is None:
            raise SceneError(path, f"image {i} ({img.name}) has no file path; cannot be stored")
        rel = os.path.relpath(Path(img.path).resolve(), folder).replace(os.sep, "/")
        raw = rel.encode("utf-8") + b"\0"
        out += [struct.pack("<I", len(raw)), raw, bytes([_channels(img)])]
    out.append(struct.pack("<I", len(scene.materials)))
    for m, mat in enumerate(scene.materials):
        refs = (mat.base_color_texture, mat.roughness_texture, mat.metallic_texture,
                mat.alpha_texture, mat.normal_texture)  # fmt: skip
        for ref in refs[1:4]:
            if ref is not None and ref.channel != 0:
                raise SceneError(path, f"material {m}: scalar map in channel {ref.channel}; "
                                 "the format reads channel 0 only (split the texture first)")  # fmt: skip
        out.append(np.array([_NONE if t is None else t.image for t in refs], "<u4").tobytes())
    out.append(struct.pack("<I", len(scene.nodes)))
    for node in scene.nodes:
        mesh = ensure_normals(scene.meshes[node.mesh])
        positions, normals = mesh.positions, mesh.normals
        m = np.asarray(node.matrix, np.float64)
        if not np.array_equal(m, np.eye(4)):
            positions = positions @ m[:3, :3].T + m[:3, 3]
            normals = normals @ np.linalg.inv(m[:3, :3])  # inverse-transpose, row vectors
            normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-20)
        nv = len(positions)
        tex = mesh.texcoords if mesh.texcoords is not None else np.zeros((nv, 2), np.float32)
        material = _NONE if mesh.material < 0 else mesh.material
        out += [
            struct.pack("<III", material, nv, len(mesh.indices)),
            *(np.ascontiguousarray(a, dt).tobytes() for a, dt in
              ((positions, "<f4"), (normals, "<f4"), (tex, "<f4"), (mesh.indices, "<u4"))),
        ]  # fmt: skip
    with atomic_writer(path) as f:  # readers never see a half-written file
        f.writelines(out)
