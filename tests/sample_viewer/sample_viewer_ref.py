"""The Khronos glTF Sample Viewer as an outside reference: renders the sample models with the
viewer itself (npm ``@khronosgroup/gltf-viewer``, the glTF-Sample-Renderer) in headless
Chromium, WebGL 2 on its software rasteriser (SwiftShader; no GPU), and vkpbr renders the same
scenarios for `fidelity_metric`.

Installed by ``VKPBR_EXTRAS=test,sample-viewer bash scripts/setup.sh`` (scripts/
setup_sample_viewer.sh: Debian's ``chromium-headless-shell`` and ``npm ci`` here); `missing()`
says what is not.

One browser run renders every scenario: `page.html` filters the environment once with the
viewer's own code, then loads each model, sets the camera and saves the canvas. A small
standard-library HTTP server on 127.0.0.1 serves the page, the viewer's files, the models and
the environment, and receives the PNGs.

Conventions matched (docs/fidelity-sample-viewer.md says why each is right):
- camera: the same world-from-camera matrix and vertical field of view (the viewer's user
  camera takes the matrix as is);
- environment: the same .hdr and intensity; the viewer's rotation R is vkpbr's -R - 90
  degrees (`vkpbr_rotation`; the default 90 is vkpbr's 180);
- tone map: Khronos PBR Neutral in both, exposure 1 (0 EV); the viewer then encodes with
  x^(1/2.2), vkpbr with the sRGB curve, so vkpbr's frame is taken linear (after its tone map)
  and encoded with x^(1/2.2) here;
- no punctual light in either (the viewer: usePunctual off; vkpbr: lights=[], so no
  automatic sun), vkpbr's shadows off (the viewer has none), 4x MSAA in both;
- both images are over black; `compare` keeps the pixels either renderer drew.

The viewer's IBL filtering is a fixed cost of the run: at its defaults (256^2 cube faces,
1024^2 BRDF LUT, 2048 / 1024 samples) SwiftShader takes minutes on two cores. BAKES["ci"]
filters 128^2 faces with five levels (the default's roughness steps: 0, 1/4 .. 1) and a 256^2
LUT with the same sample counts; ``VKPBR_SV_BAKE=full`` runs the viewer's defaults.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from io import BytesIO
from pathlib import Path

import generated_models
import numpy as np

HERE = Path(__file__).resolve().parent
VIEWER_DIST = HERE / "node_modules" / "@khronosgroup" / "gltf-viewer" / "dist"
BROWSERS = ("chromium-headless-shell", "chromium")
INSTALL = "VKPBR_EXTRAS=test,sample-viewer bash scripts/setup.sh"

SV_ROTATION = 90.0  # the viewer's default ("front face of the environment is +Z")
GAMMA = 2.2  # the viewer's linearTosRGB: pow(color, 1/2.2)

# Constructor defaults of the viewer's iblSampler -> what the CI bake uses. Each original must
# occur exactly once in the module, so a new package version that changes them fails loudly.
BAKES: dict[str, dict[str, str]] = {
    "ci": {"this.textureSize = 256;": "this.textureSize = 128;",
           "this.lowestMipLevel = 4;": "this.lowestMipLevel = 3;",
           "this.lutResolution = 1024;": "this.lutResolution = 256;"},
    "full": {},
}


def vkpbr_rotation(viewer_rotation: float) -> float:
    """vkpbr's --env-rotation showing what the viewer shows at `viewer_rotation` (degrees).

    The viewer looks its panorama up at M n, M = gl-matrix rotateY(theta_s), with
    u = 0.5 + atan2(z, x) / 2 pi: for n at azimuth phi = atan2(n.z, n.x), u = 0.5 + (phi -
    theta_s) / 2 pi. vkpbr looks up R_y(-theta_v) n (env_common.glsl's env_rotate) with
    u = 0.5 + atan2(x, -z) / 2 pi: u = 0.5 + (phi + theta_v + 90 deg) / 2 pi. Both take
    v = acos(y) / pi (row 0 the zenith), so theta_v = -theta_s - 90: the two turn the
    environment in opposite senses, and the viewer's default 90 is vkpbr's 180.
    EnvironmentBackground checks it at a rotation other than the default each run.
    """
    return (-viewer_rotation - 90.0) % 360.0


def browser() -> str | None:
    return next((b for b in map(shutil.which, BROWSERS) if b), None)


def missing() -> str | None:
    """Why the reference cannot run here (None: it can)."""
    if browser() is None:
        return f"no headless Chromium ({' or '.join(BROWSERS)}) on PATH: run `{INSTALL}`"
    if not (VIEWER_DIST / "gltf-viewer.module.js").is_file():
        return f"@khronosgroup/gltf-viewer not installed in {HERE}: run `{INSTALL}`"
    return None


@dataclass(frozen=True)
class Scenario:
    """One image: a model (path under the assets folder, or a document `make` generates), a
    camera by eye / target and vertical field of view, and whether the environment is drawn
    behind it."""

    name: str
    model: str
    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    yfov_deg: float = 45.0
    background: bool = False
    viewer_rotation: float = SV_ROTATION  # the viewer's environmentRotation, degrees
    # Material extensions removed from both renderers' copies of the .gltf.
    strip: tuple[str, ...] = ()
    # A generated model (generated_models.py): the glTF document, buffers and images embedded.
    make: Callable[[], dict] | None = None

    @property
    def viewer_model(self) -> str:
        """The path the viewer loads: the model's, or a stripped copy's beside it."""
        if not self.strip:
            return self.model
        return self.model[:-len(".gltf")] + f".{self.name}.gltf"

    def document(self, assets: Path) -> dict | None:
        """The glTF document both renderers load when it is not the file as it is: the
        generated one, or the model's without the `strip` extensions (relative URIs kept)."""
        if self.make is not None:
            return self.make()
        if not self.strip:
            return None
        doc = json.loads((assets / self.model).read_text())
        for material in doc.get("materials", []):
            for ext in self.strip:
                material.get("extensions", {}).pop(ext, None)
        for key in ("extensionsUsed", "extensionsRequired"):
            if key in doc:
                doc[key] = [e for e in doc[key] if e not in self.strip]
        return doc

    def available(self, assets: Path) -> bool:
        return self.make is not None or (assets / self.model).is_file()

    def load(self, assets: Path, folder: Path):  # noqa: ANN201 (a vkpbr Scene)
        """The scenario's model as vkpbr loads it: a stripped or generated document is written
        into `folder` (a stripped copy names its model's buffers and images by absolute path,
        so it is loaded with outside paths allowed)."""
        from vkpbr import load_scene

        doc = self.document(assets)
        if doc is None:
            return load_scene(assets / self.model)
        path = folder / f"{self.name}.gltf"
        if self.make is None:
            base = (assets / self.model).parent.resolve()
            for item in [*doc.get("buffers", []), *doc.get("images", [])]:
                if "uri" in item and not item["uri"].startswith("data:"):
                    item["uri"] = str(base / item["uri"])
        path.write_text(json.dumps(doc))
        return load_scene(path, allow_outside_paths=self.make is None)

    def world_from_camera(self) -> np.ndarray:
        """4x4 camera-to-world with OpenGL axes (x right, y up, looking down -z), up +Y."""
        eye, target = np.asarray(self.eye, float), np.asarray(self.target, float)
        z = eye - target
        z /= np.linalg.norm(z)
        x = np.cross((0.0, 1.0, 0.0), z)
        x /= np.linalg.norm(x)
        m = np.eye(4)
        m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, np.cross(z, x), z, eye
        return m

    def clip_planes(self) -> tuple[float, float]:
        """The viewer's near and far planes (vkpbr chooses its own: reversed-Z, no far plane):
        a near plane well in front of the model, as the viewer's own fit does."""
        distance = float(np.linalg.norm(np.subtract(self.eye, self.target)))
        return distance / 100.0, distance * 100.0


def environment_panorama(width: int = 512) -> np.ndarray:
    """A studio-like equirectangular environment in vkpbr's panorama convention (row 0 the
    zenith; the centre column along -Z at rotation 0): a blue sky over a brown ground, a warm
    soft box (radiance 8, 6, 4) at the centre column and a small green one a quarter turn
    away, so a wrong rotation or mirror shows at once. Float32 (H, W, 3), H = W / 2. 512
    wide: vkpbr's lavapipe cube faces are W / 4 = 128, the size of the viewer's CI bake."""
    h = width // 2
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(width) + 0.5) / width
    up = np.cos(v * np.pi)[:, None, None]
    sky = np.array([0.4, 0.6, 1.0]) * (0.3 + 0.7 * np.clip(up, 0, 1))
    pano = np.where(up > 0, sky, np.array([0.3, 0.25, 0.2])).astype(np.float32)
    pano = np.broadcast_to(pano, (h, width, 3)).copy()
    warm = (np.abs(u[None, :] - 0.5) < 0.06) & (np.abs(v[:, None] - 0.35) < 0.08)
    green = (np.abs(u[None, :] - 0.75) < 0.04) & (np.abs(v[:, None] - 0.40) < 0.05)
    pano[warm] = (8.0, 6.0, 4.0)
    pano[green] = (1.0, 4.0, 1.0)
    return pano


