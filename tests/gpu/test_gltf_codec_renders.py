"""Compressed glTF renders as its uncompressed original (issue 18, "done when"): the same bumpy,
textured height field written plain, Draco-compressed (14-bit positions, 10-bit normals, 12-bit
texcoords; vertex order not preserved), meshopt-compressed (OCTAHEDRAL 8-bit normals,
EXPONENTIAL positions), with its texture as KTX2 (UASTC) or lossless WebP, and drawn through
EXT_mesh_gpu_instancing (three instances) against three explicit nodes. 96x72 on lavapipe.

Tolerances follow the codecs' precision: a Draco/meshopt vertex moves by under 1e-4 of the
object (sub-pixel here) and a normal by under 2 degrees, so pixels differ only along silhouettes
and by a few levels of shading: mean absolute difference under 1.5 levels, and 99% of pixels
within 12 levels. Lossless paths (WebP lossless, instancing vs nodes) must match exactly.
"""

from __future__ import annotations

import io
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image as PILImage

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scene"))
from gltf_files import GltfFile, grid_mesh  # noqa: E402
from test_gltf_codecs import (  # noqa: E402
    Meshopt,
    _draco_file,
    _instanced_file,
    _need,
    exp_encode,
    ktx2_bytes,
    oct_encode,
    smooth_pixels,
)

from vkpbr.scene.gltf import load_gltf  # noqa: E402
from vkpbr.scene.types import Camera, Node  # noqa: E402

SIZE = (96, 72)


def _camera(scene):  # noqa: ANN001, ANN202
    scene.cameras = [Camera(eye=(0.3, -1.2, 2.6), target=(0.0, 0.0, 0.0), yfov_deg=50.0)]
    return scene


def _render(make_renderer, path: Path, view: str | None = None) -> np.ndarray:  # noqa: ANN001
    """The frame (the default shaded view, or `view`) as int64."""
    r = make_renderer(_camera(load_gltf(path)))
    out = r.render(size=SIZE) if view is None else r.render(size=SIZE, view=view)
    return np.asarray(out).astype(np.int64)


def _close(a: np.ndarray, b: np.ndarray) -> None:
    d = np.abs(a[..., :3] - b[..., :3])
    assert d.mean() < 1.5, d.mean()
    assert np.quantile(d.max(-1), 0.99) <= 12, np.quantile(d.max(-1), 0.99)
    assert a[..., :3].std() > 10  # something was drawn


def _plain_textured(g: dict, path: Path, image: bytes, mime: str = "image/png",
                    ext: str | None = None) -> Path:
    f = GltfFile()
    attrs = {k: f.accessor(g[k]) for k in ("POSITION", "NORMAL", "TEXCOORD_0")}
    f.doc["images"] = [{"bufferView": f.view(image), "mimeType": mime}]
    f.doc["textures"] = [{"source": 0} if ext is None else {"extensions": {ext: {"source": 0}}}]
    if ext:
        f.used(ext, required=True)
    f.doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                    "metallicFactor": 0.0, "roughnessFactor": 0.6}}]
    f.node(mesh=f.mesh(attrs, f.accessor(g["indices"]), material=0))
    return f.save(path)


def _png(px: np.ndarray) -> bytes:
    buf = io.BytesIO()
    PILImage.fromarray(px, "RGBA").save(buf, "PNG")
    return buf.getvalue()


def test_draco_renders_as_original(make_renderer, tmp_path: Path) -> None:  # noqa: ANN001
    g = grid_mesh(16, seed=4)
    plain = _plain_textured(g, tmp_path / "plain.glb", _png(smooth_pixels()))
    draco, _ = _draco_file(g, tmp_path / "draco.glb", preserve_order=False)
    _close(_render(make_renderer, draco, "geometric_normal"), _render(make_renderer, plain, "geometric_normal"))


