"""The KHR_materials_* layers on lavapipe (validation on) against their NumPy mirror
(reference/brdf.py `shade_layered`), pixel by pixel, on both frame paths.

Set-up as test_reference.py: the plane y = 0 seen obliquely, n, v and l known exactly per
pixel from an independent pinhole model. The glTF BRDF, linear float32 output.

- Punctual light: every layer view and the final image against the mirror, a light above the
  plane and, for transmission, one below it (light through the surface). Tolerance as the core
  BRDF's (test_reference.py): rtol 2e-3, atol 2e-5 (float32 against float64), plus the image's
  change over 1/64 pixel (pinhole.raster_slack: where the rasterised surface is).
- A uniform environment (a constant panorama, EnvironmentSpec.small()): the layers'
  environment terms are then analytic: the coat reflects L, the sheen returns
  sheen colour * E(n.v) * L, refraction brings k_d * L * transmittance with k_d the split
  sum's diffuse weight (read from the IBL diffuse view of the same material without
  transmission). Tolerance rtol 1e-2 (half-float cubes; the pre-filter of a constant is
  constant up to rounding).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import OpenEXR
import pytest
from pinhole import assert_close_on_raster
from test_reference import CAMERA, LIGHT, H, W, pixel_geometry

from vkpbr.reference import brdf as ref
from vkpbr.render import layouts as L
from vkpbr.render.environment import EnvironmentSpec
from vkpbr.render.options import RenderOptions
from vkpbr.scene.default import plane
from vkpbr.scene.types import Light, Material, Node, Scene

pytestmark = pytest.mark.timeout(300)

LAYERED = {
    "clearcoat": Material(base_color_factor=(0.8, 0.2, 0.1, 1), metallic_factor=0.0,
                          roughness_factor=0.6, clearcoat_factor=0.8,
                          clearcoat_roughness_factor=0.2),
    "sheen": Material(base_color_factor=(0.1, 0.2, 0.7, 1), metallic_factor=0.0,
                      roughness_factor=0.7, sheen_color_factor=(0.9, 0.6, 0.3),
                      sheen_roughness_factor=0.5),
    "ior-specular": Material(base_color_factor=(0.5, 0.6, 0.4, 1), metallic_factor=0.3,
                             roughness_factor=0.35, ior=1.8, specular_factor=0.6,
                             specular_color_factor=(1.0, 0.5, 0.25)),
    "transmission-volume": Material(base_color_factor=(0.9, 0.9, 0.8, 1), metallic_factor=0.0,
                                    roughness_factor=0.5, ior=1.3, transmission_factor=0.9,
                                    thickness_factor=0.6, attenuation_distance=0.5,
                                    attenuation_color=(0.9, 0.4, 0.2)),
    "everything": Material(base_color_factor=(0.6, 0.5, 0.4, 1), metallic_factor=0.2,
                           roughness_factor=0.45, ior=1.6, specular_factor=0.8,
                           specular_color_factor=(0.9, 1.0, 1.2), clearcoat_factor=0.5,
                           clearcoat_roughness_factor=0.35, sheen_color_factor=(0.3, 0.5, 0.2),
                           sheen_roughness_factor=0.8, transmission_factor=0.4,
                           thickness_factor=0.3, attenuation_distance=2.0,
                           attenuation_color=(0.7, 0.8, 0.9)),
}
VIEWS = ("final", "specular", "diffuse", "transmission", "sheen", "clearcoat", "ior",
         "dielectric-f0", "volume")
BELOW = Light(position=(-0.3, -1.2, 0.4), color=(0.9, 1.0, 0.7), intensity=1.1, shadows=False)


def plane_scene(material: Material, light: Light = LIGHT) -> Scene:
    mesh = plane(60.0, 60.0)
    mesh.material = 0
    return Scene("plane", meshes=[mesh], materials=[material], nodes=[Node(mesh=0)],
                 lights=[light], cameras=[CAMERA])


def mirror(mat: Material, light: Light, model_scale: float = 1.0, **env: object) -> dict[str, np.ndarray]:
    p, n, v, _ = pixel_geometry()
    to_light = np.asarray(light.position) - p
    l = to_light / np.linalg.norm(to_light, axis=-1, keepdims=True)
    c = np.broadcast_to(np.asarray(mat.base_color_factor[:3]), n.shape)
    shape = n.shape[:2]
    light_in = np.asarray(light.color) * light.intensity if env.get("env_radiance") is None \
        else np.zeros(3)
    return ref.shade_layered(n, v, l, c, np.full(shape, mat.metallic_factor),
                             np.full(shape, mat.roughness_factor), light_in,
                             ref.Layers.of(mat, model_scale), **env)


def render(r, view: str, pipeline: str, **options: object) -> np.ndarray:  # noqa: ANN001
    return r.render(size=(W, H), view=view, linear=True, lighting="pbr", brdf="gltf",
                    pipeline=pipeline, **options)[..., :3]


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
@pytest.mark.parametrize("material", list(LAYERED))
def test_layers_match_mirror(make_renderer, material: str, pipeline: str) -> None:
    mat = LAYERED[material]
    lights = [LIGHT] + ([BELOW] if mat.transmission_factor > 0 else [])
    for light in lights:
        r = make_renderer(plane_scene(mat, light))
        if pipeline == "compute" and not r.device.compute_path:
            pytest.skip(f"{r.device.info.name} lacks the compute path's features")
        want = mirror(mat, light)
        for view in VIEWS:
            got = render(r, view, pipeline, env="none")
            key = view.replace("-", "_")
            assert_close_on_raster(got, np.broadcast_to(want[key], got.shape), rtol=2e-3,
                                   atol=2e-5, what=f"{view}, light {light.position}")
        if light is BELOW:
            # Light from behind reaches the viewer only through the transmitted lobe.
            assert want["diffuse"].max() == 0.0 and want["transmission"].max() > 1e-3


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_volume_thickness_scales_with_the_node(make_renderer, pipeline: str) -> None:
    """KHR_materials_volume's thickness is in the mesh's space: the plane's node scaled by
    2.5 (the surface stays y = 0) attenuates as the mirror with 2.5 times the thickness."""
    mat = LAYERED["transmission-volume"]
    scene = plane_scene(mat, BELOW)
    scene.nodes = [Node(mesh=0, matrix=np.diag([2.5, 2.5, 2.5, 1.0]).astype(np.float32))]
    r = make_renderer(scene)
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    scaled, plain = mirror(mat, BELOW, model_scale=2.5), mirror(mat, BELOW)
    assert not np.allclose(scaled["volume"], plain["volume"])  # the scale matters here
    for view in ("volume", "transmission", "final"):
        got = render(r, view, pipeline, env="none")
        assert_close_on_raster(got, np.broadcast_to(scaled[view], got.shape), rtol=2e-3,
                               atol=2e-5, what=view)


def test_unlit_is_the_base_colour(make_renderer) -> None:
    mat = dataclasses.replace(LAYERED["everything"], unlit=True)
    r = make_renderer(plane_scene(mat))
    for pipeline in ("forward", "compute") if r.device.compute_path else ("forward",):
        got = render(r, "final", pipeline, env="sky")
        np.testing.assert_allclose(got, np.broadcast_to(mat.base_color_factor[:3], got.shape),
                                   rtol=1e-6, atol=1e-7)


def test_default_layers_leave_the_core_brdf(make_renderer) -> None:
    """A material with every layer at its default renders the core glTF BRDF's mirror
    (ref.shade), independent of the layered code."""
    mat = Material(base_color_factor=(0.7, 0.4, 0.2, 1), metallic_factor=0.4,
                   roughness_factor=0.3)
    r = make_renderer(plane_scene(mat))
    _, n, v, l = pixel_geometry()
    c = np.broadcast_to(np.asarray(mat.base_color_factor[:3]), n.shape)
    s = ref.shade(n, v, l, c, np.full(n.shape[:2], 0.4), np.full(n.shape[:2], 0.3),
                  np.asarray(LIGHT.color) * LIGHT.intensity, brdf=ref.Brdf.GLTF, ambient=0.0)
    for pipeline in ("forward", "compute") if r.device.compute_path else ("forward",):
        got = render(r, "final", pipeline, env="none")
        np.testing.assert_allclose(got, s["final"], rtol=2e-3, atol=2e-5, err_msg=pipeline)


ENV_RADIANCE = 0.7


@pytest.fixture(scope="module")
def uniform_env(tmp_path_factory) -> Path:  # noqa: ANN001
    folder = tmp_path_factory.mktemp("uniform-env")
    path = folder / "uniform.exr"
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    rgb = np.full((16, 32, 3), ENV_RADIANCE, np.float32)
    with OpenEXR.File(header, {"RGB": rgb}) as f:
        f.write(str(path))
    return path


def _uniform_pair(make_renderer, mat, plain, tmp_path: Path, uniform_env: Path,  # noqa: ANN001, ANN202
                  pipeline: str):
    """Renderers of a plane of `mat` and of `plain` (the material without the layer) lit by
    the uniform environment alone, and the render options (GTAO off: the layers' image-based
    terms, not occlusion); skips the compute path where the device lacks it."""
    kw = {"env_spec": EnvironmentSpec.small(), "cache_dir": tmp_path / "cache"}
    r = make_renderer(plane_scene(mat), **kw)
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    opts = {"env": str(uniform_env), "lights": [], "env_background": False, "ao": "off"}
    return r, make_renderer(plane_scene(plain), **kw), opts


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
@pytest.mark.parametrize("material", ["clearcoat", "sheen", "transmission-volume", "everything"])
def test_environment_layers_in_a_uniform_environment(make_renderer, uniform_env: Path,
                                                     tmp_path: Path, material: str,
                                                     pipeline: str) -> None:
    mat = LAYERED[material]
    opaque = dataclasses.replace(mat, transmission_factor=0.0)
    # GTAO off (in opts): occlusion would occlude the ibl-diffuse view k_d is measured from,
    # not the transmission's share.
    r, r0, opts = _uniform_pair(make_renderer, mat, opaque, tmp_path, uniform_env, pipeline)
    k_d = render(r0, "ibl-diffuse", pipeline, **opts) / ENV_RADIANCE
    want = mirror(mat, LIGHT, env_radiance=ENV_RADIANCE, ibl_diffuse_weight=k_d)
    got = {view: render(r, view, pipeline, **opts)
           for view in ("clearcoat", "sheen", "transmission", "ibl-diffuse", "ibl-specular",
                        "final")}
    for view in ("clearcoat", "sheen", "transmission"):
        np.testing.assert_allclose(got[view], np.broadcast_to(want[view], got[view].shape),
                                   rtol=1e-2, atol=1e-4, err_msg=view)
    # The composition: the coat's blend over sheen + the base scaled by sheen's albedo.
    blend = want["coat_blend"][..., None]
    base = got["ibl-diffuse"] + got["ibl-specular"] + got["transmission"]
    composed = (got["sheen"] + base * want["sheen_scaling"][..., None]) * (1.0 - blend) \
        + got["clearcoat"]
    np.testing.assert_allclose(got["final"], composed, rtol=2e-3, atol=1e-4)
    if mat.transmission_factor > 0:  # the refracted light replaces that much irradiance
        np.testing.assert_allclose(got["ibl-diffuse"], k_d * ENV_RADIANCE
                                   * (1.0 - mat.transmission_factor), rtol=1e-3, atol=1e-5)


def test_golden_layer_spheres(make_renderer, tmp_path: Path) -> None:
    """tests/gpu/layer_scene.py's six spheres (a generated glTF file, every layer through the
    loader) in the default physically based mode, against a golden checked by eye when made
    (clearcoat, sheen, ior 2.4 with a gold specular colour; a thick orange volume, a thin
    transmissive sphere, unlit green). Tolerances: goldens.py's (tight on llvmpipe)."""
    from goldens import PBR_OTHER, TIGHT, Golden, mismatch
    from layer_scene import CAMERA, write_layer_spheres
    from PIL import Image

    from vkpbr.scene.loader import load_scene

    golden = Golden("pbr_material_layers_160x120.png", None, (160, 120), TIGHT, PBR_OTHER, "pbr")
    scene = load_scene(write_layer_spheres(tmp_path / "layers.gltf"))
    r = make_renderer(scene)
    got = np.ascontiguousarray(r.render(CAMERA, size=golden.size, lighting="pbr")[..., :3])
    why = mismatch(got, golden, r.device.info.name)
    if why:
        Image.fromarray(got).save(tmp_path / golden.file)
        pytest.fail(f"{why}; the render is in {tmp_path / golden.file}")
    # The variant swaps the first sphere's material only (red -> blue coat).
    variant = make_renderer(load_scene(tmp_path / "layers.gltf", variant="blue-coat"))
    other = variant.render(CAMERA, size=golden.size, lighting="pbr")[..., :3].astype(int)
    changed = np.abs(other - got).max(-1) > 8
    assert changed[:, :65].mean() > 0.05 and not changed[:, 70:].any()


