"""The per-frame uniform blocks are written by field name (no GPU needed): each block's
generated `pack_into` lands every named value where the NumPy std140 layout says, and the
renderer's `write_frame_uniforms` puts each input in the field of that name (the camera in
the frame's view record)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from vkpbr.render import layouts as L
from vkpbr.render.camera import forward, view_projection
from vkpbr.render.frames import Bounds, FrameLighting, FrameSlot, write_frame_uniforms
from vkpbr.render.options import RenderOptions
from vkpbr.scene.types import Camera, Light


def _random_values(block: L.Std140Block, rng: np.random.Generator) -> dict:
    arr = block.zeros()
    values = {}
    for name, glsl in block.fields:
        shape = arr[name].shape
        v = rng.integers(0, 1000, shape) if glsl in ("int", "uint", "uvec4") else \
            rng.random(shape).astype(np.float32)
        values[name] = v
    return values


@pytest.mark.parametrize("block", L.BLOCKS, ids=lambda b: b.name)
def test_pack_by_name_matches_the_numpy_layout(block: L.Std140Block) -> None:
    values = _random_values(block, np.random.default_rng(3))
    want = block.zeros()
    for name, v in values.items():
        want[name] = v
    buf = bytearray(block.size)
    # Vectors as sequences; a mat4 as its 16 floats in memory order (the dtype's (4, 4) field
    # holds the GLSL column-major matrix, as layouts.mat4_to_std140 writes it).
    block.pack_into(buf, **{n: (np.asarray(v).ravel().tolist() if np.ndim(v) else v.item())
                            for n, v in values.items()})
    got = np.frombuffer(bytes(buf), dtype=block.dtype)[0]
    for name in values:
        np.testing.assert_array_equal(got[name], want[name], err_msg=name)


def test_packing_needs_every_field_by_name() -> None:
    buf = bytearray(L.LIGHTING.size)
    with pytest.raises(TypeError):
        L.LIGHTING.pack_into(buf, light_count=1)  # the other fields are missing
    with pytest.raises(TypeError):
        L.LIGHTING.pack_into(buf, 1)  # positional values are refused


def test_swapped_fields_are_caught() -> None:
    """A layout whose packer order disagreed with its offsets would fail the check above:
    build one with two fields swapped and show that the by-name bytes differ."""
    fields = list(L.LIGHTING.fields)
    fields[0], fields[1] = fields[1], fields[0]  # light_count <-> mode
    swapped = dataclasses.replace(L.LIGHTING, fields=tuple(fields))
    values = dict(light_count=7, mode=1, flags=2, env_intensity=0.5,
                  env_rotation=(1, 0, 4, 0), ambient_color=(0.02, 0.02, 0.02, 0))
    a, b = bytearray(L.LIGHTING.size), bytearray(swapped.size)
    L.LIGHTING.pack_into(a, **values)
    swapped.pack_into(b, **values)
    assert a != b
    assert np.frombuffer(bytes(a), L.LIGHTING.dtype)[0]["light_count"] == 7


def _slot() -> FrameSlot:
    mv = [memoryview(bytearray(b.size)) for b in (L.VIEW_RECORD, L.SETTINGS, L.LIGHTING)]
    return FrameSlot(0, None, None, *mv, lights=np.zeros((L.MAX_LIGHTS, 20), np.float32))


def test_frame_uniforms_land_in_their_fields() -> None:
    camera = Camera(eye=(1.0, 2.0, 3.0), target=(0.0, 0.5, 0.0), yfov_deg=50.0)
    light = Light(position=(4.0, 5.0, 6.0), color=(0.2, 0.4, 0.6), intensity=3.5,
                  falloff="inverse_square", range=9.0)
    spot = Light(kind="spot", position=(1.0, 2.0, 3.0), direction=(0.0, -1.0, 0.0),
                 inner_cone=0.25, outer_cone=0.5)
    opts = RenderOptions(view="roughness", brdf="blinn-phong", tonemap="aces", exposure=1.5,
                         occlusion=False)
    bounds = Bounds.of(np.array([-1.0, -1, -1]), np.array([1.0, 1, 1]))
    slot = _slot()
    lighting = FrameLighting(mode=1, flags=L.LIGHTING_IBL, ambient=0.02, env_intensity=0.5,
                             env_rotation=np.pi / 2, env_max_lod=6.0)
    write_frame_uniforms(slot, camera, (light, spot), (64, 32), opts, False, bounds, lighting)
    view = np.frombuffer(slot.m_view, L.VIEW_RECORD.dtype)[0]
    st = np.frombuffer(slot.m_settings, L.SETTINGS.dtype)[0]
    lg = np.frombuffer(slot.m_lighting, L.LIGHTING.dtype)[0]
    rec = slot.lights[:2].copy().view(L.LIGHT_RECORD.dtype)[:, 0]
    vp = view_projection(camera, (64, 32), slot.znear)
    np.testing.assert_allclose(view["VP"], L.mat4_to_std140(vp), rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(view["inv_VP"], L.mat4_to_std140(np.linalg.inv(vp)), rtol=1e-5,
                               atol=1e-6)
    np.testing.assert_allclose(view["eye_near"], (1, 2, 3, slot.znear), rtol=1e-6)
    np.testing.assert_allclose(view["forward_far"][:3], forward(camera), rtol=1e-6)
    assert view["forward_far"][3] == np.float32(slot.zfar) > slot.znear
    g = 1 / np.tan(np.radians(25.0))
    np.testing.assert_allclose(view["intrinsics"], (g * 32 / 64, g, 0, 0), rtol=1e-6)
    assert tuple(view["viewport"]) == (0, 0, 64, 32) and view["layer"] == 0
    assert (st["view"], st["brdf"], st["tonemap"]) == (L.View.ROUGHNESS, L.Brdf.BLINN_PHONG, L.Tonemap.ACES)
    assert st["flags"] == L.SETTINGS_NORMAL_MAPPING | L.SETTINGS_SRGB_TARGET
    assert st["exposure"] == pytest.approx(2 ** 1.5)
    assert 0 < slot.znear < np.linalg.norm(camera.eye) - 1.8
    assert (lg["light_count"], lg["mode"], lg["flags"]) == (2, 1, L.LIGHTING_IBL)
    np.testing.assert_allclose(lg["env_rotation"], (0, 1, 6, 0), atol=1e-7)
    np.testing.assert_allclose(lg["ambient_color"], (0.02, 0.02, 0.02, 0), rtol=1e-6)
    assert lg["env_intensity"] == 0.5
    np.testing.assert_allclose(rec[0]["position_range"], (4, 5, 6, 9))
    np.testing.assert_allclose(rec[0]["color_falloff"], (0.7, 1.4, 2.1, 1), rtol=1e-6)
    np.testing.assert_allclose(rec[0]["direction_kind"][3], L.LightKind.POINT)
    np.testing.assert_allclose(rec[1]["direction_kind"], (0, -1, 0, L.LightKind.SPOT))
    scale = 1 / (np.cos(0.25) - np.cos(0.5))
    np.testing.assert_allclose(rec[1]["cone"][:2], (scale, -np.cos(0.5) * scale), rtol=1e-6)
    np.testing.assert_allclose(rec[1]["shadow"][0], -1.0)


def test_near_plane_follows_the_bounds() -> None:
    """Outside the bounds: just in front of the nearest corner; inside: tiny but positive."""
    from vkpbr.render.camera import depth_range

    def near_plane(c, corners, scale):  # noqa: ANN001, ANN202
        return depth_range(c, corners, scale)[0]

    b = Bounds.of(np.array([-1.0, -1, -1]), np.array([1.0, 1, 1]))
    far = Camera(eye=(0.0, 0.0, 100.0), target=(0.0, 0.0, 0.0))
    assert 0.5 * 99 * 0.99 < near_plane(far, b.corners, b.radius) <= 99
    inside = Camera(eye=(0.0, 0.0, 0.5), target=(0.0, 0.0, 0.0))
    assert 0 < near_plane(inside, b.corners, b.radius) <= 1e-4
    own = Camera(eye=(0.0, 0.0, 100.0), target=(0.0, 0.0, 0.0), znear=3.0)
    assert near_plane(own, b.corners, b.radius) == 3.0
    assert depth_range(far, b.corners, b.radius)[1] == pytest.approx(101.0)  # farthest corner


def test_inverse_view_projection_is_the_inverse() -> None:
    """camera_frame_columns' closed-form inverse (the compute path's pixel rays) equals
    NumPy's inverse of VP, for cameras anywhere, with and without pixel intrinsics; the
    rotation is orthonormal with columns right, up, backward."""
    from vkpbr.render.camera import camera_frame_columns, forward

    rng = np.random.default_rng(11)
    for i in range(200):
        eye = tuple(rng.uniform(-50, 50, 3))
        target = tuple(np.add(eye, rng.normal(size=3)))
        cam = Camera(eye=eye, target=target, yfov_deg=float(rng.uniform(5, 150)))
        if i % 2:
            fy = float(rng.uniform(50, 900))
            cam = dataclasses.replace(cam, yfov_deg=float(np.degrees(2 * np.arctan(240 / fy))),
                                      pixel_intrinsics=(float(rng.uniform(50, 900)), fy,
                                                        float(rng.uniform(0, 640)),
                                                        float(rng.uniform(0, 480)), 640, 480))
        vp, inv, rot = camera_frame_columns(cam, (640, 480), float(rng.uniform(1e-4, 1.0)))
        m = np.array(vp).reshape(4, 4).T
        np.testing.assert_allclose(np.array(inv).reshape(4, 4).T @ m, np.eye(4), atol=1e-9)
        r = np.array(rot).reshape(3, 3).T
        np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(-r[:, 2], forward(cam), atol=1e-12)


def test_a_split_batch_reports_every_submission() -> None:
    """render_batch's last_stats over several submissions: each time summed, each pass too."""
    from vkpbr.render.frames import FrameStats, summed_stats

    a = FrameStats(1.0, 2.0, 3.0, 4.0, {"shading": 1.5, "raster": 0.5}, 0.25)
    b = FrameStats(0.5, 1.0, 2.0, 0.5, {"shading": 1.0, "shadows": 2.0}, 0.25)
    got = summed_stats(a, b)
    assert (got.cpu_ms, got.wait_ms, got.gpu_ms, got.readback_ms, got.driver_ms) == (1.5, 3.0, 5.0, 4.5, 0.5)
    assert got.pass_ms == {"shading": 2.5, "raster": 0.5, "shadows": 2.0}
    assert a.pass_ms == {"shading": 1.5, "raster": 0.5}  # the inputs are left alone
