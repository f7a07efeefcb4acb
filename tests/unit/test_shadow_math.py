"""Shadow-map projections (render/shadow_math.py), checked geometrically with hypothesis:
cascades hold their frustum slices and the scene's casters, snap to whole texels as the camera
moves, spot and cube maps put points where Vulkan's sampling will look for them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from vkpbr.render import shadow_math as S
from vkpbr.scene.types import Camera

coord = st.floats(-20.0, 20.0, allow_nan=False)
vec3 = st.tuples(coord, coord, coord)
unit_ish = st.tuples(*(st.floats(-1.0, 1.0, allow_nan=False),) * 3).filter(
    lambda v: math.hypot(*v) > 0.2)
sizes = st.tuples(st.integers(16, 4096), st.integers(16, 4096))
resolutions = st.sampled_from([256, 512, 1024, 2048, 4096])
LO, HI = np.array([-12.0, -3.0, -7.0]), np.array([14.0, 9.0, 6.0])


def _camera(eye, target, fov) -> Camera:
    assume(np.linalg.norm(np.subtract(target, eye)) > 1e-2)
    d = np.subtract(target, eye) / np.linalg.norm(np.subtract(target, eye))
    assume(abs(d[1]) < 0.999)  # look_at with up = +Y
    return Camera(eye=tuple(eye), target=tuple(target), yfov_deg=fov)


@given(st.floats(1e-5, 10.0), st.floats(1.1, 1e4), st.integers(1, 6))
def test_splits_increase_from_near_to_far(znear, ratio, count) -> None:
    s = S.cascade_splits(znear, znear * ratio, count)
    assert s.shape == (count + 1,) and s[0] == znear and s[-1] == znear * ratio
    assert np.all(np.diff(s) > 0)


@settings(max_examples=150, deadline=None)
@given(vec3, vec3, st.floats(10.0, 120.0), sizes, unit_ish, resolutions,
       st.floats(0.01, 1.0), st.floats(2.0, 200.0))
def test_cascades_hold_their_slices_and_the_scene_towards_the_light(
        eye, target, fov, size, direction, res, znear, ratio) -> None:
    cam = _camera(eye, target, fov)
    fit = S.directional_cascades(cam, size, direction, LO, HI, res, znear, znear * ratio)
    lo, hi = S.cascade_range(znear, znear * ratio)
    assert lo <= znear and hi >= znear * ratio  # the cascades reach the whole view range
    splits = S.cascade_splits(lo, hi)
    assert np.allclose(fit.far, splits[1:])
    scene = np.array([[x, y, z] for x in (LO[0], HI[0]) for y in (LO[1], HI[1])
                      for z in (LO[2], HI[2])])
    f = np.asarray(direction) / np.linalg.norm(direction)
    for i, m in enumerate(fit.matrices):
        clip = S.project(m, S.slice_corners(cam, size, splits[i], splits[i + 1]))
        assert np.allclose(clip[:, 3], 1.0)  # orthographic
        assert np.all(np.abs(clip[:, :2]) <= 1.0 + 1e-9), "a slice corner is outside the box"
        assert np.all((clip[:, 2] >= -1e-9) & (clip[:, 2] <= 1.0 + 1e-9))
        # Every scene point is no nearer the light than depth 1: nothing is clipped on
        # the light's side, so casters outside the view still cast.
        assert np.all(S.project(m, scene)[:, 2] <= 1.0 + 1e-9)
        # Depth falls along the light's travel (reversed: 1 nearest the light).
        p = S.slice_sphere(cam, size, splits[i], splits[i + 1])[0]
        a, b = S.project(m, np.array([p, p + 0.1 * f]))[:, 2]
        assert b < a
        assert fit.texel[i] == pytest.approx(2.0 / res / np.linalg.norm(m[0, :3]))


@settings(max_examples=150, deadline=None)
@given(vec3, vec3, st.floats(20.0, 100.0), unit_ish, resolutions, vec3,
       st.tuples(*(st.floats(-1.0, 1.0),) * 3), st.floats(0.0, 1.0))
def test_a_moving_camera_moves_cascades_by_whole_texels(
        eye, target, fov, direction, res, point, step, texels) -> None:
    """The radius is the same for every pose (view-space fit) and the centre is snapped:
    a fixed world point's position in texels changes by whole snapping steps only."""
    cam = _camera(eye, target, fov)
    size = (320, 240)
    fit0 = S.directional_cascades(cam, size, direction, LO, HI, res, 0.1, 60.0)
    # Move the camera by up to one texel of the first cascade, keeping its orientation.
    delta = np.asarray(step) * texels * fit0.texel[0]
    moved = Camera(eye=tuple(np.add(eye, delta)), target=tuple(np.add(target, delta)),
                   yfov_deg=fov)
    fit1 = S.directional_cascades(moved, size, direction, LO, HI, res, 0.1, 60.0)
    assert np.array_equal(fit0.texel, fit1.texel)
    for m0, m1 in zip(fit0.matrices, fit1.matrices, strict=True):
        t0 = (S.project(m0, np.array([point]))[0, :2] * 0.5 + 0.5) * res
        t1 = (S.project(m1, np.array([point]))[0, :2] * 0.5 + 0.5) * res
        shift = (t1 - t0) / S.snap_texels(res)
        assert np.allclose(shift, np.round(shift), atol=1e-6 * res), shift