def write_environment(path: Path) -> Path:
    import imagecodecs

    path.write_bytes(imagecodecs.rgbe_encode(environment_panorama()))
    return path


def encode_gamma(linear_rgb: np.ndarray) -> np.ndarray:
    """Display-linear [0, 1] RGB -> 8-bit with the viewer's transfer function x^(1/2.2)."""
    return np.round(np.clip(linear_rgb, 0.0, 1.0) ** (1.0 / GAMMA) * 255.0).astype(np.uint8)


@dataclass
class ViewerRun:
    """What one browser run gave: RGBA uint8 images by scenario name, its log, its seconds."""

    images: dict[str, np.ndarray]
    log: list[str]
    seconds: float


# The viewer's roughness clamp, for `roughness_floor` (an experiment of fidelity_table.py).
ROUGHNESS_CLAMP = "materialInfo.perceptualRoughness=clamp(materialInfo.perceptualRoughness,0.0,1.0);"


# Experiments of fidelity_table.py (`--viewer-fix NAME`), never the test's reference: the
# viewer 1.1.0's handling of KHR_materials_pbrSpecularGlossiness, made as the extension says.
# "sg": its diffuse and specular-glossiness textures decoded as sRGB (gltfTextureInfo is
# linear by default, and only the metallic-roughness colour textures are made sRGB), and its
# metallic-roughness shading off where the extension is present (material.type is never
# "SG", so MATERIAL_METALLICROUGHNESS is always defined and the fallback's metallic and
# roughness replace the extension's).
VIEWER_FIXES: dict[str, dict[str, str]] = {
    "sg": {"const diffuseTexture = new gltfTextureInfo();":
           "const diffuseTexture = new gltfTextureInfo(undefined, 0, false);",
           "const specularGlossinessTexture = new gltfTextureInfo();":
           "const specularGlossinessTexture = new gltfTextureInfo(undefined, 0, false);",
           'if (this.type !== "SG")':
           "if (this.extensions?.KHR_materials_pbrSpecularGlossiness === undefined)"},
}