def constant_image(name: str, rgba: tuple[int, int, int, int]):  # noqa: ANN201
    from vkpbr.scene.types import Image

    return Image(name=name, pixels=np.broadcast_to(np.asarray(rgba, np.uint8), (4, 4, 4)).copy())


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_layer_textures_multiply_their_factors(make_renderer, pipeline: str) -> None:
    """Every extension texture (constant texels, so that filtering cannot matter) scales its
    factor: scalar maps from the channel the extension names (R, G or A of a linear image),
    sheen and specular colour decoded from sRGB, the coat's normal map tilting the coat's
    normal in the surface's tangent frame (read from the tangent and bitangent views)."""
    from vkpbr.scene.types import TextureRef

    data, color, normal = (16, 64, 200, 191), (200, 120, 60, 255), (166, 102, 242, 255)
    images = [constant_image("data", data), constant_image("color", color),
              constant_image("normal", normal)]
    mat = Material(base_color_factor=(0.6, 0.5, 0.4, 1), metallic_factor=0.1,
                   roughness_factor=0.5, ior=1.45, specular_factor=0.9,
                   specular_color_factor=(1.2, 1.0, 0.8), clearcoat_factor=0.9,
                   clearcoat_roughness_factor=0.8, clearcoat_normal_scale=0.7,
                   sheen_color_factor=(1.0, 0.8, 0.6), sheen_roughness_factor=0.9,
                   transmission_factor=0.8, thickness_factor=2.0, attenuation_distance=1.5,
                   attenuation_color=(0.8, 0.6, 0.3),
                   clearcoat_texture=TextureRef(0, channel=0),
                   clearcoat_roughness_texture=TextureRef(0, channel=1),
                   clearcoat_normal_texture=TextureRef(2),
                   sheen_color_texture=TextureRef(1), sheen_roughness_texture=TextureRef(0, channel=3),
                   specular_texture=TextureRef(0, channel=3), specular_color_texture=TextureRef(1),
                   transmission_texture=TextureRef(0, channel=0),
                   thickness_texture=TextureRef(0, channel=1))
    scene = plane_scene(mat)
    scene.images = images
    r = make_renderer(scene)
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    unorm = np.asarray(data) / 255.0
    srgb = ref.srgb_to_linear(np.asarray(color[:3]) / 255.0)
    layers = ref.Layers(
        ior=1.45, specular_color=tuple(np.asarray(mat.specular_color_factor) * srgb),
        specular=0.9 * unorm[3], clearcoat=0.9 * unorm[0],
        clearcoat_roughness=0.8 * unorm[1],
        sheen_color=tuple(np.asarray(mat.sheen_color_factor) * srgb),
        sheen_roughness=0.9 * unorm[3], transmission=0.8 * unorm[0], thickness=2.0 * unorm[1],
        attenuation_color=mat.attenuation_color, attenuation_distance=1.5)
    p, n, v, _ = pixel_geometry()
    to_light = np.asarray(LIGHT.position) - p
    l = to_light / np.linalg.norm(to_light, axis=-1, keepdims=True)
    t = render(r, "tangent", pipeline, env="none") * 2.0 - 1.0
    b = render(r, "bitangent", pipeline, env="none") * 2.0 - 1.0
    tn = np.asarray(normal[:3]) / 255.0 * 2.0 - 1.0
    tn[:2] *= 0.7
    nc = t * tn[0] + b * tn[1] + n * tn[2]
    nc /= np.linalg.norm(nc, axis=-1, keepdims=True)
    assert np.degrees(np.arccos(np.clip(nc[..., 1], -1, 1))).min() > 5.0  # the coat tilts
    c = np.broadcast_to(np.asarray(mat.base_color_factor[:3]), n.shape)
    shape = n.shape[:2]
    want = ref.shade_layered(n, v, l, c, np.full(shape, 0.1), np.full(shape, 0.5),
                             np.asarray(LIGHT.color) * LIGHT.intensity, layers, nc=nc)
    for view in VIEWS:
        got = render(r, view, pipeline, env="none")
        np.testing.assert_allclose(got, np.broadcast_to(want[view.replace("-", "_")], got.shape),
                                   rtol=3e-3, atol=5e-5, err_msg=view)