@settings(max_examples=60, deadline=None)
@given(vec3, vec3, st.floats(20.0, 100.0), unit_ish, resolutions,
       st.tuples(*(st.floats(-1.0, 1.0),) * 3).filter(lambda v: math.hypot(*v) > 0.1))
@example(eye=(0.0, 12.0, 0.0), target=(-1.0, 0.0, 0.0), fov=22.0, direction=(-0.75, 1.0, 0.25),
         res=256, heading=(1.0, 0.0, 0.5))  # a centre rounded to -0.0 and 0.0 (other bytes)
def test_a_walking_camera_keeps_its_cascades_within_a_step(
        eye, target, fov, direction, res, heading) -> None:
    """A camera walking one snapping step of the first cascade in 50 small steps, with an
    automatic far plane that drifts with it, changes each cascade's matrix at most once per
    light-space axis (a redraw), so the renderer redraws a cascade every few dozen frames."""
    cam = _camera(eye, target, fov)
    size = (320, 240)
    fit0 = S.directional_cascades(cam, size, direction, LO, HI, res, 0.1, 60.0)
    walk = np.asarray(heading) / np.linalg.norm(heading) * fit0.texel[0] * S.snap_texels(res)
    seen: list[set[bytes]] = [set() for _ in fit0.matrices]
    for i in range(51):
        d = walk * i / 50
        moved = Camera(eye=tuple(np.add(eye, d)), target=tuple(np.add(target, d)), yfov_deg=fov)
        fit = S.directional_cascades(moved, size, direction, LO, HI, res, 0.1, 60.0 + 0.01 * i)
        for held, m in zip(seen, fit.matrices, strict=True):
            held.add(m.tobytes())
    assert all(len(held) <= 4 for held in seen), [len(h) for h in seen]


@given(st.floats(1e-6, 1e3), st.floats(1.01, 1e5))
def test_cascade_range_rounds_outwards_to_quarter_octaves(znear, ratio) -> None:
    lo, hi = S.cascade_range(znear, znear * ratio)
    assert lo <= znear and hi >= znear * ratio and hi > lo
    for v, given_v in ((lo, znear), (hi, znear * ratio)):
        k = 4.0 * math.log2(v)
        assert v == given_v or abs(k - round(k)) < 1e-9


@given(vec3, vec3, st.floats(20.0, 100.0), unit_ish)
def test_cascade_radius_ignores_camera_rotation(eye, target, fov, direction) -> None:
    cam = _camera(eye, target, fov)
    other = _camera(eye, tuple(np.add(eye, [0.3, -0.2, 1.0])), fov)
    for d0, d1 in ((0.1, 2.0), (2.0, 9.0), (9.0, 40.0)):
        r0 = S.slice_sphere(cam, (640, 480), d0, d1)[1]
        r1 = S.slice_sphere(other, (640, 480), d0, d1)[1]
        assert r0 == pytest.approx(r1, rel=1e-12)


def test_sphere_fits_off_centre_intrinsics() -> None:
    cam = Camera(eye=(0.0, 1.0, 5.0), target=(0.0, 1.0, 0.0), yfov_deg=2 * math.degrees(
        math.atan(480 / (2 * 300.0))), pixel_intrinsics=(300.0, 300.0, 100.0, 60.0, 640, 480))
    c, r = S.slice_sphere(cam, (640, 480), 1.0, 8.0)
    corners = S.slice_corners(cam, (640, 480), 1.0, 8.0)
    assert np.all(np.linalg.norm(corners - c, axis=1) <= r + 1e-9)


@settings(max_examples=100, deadline=None)
@given(vec3, unit_ish, st.floats(0.05, 1.3), st.floats(0.01, 50.0),
       st.floats(0.0, 0.999), st.floats(0.0, 2 * math.pi))
