"""Cameras anywhere around and inside a scene see all of it: reversed-Z with an infinite far
plane and a near plane chosen per render (render/camera.py depth_range).

The scene is a finely tessellated sphere of radius R; the expected image is an independent
ray cast (tests/pinhole.py) against two analytic spheres that bracket the polygon mesh: a
pixel whose ray hits the inner one must be drawn, one whose ray misses the outer one must be
background, and the depth output must lie between the two spheres' distances. Far away the
two spheres are closer together than the rasterizer's sub-pixel grid (Vulkan guarantees
1/16 pixel: subPixelPrecisionBits >= 4), so the bracket is widened by 1/16 of a pixel there.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st
from pinhole import basis, pixel_rays

from vkpbr.scene.default import uv_sphere
from vkpbr.scene.types import Camera, Light, Material, Node, Scene

R = 2.0
INNER, OUTER = 0.995 * R, 1.0005 * R  # the mesh's faces lie between (rings 64: cos(pi/64))
W, H = 96, 72


def sphere_scene(double_sided: bool = False) -> Scene:
    mesh = uv_sphere(R, 64, 128)
    mesh.material = 0
    mat = Material(base_color_factor=(0.8, 0.8, 0.8, 1.0), double_sided=double_sided)
    return Scene("sphere", meshes=[mesh], materials=[mat], nodes=[Node(mesh=0)],
                 lights=[Light(position=(0.0, 0.0, 0.0))])


def ray_sphere(eye: np.ndarray, d: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Per ray: (near, far) hit distances along unit directions `d` (NaN where it misses)."""
    b = d @ eye
    disc = b * b - (eye @ eye - radius * radius)
    root = np.sqrt(np.where(disc >= 0, disc, np.nan))
    return -b - root, -b + root


def check(r, camera: Camera, inside: bool = False) -> None:  # noqa: ANN001
    color, depth = r.render(camera, size=(W, H), depth=True, view="base_color")
    drawn = color[..., :3].max(axis=-1) > 0
    d = pixel_rays(camera, W, H)
    eye = np.asarray(camera.eye, dtype=np.float64)
    f = basis(camera)[2]
    cos = d @ f  # depth along the axis = hit distance * cos
    # The sub-pixel snap moves an edge by up to 1/16 pixel: that angle at the sphere's distance.
    snap = np.linalg.norm(eye) * np.tan(np.radians(camera.yfov_deg) / H / 16)
    in_near, in_far = ray_sphere(eye, d, INNER - (0.0 if inside else snap))
    out_near, out_far = ray_sphere(eye, d, OUTER + (0.0 if inside else snap))
    if inside:  # from inside, the far side of the sphere, in every direction
        assert drawn.all(), f"{np.count_nonzero(~drawn)} pixels clipped from inside"
        lo, hi = in_far * cos, out_far * cos
        got = depth
    else:
        must = np.isfinite(in_near) & (in_near > 0)
        must_not = ~np.isfinite(out_near)
        assert must.any(), "the sphere should be in view"
        assert drawn[must].all(), f"{np.count_nonzero(~drawn[must])} of {must.sum()} sphere pixels missing"
        assert not drawn[must_not].any(), f"{np.count_nonzero(drawn[must_not])} pixels off the sphere drawn"
        assert np.isinf(depth[must_not]).all()
        lo, hi, got = out_near[must] * cos[must], in_near[must] * cos[must], depth[must]
    rel = 1e-5
    assert np.all(got >= lo * (1 - rel)) and np.all(got <= hi * (1 + rel)), (
        f"depth outside the bracket: {np.max(lo - got):.3g} / {np.max(got - hi):.3g}")


@pytest.fixture(scope="module")
def spheres():  # noqa: ANN201
    from vkpbr.render.renderer import Renderer

    with Renderer(sphere_scene(), validation=True) as outside, \
            Renderer(sphere_scene(double_sided=True), validation=True) as inside:
        yield outside, inside
        for r in (outside, inside):
            r.check_validation()


@pytest.mark.parametrize("distance, fov", [(1.1, 60.0), (1.01, 90.0), (3.0, 45.0), (50.0, 4.0),
                                           (400.0, 0.6)], ids=["0.1R", "0.01R", "3R", "50R", "400R"])
def test_camera_outside_sees_the_whole_sphere(spheres, distance: float, fov: float) -> None:  # noqa: ANN001
    """0.1 R and 0.01 R from the surface (the automatic camera's old near plane, 0.5 R, would
    have cut the sphere open) and 50 R / 400 R away (beyond the old 4.5 R far plane)."""
    eye = np.array([0.3, 0.5, 1.0]) / np.linalg.norm([0.3, 0.5, 1.0]) * distance * R
    check(spheres[0], Camera(eye=tuple(eye), target=(0.1 * R, 0.0, 0.0), yfov_deg=fov))