def test_only_default_layers_take_the_specialised_kernel(make_renderer) -> None:  # noqa: ANN001
    """The compute path compiles a material's shading without layers (shade.glsl
    SHADE_LAYERS false) only where its layers are the defaults: every layered material
    here keeps them (its pixels are checked against the mirror above), a plain one does
    not, and the kernels a frame binds carry the frame's lighting flags and BRDF."""
    from vkpbr.render.gpu_scene import default_layer_mask, has_default_layers, material_block

    def block(mat: Material) -> np.ndarray:
        return material_block(mat, dict.fromkeys(L.MATERIAL_TEXTURES, False))

    plain = block(Material(base_color_factor=(0.3, 0.4, 0.5, 1.0)))
    assert has_default_layers(plain)
    for name, mat in LAYERED.items():
        assert not has_default_layers(block(mat)), name
    # (a scene's table at once, as the compute path asks: the same answer per material)
    mixed = [plain, *(block(m) for m in LAYERED.values()), plain]
    assert default_layer_mask(mixed).tolist() == [True, *[False] * len(LAYERED), True]
    r = make_renderer(plane_scene(LAYERED["clearcoat"]))
    if not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    render(r, "final", "compute", env="none")
    variant = r.shade_variant(RenderOptions(lighting="pbr", brdf="gltf", env="none"))
    kernels = {k for k in r.compute_scene()._pipelines if k[0].startswith("shade_")}
    assert any(constants == variant.constants(True) for _, constants in kernels), kernels
    assert variant.brdf == int(L.Brdf.GLTF) and variant.lighting_flags != 0xFFFFFFFF