def test_spot_map_holds_the_cone_with_reversed_depth(pos, direction, outer, dist, frac,
                                                     phi) -> None:
    near = 1e-3
    m = S.spot_matrix(pos, direction, outer, near)
    r, u, f = S.light_basis(direction)
    # A point inside the cone (angle frac * min(outer, limit) off the axis).
    a = frac * min(outer, S.MAX_SPOT_HALF_ANGLE)
    d = math.cos(a) * f + math.sin(a) * (math.cos(phi) * r + math.sin(phi) * u)
    p = np.asarray(pos) + dist * d
    clip = S.project(m, np.array([p]))[0]
    ndc = clip[:3] / clip[3]
    assert clip[3] == pytest.approx(dist * math.cos(a), rel=1e-9, abs=1e-12)
    assert np.all(np.abs(ndc[:2]) <= 1.0)
    assert ndc[2] == pytest.approx(near / (dist * math.cos(a)), rel=1e-9)
    # The axis lands in the middle of the map.
    on_axis = S.project(m, np.array([np.asarray(pos) + dist * f]))[0]
    assert np.allclose(on_axis[:2] / on_axis[3], 0.0, atol=1e-9)


@settings(max_examples=200, deadline=None)
@given(vec3, st.tuples(*(st.floats(-5.0, 5.0),) * 3).filter(lambda v: max(map(abs, v)) > 1e-3))
def test_cube_faces_follow_vulkan_face_selection(pos, q) -> None:
    """The face of the largest component renders the point inside its square at depth
    near / |ma|, at the (s, t) the spec's face-selection table samples."""
    near = 0.01
    m = S.point_matrices(pos, near)
    q = np.asarray(q)
    axis = int(np.argmax(np.abs(q)))
    face = 2 * axis + (0 if q[axis] > 0 else 1)
    clip = S.project(m[face], np.array([np.asarray(pos) + q]))[0]
    ma = abs(q[axis])
    assert clip[3] == pytest.approx(ma)
    assert clip[2] / clip[3] == pytest.approx(near / ma)
    rx, ry, rz = q
    sc, tc = {0: (-rz, -ry), 1: (rz, -ry), 2: (rx, rz), 3: (rx, -rz), 4: (rx, -ry),
              5: (-rx, -ry)}[face]
    assert clip[0] / clip[3] == pytest.approx(sc / ma, abs=1e-12)
    assert clip[1] / clip[3] == pytest.approx(tc / ma, abs=1e-12)
    # The other faces either put it behind (w <= 0) or outside their square (or on an edge).
    for other in range(6):
        if other != face:
            c = S.project(m[other], np.array([np.asarray(pos) + q]))[0]
            assert c[3] <= 0 or np.max(np.abs(c[:2])) >= c[3] * (1 - 1e-12)


def test_perspective_near_scales_with_reach() -> None:
    assert S.perspective_near((0, 0, 0), 10.0, LO, HI) == pytest.approx(0.01)
    far = max(np.linalg.norm([x, y, z]) for x in (LO[0], HI[0]) for y in (LO[1], HI[1])
              for z in (LO[2], HI[2]))
    assert S.perspective_near((0, 0, 0), 0.0, LO, HI) == pytest.approx(far * 1e-3)


@settings(max_examples=200, deadline=None)
@given(vec3, vec3, st.floats(10.0, 120.0), sizes, unit_ish, resolutions,
       st.floats(0.01, 1.0), st.floats(2.0, 200.0))
@example(eye=(0.0, 12.0, 0.0), target=(-1.0, 0.0, 0.0), fov=22.0, size=(320, 240),
         direction=(-0.75, 1.0, 0.25), res=256, znear=0.1, ratio=600.0)  # centres rounded to 0
def test_cascades_in_floats_equal_the_array_fit(eye, target, fov, size, direction, res,
                                                znear, ratio) -> None:
    """directional_cascades (cascade_columns: Python floats, the view's axes) gives the bytes
    of the NumPy fit it replaced (slice spheres through the view matrix's inverse, then
    `_fit_cascades`), unless a centre lies on a tie of the snapping grid, where the two
    roundings of the last bit may differ (excluded here)."""
    cam = _camera(eye, target, fov)
    zfar = znear * ratio
    splits = S.cascade_splits(*S.cascade_range(znear, zfar))
    centres, radii = S._slice_spheres(cam, size, splits[:-1], splits[1:])
    basis = S.light_basis(direction)
    grid = S.snap_texels(res) * S.cascade_texel(radii, res)
    at = (centres @ basis.T) / grid[:, None]
    assume(np.all(np.abs(np.abs(at - np.floor(at)) - 0.5) > 1e-6))
    want = S._fit_cascades(centres, radii, basis, LO, HI, res)
    fit = S.directional_cascades(cam, size, direction, LO, HI, res, znear, zfar)
    assert fit.matrices.tobytes() == want.tobytes()
    assert fit.far.tobytes() == splits[1:].tobytes()
    assert fit.texel.tobytes() == S.cascade_texel(radii, res).tobytes()


