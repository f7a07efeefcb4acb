"""OrientationTest comes out the right way round (issue: "TextureCoordinateTest and
OrientationTest come out the right way round (pixel checks against what their screenshots
show)").

The model (its README): a light-blue cube with an arrow on each face, placed by its node's
rotation (red on +X, green on +Y, blue on +Z by quaternions; cyan on -X, magenta on -Y,
yellow on -Z by matrices), each pointing at a target of its own colour whose position is
baked into the target's vertices. The screenshot looks from the +X+Y+Z octant: blue arrow on
the left face, red on the right face, green on top, each arrow touching its target.

The test renders the base-colour view (flat material colours, no lighting) from that octant and
from the opposite one, and probes pixels at model points projected with the renderer's own
camera maths (vkpbr.render.camera): three points along each arrow, from its node's origin
towards its target, the target itself, and two points that must show the bare cube face
(behind the arrow's tail, and beside the arrow). The expected points come from the glTF file
alone (node translations, the targets' baked vertices, material colours), not through the
loader, so a mirrored image, a lost node matrix or an arrow turned the wrong way does not match
them (a transposed rotation fails the 35, 70, 15 and 17 degree arrows; the 5 and 12 degree
ones stay within their own width at this size: tests/scene/test_gltf.py checks the matrices).
A second check, which does not use the projection, puts each colour's pixels on the side of
the image the screenshot shows, so camera maths that mirrored both the render and the probes
would fail too. Every probe has at least one pixel of margin: its 8 neighbours match too.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from pinhole import project as pinhole_project

from vkpbr.scene.loader import load_scene
from vkpbr.scene.types import Camera

GLTF = Path("OrientationTest") / "glTF" / "OrientationTest.gltf"
SIZE = 224  # square image: about 12 pixels per model unit at the cube; arrow shafts 7-10 wide
LIFT = 0.3  # the arrows and targets stand 0.33 proud of the cube's faces (their meshes' extent)
TARGET_BACK = 0.1  # a target is a bar ~0.35 across, just beyond the tip: probe its arrow side
BLACK = (0, 0, 0)


@dataclass(frozen=True)
class Arrow:
    name: str  # "X1" ... "Z2", as in the node names ArrowX1 / TargetX1
    origin: np.ndarray  # the node's translation: the centre of its cube face
    normal: np.ndarray  # outward normal of that face
    direction: np.ndarray  # unit, in the face plane, from the origin towards the target
    target: np.ndarray  # mean of the target's vertices (baked: no node transform applies)
    colour: tuple[int, int, int]  # base colour factor, sRGB-encoded as the sRGB render target stores it


def srgb8(linear: list[float]) -> tuple[int, int, int]:
    from vkpbr.scene.color import linear_to_srgb  # the project's one sRGB curve

    return tuple(int(round(v * 255)) for v in linear_to_srgb(linear[:3]))


def read_model(path: Path) -> tuple[dict[str, Arrow], tuple[int, int, int]]:
    """The six arrows and the cube's colour, straight from the glTF JSON and its buffer."""
    gltf = json.loads(path.read_text())
    nodes = {n["name"]: n for n in gltf["nodes"]}
    buffer = (path.parent / gltf["buffers"][0]["uri"]).read_bytes()

    def positions(index: int) -> np.ndarray:
        acc = gltf["accessors"][index]
        view = gltf["bufferViews"][acc["bufferView"]]
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        assert acc["componentType"] == 5126 and view.get("byteStride", 12) == 12  # tight float vec3
        return np.frombuffer(buffer, np.float32, 3 * acc["count"], start).reshape(-1, 3)

    def primitive(node: dict) -> dict:
        return gltf["meshes"][node["mesh"]]["primitives"][0]

    def colour(prim: dict) -> tuple[int, int, int]:
        return srgb8(gltf["materials"][prim["material"]]["pbrMetallicRoughness"]["baseColorFactor"])

    arrows = {}
    for name in ("X1", "X2", "Y1", "Y2", "Z1", "Z2"):
        node, target_node = nodes[f"Arrow{name}"], nodes[f"Target{name}"]
        # glTF matrices are column-major: the translation is elements 12..14.
        origin = np.asarray(node["translation"] if "translation" in node else node["matrix"][12:15], float)
        normal = origin / np.linalg.norm(origin)
        target = positions(primitive(target_node)["attributes"]["POSITION"]).mean(axis=0).astype(float)
        d = target - origin
        d -= normal * (d @ normal)
        assert primitive(node)["material"] == primitive(target_node)["material"], name
        arrows[name] = Arrow(name, origin, normal, d / np.linalg.norm(d), target, colour(primitive(node)))
    return arrows, colour(primitive(nodes["BaseCube"]))


def octant_camera(sign: float) -> Camera:
    """From the screenshot's +X+Y+Z octant (sign 1) or the opposite one (sign -1)."""
    eye = sign * 22.0 * np.array([1.0, 0.8, 1.0]) / np.linalg.norm([1.0, 0.8, 1.0])
    return Camera(eye=tuple(eye), target=(0.0, 0.0, 0.0), yfov_deg=45.0, znear=1.0, zfar=100.0)