def _png_uri(rgba: tuple[int, int, int, int]) -> str:
    """A 4x4 PNG of one texel value as a data URI (the glTF loader's path for images)."""
    import base64
    import io

    from PIL import Image as PilImage

    out = io.BytesIO()
    PilImage.fromarray(np.broadcast_to(np.asarray(rgba, np.uint8), (4, 4, 4)).copy()).save(out, "PNG")
    return "data:image/png;base64," + base64.b64encode(out.getvalue()).decode()


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_specular_glossiness_matches_mirror(make_renderer, tmp_path: Path, pipeline: str) -> None:
    """KHR_materials_pbrSpecularGlossiness read from a glTF file (factors and textures of
    constant texels, so that filtering cannot matter) shades as the mirror's
    `specular_glossiness`: base colour = diffuse x its sRGB texel, F0 = specular x the
    specular-glossiness texel's sRGB RGB (the dielectric-f0 view), roughness = 1 -
    glossiness x its linear A (the roughness view), metallic 0; every view as
    test_layers_match_mirror's."""
    import json

    from vkpbr.scene.gltf import load_gltf

    diffuse_texel, sg_texel = (200, 120, 60, 255), (90, 140, 30, 153)
    sg = {"diffuseFactor": [0.8, 0.9, 1.0, 1.0], "specularFactor": [0.5, 0.8, 1.0],
          "glossinessFactor": 0.9, "diffuseTexture": {"index": 0},
          "specularGlossinessTexture": {"index": 1}}
    doc = {"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_materials_pbrSpecularGlossiness"],
           "extensionsRequired": ["KHR_materials_pbrSpecularGlossiness"],
           "images": [{"uri": _png_uri(diffuse_texel)}, {"uri": _png_uri(sg_texel)}],
           "textures": [{"source": 0}, {"source": 1}],
           "materials": [{"pbrMetallicRoughness": {"metallicFactor": 1.0},
                          "extensions": {"KHR_materials_pbrSpecularGlossiness": sg}}]}
    (tmp_path / "sg.gltf").write_text(json.dumps(doc))
    loaded = load_gltf(tmp_path / "sg.gltf")  # the material and its images (no mesh)
    scene = plane_scene(loaded.materials[0])
    scene.images = loaded.images
    r = make_renderer(scene)
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    # The textures as the GPU decoded them: each colour texel within half an 8-bit code of
    # the file's through the sRGB curve (lavapipe's decode is off by up to 0.35 of a code:
    # 2% at a code of 30), glossiness in A linear. The shading is then checked with these.
    diffuse = render(r, "base-color", pipeline, env="none")[0, 0]
    specular = render(r, "dielectric-f0", pipeline, env="none")[0, 0]
    for value, factor, texel in ((diffuse, sg["diffuseFactor"][:3], diffuse_texel),
                                 (specular, sg["specularFactor"], sg_texel)):
        codes = ref.linear_to_srgb(value / np.asarray(factor)) * 255.0
        np.testing.assert_allclose(codes, texel[:3], atol=0.5)
    glossiness = sg["glossinessFactor"] * sg_texel[3] / 255
    c, metallic, roughness, layers = ref.specular_glossiness(diffuse, specular, glossiness)
    p, n, v, l = pixel_geometry()
    shape = n.shape[:2]
    want = ref.shade_layered(n, v, l, np.broadcast_to(c, n.shape), np.full(shape, metallic),
                             np.full(shape, roughness), np.asarray(LIGHT.color) * LIGHT.intensity,
                             layers)
    np.testing.assert_allclose(want["dielectric_f0"][0, 0], specular, rtol=1e-6)  # F0 = specular
    f0_image = render(r, "dielectric-f0", pipeline, env="none").reshape(-1, 3)
    assert np.ptp(f0_image, axis=0).max() < 1e-5  # constant texels
    checks = {**{view: want[view.replace("-", "_")] for view in VIEWS},
              "roughness": np.full(n.shape, 1.0 - glossiness), "metallic": np.zeros(n.shape),
              "base-color": np.broadcast_to(diffuse, n.shape)}
    for view, value in checks.items():
        got = render(r, view, pipeline, env="none")
        # As test_layer_textures_multiply_their_factors, plus the image's change over 1/64
        # pixel (where the rasterised surface is: the highlight is sharp here).
        assert_close_on_raster(got, np.broadcast_to(value, got.shape), rtol=3e-3, atol=5e-5,
                               what=view)


