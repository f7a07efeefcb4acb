"""Debug views, switches, depth, MSAA, resource lifetime (the default scene's golden image is
checked in test_goldens.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from vkpbr.render.layouts import View

SIZE = (160, 120)
# The course's views, rendered in its lighting mode. The shadow and image-based views are
# checked where those are (test_shadows.py, test_ibl.py): the course mode has neither.
# The KHR_materials_* layer views are flat on the chart (no layered material) and checked in
# test_material_layers.py.
LAYER_VIEWS = (View.IOR, View.DIELECTRIC_F0, View.CLEARCOAT, View.SHEEN, View.TRANSMISSION,
               View.VOLUME, View.ANISOTROPY, View.IRIDESCENCE, View.DIFFUSE_TRANSMISSION)
COURSE_VIEWS = [v for v in View
                if v not in (View.SHADOW, View.IBL_DIFFUSE, View.IBL_SPECULAR, *LAYER_VIEWS)]


@pytest.fixture(scope="module")
def default_renders():
    from vkpbr.render.renderer import Renderer

    with Renderer(validation=True) as r:
        renders = {v: r.render(size=SIZE, view=v.name.lower(), lighting="course")
                   for v in COURSE_VIEWS}
        renders["blinn"] = r.render(size=SIZE, view="d", brdf="blinn-phong", lighting="course")
        renders["no-mask"] = r.render(size=SIZE, alpha_mask=False, lighting="course")
        renders["no-normal-maps"] = r.render(size=SIZE, view="mapped_normal", normal_mapping=False)
        color, depth = r.render(size=SIZE, depth=True, lighting="course")
        renders["depth-array"] = depth
        renders["msaa-off"] = color
        assert r.device.instance.errors == []
    return renders


def test_every_view_is_distinct_and_in_range(default_renders) -> None:
    images = {v: default_renders[v] for v in COURSE_VIEWS}
    for v, img in images.items():
        assert img.shape == (SIZE[1], SIZE[0], 4) and img.dtype == np.uint8
        assert img[..., :3].std() > 1.0, f"{v.name} is flat"
    names = list(images)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            assert not np.array_equal(images[a], images[b]), f"{a.name} == {b.name}"


def test_switches_change_the_image(default_renders) -> None:
    assert not np.array_equal(default_renders["blinn"], default_renders[View.D])
    assert not np.array_equal(default_renders["no-mask"], default_renders[View.FINAL])
    assert not np.array_equal(default_renders["no-normal-maps"], default_renders[View.MAPPED_NORMAL])
    # Without normal mapping the shading normal is the geometric normal.
    assert np.array_equal(default_renders["no-normal-maps"], default_renders[View.GEOMETRIC_NORMAL])


def test_depth_output(default_renders) -> None:
    depth = default_renders["depth-array"]
    finite = np.isfinite(depth)
    assert finite.mean() > 0.3 and (~finite).any()  # spheres and floor, and background
    assert depth[finite].min() > 0.1 and depth[finite].max() < 100.0


def test_msaa_renders_and_smooths_edges(make_renderer, default_renders) -> None:
    r = make_renderer(msaa=4)
    img = r.render(size=SIZE, lighting="course")
    single = default_renders["msaa-off"]
    assert np.abs(img.astype(int) - single.astype(int)).mean() < 4.0  # the same picture
    # Anti-aliasing creates intermediate values: more distinct colours than without.
    assert len(np.unique(img.reshape(-1, 4), axis=0)) > len(np.unique(single.reshape(-1, 4), axis=0))


def test_create_destroy_loop_leaks_nothing() -> None:
    """Renderers created, used and destroyed: every Vulkan object is released each time (the
    validation layer reports undestroyed children of a device as errors at vkDestroyDevice).
    Three, each checked on its own: the first, the second (which meets whatever the first left
    in module-level state) and one more; later cycles meet the same state as the third.
    Growth over many cycles is test_leaks' (16 cycles, the object count checked after each
    close)."""
    from vkpbr.render.renderer import Renderer

    for _ in range(3):
        r = Renderer(validation=True)
        r.render(size=(32, 24))
        instance = r.device.instance
        device = r.device
        r.close()
        assert device.live_children == 0
        assert instance.errors == [], instance.errors[:2]


# A camera at which, at 160x120, one sub-pixel triangle on a sphere's silhouette sent
# llvmpipe's anisotropic sampling (Mesa 22.3.6) into an endless loop: the viewer hung in
# vkQueuePresentKHR while flying forward. gpu/device.py's anisotropy_usable keeps it off there.
HANG_CAMERA = ("0.5962890256597512,3.18144512829876,8.8330061546888,"
               "0.396289025659752,2.18144512829876,-0.16699384531120032")


def test_llvmpipe_tiny_triangle_does_not_hang(tmp_path: Path) -> None:
    import subprocess
    import sys

    out = tmp_path / "hang.png"
    cmd = [sys.executable, "-m", "vkpbr", "render", "--size", "160x120", "--fov", "45",
           "--camera", HANG_CAMERA, "--out", str(out)]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail("render hung (llvmpipe anisotropic filtering loop?)")
    assert proc.returncode == 0, proc.stderr
    img = np.asarray(Image.open(out))
    assert img.shape == (120, 160, 4) and img[..., :3].std() > 1.0