def test_meshopt_renders_as_original(make_renderer, tmp_path: Path) -> None:  # noqa: ANN001
    _need("meshoptimizer")
    g = grid_mesh(16, seed=4)
    plain = _plain_textured(g, tmp_path / "plain.glb", _png(smooth_pixels()))
    f = GltfFile()
    m = Meshopt(f)
    pos = exp_encode(g["POSITION"].reshape(-1), 18).reshape(-1, 3)
    pview = m.view(pos.tobytes(), len(pos), 12, "ATTRIBUTES", "EXPONENTIAL")
    nrm = oct_encode(g["NORMAL"].astype(np.float64), 8, 4)
    nview = m.view(nrm.tobytes(), len(nrm), 4, "ATTRIBUTES", "OCTAHEDRAL")
    uv = np.ascontiguousarray(g["TEXCOORD_0"])
    uview = m.view(uv.tobytes(), len(uv), 8, "ATTRIBUTES")
    idx = g["indices"]
    iview = m.view(idx.tobytes(), len(idx), 4, "TRIANGLES")
    f.used("KHR_mesh_quantization", required=True)
    attrs = {"POSITION": f.accessor(None, pview, ctype=5126, ncomp=3, count=len(pos)),
             "NORMAL": f.accessor(None, nview, ctype=5120, ncomp=3, count=len(nrm),
                                  normalized=True),
             "TEXCOORD_0": f.accessor(None, uview, ctype=5126, ncomp=2, count=len(uv))}
    f.doc["images"] = [{"bufferView": f.view(_png(smooth_pixels())), "mimeType": "image/png"}]
    f.doc["textures"] = [{"source": 0}]
    f.doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                    "metallicFactor": 0.0, "roughnessFactor": 0.6}}]
    f.node(mesh=f.mesh(attrs, f.accessor(None, iview, ctype=5125, ncomp=1, count=len(idx)),
                       material=0))
    meshopt = f.save(tmp_path / "meshopt.glb")
    _close(_render(make_renderer, meshopt), _render(make_renderer, plain))


def test_ktx2_and_webp_textures_render_as_png(make_renderer, tmp_path: Path) -> None:  # noqa: ANN001
    g = grid_mesh(8, seed=1)
    px = smooth_pixels()
    png = _render(make_renderer, _plain_textured(g, tmp_path / "png.glb", _png(px)), "base_color")
    buf = io.BytesIO()
    PILImage.fromarray(px, "RGBA").save(buf, "WEBP", lossless=True, exact=True)
    webp = _plain_textured(g, tmp_path / "webp.glb", buf.getvalue(), "image/webp",
                           "EXT_texture_webp")
    np.testing.assert_array_equal(_render(make_renderer, webp, "base_color"), png)
    ktx = _plain_textured(g, tmp_path / "ktx.glb", ktx2_bytes(px), "image/ktx2",
                          "KHR_texture_basisu")
    _close(_render(make_renderer, ktx, "base_color"), png)


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_ktx2_with_mips_is_sampled_as_bc7(make_renderer, tmp_path: Path, pipeline: str) -> None:  # noqa: ANN001
    """A KTX2 texture with its mip chain is uploaded as BC7 where the device samples it
    (lavapipe and NVIDIA do): a quarter of RGBA8's bytes, the file's own levels, and it
    renders as the PNG within the codec's precision (the same bound as RGBA8 from UASTC);
    without mips it stays RGBA8 (blitted mips)."""
    g = grid_mesh(8, seed=1)
    px = smooth_pixels(64, 32)
    png = _plain_textured(g, tmp_path / "png.glb", _png(px))
    r = make_renderer(_camera(load_gltf(png)))
    if not r.device.bc7_textures:
        pytest.skip(f"{r.device.info.name} does not sample BC7")
    want = np.asarray(r.render(size=SIZE, view="base_color", pipeline=pipeline)).astype(np.int64)
    rgba8_bytes = r.gpu_scene.texture_bytes
    for mipmaps, fmt in ((True, "VK_FORMAT_BC7_SRGB_BLOCK"), (False, "VK_FORMAT_R8G8B8A8_SRGB")):
        path = _plain_textured(g, tmp_path / f"ktx{mipmaps}.glb", ktx2_bytes(px, mipmaps=mipmaps),
                               "image/ktx2", "KHR_texture_basisu")
        r = make_renderer(_camera(load_gltf(path)))
        [image] = r.gpu_scene.images.values()
        assert image.format == getattr(r.device.vk, fmt), (mipmaps, image.format)
        if mipmaps:
            assert r.gpu_scene.texture_bytes <= rgba8_bytes / 3, (r.gpu_scene.texture_bytes, rgba8_bytes)
        got = np.asarray(r.render(size=SIZE, view="base_color", pipeline=pipeline)).astype(np.int64)
        _close(got, want)
        assert r.device.instance.errors == []
    # A plain bake keeps the KTX2 bytes: its scene is BC7 too; --embed-textures stores RGBA8.
    from vkpbr.bake.bake import bake_file
    from vkpbr.scene.loader import load_scene

    for embed, fmt in ((False, "VK_FORMAT_BC7_SRGB_BLOCK"), (True, "VK_FORMAT_R8G8B8A8_SRGB")):
        baked = tmp_path / f"ktx-{embed}.vkpbr"
        bake_file(tmp_path / "ktxTrue.glb", baked, embed_textures=embed, progress=False)
        r = make_renderer(_camera(load_scene(baked)))
        [image] = r.gpu_scene.images.values()
        assert image.format == getattr(r.device.vk, fmt), (embed, image.format)