ANISOTROPIC = Material(base_color_factor=(0.7, 0.5, 0.3, 1), metallic_factor=0.6,
                       roughness_factor=0.3, anisotropy_strength=0.8, anisotropy_rotation=0.6)


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
@pytest.mark.parametrize("texture", [False, True])
def test_anisotropy_matches_mirror(make_renderer, pipeline: str, texture: bool) -> None:
    """KHR_materials_anisotropy: the anisotropic GGX lobe (D, V of the extension, as the Sample
    Viewer) along the direction rotated by anisotropyRotation in the surface's tangent frame
    (read from the tangent and bitangent views), with and without a texture (a constant
    texel: direction RG * 2 - 1, strength x B); the specular and final views and the
    anisotropy view (direction in the tangent plane, strength) against the mirror."""
    from vkpbr.scene.types import TextureRef

    texel = (64, 200, 153, 255)
    mat = ANISOTROPIC
    scene = plane_scene(mat)
    if texture:
        scene.images = [constant_image("anisotropy", texel)]
        mat = dataclasses.replace(mat, anisotropy_texture=TextureRef(0))
        scene.materials = [mat]
    r = make_renderer(scene)
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    t = render(r, "tangent", pipeline, env="none") * 2.0 - 1.0
    b = render(r, "bitangent", pipeline, env="none") * 2.0 - 1.0
    _, n, v, l = pixel_geometry()
    at, ab, scale = ref.anisotropy_frame(t, b, n, n, mat.anisotropy_rotation,
                                         np.asarray(texel[:3]) / 255.0 if texture else None)
    layers = dataclasses.replace(ref.Layers.of(mat), anisotropy=mat.anisotropy_strength * scale)
    c = np.broadcast_to(np.asarray(mat.base_color_factor[:3]), n.shape)
    shape = n.shape[:2]
    want = ref.shade_layered(n, v, l, c, np.full(shape, mat.metallic_factor),
                             np.full(shape, mat.roughness_factor),
                             np.asarray(LIGHT.color) * LIGHT.intensity, layers, frame=(at, ab))
    iso = ref.shade_layered(n, v, l, c, np.full(shape, mat.metallic_factor),
                            np.full(shape, mat.roughness_factor),
                            np.asarray(LIGHT.color) * LIGHT.intensity, ref.Layers())
    assert np.abs(want["specular"] - iso["specular"]).max() > 0.1 * iso["specular"].max()
    for view in ("specular", "diffuse", "final"):
        got = render(r, view, pipeline, env="none")
        assert_close_on_raster(got, np.broadcast_to(want[view], got.shape), rtol=3e-3,
                               atol=5e-5, what=view)
    direction = np.stack([np.sum(at * t, -1), np.sum(at * b, -1)], -1) * 0.5 + 0.5
    got = render(r, "anisotropy", pipeline, env="none")
    np.testing.assert_allclose(got[..., :2], direction, atol=2e-3)
    np.testing.assert_allclose(got[..., 2], layers.anisotropy, atol=2e-3)