def _viewer_module(bake: str, roughness_floor: float | None = None,
                   fixes: Sequence[str] = ()) -> bytes:
    data = (VIEWER_DIST / "gltf-viewer.module.js").read_bytes()
    patches = dict(BAKES[bake])
    for fix in fixes:
        patches.update(VIEWER_FIXES[fix])
    if roughness_floor is not None:
        patches[ROUGHNESS_CLAMP] = ROUGHNESS_CLAMP.replace("0.0,1.0", f"{roughness_floor!r},1.0")
    for old, new in patches.items():
        count = data.count(old.encode())
        if count != 1:
            raise RuntimeError(f"gltf-viewer.module.js has {count} of {old!r}: "
                               "BAKES in sample_viewer_ref.py needs updating for this version")
        data = data.replace(old.encode(), new.encode())
    return data


def _sheen_lut_png() -> bytes:
    """The sheen albedo LUT the viewer loads from a file the npm package does not ship; no
    compared model uses KHR_materials_sheen, so a 1x1 white image stands in for it."""
    from PIL import Image

    out = BytesIO()
    Image.new("RGBA", (1, 1), (255, 255, 255, 255)).save(out, "PNG")
    return out.getvalue()


_TYPES = {".js": "text/javascript", ".html": "text/html", ".wasm": "application/wasm",
          ".json": "application/json", ".png": "image/png", ".jpg": "image/jpeg"}


