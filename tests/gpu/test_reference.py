"""GPU output against the NumPy reference of renderer-spec section 2, pixel by pixel.

Set-up: an infinite-looking plane y = 0 with one constant material, seen obliquely, lit by
one point light. For every pixel the test intersects the pixel-centre ray with the plane, so
n, v and l are known exactly, evaluates reference/brdf.py and compares the 8-bit output.
Tolerance: at most 1/255 on every pixel of every term, all views (quantisation of the sRGB
store and float32 rounding stay within one step).
"""

from __future__ import annotations

import numpy as np
import pytest
from pinhole import pixel_rays

from vkpbr.reference import brdf as ref
from vkpbr.render.layouts import Brdf, Tonemap
from vkpbr.scene.default import plane
from vkpbr.scene.types import Camera, Light, Material, Node, Scene

W, H = 96, 64
CAMERA = Camera(eye=(0.3, 2.0, 2.5), target=(0.0, 0.0, 0.0), yfov_deg=60.0, znear=0.1, zfar=100.0)
LIGHT = Light(position=(0.4, 1.5, 0.2), color=(1.0, 0.9, 0.8), intensity=1.3)
MATERIALS = {
    "dielectric-smooth": Material(base_color_factor=(0.8, 0.3, 0.2, 1), metallic_factor=0.0, roughness_factor=0.25),
    "dielectric-rough": Material(base_color_factor=(0.2, 0.6, 0.9, 1), metallic_factor=0.0, roughness_factor=0.9),
    "metal-mid": Material(base_color_factor=(0.95, 0.64, 0.54, 1), metallic_factor=1.0, roughness_factor=0.5),
    "half-metal": Material(base_color_factor=(0.5, 0.5, 0.5, 1), metallic_factor=0.5, roughness_factor=0.35),
}


def plane_scene(material: Material) -> Scene:
    mesh = plane(60.0, 60.0)
    mesh.material = 0
    return Scene("plane", meshes=[mesh], materials=[material], nodes=[Node(mesh=0)], lights=[LIGHT], cameras=[CAMERA])


def pixel_geometry() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """World position, n, v, l per pixel: (H, W, 3) each, by casting each pixel centre's ray
    onto the plane y = 0 (an independent pinhole model, not the renderer's matrices)."""
    d = pixel_rays(CAMERA, W, H)
    eye = np.asarray(CAMERA.eye, dtype=np.float64)
    t = -eye[1] / d[..., 1]
    p = eye + t[..., None] * d
    n = np.broadcast_to([0.0, 1.0, 0.0], p.shape)
    v = eye - p
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    l = np.asarray(LIGHT.position) - p
    l /= np.linalg.norm(l, axis=-1, keepdims=True)
    return p, n, v, l


def to_bytes(value: np.ndarray, kind: str) -> np.ndarray:
    """What the sRGB target stores: colour/radiance encoded, data views raw."""
    v = np.clip(value, 0.0, 1.0)
    return np.round((ref.linear_to_srgb(v) if kind != "data" else v) * 255.0)


def expected(view: str, mat: Material, brdf: int) -> tuple[np.ndarray, str]:
    _, n, v, l = pixel_geometry()
    c = np.broadcast_to(np.asarray(mat.base_color_factor[:3]), n.shape)
    m = np.full(n.shape[:2], mat.metallic_factor)
    r = np.full(n.shape[:2], mat.roughness_factor)
    light_in = np.asarray(LIGHT.color) * LIGHT.intensity
    s = ref.shade(n, v, l, c, m, r, light_in, brdf=brdf)
    t = s["terms"]
    grey = lambda x: np.repeat(x[..., None], 3, -1)  # noqa: E731
    table = {
        "final": (s["final"], "radiance"), "specular": (s["specular"], "radiance"),
        "diffuse": (s["diffuse"], "radiance"), "ambient": (s["ambient"], "radiance"),
        "d": (grey(t.D), "data"), "f": (t.F, "data"), "g": (grey(t.G), "data"),
        "view_dir": (v * 0.5 + 0.5, "data"), "light_dir": (l * 0.5 + 0.5, "data"),
        "mapped_normal": (n * 0.5 + 0.5, "data"), "base_color": (c, "color"),
        "metallic": (grey(m), "data"), "roughness": (grey(r), "data"),
    }
    value, kind = table[view]
    return to_bytes(value, kind), kind


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
@pytest.mark.parametrize("material", list(MATERIALS))
@pytest.mark.parametrize("brdf", ["ggx", "blinn-phong"])
def test_terms_match_reference(make_renderer, material: str, brdf: str, pipeline: str) -> None:
    """Both frame paths (the fragment path and the compute path, render/compute_path.py)."""
    mat = MATERIALS[material]
    r = make_renderer(plane_scene(mat))
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    views = ["final", "specular", "diffuse", "ambient", "d", "f", "g", "view_dir", "light_dir",
             "mapped_normal", "base_color", "metallic", "roughness"]
    failures = []
    for view in views:
        got = r.render(size=(W, H), view=view, brdf=brdf, lighting="course",
                       pipeline=pipeline)[..., :3].astype(np.int32)
        want, _ = expected(view, mat, Brdf.BLINN_PHONG if brdf == "blinn-phong" else Brdf.GGX)
        diff = np.abs(got - want)
        if diff.max() > 1:
            failures.append(f"{view}: max diff {diff.max()} at {np.unravel_index(diff.argmax(), diff.shape)}")
    assert not failures, failures