IRIDESCENT = Material(base_color_factor=(0.3, 0.5, 0.7, 1), metallic_factor=0.4,
                      roughness_factor=0.35, iridescence_factor=0.9, iridescence_ior=1.6,
                      iridescence_thickness_minimum=150.0, iridescence_thickness_maximum=520.0)


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
@pytest.mark.parametrize("texture", [False, True])
def test_iridescence_matches_mirror(make_renderer, pipeline: str, texture: bool) -> None:
    """KHR_materials_iridescence: the thin film's Fresnel (the mirror's eval_iridescence at
    n.v over the dielectric's F0 and over the base colour) mixed into both lobes by the
    factor, with and without textures (factor x R; thickness = mix(minimum, maximum, G));
    the specular, diffuse, final and iridescence views against the mirror."""
    from vkpbr.scene.types import TextureRef

    texel = (204, 77, 0, 255)
    mat = IRIDESCENT
    scene = plane_scene(mat)
    if texture:
        scene.images = [constant_image("iridescence", texel)]
        mat = dataclasses.replace(mat, iridescence_texture=TextureRef(0),
                                  iridescence_thickness_texture=TextureRef(0, channel=1))
        scene.materials = [mat]
    r = make_renderer(scene)
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    layers = ref.Layers.of(mat)
    if texture:
        g = texel[1] / 255.0
        layers = dataclasses.replace(layers, iridescence=mat.iridescence_factor * texel[0] / 255.0,
                                     iridescence_thickness=150.0 + (520.0 - 150.0) * g)
    _, n, v, l = pixel_geometry()
    c = np.broadcast_to(np.asarray(mat.base_color_factor[:3]), n.shape)
    shape = n.shape[:2]
    args = (n, v, l, c, np.full(shape, mat.metallic_factor), np.full(shape, mat.roughness_factor),
            np.asarray(LIGHT.color) * LIGHT.intensity)
    want = ref.shade_layered(*args, layers)
    plain = ref.shade_layered(*args, ref.Layers())
    assert np.abs(want["specular"] - plain["specular"]).max() > 0.1 * plain["specular"].max()
    for view in ("specular", "diffuse", "final", "iridescence"):
        got = render(r, view, pipeline, env="none")
        assert_close_on_raster(got, np.broadcast_to(want[view], got.shape), rtol=3e-3,
                               atol=1e-4, what=view)