def test_instancing_renders_as_nodes(make_renderer, tmp_path: Path) -> None:  # noqa: ANN001
    f, want = _instanced_file(3, 8)
    scene = _camera(load_gltf(f.save(tmp_path / "inst.glb")))
    scene.cameras = [Camera(eye=(2.0, 0.0, 14.0), target=(2.0, 0.0, 0.0), yfov_deg=60.0)]
    instanced = make_renderer(scene).render(size=SIZE, view="geometric_normal")
    explicit = _camera(load_gltf(tmp_path / "inst.glb"))
    explicit.cameras = scene.cameras
    explicit.nodes = [Node(mesh=n.mesh, matrix=(n.matrix.astype(np.float64) @ m).astype(np.float32))
                      for n in explicit.nodes for m in want]
    expected = make_renderer(explicit).render(size=SIZE, view="geometric_normal")
    assert instanced[..., :3].std() > 5
    np.testing.assert_allclose(instanced.astype(np.int64), expected.astype(np.int64), atol=2)


def test_instances_are_one_draw_call_with_their_own_ids(make_renderer, tmp_path: Path) -> None:  # noqa: ANN001
    """The node's 8 instances of each of its two primitives are one draw call of 8 instances
    each (passes._instance_runs); each instance is its own record: its own instance id in
    the outputs, of the same node."""
    from vkpbr.render.passes import _instance_runs

    f, want = _instanced_file(8, 3)
    scene = _camera(load_gltf(f.save(tmp_path / "inst.glb")))
    scene.cameras = [Camera(eye=(2.0, 0.0, 14.0), target=(2.0, 0.0, 0.0), yfov_deg=60.0)]
    r = make_renderer(scene)
    draws = list(enumerate(r.gpu_scene.draws))
    assert len(draws) == 2 * len(want)
    assert [(i, n) for i, _, n in _instance_runs(draws)] == [(0, 8), (8, 8)]
    if not r.device.compute_path:
        pytest.skip("the instance ids need the compute path's features")
    ids = r.render(size=SIZE, outputs=("instance",))["instance"]
    seen = set(np.unique(ids).tolist()) - {0}
    # The two primitives coincide (the later one wins each pixel): most of its 8 instances show.
    assert len(seen) >= 4, f"instance ids seen: {sorted(seen)}"
    assert len({r.instances[i - 1]["node"] for i in seen}) == 1