def _server(files: dict[str, bytes], assets: Path, inbox: dict[str, bytes],
            done: threading.Event) -> ThreadingHTTPServer:
    root = assets.resolve()

    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args: object) -> None:
            pass

        def do_GET(self) -> None:  # noqa: N802 (http.server's name)
            path = self.path.split("?")[0]
            data = files.get(path)
            if data is None and path.startswith("/viewer/libs/"):
                local = (VIEWER_DIST / "libs" / path[len("/viewer/libs/"):]).resolve()
                data = local.read_bytes() if local.parent == VIEWER_DIST / "libs" else None
            elif data is None and path.startswith("/model/"):
                local = (root / path[len("/model/"):]).resolve()
                data = local.read_bytes() if local.is_relative_to(root) and local.is_file() else None
            if data is None:
                self.send_error(404)
                return
            self.send_response(200)
            self.send_header("Content-Type", _TYPES.get(Path(path).suffix, "application/octet-stream"))
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def do_POST(self) -> None:  # noqa: N802
            body = self.rfile.read(int(self.headers.get("Content-Length", 0)))
            inbox.setdefault(self.path, b"")
            inbox[self.path] += body if self.path != "/log" else body + b"\n"
            self.send_response(200)
            self.end_headers()
            if self.path in ("/done", "/error"):
                done.set()

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def render_viewer(scenarios: Sequence[Scenario], assets: Path, environment: Path,
                  size: int = 256, env_intensity: float = 1.0, bake: str | None = None,
                  timeout: float = 900.0, roughness_floor: float | None = None,
                  fixes: Sequence[str] = ()) -> ViewerRun:
    """Render `scenarios` with the Sample Viewer; raises RuntimeError with the page's error or
    the browser's last lines when the run fails or takes longer than `timeout` seconds.
    `roughness_floor`: serve the viewer with its perceptual roughness clamped to at least this
    (vkpbr's MIN_ROUGHNESS is 0.03), to tell that clamp's effect from others; `fixes`: names
    of VIEWER_FIXES to apply (experiments)."""
    from PIL import Image

    bake = bake or os.environ.get("VKPBR_SV_BAKE", "ci")
    jobs = []
    for s in scenarios:
        znear, zfar = s.clip_planes()
        jobs.append({"name": s.name, "model": s.viewer_model, "yfov": math.radians(s.yfov_deg),
                     "cameraToWorld": s.world_from_camera().T.reshape(-1).tolist(),
                     "znear": znear, "zfar": zfar, "envRotation": s.viewer_rotation,
                     "background": s.background})
    config = {"width": size, "height": size, "antialias": True, "envIntensity": env_intensity,
              "jobs": jobs}
    files = {"/page.html": (HERE / "page.html").read_bytes(),
             "/config.json": json.dumps(config).encode(),
             "/viewer/gltf-viewer.module.js": _viewer_module(bake, roughness_floor, fixes),
             "/env.hdr": environment.read_bytes(), "/sheen_E.png": _sheen_lut_png()}
    files.update({"/model/" + s.viewer_model: json.dumps(doc).encode()
                  for s in scenarios if (doc := s.document(assets)) is not None})
    inbox: dict[str, bytes] = {}
    done = threading.Event()
    server = _server(files, assets, inbox, done)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="vkpbr-sv-") as profile:
        stderr_path = Path(profile) / "stderr.txt"
        with stderr_path.open("wb") as stderr:
            # SwiftShader through ANGLE is Chromium's software WebGL; --enable-unsafe-swiftshader
            # keeps it available for WebGL (newer Chromiums refuse it without the flag).
            proc = subprocess.Popen(
                [browser(), "--headless", "--no-sandbox", "--use-angle=swiftshader",
                 "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--mute-audio",
                 "--disable-dev-shm-usage",  # containers' /dev/shm is often 64 MB
                 "--no-first-run", f"--user-data-dir={profile}/user",
                 f"http://127.0.0.1:{server.server_port}/page.html"],
                stdout=subprocess.DEVNULL, stderr=stderr, start_new_session=True)
            try:
                finished = done.wait(timeout)
            finally:
                # The browser's zygote, GPU and renderer processes are in its session.
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
                server.shutdown()
                server.server_close()
        tail = stderr_path.read_text(errors="replace").splitlines()[-8:]
    seconds = time.perf_counter() - t0
    log = inbox.get("/log", b"").decode().splitlines()
    if "/error" in inbox:
        raise RuntimeError(f"Sample Viewer page: {inbox['/error'].decode()[:2000]}")
    if not finished:
        raise RuntimeError(f"Sample Viewer gave no result in {timeout:.0f} s; log: {log}; "
                           f"browser: {tail}")
    images = {k[len("/result/"):]: np.asarray(Image.open(BytesIO(v)).convert("RGBA"))
              for k, v in inbox.items() if k.startswith("/result/")}
    return ViewerRun(images, log, seconds)