DIFFUSE_TRANSMISSIVE = Material(base_color_factor=(0.6, 0.7, 0.3, 1), metallic_factor=0.1,
                                roughness_factor=0.5, diffuse_transmission_factor=0.7,
                                diffuse_transmission_color_factor=(0.9, 0.4, 0.2),
                                double_sided=True)


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_diffuse_transmission_matches_mirror(make_renderer, pipeline: str) -> None:
    """KHR_materials_diffuse_transmission under a light above and one below the plane: the
    diffuse lobe mixed by the factor with a Lambertian lobe of the transmission colour about
    -n (light from below reaches the viewer through it alone, besides the specular's
    nothing); the diffuse, diffuse-transmission and final views against the mirror."""
    mat = DIFFUSE_TRANSMISSIVE
    for light in (LIGHT, BELOW):
        r = make_renderer(plane_scene(mat, light))
        if pipeline == "compute" and not r.device.compute_path:
            pytest.skip(f"{r.device.info.name} lacks the compute path's features")
        want = mirror(mat, light)
        for view in ("diffuse", "diffuse-transmission", "final", "specular"):
            got = render(r, view, pipeline, env="none")
            assert_close_on_raster(got, np.broadcast_to(want[view.replace("-", "_")], got.shape),
                                   rtol=2e-3, atol=2e-5, what=f"{view}, light {light.position}")
        if light is BELOW:
            assert want["diffuse_transmission"].min() > 1e-4
            np.testing.assert_allclose(want["diffuse"], want["diffuse_transmission"])


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_diffuse_transmission_in_a_uniform_environment(make_renderer, uniform_env: Path,
                                                       tmp_path: Path, pipeline: str) -> None:
    """In a uniform environment the irradiance behind equals the irradiance in front, so the
    image-based diffuse is the material's without the extension times mix(c, transmission
    colour, factor) / c, channel by channel (split_sum_ibl's mix, analytic here)."""
    mat = DIFFUSE_TRANSMISSIVE
    plain = dataclasses.replace(mat, diffuse_transmission_factor=0.0)
    r, r0, opts = _uniform_pair(make_renderer, mat, plain, tmp_path, uniform_env, pipeline)
    c = np.asarray(mat.base_color_factor[:3])
    f, dtc = mat.diffuse_transmission_factor, np.asarray(mat.diffuse_transmission_color_factor)
    got = render(r, "ibl-diffuse", pipeline, **opts)
    want = render(r0, "ibl-diffuse", pipeline, **opts) * ((1 - f) * c + f * dtc) / c
    np.testing.assert_allclose(got, want, rtol=1e-2, atol=1e-5)
    view = render(r, "diffuse-transmission", pipeline, **opts)
    np.testing.assert_allclose(view, render(r0, "ibl-diffuse", pipeline, **opts) * f * dtc / c,
                               rtol=1e-2, atol=1e-5)


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_iridescence_in_a_uniform_environment(make_renderer, uniform_env: Path, tmp_path: Path,
                                              pipeline: str) -> None:
    """Under a uniform environment L the film's share of each lobe is F_i L (radiance alone):
    ibl-specular = (1 - k) x the same material's without the film + k L ((1 - M) F_i,d +
    M F_i,m), ibl-diffuse = (1 - k) x its + k (1 - M) c (1 - max3 F_i,d) L, with F_i the
    mirror's eval_iridescence at n.v (split_sum_ibl's mix, written out: no table needed)."""
    mat = IRIDESCENT
    plain = dataclasses.replace(mat, iridescence_factor=0.0)
    r, r0, opts = _uniform_pair(make_renderer, mat, plain, tmp_path, uniform_env, pipeline)
    _, n, v, _ = pixel_geometry()
    c = np.asarray(mat.base_color_factor[:3])
    f_d, f_m = ref.iridescence_fresnel(ref.Layers.of(mat), np.clip(np.sum(n * v, -1), 0, 1),
                                       np.broadcast_to(c, n.shape))
    k, m, big_l = mat.iridescence_factor, mat.metallic_factor, ENV_RADIANCE
    spec0, diff0 = (render(r0, view, pipeline, **opts) for view in ("ibl-specular", "ibl-diffuse"))
    want_spec = (1 - k) * spec0 + k * big_l * ((1 - m) * f_d + m * f_m)
    want_diff = (1 - k) * diff0 + k * (1 - m) * c * (1 - f_d.max(-1, keepdims=True)) * big_l
    np.testing.assert_allclose(render(r, "ibl-specular", pipeline, **opts), want_spec,
                               rtol=1e-2, atol=1e-4)
    np.testing.assert_allclose(render(r, "ibl-diffuse", pipeline, **opts), want_diff,
                               rtol=1e-2, atol=1e-4)