def _texels(cols: list[float], points: np.ndarray, resolution: int) -> np.ndarray:
    """World points' texel (x, y) in the map of column-major matrix `cols` (float32, as the
    kernels read it): (ndc * 0.5 + 0.5) * resolution."""
    m = np.asarray(cols, np.float32).astype(np.float64).reshape(4, 4).T
    clip = S.project(m, points)
    return (clip[:, :2] / clip[:, 3:] * 0.5 + 0.5) * resolution


@settings(max_examples=60, deadline=None)
@given(st.floats(-20, 20), st.floats(-20, 20), st.floats(0.01, 0.6), st.floats(0, 2 * math.pi),
       st.sampled_from([256, 1024, 2048]))
def test_a_scroll_moves_every_point_by_its_whole_texels(x: float, z: float, step: float,
                                                        heading: float, resolution: int) -> None:
    """layer_scroll of a walking camera's cascade matrices (cascade_columns before and after a
    step): where it gives (dx, dy), every point of the scene lands (dx, dy) texels from where
    it was, within 1e-3 of a texel (so the moved texels are the map the new matrix draws); it
    is whole grid steps along each axis (the snapping); and it gives None where the matrices
    differ otherwise."""
    lo, hi = (-30.0, -2.0, -30.0), (30.0, 12.0, 30.0)
    sun = (0.35, -1.0, 0.25)
    a = Camera(eye=(x, 1.7, z), target=(x + math.cos(heading), 1.6, z + math.sin(heading)))
    b = Camera(eye=(x + step * math.cos(heading), 1.7, z + step * math.sin(heading)),
               target=(x + (1 + step) * math.cos(heading), 1.6, z + (1 + step) * math.sin(heading)))
    shape = S.cascade_shape(a, (640, 480), sun, lo, hi, resolution, 0.1, 60.0)
    assert shape == S.cascade_shape(b, (640, 480), sun, lo, hi, resolution, 0.1, 60.0)
    before, after = S.cascade_columns(a, shape), S.cascade_columns(b, shape)
    points = np.random.default_rng(0).uniform(lo, hi, (64, 3))
    for k in range(len(before) // 16):
        old, new = before[16 * k:16 * k + 16], after[16 * k:16 * k + 16]
        moved = S.layer_scroll(np.array(old, np.float32), np.array(new, np.float32), resolution)
        if moved is None:
            continue
        dx, dy = moved
        assert (dx, dy) != (0, 0) and dx % S.snap_texels(resolution) == dy % S.snap_texels(resolution) == 0
        shift = _texels(new, points, resolution) - _texels(old, points, resolution)
        assert np.abs(shift - (dx, dy)).max() < 1e-3, (k, moved, shift[:3])


def test_a_scroll_is_only_a_whole_texel_move_along_one_axis() -> None:
    """layer_scroll's moves, along one axis or both, and its None: the same matrix, a scale or
    depth change, half a texel, the whole map along an axis."""
    m = np.eye(4, dtype=np.float32).T.reshape(16).copy()  # column-major: [12], [13] translate
    def moved(**at: float) -> np.ndarray:  # noqa: ANN202
        out = m.copy()
        for i, v in at.items():
            out[int(i[1:])] += v
        return out
    res = 256
    assert S.layer_scroll(m, moved(t12=2 * 32 / res), res) == (32, 0)
    assert S.layer_scroll(m, moved(t13=-2 * 3 / res), res) == (0, -3)
    assert S.layer_scroll(m, m.copy(), res) is None
    assert S.layer_scroll(m, moved(t0=0.01), res) is None  # a scale
    assert S.layer_scroll(m, moved(t14=0.01), res) is None  # the depth
    assert S.layer_scroll(m, moved(t12=1.0 / res), res) is None  # half a texel
    assert S.layer_scroll(m, moved(t12=2 / res, t13=-4 / res), res) == (1, -2)  # both axes
    assert S.layer_scroll(m, moved(t12=2.0), res) is None  # the whole map
    assert S.layer_scroll(m, moved(t12=2 / res, t13=2.0), res) is None