def project(camera: Camera, point: np.ndarray) -> tuple[int, int]:
    """(row, column) of the pixel that `point` (world) falls in (tests/pinhole.py)."""
    row, col, _ = pinhole_project(camera, point, SIZE, SIZE)
    return int(row), int(col)


def probes(arrow: Arrow, cube: tuple[int, int, int]) -> list[tuple[str, np.ndarray, tuple[int, int, int]]]:
    """(what, world point, expected colour) for one arrow. The arrow's mesh runs along its axis
    from -1 to 3: a shaft 0.84 wide up to 1.23, then a head 1.43 wide narrowing to the tip,
    which touches the target."""
    lifted = arrow.origin + LIFT * arrow.normal
    side = np.cross(arrow.normal, arrow.direction)
    target = lifted + (arrow.target - arrow.origin) @ (np.eye(3) - np.outer(arrow.normal, arrow.normal))
    return [
        *((f"arrow {t:+}", lifted + t * arrow.direction, arrow.colour) for t in (-0.4, 0.5, 1.6)),
        ("target", target - TARGET_BACK * arrow.direction, arrow.colour),
        ("face behind the tail", arrow.origin - 2.5 * arrow.direction, cube),
        ("face beside the arrow", arrow.origin + 2.0 * side, cube),
    ]


def nearest(pixel: np.ndarray, palette: list[tuple[int, int, int]]) -> tuple[int, int, int]:
    return min(palette, key=lambda c: float(np.abs(pixel.astype(int) - c).sum()))


def probe_failures(img: np.ndarray, camera: Camera, arrows: list[Arrow], cube: tuple[int, int, int],
                   palette: list[tuple[int, int, int]]) -> list[str]:
    failures = []
    for arrow in arrows:
        for what, point, want in probes(arrow, cube):
            row, col = project(camera, point)
            assert 0 <= row < SIZE and 0 <= col < SIZE, (arrow.name, what, row, col)
            pixel = tuple(int(v) for v in img[row, col, :3])
            got = nearest(np.asarray(pixel), palette)
            if got != want:
                failures.append(f"{arrow.name} {what} at (row {row}, col {col}): "
                                f"{pixel} is nearest {got}, want {want}")
    return failures


def centroid(img: np.ndarray, colour: tuple[int, int, int]) -> tuple[float, float]:
    """(row, column) centre of the pixels within 40 (summed |diff|) of `colour`, in [0, 1]."""
    rows, cols = np.nonzero(np.abs(img[..., :3].astype(int) - colour).sum(axis=-1) < 40)
    assert rows.size > 20, f"no {colour} pixels"
    return rows.mean() / SIZE, cols.mean() / SIZE


def layout_failures(img: np.ndarray, arrows: dict[str, Arrow], front: bool) -> list[str]:
    """Where each face's arrow appears, as the screenshot shows it (no projection used): from
    the +X+Y+Z octant blue (+Z) is left, red (+X) right, green (+Y) at the top; from the
    opposite octant yellow (-Z) is left, cyan (-X) right, magenta (-Y) at the bottom."""
    left, right, updown = ("Z1", "X1", "Y1") if front else ("Z2", "X2", "Y2")
    at = {name: centroid(img, arrows[name].colour) for name in (left, right, updown)}
    failures = []
    if not at[left][1] < 0.45:
        failures.append(f"{left} not on the left: column {at[left][1]:.2f}")
    if not at[right][1] > 0.55:
        failures.append(f"{right} not on the right: column {at[right][1]:.2f}")
    lateral = (at[left][0] + at[right][0]) / 2
    if front and not at[updown][0] < min(0.45, lateral - 0.1):
        failures.append(f"{updown} not at the top: row {at[updown][0]:.2f}, sides at {lateral:.2f}")
    if not front and not at[updown][0] > max(0.55, lateral + 0.1):
        failures.append(f"{updown} not at the bottom: row {at[updown][0]:.2f}, sides at {lateral:.2f}")
    return failures


@pytest.mark.parametrize("front", [True, False], ids=["quaternions-octant+", "matrices-octant-"])
def test_orientation_test_right_way_round(make_renderer, assets: Path, front: bool) -> None:
    path = assets / GLTF
    arrows, cube = read_model(path)
    palette = [a.colour for a in arrows.values()] + [cube, BLACK]
    camera = octant_camera(1.0 if front else -1.0)
    img = make_renderer(load_scene(path)).render(camera, size=(SIZE, SIZE), view="base_color")
    seen = [arrows[n] for n in (("X1", "Y1", "Z1") if front else ("X2", "Y2", "Z2"))]
    failures = layout_failures(img, arrows, front) + probe_failures(img, camera, seen, cube, palette)
    assert not failures, "\n".join(failures)