def test_camera_inside_sees_the_inside(spheres) -> None:  # noqa: ANN001
    check(spheres[1], Camera(eye=(0.3 * R, -0.2 * R, 0.1 * R), target=(0.0, 0.0, -R),
                             yfov_deg=100.0), inside=True)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(direction=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1),
       distance=st.floats(1.02, 80.0), fov=st.floats(5.0, 120.0),
       look=st.tuples(*[st.floats(-0.9, 0.9)] * 3))
@example(direction=(1.0, -0.4140625, 0.41796875), distance=49.75, fov=42.0,  # CI, stop 20:
         look=(-0.28259329253865284, -0.056640625, 0.0))  # an edge within the sub-pixel snap
def test_random_cameras_outside(spheres, direction, distance, fov, look) -> None:  # noqa: ANN001
    eye = np.asarray(direction) / np.linalg.norm(direction) * distance * R
    target = np.asarray(look) * R
    if np.linalg.norm(np.cross(target - eye, (0, 1, 0))) < 1e-3 * np.linalg.norm(target - eye):
        return  # looking straight up or down: up is parallel to the view (a UsageError)
    half = np.degrees(np.arcsin(1 / distance))  # the sphere's angular radius
    off_axis = np.degrees(np.arccos(np.clip(
        np.dot(-eye, target - eye) / np.linalg.norm(eye) / np.linalg.norm(target - eye), -1, 1)))
    # In view (with margin), yet at least ~4 pixels across so some pixel centre hits it.
    fov = min(max(fov, 2.4 * (off_axis + half)), 2 * half * H / 4)
    assume(2 * (off_axis + half) < 0.8 * fov < 140)
    check(spheres[0], Camera(eye=tuple(eye), target=tuple(target), yfov_deg=fov))


def test_user_near_plane_is_honoured(spheres) -> None:  # noqa: ANN001
    """A camera's own znear clips what is nearer than it (the sphere's front is 0.1 R away)."""
    eye = (0.0, 0.0, 1.1 * R)
    camera = Camera(eye=eye, target=(0.0, 0.0, 0.0), yfov_deg=60.0, znear=0.5 * R)
    color, depth = spheres[0].render(camera, size=(W, H), depth=True)
    assert np.isinf(depth[H // 2, W // 2])  # the front cap is cut away, the back is culled


@pytest.mark.parametrize("k", [((140.0, 0, 20.0), (0, 110.0, 50.0), (0, 0, 1)),
                               ((90.0, 0, 47.5), (0, 90.0, 35.5), (0, 0, 1))],
                         ids=["off-centre-anisotropic", "centred"])
@pytest.mark.parametrize("scale", [1, 2])
def test_opencv_camera_lands_on_opencv_pixels(spheres, k, scale: int) -> None:  # noqa: ANN001
    """Camera.from_opencv(K, pose, size) rendered at size (and at twice it): the drawn pixels
    are those whose K^-1 ray (OpenCV: pixel centres at integers) hits the sphere."""
    base = Camera(eye=(0.5, 0.8, 7.0), target=(0.0, 0.0, 0.0))
    pose = base.world_from_camera("opencv")
    cam = Camera.from_opencv(np.array(k), pose, (W, H))
    size = (W * scale, H * scale)
    drawn = spheres[0].render(cam, size=size, view="base_color")[..., :3].max(-1) > 0
    jj, ii = np.meshgrid(np.arange(size[0]), np.arange(size[1]))
    pix = np.stack([jj, ii, np.ones_like(ii)], -1).astype(float)
    d = pix @ np.linalg.inv(cam.intrinsics(size)).T @ pose[:3, :3].T
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    eye = pose[:3, 3]
    must = np.isfinite(ray_sphere(eye, d, INNER)[0])
    must_not = ~np.isfinite(ray_sphere(eye, d, OUTER)[0])
    assert must.sum() > 100
    assert drawn[must].all() and not drawn[must_not].any()


def test_render_takes_a_pose_matrix_and_names_a_wrong_type(spheres) -> None:  # noqa: ANN001
    """A 4x4 world-from-camera pose (OpenGL axes, as NeRF and Blender write them) renders
    what the Camera it came from renders; a wrong type is a one-line UsageError."""
    from vkpbr.errors import UsageError

    r = spheres[0]
    cam = Camera(eye=(0.5, 0.8, 7.0), target=(0.0, 0.0, 0.0), yfov_deg=60.0)
    a = r.render(cam, size=(W, H)).astype(int)
    b = r.render(cam.world_from_camera("opengl"), size=(W, H)).astype(int)
    assert np.abs(a - b).max() <= 1 and np.mean(a != b) < 1e-3
    with pytest.raises(UsageError, match=r"camera: expected .* got ndarray of shape \(3, 3\)"):
        r.render(np.eye(3), size=(W, H))
    with pytest.raises(UsageError):
        list(r.render_many([cam, "not a camera"], size=(W, H)))
