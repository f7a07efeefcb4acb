"""vkpbr against an outside reference: the Khronos glTF Sample Viewer itself (npm
@khronosgroup/gltf-viewer in headless Chromium, WebGL 2 on SwiftShader), rendering the sample
models with the same camera, environment, intensity and tone map (sample_viewer_ref.py), scored
with the glTF Render Fidelity metric (fidelity_metric.py). docs/fidelity-sample-viewer.md has
the table, the pictures and what differs on purpose.

Skips only when the sample-viewer extra is not installed (`sample_viewer_ref.missing()`), or a
model is not in the assets; a browser that runs but fails is a failure.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from fidelity_metric import MAX_DELTA, fidelity_db, yiq_delta
from sample_viewer_ref import (
    SCENARIOS,
    Scenario,
    compare,
    missing,
    render_viewer,
    render_vkpbr,
    write_environment,
)

# Fail above these (dB; lower is closer). model-viewer fails its own regressions above -22 dB,
# and mature real-time renderers sit at -14 to -18 dB against path-traced references. Each
# limit is the measured value (docs/fidelity-sample-viewer.md) plus about 1.5 dB of room for
# the two software rasterisers' and the bakes' variation; a shading or convention error costs
# several dB (a wrong environment rotation: DamagedHelmet -13 dB).
THRESHOLDS_DB = {
    "DamagedHelmet": -22.0,
    # Fractional metallic (the middle rows): vkpbr mixes F0 before the compensation, the viewer
    # mixes the dielectric and metal lobes (issue 34 item 1); tighten when that lands.
    "MetalRoughSpheresNoTextures": -17.5,
    # Mirror panels (roughness 0) reflect the soft boxes' hard edges: the two cubes' texels
    # (-19.0 dB while vkpbr read its environment at the punctual floor's roughness, 0.03).
    "NormalTangentMirrorTest": -19.0,
    "AlphaBlendModeTest": -19.5,
    "TextureCoordinateTest": -25.0,
    # KHR_materials_pbrSpecularGlossiness in both, but the viewer 1.1.0 reads its textures as
    # linear and shades the fallback's metallic and roughness (docs/fidelity-sample-viewer.md:
    # with both fixed in the viewer, -23.6 dB); the generated spheres (factors only, a
    # fallback that agrees) compare the extension itself.
    "BoomBox": -12.0,
    "BoomBoxMetalRough": -22.5,
    "SpecGlossSpheres": -21.0,
    "AnisotropySpheres": -18.5,
    "IridescenceSpheres": -21.0,
    "DiffuseTransmissionSpheres": -20.0,
    # The striped backdrop fills the frame (the spheres' pixels alone: -26.3 dB).
    "DispersionSpheres": -26.5,
    # The viewer draws its background with a 10% magnification (cubemap.vert's w = z + 0.1).
    "EnvironmentBackground": -15.5,
}


def test_every_scenario_has_a_threshold() -> None:
    assert {s.name for s in SCENARIOS} == set(THRESHOLDS_DB)


def test_yiq_delta_by_hand() -> None:
    """A pure-red difference against the formula written out; the largest delta, searched
    over the corners of the RGB difference cube (the form is convex), is model-viewer's
    35215; black against white is 32857 (-0.31 dB)."""
    red = np.array([255.0, 0, 0])
    y, i, q = 0.29889531 * 255, 0.59597799 * 255, 0.21147017 * 255
    assert yiq_delta(red, np.zeros(3)) == pytest.approx(0.5053 * y * y + 0.299 * i * i
                                                        + 0.1957 * q * q)
    corners = np.array(list(itertools.product((-255.0, 0.0, 255.0), repeat=3)))
    assert yiq_delta(corners, np.zeros(3)).max() == pytest.approx(MAX_DELTA, abs=1.0)
    white, black = np.full((2, 2, 3), 255), np.zeros((2, 2, 3))
    mask = np.ones((2, 2), bool)
    assert fidelity_db(white, black, mask) == pytest.approx(10 * np.log10(32857.0 / MAX_DELTA),
                                                            abs=0.01)
    assert fidelity_db(white, white, mask) == -np.inf


def test_fidelity_db_counts_only_covered_pixels() -> None:
    a = np.zeros((4, 4, 3))
    b = a.copy()
    b[0, 0] = (10, 20, 30)
    one = np.zeros((4, 4), bool)
    one[0, 0] = True
    d = yiq_delta(b[0, 0], a[0, 0])
    assert fidelity_db(a, b, one) == pytest.approx(10 * np.log10(d / MAX_DELTA))
    # Over all 16 pixels the RMS of delta falls by 4: -6.02 dB.
    assert fidelity_db(a, b, np.ones((4, 4), bool)) == pytest.approx(
        10 * np.log10(d / 4 / MAX_DELTA))


@pytest.fixture(scope="module")
def viewer(assets: Path, tmp_path_factory: pytest.TempPathFactory):
    why = missing()
    if why is not None:
        pytest.skip(f"Sample Viewer reference not installed: {why}")
    present = [s for s in SCENARIOS if s.available(assets)]
    env = write_environment(tmp_path_factory.mktemp("sv") / "studio.hdr")
    return render_viewer(present, assets, env, timeout=540.0), env


# The first scenario's setup runs the browser, mostly the viewer's IBL filtering in
# SwiftShader (130 s on two cores that other jobs kept at a load of 12): room beyond the
# suite's 300 s per test.
@pytest.mark.timeout(600)
@pytest.mark.parametrize("scenario", SCENARIOS, ids=lambda s: s.name)
def test_vkpbr_against_sample_viewer(scenario: Scenario, viewer, assets: Path, make_renderer,
                                     tmp_path: Path) -> None:
    run, env = viewer
    if scenario.name not in run.images:
        pytest.skip(f"{scenario.model} not in the assets at {assets}")
    from PIL import Image

    r = make_renderer(scenario.load(assets, tmp_path), msaa=4)
    rgb, covered = render_vkpbr(r, scenario, env)
    c = compare(scenario, run.images[scenario.name], rgb, covered)
    if not scenario.background:  # both drew the model: each covers most of what the other does
        viewer_covered = run.images[scenario.name][..., 3] > 0
        both = np.count_nonzero(viewer_covered & covered)
        assert both >= 0.9 * max(np.count_nonzero(viewer_covered), np.count_nonzero(covered))
    db = c.db
    if db > THRESHOLDS_DB[scenario.name]:
        picture = tmp_path / f"{scenario.name}.png"
        Image.fromarray(c.picture()).save(picture)
        pytest.fail(f"{scenario.name}: {db:.1f} dB against the Sample Viewer, above "
                    f"{THRESHOLDS_DB[scenario.name]} dB (viewer | vkpbr | 4x difference: "
                    f"{picture})")