def render_vkpbr(renderer: object, scenario: Scenario, environment: Path,
                 size: int = 256, env_intensity: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """vkpbr's image of `scenario` in the viewer's conventions: (RGB uint8 encoded with
    x^(1/2.2), coverage bool) at size x size. `renderer` holds the scenario's model, msaa=4."""
    from vkpbr import Camera

    camera = Camera(eye=scenario.eye, target=scenario.target, yfov_deg=scenario.yfov_deg)
    linear, depth = renderer.render(
        camera, lights=[], size=(size, size), linear=True, depth=True, tonemap="pbr-neutral",
        exposure=0.0, env=str(environment), env_intensity=env_intensity,
        env_rotation=vkpbr_rotation(scenario.viewer_rotation), env_background=scenario.background,
        shadows=False, ao="off")  # (the Sample Viewer has no screen-space occlusion)
    return encode_gamma(linear[..., :3]), np.isfinite(depth)


# The compared models (under the assets folder) and cameras framing each at 256 x 256.
SCENARIOS: tuple[Scenario, ...] = (
    Scenario("DamagedHelmet", "DamagedHelmet/glTF/DamagedHelmet.gltf", (0, 0, 3), (0, 0, 0)),
    Scenario("MetalRoughSpheresNoTextures",
             "MetalRoughSpheresNoTextures/glTF/MetalRoughSpheresNoTextures.gltf",
             (0.00278, 0.00274, 0.0095), (0.00278, 0.00274, -0.0015)),
    Scenario("NormalTangentMirrorTest",
             "NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf",
             (0, -0.08, 3.6), (0, -0.08, 0)),
    Scenario("AlphaBlendModeTest", "AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf",
             (0, 1.1, 11.0), (0, 1.1, 0)),
    Scenario("TextureCoordinateTest", "TextureCoordinateTest/glTF/TextureCoordinateTest.gltf",
             (0, 0, 3.2), (0, 0, 0)),
    # The only BoomBox in the assets has KHR_materials_pbrSpecularGlossiness over a
    # metallic-roughness fallback: both render the extension. "BoomBoxMetalRough": both the
    # fallback (the extension stripped from both copies).
    Scenario("BoomBox", "BoomBox/glTF-pbrSpecularGlossiness/BoomBox.gltf",
             (0, 0, 0.03), (0, 0, 0)),
    Scenario("BoomBoxMetalRough", "BoomBox/glTF-pbrSpecularGlossiness/BoomBox.gltf",
             (0, 0, 0.03), (0, 0, 0), strip=("KHR_materials_pbrSpecularGlossiness",)),
    # Generated models (generated_models.py): six spheres a material extension's parameters.
    Scenario("SpecGlossSpheres", "generated/SpecGlossSpheres.gltf", (0, 0, 10.5), (0, 0, 0),
             make=generated_models.specular_glossiness_spheres),
    Scenario("AnisotropySpheres", "generated/AnisotropySpheres.gltf", (0, 0, 10.5), (0, 0, 0),
             make=generated_models.anisotropy_spheres),
    Scenario("IridescenceSpheres", "generated/IridescenceSpheres.gltf", (0, 0, 10.5),
             (0, 0, 0), make=generated_models.iridescence_spheres),
    Scenario("DiffuseTransmissionSpheres", "generated/DiffuseTransmissionSpheres.gltf",
             (0, 0, 10.5), (0, 0, 0), make=generated_models.diffuse_transmission_spheres),
    Scenario("DispersionSpheres", "generated/DispersionSpheres.gltf", (0, 0, 10.5), (0, 0, 0),
             make=generated_models.dispersion_spheres),
    # The environment drawn behind the helmet, turned by 30 degrees in the viewer (vkpbr:
    # 240): the panorama mapping and the rotation's sense, apart from any shading. Looking
    # along +Z at the soft boxes.
    Scenario("EnvironmentBackground", "DamagedHelmet/glTF/DamagedHelmet.gltf",
             (0, 0, -3), (0, 0, 0), yfov_deg=90.0, background=True, viewer_rotation=30.0),
)


@dataclass
class Comparison:
    scenario: Scenario
    viewer: np.ndarray  # RGB uint8
    vkpbr: np.ndarray  # RGB uint8
    mask: np.ndarray  # bool: covered by either

    @property
    def db(self) -> float:
        from fidelity_metric import fidelity_db

        return fidelity_db(self.vkpbr, self.viewer, self.mask)

    def picture(self) -> np.ndarray:
        """Viewer | vkpbr | 4 x |difference|, side by side (RGB uint8)."""
        diff = np.abs(self.vkpbr.astype(np.int16) - self.viewer.astype(np.int16)) * 4
        return np.concatenate([self.viewer, self.vkpbr, np.clip(diff, 0, 255).astype(np.uint8)], 1)


def compare(scenario: Scenario, viewer_rgba: np.ndarray, vkpbr_rgb: np.ndarray,
            vkpbr_covered: np.ndarray) -> Comparison:
    """The two images over black and the pixels either drew (the whole frame with the
    environment behind)."""
    covered = vkpbr_covered | (viewer_rgba[..., 3] > 0)
    if scenario.background:
        covered = np.ones_like(covered)
    return Comparison(scenario, viewer_rgba[..., :3].copy(), vkpbr_rgb, covered)