def test_tonemap_and_exposure_match_reference(make_renderer) -> None:
    mat = MATERIALS["metal-mid"]
    r = make_renderer(plane_scene(mat))
    _, n, v, l = pixel_geometry()
    c = np.broadcast_to(np.asarray(mat.base_color_factor[:3]), n.shape)
    s = ref.shade(n, v, l, c, mat.metallic_factor, mat.roughness_factor, np.asarray(LIGHT.color) * LIGHT.intensity)
    for name, mode in (("reinhard", Tonemap.REINHARD), ("aces", Tonemap.ACES)):
        got = r.render(size=(W, H), tonemap=name, exposure=1.5, lighting="course")[..., :3].astype(np.int32)
        want = to_bytes(ref.tonemap(s["final"] * 2**1.5, mode), "radiance")
        assert np.abs(got - want).max() <= 1, name


def test_linear_float_output_matches_reference(make_renderer) -> None:
    mat = MATERIALS["dielectric-smooth"]
    r = make_renderer(plane_scene(mat))
    _, n, v, l = pixel_geometry()
    c = np.broadcast_to(np.asarray(mat.base_color_factor[:3]), n.shape)
    s = ref.shade(n, v, l, c, mat.metallic_factor, mat.roughness_factor, np.asarray(LIGHT.color) * LIGHT.intensity)
    got = r.render(size=(W, H), linear=True, lighting="course")
    assert got.dtype == np.float32
    np.testing.assert_allclose(got[..., :3], s["final"], rtol=2e-3, atol=2e-5)
    d_got = r.render(size=(W, H), linear=True, view="d", lighting="course")[..., 0]
    np.testing.assert_allclose(d_got, np.clip(s["terms"].D, 0, 1), rtol=2e-3, atol=2e-5)


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
@pytest.mark.parametrize("material", list(MATERIALS))
def test_gltf_brdf_terms_match_reference(make_renderer, material: str, pipeline: str) -> None:
    """The physically based mode's glTF BRDF (spec Appendix B) against the NumPy mirror:
    the point light alone (no ambient; image-based light and shadows are not part of these
    terms), linear float32 output, every term view, on both frame paths."""
    mat = MATERIALS[material]
    r = make_renderer(plane_scene(mat))
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    _, n, v, l = pixel_geometry()
    c = np.broadcast_to(np.asarray(mat.base_color_factor[:3]), n.shape)
    m = np.full(n.shape[:2], mat.metallic_factor)
    rough = np.full(n.shape[:2], mat.roughness_factor)
    s = ref.shade(n, v, l, c, m, rough, np.asarray(LIGHT.color) * LIGHT.intensity, brdf=Brdf.GLTF,
                  ambient=0.0)
    t = s["terms"]
    want = {"specular": s["specular"], "diffuse": s["diffuse"], "d": np.clip(t.D, 0, 1)[..., None],
            "f": t.F, "g": np.clip(t.G, 0, 1)[..., None]}
    for view, value in want.items():
        got = r.render(size=(W, H), view=view, linear=True, lighting="pbr", brdf="gltf",
                       env="none", pipeline=pipeline)
        np.testing.assert_allclose(got[..., :3], np.broadcast_to(value, n.shape), rtol=2e-3,
                                   atol=2e-5, err_msg=view)
