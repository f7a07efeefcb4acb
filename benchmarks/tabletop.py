"""The tabletop worlds scene (issue 32, must-have 4): a robot-learning world made here, no download.

One world is a floor, a table, a 7-link arm (a capsule a link and a box hand, each its own
mesh and node), 10 objects on the table (boxes, spheres and capsules; optionally two of them
glTF sample models: DamagedHelmet and CesiumMilkTruck from the sample-models folder), one
directional light and the sky. W worlds share it all but the poses of N = 17 moving bodies
(`MOVING`: link0..link6, obj0..obj9), which a simulator would write every step:

    world = make_tabletop(seed=32)                  # primitives only: make_tabletop(models=())
    write_gltf(world, "out/tabletop")               # -> out/tabletop/tabletop.gltf (+ .bin, models)
    write_mjcf(world, "out/tabletop/tabletop.xml")  # the primitives-only world for MuJoCo
    motion = Motion(world, worlds=4096)             # per-world joint phases, object paths
    poses = motion.poses(step=10, quaternion="wxyz")          # (W, N, 7) float32, NumPy
    poses = motion.poses(10, "wxyz", device="cuda")           # the same numbers, a torch tensor
    spin = Spin(rest_rows, worlds=8192)             # any objects turning in place (the helmet worlds)

Frames and conventions:
- The world is z-up, in metres (MuJoCo, SAPIEN, ROS). A pose row is position (x, y, z) then
  a unit quaternion in the order asked for by name: "xyzw" (glTF, SciPy) or "wxyz" (MuJoCo,
  SAPIEN, Isaac).
- In the glTF, every body is a child of one root node, "tabletop", that turns z-up into glTF's
  y-up (-90 degrees about x). The moving nodes' local poses are therefore the z-up world
  poses: `Renderer.set_poses(MOVING, poses)` (space="local", the default) takes the same rows
  as MuJoCo's qpos and SAPIEN's pose buffer.
- The camera (`world.camera`) is an OpenGL world-from-camera pose (looks down its -z, +y up) in
  the z-up world; `camera_gltf(world)` gives it in the glTF's y-up world for vkpbr.

Everything is deterministic per seed: the scene (sizes, colours, places) from `seed`, the
motion from `Motion(seed=...)` (NumPy's PCG64, stable across versions). NumPy only (torch
when a device is asked for), so the peer scripts import it without vkpbr.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import sys
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

SEED = 32
DT = 1.0 / 60.0  # seconds a step (a 60 Hz control loop)
TABLE_HEIGHT = 0.75
TABLE_HALF = (0.6, 0.4, 0.02)  # the top's half extents (x, y, z)
ARM_BASE = (-0.45, 0.0, TABLE_HEIGHT)
# The arm: link i turns about its joint's axis (in the frame of link i - 1's end) and reaches
# LINK_LENGTH[i] along its own +z. Axes alternate as on a 7-DoF arm (yaw, pitch, yaw, ...).
LINK_AXIS = "zyzyzyz"
LINK_LENGTH = (0.12, 0.28, 0.10, 0.26, 0.08, 0.12, 0.06)
LINK_RADIUS = (0.06, 0.05, 0.045, 0.04, 0.04, 0.035, 0.0)  # link6 is a box (the hand)
HAND_HALF = (0.05, 0.025, 0.03)
ARM_REST = (0.0, 0.5, 0.0, 1.1, 0.0, 0.7, 0.0)  # joint angles (radians) of the rest pose
ARM_AMPLITUDE = (0.8, 0.25, 0.6, 0.3, 0.8, 0.4, 1.2)
OBJECTS = 10
ARM_LINKS = 7
MOVING = tuple([f"link{i}" for i in range(ARM_LINKS)] + [f"obj{k}" for k in range(OBJECTS)])
# Sample models (folder, glTF path inside the sample-models folder, height in metres): they
# replace the last objects when asked for.
MODELS = {"DamagedHelmet": ("DamagedHelmet/glTF/DamagedHelmet.gltf", 0.16),
          "CesiumMilkTruck": ("CesiumMilkTruck/glTF/CesiumMilkTruck.gltf", 0.09)}
MODEL_SLOTS = (9, 4)  # the objects the models replace: the far end of each row, apart
LIGHT_DIRECTION = (-0.35, 0.25, -1.0)  # where the sun's light travels (z-up)
LIGHT_LUX = 4.0
CAMERA_EYE, CAMERA_TARGET, CAMERA_YFOV = (1.05, -0.95, 1.5), (0.0, 0.0, 0.85), 45.0
_ZUP_TO_YUP = (-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))  # x, y, z, w: -90 degrees about x


@dataclass(frozen=True)
class Shape:
    """One piece of geometry of a body, in the body's frame.

    kind: "box" (size = half extents x, y, z), "sphere" (radius,), "capsule" (radius, half
    length of its cylinder; along the body's z, as MJCF's), "plane" (half extents x, y; facing
    +z) or "model" (a sample model: `model` is its MODELS key, size = (scale,)).
    """

    kind: str
    size: tuple[float, ...]
    pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)  # x, y, z, w
    color: tuple[float, float, float, float] = (0.8, 0.8, 0.8, 1.0)  # linear RGBA
    metallic: float = 0.0
    roughness: float = 0.6
    model: str | None = None


@dataclass(frozen=True)
class Body:
    name: str
    shape: Shape
    rest: tuple[float, ...]  # position + quaternion x, y, z, w (z-up world)
    moving: bool


@dataclass(frozen=True)
class Tabletop:
    seed: int
    bodies: tuple[Body, ...]
    camera: np.ndarray  # (4, 4) OpenGL world-from-camera, z-up world
    yfov_deg: float
    light_direction: tuple[float, float, float]
    light_lux: float
    object_centres: np.ndarray  # (OBJECTS, 2): the middle of each object's cell on the table
    object_rest: np.ndarray  # (OBJECTS, 5): resting height z, then its rest quaternion x, y, z, w
    models: tuple[str, ...] = field(default=())

    @property
    def primitives_only(self) -> bool:
        return not self.models

    @property
    def moving(self) -> tuple[Body, ...]:
        return tuple(b for b in self.bodies if b.moving)


# ---------------------------------------------------------------------------------------------
# Quaternions (x, y, z, w in the last axis), written once for NumPy and torch alike.

def _stack(xp, parts, axis: int = -1):  # noqa: ANN001, ANN202
    return xp.stack(parts, axis) if xp is np else xp.stack(parts, dim=axis)


def qmul(xp, a, b):  # noqa: ANN001, ANN201
    """Hamilton product a * b (rotate by b, then by a)."""
    ax, ay, az, aw = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bx, by, bz, bw = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return _stack(xp, [aw * bx + ax * bw + ay * bz - az * by,
                       aw * by - ax * bz + ay * bw + az * bx,
                       aw * bz + ax * by - ay * bx + az * bw,
                       aw * bw - ax * bx - ay * by - az * bz])


def qrotate(xp, q, v):  # noqa: ANN001, ANN201
    """v rotated by unit quaternion q: v + 2 w (u x v) + 2 u x (u x v)."""
    u, w = q[..., :3], q[..., 3:4]
    t = 2 * _cross(xp, u, v)
    return v + w * t + _cross(xp, u, t)


def _cross(xp, a, b):  # noqa: ANN001, ANN202
    return _stack(xp, [a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                       a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                       a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]])


def axis_angle(xp, axis: str, angle):  # noqa: ANN001, ANN201
    """Quaternions (..., 4) of `angle` (radians, any shape) about "x", "y" or "z"."""
    s, c = xp.sin(angle / 2), xp.cos(angle / 2)
    zero = s * 0
    parts = [zero, zero, zero, c]
    parts["xyz".index(axis)] = s
    return _stack(xp, parts)


def quat_matrix(q: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotation matrices of unit quaternions (..., 4) x, y, z, w."""
    x, y, z, w = np.moveaxis(np.asarray(q, np.float64), -1, 0)
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
                     np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
                     np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1)],
                    -2)


def pose_matrix(rows: np.ndarray, quaternion: str = "xyzw") -> np.ndarray:
    """(..., 4, 4) matrices of (..., 7) pose rows (position + quaternion in that order)."""
    rows = np.asarray(rows, np.float64)
    q = rows[..., 3:] if quaternion == "xyzw" else rows[..., [4, 5, 6, 3]]
    m = np.zeros(rows.shape[:-1] + (4, 4))
    m[..., :3, :3], m[..., :3, 3], m[..., 3, 3] = quat_matrix(q), rows[..., :3], 1.0
    return m


# ---------------------------------------------------------------------------------------------
# The scene

def arm_fk(xp, angles, base):  # noqa: ANN001, ANN201
    """Link poses of the arm: angles (..., 7) radians, base (..., 3) -> positions (..., 7, 3)
    and quaternions (..., 7, 4) x, y, z, w of each link's frame (at its joint; the link
    reaches LINK_LENGTH[i] along that frame's +z)."""
    p, q = base, None
    ps, qs = [], []
    for i in range(ARM_LINKS):
        turn = axis_angle(xp, LINK_AXIS[i], angles[..., i])
        if q is None:
            q = turn
        else:
            reach = _stack(xp, [p[..., 0] * 0, p[..., 0] * 0, p[..., 0] * 0 + LINK_LENGTH[i - 1]])
            p = p + qrotate(xp, q, reach)
            q = qmul(xp, q, turn)
        ps.append(p)
        qs.append(q)
    return _stack(xp, ps, -2), _stack(xp, qs, -2)


def _object_shapes(rng: np.random.Generator, models: tuple[str, ...]) -> list[tuple[Shape, float, tuple]]:
    """The objects' shapes with their resting height above the table top and rest quaternion
    (capsules lie on their side)."""
    palette = [(0.80, 0.15, 0.12), (0.95, 0.60, 0.10), (0.15, 0.45, 0.85), (0.20, 0.65, 0.30),
               (0.60, 0.25, 0.70), (0.90, 0.85, 0.20), (0.10, 0.70, 0.70), (0.85, 0.40, 0.55),
               (0.45, 0.30, 0.20), (0.75, 0.75, 0.78)]
    out = []
    lying = (0.0, math.sqrt(0.5), 0.0, math.sqrt(0.5))  # +90 degrees about y: z axis -> x
    for k in range(OBJECTS):
        color = (*palette[k], 1.0)
        metallic = 1.0 if k % 5 == 2 else 0.0
        rough = float(rng.uniform(0.25, 0.8))
        if k % 3 == 0:
            half = tuple(float(v) for v in rng.uniform(0.025, 0.06, 3))
            item = (Shape("box", half, color=color, metallic=metallic, roughness=rough),
                    half[2], (0.0, 0.0, 0.0, 1.0))
        elif k % 3 == 1:
            r = float(rng.uniform(0.03, 0.055))
            item = (Shape("sphere", (r,), color=color, metallic=metallic, roughness=rough),
                    r, (0.0, 0.0, 0.0, 1.0))
        else:
            r, h = float(rng.uniform(0.02, 0.035)), float(rng.uniform(0.03, 0.06))
            item = (Shape("capsule", (r, h), color=color, metallic=metallic, roughness=rough),
                    r, lying)
        # a model replaces the primitive after its draws: the other objects stay the same
        slot = MODEL_SLOTS.index(k) if k in MODEL_SLOTS else len(models)
        if slot < len(models):
            item = (Shape("model", (1.0,), model=models[slot]), 0.0, (0.0, 0.0, 0.0, 1.0))
        out.append(item)
    return out


def make_tabletop(seed: int = SEED, models: tuple[str, ...] = tuple(MODELS)) -> Tabletop:
    """The world: static floor and table, the arm at rest (ARM_REST), 10 objects at the
    middle of their cells (a 5 x 2 grid on the table's far side from the arm). `models`:
    up to two sample models (MODELS keys) that replace objects MODEL_SLOTS; () for the
    primitives-only world (the MJCF variant)."""
    unknown = [m for m in models if m not in MODELS]
    if unknown or len(models) > len(MODEL_SLOTS):
        raise ValueError(f"models {list(models)}: choose at most {len(MODEL_SLOTS)} of {', '.join(MODELS)}")
    rng = np.random.default_rng(seed)
    top = TABLE_HEIGHT
    wood = dict(color=(0.55, 0.38, 0.22, 1.0), roughness=0.55)
    bodies = [Body("floor", Shape("plane", (3.0, 3.0), color=(0.42, 0.42, 0.40, 1.0), roughness=0.9),
                   (0, 0, 0, 0, 0, 0, 1), False),
              Body("table", Shape("box", TABLE_HALF, (0, 0, -TABLE_HALF[2]), **wood),
                   (0, 0, top, 0, 0, 0, 1), False)]
    leg = (0.025, 0.025, (top - 2 * TABLE_HALF[2]) / 2)
    for i, (sx, sy) in enumerate([(1, 1), (-1, 1), (-1, -1), (1, -1)]):
        at = (sx * (TABLE_HALF[0] - 0.05), sy * (TABLE_HALF[1] - 0.05), leg[2])
        bodies.append(Body(f"leg{i}", Shape("box", leg, **wood), (*at, 0, 0, 0, 1), False))
    pos, quat = arm_fk(np, np.asarray(ARM_REST), np.asarray(ARM_BASE, np.float64))
    grey = [(0.85, 0.85, 0.87, 1.0), (0.20, 0.22, 0.25, 1.0)]
    for i in range(ARM_LINKS):
        if i < ARM_LINKS - 1:
            r, half = LINK_RADIUS[i], LINK_LENGTH[i] / 2
            shape = Shape("capsule", (r, half), (0, 0, half), color=grey[i % 2], metallic=0.3 * (i % 2),
                          roughness=0.35)
        else:
            shape = Shape("box", HAND_HALF, (0, 0, HAND_HALF[2]), color=grey[1], roughness=0.5)
        bodies.append(Body(f"link{i}", shape, (*pos[i], *quat[i]), True))
    cells = np.array([(x, y) for y in (-0.17, 0.17) for x in np.linspace(-0.12, 0.45, 5)])
    centres = cells + rng.uniform(-0.03, 0.03, cells.shape)
    rest = np.zeros((OBJECTS, 5))
    for k, (shape, height, q) in enumerate(_object_shapes(rng, tuple(models))):
        if shape.kind == "model":
            shape, height = _model_shape(shape.model)
        rest[k] = (top + height, *q)
        bodies.append(Body(f"obj{k}", shape, (*centres[k], top + height, *q), True))
    return Tabletop(seed, tuple(bodies), look_at(CAMERA_EYE, CAMERA_TARGET), CAMERA_YFOV,
                    LIGHT_DIRECTION, LIGHT_LUX, centres, rest, tuple(models))


def _model_shape(name: str) -> tuple[Shape, float]:
    """A sample model as an object: turned from glTF's y-up to z-up, scaled to its height in
    MODELS, lifted so that it rests on the table (its bounds' lowest point at the body's
    origin). The bounds come from the file (accessor min/max through its node transforms),
    so the scale is known without the assets only when the file is there: without it the
    model's nominal bounds (a unit cube) stand in, and write_gltf fails naming the file."""
    lo, hi = _model_bounds(name)
    size = hi - lo
    scale = MODELS[name][1] / max(size[1], 1e-9)  # glTF's height is y
    centre = (lo + hi) / 2
    # y-up -> z-up: +90 degrees about x maps y to z; the model's (x, y, z) lands at (x, -z, y)
    pos = (-centre[0] * scale, centre[2] * scale, -lo[1] * scale)
    q = (math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))
    return Shape("model", (scale,), pos, q, model=name), 0.0


def assets_dir() -> Path:
    """The sample-models folder, as the tests and the peers find it (tests/assets_path.py)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    try:
        from assets_path import ASSETS
    finally:
        sys.path.pop(0)
    return ASSETS


def _model_bounds(name: str) -> tuple[np.ndarray, np.ndarray]:
    path = assets_dir() / MODELS[name][0]
    if not path.exists():
        return np.full(3, -0.5), np.full(3, 0.5)
    doc = json.loads(path.read_text())
    corners = []
    scene = doc.get("scenes", [{}])[doc.get("scene", 0)]

    def walk(i: int, parent: np.ndarray) -> None:
        node = doc["nodes"][i]
        m = parent @ _node_matrix(node)
        if "mesh" in node:
            for prim in doc["meshes"][node["mesh"]]["primitives"]:
                acc = doc["accessors"][prim["attributes"]["POSITION"]]
                lo, hi = np.array(acc["min"]), np.array(acc["max"])
                box = np.array([[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                                for z in (lo[2], hi[2])])
                corners.append((box @ m.T)[:, :3])
        for c in node.get("children", []):
            walk(c, m)

    for root in scene.get("nodes", []):
        walk(root, np.eye(4))
    pts = np.concatenate(corners)
    return pts.min(0), pts.max(0)


def _node_matrix(node: dict) -> np.ndarray:
    if "matrix" in node:
        return np.asarray(node["matrix"], np.float64).reshape(4, 4).T  # glTF: column-major
    m = pose_matrix(np.array([*node.get("translation", (0, 0, 0)), *node.get("rotation", (0, 0, 0, 1))]))
    return m @ np.diag([*node.get("scale", (1, 1, 1)), 1.0])


def look_at(eye, target, up=(0.0, 0.0, 1.0)) -> np.ndarray:  # noqa: ANN001
    """(4, 4) OpenGL world-from-camera: the camera looks down its -z with +y towards `up`."""
    eye, target, up = (np.asarray(v, np.float64) for v in (eye, target, up))
    z = eye - target
    z /= np.linalg.norm(z)
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, np.cross(z, x), z, eye
    return m


def zup_to_yup() -> np.ndarray:
    """(4, 4): z-up world -> the glTF's y-up world (the root node's transform)."""
    return pose_matrix(np.array([0, 0, 0, *_ZUP_TO_YUP]))


def camera_gltf(world: Tabletop) -> np.ndarray:
    """The camera as an OpenGL world-from-camera pose in the glTF's (y-up) world."""
    return zup_to_yup() @ world.camera


# ---------------------------------------------------------------------------------------------
# Motion: what a simulator would write every step

class _Steps:
    """What the motions share: several steps at once, and the arrays on a device."""

    params: dict[str, np.ndarray]
    _on: dict[str, dict]

    def _arrays(self, device: str | None):  # noqa: ANN202
        if device is None:
            return np, self.params
        import torch

        if device not in self._on:  # float64 on the device: the same numbers as NumPy's
            self._on[device] = {n: torch.as_tensor(a, dtype=torch.float64, device=device)
                                for n, a in self.params.items()}
        return torch, self._on[device]

    def poses(self, step: int, quaternion: str = "wxyz", device: str | None = None):  # noqa: ANN201
        raise NotImplementedError

    def steps(self, count: int, quaternion: str = "wxyz", device: str | None = None, start: int = 0):  # noqa: ANN201
        """(count, W, N, 7): `count` consecutive steps, made before a timed loop so that the
        loop measures the renderer, not this (a simulator's step is its own cost)."""
        frames = [self.poses(start + s, quaternion, device) for s in range(count)]
        if device is None:
            return np.stack(frames)
        import torch

        return torch.stack(frames)


def _rows(xp, p, q, quaternion: str):  # noqa: ANN001, ANN202
    """(..., 7) float32 rows of positions and x, y, z, w quaternions, in `quaternion` order."""
    if quaternion not in ("xyzw", "wxyz"):
        raise ValueError(f"quaternion {quaternion!r}: choose 'xyzw' or 'wxyz'")
    if quaternion == "wxyz":
        q = q[..., [3, 0, 1, 2]]
    out = xp.concatenate([p, q], -1) if xp is np else xp.cat([p, q], -1)
    return out.astype(np.float32) if xp is np else out.float()


class Spin(_Steps):
    """Objects turning in place, each world its own way (the helmet worlds of issue 32): node
    n of world w turns about a random axis (uniform on the sphere) at 0.5 to 2 rad/s from a
    random angle, about its rest pose `rest` ((N, 7) position + quaternion x, y, z, w: the
    rows of its local transform), and drifts up to `drift` (0.1) along x and y. poses(step) as
    Motion's."""

    def __init__(self, rest: np.ndarray, worlds: int, seed: int = SEED, dt: float = DT,
                 drift: float = 0.1) -> None:
        rest = np.asarray(rest, np.float64).reshape(-1, 7)
        rng = np.random.default_rng([seed, 64])
        n = len(rest)
        axis = rng.normal(size=(worlds, n, 3))
        self.worlds, self.dt, self._on = worlds, dt, {}
        self.params = {"axis": axis / np.linalg.norm(axis, axis=-1, keepdims=True),
                       "rate": rng.uniform(0.5, 2.0, (worlds, n)) * rng.choice([-1, 1], (worlds, n)),
                       "angle": rng.uniform(0, 2 * np.pi, (worlds, n)),
                       "offset": np.concatenate([rng.uniform(-drift, drift, (worlds, n, 2)),
                                                 np.zeros((worlds, n, 1))], -1),
                       "rest": np.broadcast_to(rest, (worlds, n, 7)).copy()}

    def poses(self, step: int, quaternion: str = "wxyz", device: str | None = None):  # noqa: ANN201
        xp, a = self._arrays(device)
        half = (a["angle"] + a["rate"] * step * self.dt) / 2
        s = xp.sin(half)
        turn = _stack(xp, [a["axis"][..., 0] * s, a["axis"][..., 1] * s, a["axis"][..., 2] * s, xp.cos(half)])
        q = qmul(xp, turn, a["rest"][..., 3:])
        return _rows(xp, a["rest"][..., :3] + a["offset"], q, quaternion)


class Motion(_Steps):
    """Per-world motion of the 17 moving bodies, drawn once from `seed`:

    - the arm: joint j at ARM_REST[j] + a_wj sin(2 pi f_wj t + phi_wj), amplitudes 0.5 to 1
      times ARM_AMPLITUDE[j], frequencies 0.15 to 0.6 Hz, phases uniform; links placed by
      forward kinematics (arm_fk);
    - each object: slides round a circle (radius 0 to 3 cm, 0.2 to 1 turn/s either way) about
      a per-world point of its cell (+-3 cm), and turns about z (0 to 1 rad/s either way) from
      a per-world yaw, at its resting height and tilt.

    `poses(step)` evaluates time step * dt for all W worlds at once (no per-world Python), in
    NumPy or (device=...) torch on that device, float32.
    """

    def __init__(self, world: Tabletop, worlds: int, seed: int = SEED, dt: float = DT) -> None:
        if worlds < 1:
            raise ValueError(f"worlds {worlds}: need at least 1")
        rng = np.random.default_rng([seed, world.seed])
        w, k = worlds, OBJECTS
        self.world, self.worlds, self.dt = world, worlds, dt
        self.params = {
            "amp": np.asarray(ARM_AMPLITUDE) * rng.uniform(0.5, 1.0, (w, ARM_LINKS)),
            "freq": 2 * np.pi * rng.uniform(0.15, 0.6, (w, ARM_LINKS)),
            "phase": rng.uniform(0, 2 * np.pi, (w, ARM_LINKS)),
            "centre": world.object_centres[None] + rng.uniform(-0.03, 0.03, (w, k, 2)),
            "radius": rng.uniform(0.0, 0.03, (w, k)),
            "omega": 2 * np.pi * rng.uniform(0.2, 1.0, (w, k)) * rng.choice([-1, 1], (w, k)),
            "orbit": rng.uniform(0, 2 * np.pi, (w, k)),
            "yaw0": rng.uniform(-np.pi, np.pi, (w, k)),
            "yaw_rate": rng.uniform(-1.0, 1.0, (w, k)),
            "rest": np.broadcast_to(world.object_rest[None], (w, k, 5)).copy(),
            "base": np.broadcast_to(np.asarray(ARM_BASE, np.float64), (w, 3)).copy(),
            "q0": np.broadcast_to(np.asarray(ARM_REST, np.float64), (w, ARM_LINKS)).copy(),
        }
        self._on: dict[str, dict] = {}

    def poses(self, step: int, quaternion: str = "wxyz", device: str | None = None):  # noqa: ANN201
        """(W, N, 7) float32 poses at time step * dt: link0..link6 then obj0..obj9, each
        position + quaternion in `quaternion` order ("xyzw" or "wxyz"). A torch tensor on
        `device` when one is given (computed there), else a NumPy array."""
        xp, a = self._arrays(device)
        t = step * self.dt
        angles = a["q0"] + a["amp"] * xp.sin(a["freq"] * t + a["phase"])
        arm_p, arm_q = arm_fk(xp, angles, a["base"])
        turn = a["omega"] * t + a["orbit"]
        obj_p = _stack(xp, [a["centre"][..., 0] + a["radius"] * xp.cos(turn),
                            a["centre"][..., 1] + a["radius"] * xp.sin(turn), a["rest"][..., 0]])
        yaw = axis_angle(xp, "z", a["yaw0"] + a["yaw_rate"] * t)
        obj_q = qmul(xp, yaw, a["rest"][..., 1:])
        p = xp.concatenate([arm_p, obj_p], 1) if xp is np else xp.cat([arm_p, obj_p], 1)
        q = xp.concatenate([arm_q, obj_q], 1) if xp is np else xp.cat([arm_q, obj_q], 1)
        return _rows(xp, p, q, quaternion)



# ---------------------------------------------------------------------------------------------
# Meshes (for the glTF): positions, normals, texcoords, triangle indices; counter-clockwise
# seen from outside, as glTF's front faces are.

def box_mesh(half) -> tuple[np.ndarray, ...]:  # noqa: ANN001
    half = np.asarray(half, np.float64)
    pos, nrm, uv, tri = [], [], [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = np.zeros(3)
            n[axis] = sign
            u = np.zeros(3)
            u[(axis + 1) % 3] = 1.0
            v = np.cross(n, u)
            base = len(pos)
            for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                pos.append((n + su * u + sv * v) * half)
                nrm.append(n)
                uv.append(((su + 1) / 2, (1 - sv) / 2))
            tri += [(base, base + 1, base + 2), (base, base + 2, base + 3)]
    return _mesh(pos, nrm, uv, tri)


def capsule_mesh(radius: float, half: float, rings: int = 8, segments: int = 24) -> tuple[np.ndarray, ...]:
    """A capsule along z (half = the cylinder's half length; 0 gives a sphere): two
    hemispheres of `rings` bands each, joined by the cylinder."""
    theta = np.concatenate([np.linspace(0, np.pi / 2, rings + 1), np.linspace(np.pi / 2, np.pi, rings + 1)])
    lift = np.where(np.arange(theta.size) <= rings, half, -half)
    phi = np.linspace(0, 2 * np.pi, segments + 1)
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    n = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)
    p = radius * n
    p[..., 2] += lift[:, None]
    uv = np.stack([ph / (2 * np.pi), th / np.pi], -1)
    cols = segments + 1
    i, j = np.meshgrid(np.arange(theta.size - 1), np.arange(segments), indexing="ij")
    a, b = i * cols + j, (i + 1) * cols + j
    tri = np.concatenate([np.stack([a, b, b + 1], -1).reshape(-1, 3), np.stack([a, b + 1, a + 1], -1).reshape(-1, 3)])
    return _mesh(p.reshape(-1, 3), n.reshape(-1, 3), uv.reshape(-1, 2), tri)


def plane_mesh(hx: float, hy: float) -> tuple[np.ndarray, ...]:
    pos = [(-hx, -hy, 0), (hx, -hy, 0), (hx, hy, 0), (-hx, hy, 0)]
    uv = [(0, 1), (1, 1), (1, 0), (0, 0)]
    return _mesh(pos, [(0, 0, 1)] * 4, uv, [(0, 1, 2), (0, 2, 3)])


def _mesh(pos, nrm, uv, tri) -> tuple[np.ndarray, ...]:  # noqa: ANN001
    """Arrays of a mesh, each triangle wound so that its face normal agrees with its vertex
    normals (counter-clockwise from outside); triangles of no area (a pole's) dropped."""
    pos, nrm = np.asarray(pos, np.float32), np.asarray(nrm, np.float32)
    tri = np.asarray(tri, np.uint32).reshape(-1, 3)
    a, b, c = (pos[tri[:, k]].astype(np.float64) for k in range(3))
    face = np.cross(b - a, c - a)
    area = np.linalg.norm(face, axis=1)
    keep = area > 1e-12
    flip = np.einsum("ij,ij->i", face, nrm[tri].sum(1)) < 0
    tri = np.where(flip[:, None], tri[:, [0, 2, 1]], tri)[keep]
    return pos, nrm, np.asarray(uv, np.float32), np.ascontiguousarray(tri)


def shape_mesh(shape: Shape) -> tuple[np.ndarray, ...]:
    """The triangle mesh of a primitive shape, placed at its offset (and turned by its
    quaternion) in the body's frame."""
    if shape.kind == "box":
        p, n, uv, t = box_mesh(shape.size)
    elif shape.kind == "sphere":
        p, n, uv, t = capsule_mesh(shape.size[0], 0.0, 12, 24)
    elif shape.kind == "capsule":
        p, n, uv, t = capsule_mesh(shape.size[0], shape.size[1])
    elif shape.kind == "plane":
        p, n, uv, t = plane_mesh(*shape.size)
    else:
        raise ValueError(f"no mesh for a {shape.kind!r} shape")
    r = quat_matrix(np.asarray(shape.quat))
    return ((p @ r.T + np.asarray(shape.pos)).astype(np.float32), (n @ r.T).astype(np.float32), uv, t)


# ---------------------------------------------------------------------------------------------
# glTF

class _Bin:
    """One binary buffer and its bufferViews / accessors, appended as meshes are written."""

    def __init__(self, doc: dict) -> None:
        self.doc, self.data = doc, bytearray()

    def accessor(self, array: np.ndarray, target: int, kind: str, bounds: bool = False) -> int:
        array = np.ascontiguousarray(array)
        while len(self.data) % 4:
            self.data.append(0)
        views = self.doc.setdefault("bufferViews", [])
        views.append({"buffer": 0, "byteOffset": len(self.data), "byteLength": array.nbytes, "target": target})
        self.data += array.tobytes()
        comp = 5126 if array.dtype == np.float32 else 5125
        acc = {"bufferView": len(views) - 1, "componentType": comp, "count": len(array), "type": kind}
        if bounds:
            acc["min"], acc["max"] = array.min(0).tolist(), array.max(0).tolist()
        accessors = self.doc.setdefault("accessors", [])
        accessors.append(acc)
        return len(accessors) - 1


def write_gltf(world: Tabletop, folder: str | Path, name: str = "tabletop") -> Path:
    """Write FOLDER/NAME.gltf + NAME.bin (sample models copied into FOLDER/<model>/ so that
    every file the scene names stays inside its folder); returns the .gltf path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    doc: dict = {"asset": {"version": "2.0", "generator": "vkpbr benchmarks/tabletop.py"},
                 "scene": 0, "nodes": [], "meshes": [], "materials": []}
    buf = _Bin(doc)
    root = {"name": "tabletop", "rotation": list(_ZUP_TO_YUP), "children": []}
    doc["nodes"].append(root)
    for body in world.bodies:
        node = {"name": body.name, "translation": [float(v) for v in body.rest[:3]],
                "rotation": [float(v) for v in body.rest[3:]]}
        root["children"].append(len(doc["nodes"]))
        doc["nodes"].append(node)
        if body.shape.kind == "model":
            node["children"] = [_merge_model(doc, buf, body.shape, folder)]
        else:
            node["mesh"] = _write_mesh(doc, buf, body.name, body.shape)
    _add_camera_and_light(doc, world, root)
    doc["scenes"] = [{"name": "tabletop", "nodes": [0]}]
    (folder / f"{name}.bin").write_bytes(bytes(buf.data))
    doc["buffers"] = [{"uri": f"{name}.bin", "byteLength": len(buf.data)}] + doc.get("buffers", [])[1:]
    path = folder / f"{name}.gltf"
    path.write_text(json.dumps(doc, indent=1))
    return path


def _write_mesh(doc: dict, buf: _Bin, name: str, shape: Shape) -> int:
    p, n, uv, t = shape_mesh(shape)
    doc["materials"].append({"name": name, "pbrMetallicRoughness": {
        "baseColorFactor": list(shape.color), "metallicFactor": shape.metallic,
        "roughnessFactor": shape.roughness}})
    attributes = {"POSITION": buf.accessor(p, 34962, "VEC3", bounds=True),
                  "NORMAL": buf.accessor(n, 34962, "VEC3"), "TEXCOORD_0": buf.accessor(uv, 34962, "VEC2")}
    doc["meshes"].append({"name": name, "primitives": [{
        "attributes": attributes, "indices": buf.accessor(t.reshape(-1), 34963, "SCALAR"),
        "material": len(doc["materials"]) - 1}]})
    return len(doc["meshes"]) - 1


def _add_camera_and_light(doc: dict, world: Tabletop, root: dict) -> None:
    """The view every world is rendered from (a perspective camera, aspect left to the
    renderer) and the sun (KHR_lights_punctual, directional), as children of the root."""
    doc["cameras"] = [{"type": "perspective", "perspective": {
        "yfov": math.radians(world.yfov_deg), "znear": 0.05}}]
    cam = world.camera
    doc["nodes"].append({"name": "camera", "camera": 0, "translation": cam[:3, 3].tolist(),
                         "rotation": matrix_quat(cam[:3, :3]).tolist()})
    d = np.asarray(world.light_direction, np.float64)
    d /= np.linalg.norm(d)
    # a directional light shines down its node's -z: turn -z onto d
    z = -d
    x = np.cross((0.0, 1.0, 0.0), z) if abs(z[1]) < 0.9 else np.cross((1.0, 0.0, 0.0), z)
    x /= np.linalg.norm(x)
    rot = np.stack([x, np.cross(z, x), z], 1)
    doc["extensionsUsed"] = sorted(set(doc.get("extensionsUsed", [])) | {"KHR_lights_punctual"})
    doc.setdefault("extensions", {})["KHR_lights_punctual"] = {"lights": [
        {"name": "sun", "type": "directional", "color": [1.0, 0.97, 0.92], "intensity": world.light_lux}]}
    doc["nodes"].append({"name": "sun", "rotation": matrix_quat(rot).tolist(),
                         "extensions": {"KHR_lights_punctual": {"light": 0}}})
    root["children"] += [len(doc["nodes"]) - 2, len(doc["nodes"]) - 1]


def matrix_quat(r: np.ndarray) -> np.ndarray:
    """Unit quaternion x, y, z, w of a rotation matrix (Shepperd's method)."""
    t = np.trace(r)
    if t > 0:
        s = 2 * math.sqrt(1 + t)
        q = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, s / 4)
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2 * math.sqrt(1 + r[i, i] - r[j, j] - r[k, k])
        q = [0.0, 0.0, 0.0, (r[k, j] - r[j, k]) / s]
        q[i], q[j], q[k] = s / 4, (r[j, i] + r[i, j]) / s, (r[k, i] + r[i, k]) / s
    q = np.asarray(q)
    return q / np.linalg.norm(q)


def _merge_model(doc: dict, buf: _Bin, shape: Shape, folder: Path) -> int:
    """Copy a sample model into the document: its buffers, views, accessors, images,
    samplers, textures, materials, meshes and the nodes of its scene, with every index
    shifted by what the document held before; its files copied into FOLDER/<model>/.
    Returns the node that holds it (placed, turned to z-up and scaled by `shape`)."""
    src = assets_dir() / MODELS[shape.model][0]
    if not src.exists():
        raise FileNotFoundError(f"{src}: sample model {shape.model} not found "
                                "($VKPBR_ASSETS or ../shared/assets; or make_tabletop(models=()))")
    model = json.loads(src.read_text())
    dst = folder / shape.model
    dst.mkdir(parents=True, exist_ok=True)
    doc.setdefault("buffers", [{"uri": "", "byteLength": 0}])  # 0: the tabletop's own (set last)
    base = {k: len(doc.setdefault(k, [])) for k in ("buffers", "bufferViews", "accessors", "images",
                                                    "samplers", "textures", "materials", "meshes", "nodes")}
    for item in model.get("buffers", []) + model.get("images", []):
        uri = item.get("uri")
        if uri and not uri.startswith("data:"):
            shutil.copyfile(src.parent / uri, dst / Path(uri).name)
            item["uri"] = f"{shape.model}/{Path(uri).name}"
    for v in model.get("bufferViews", []):
        v["buffer"] += base["buffers"]
    for a in model.get("accessors", []):
        _shift(a, "bufferView", base["bufferViews"])
        for part in ("indices", "values"):
            if "sparse" in a:
                a["sparse"][part]["bufferView"] += base["bufferViews"]
    for img in model.get("images", []):
        _shift(img, "bufferView", base["bufferViews"])
    for t in model.get("textures", []):
        _shift(t, "source", base["images"])
        _shift(t, "sampler", base["samplers"])
    for m in model.get("materials", []):
        _shift_textures(m, base["textures"])
    for mesh in model.get("meshes", []):
        for prim in mesh["primitives"]:
            prim["attributes"] = {k: v + base["accessors"] for k, v in prim["attributes"].items()}
            _shift(prim, "indices", base["accessors"])
            _shift(prim, "material", base["materials"])
            for tgt in prim.get("targets", []):
                for k in tgt:
                    tgt[k] += base["accessors"]
    for node in model.get("nodes", []):
        for drop in ("camera", "skin", "extensions"):
            node.pop(drop, None)
        _shift(node, "mesh", base["meshes"])
        if "children" in node:
            node["children"] = [c + base["nodes"] for c in node["children"]]
    for key in base:
        doc[key] += model.get(key, [])
    used = set(model.get("extensionsUsed", [])) - {"KHR_lights_punctual"}
    doc["extensionsUsed"] = sorted(set(doc.get("extensionsUsed", [])) | used)
    scene = model.get("scenes", [{}])[model.get("scene", 0)]
    holder = {"name": f"{shape.model}", "translation": list(shape.pos), "rotation": list(shape.quat),
              "scale": [shape.size[0]] * 3, "children": [n + base["nodes"] for n in scene.get("nodes", [])]}
    doc["nodes"].append(holder)
    return len(doc["nodes"]) - 1


def _shift(item: dict, key: str, by: int) -> None:
    if key in item:
        item[key] += by


def _shift_textures(value: object, by: int) -> None:
    """Every texture reference ({"index": i} under a key ending in "Texture") inside a
    material, its extensions included."""
    if isinstance(value, dict):
        for k, v in value.items():
            if k.endswith("Texture") and isinstance(v, dict) and "index" in v:
                v["index"] += by
            _shift_textures(v, by)
    elif isinstance(value, list):
        for v in value:
            _shift_textures(v, by)


# ---------------------------------------------------------------------------------------------
# MJCF (MuJoCo; MuJoCo Warp and mujoco-warp-pbr read it through mujoco.MjModel)

def write_mjcf(world: Tabletop, path: str | Path) -> Path:
    """The primitives-only world as MJCF: static geoms on the world body, each moving body a
    free body (a freejoint: its qpos is the pose row, position + quaternion w, x, y, z, in
    MOVING's order) with one geom that collides with nothing; the camera "view"; the sun as a
    directional light with shadows; a gradient skybox for the sky. Materials carry rgba,
    metallic and roughness (MuJoCo >= 3.2), which mujoco-warp-pbr shades with."""
    if not world.primitives_only:
        raise ValueError(f"write_mjcf: the world holds sample models ({', '.join(world.models)}); "
                         "MJCF takes the primitives-only world: make_tabletop(models=())")
    lines = ['<mujoco model="tabletop">', '  <compiler angle="radian"/>',
             '  <option gravity="0 0 0"/>',
             '  <visual><global offwidth="640" offheight="480"/>'
             '<headlight ambient="0.25 0.25 0.25" diffuse="0 0 0" specular="0 0 0"/></visual>',
             '  <asset>',
             '    <texture name="sky" type="skybox" builtin="gradient" rgb1="0.55 0.7 0.9" '
             'rgb2="0.9 0.9 0.9" width="256" height="256"/>']
    for body in world.bodies:
        s = body.shape
        lines.append(f'    <material name="m_{body.name}" rgba="{_f(s.color)}" metallic="{s.metallic:g}" '
                     f'roughness="{s.roughness:g}" specular="0.5"/>')
    lines += ['  </asset>', '  <worldbody>']
    d = np.asarray(world.light_direction, np.float64)
    d /= np.linalg.norm(d)
    lines.append(f'    <light name="sun" directional="true" castshadow="true" pos="{_f(-3 * d + (0, 0, 1))}" '
                 f'dir="{_f(d)}" diffuse="1 0.97 0.92" specular="0.3 0.3 0.3"/>')
    for body in world.bodies:
        geom = _mjcf_geom(body)
        pos, q = body.rest[:3], (body.rest[6], *body.rest[3:6])  # MJCF quat: w, x, y, z
        if body.moving:
            lines.append(f'    <body name="{body.name}" pos="{_f(pos)}" quat="{_f(q)}">'
                         f'<freejoint name="{body.name}"/>{geom}</body>')
        else:  # a static geom placed in the world frame
            r = quat_matrix(np.asarray(body.rest[3:]))
            at = r @ np.asarray(body.shape.pos) + np.asarray(pos)
            lines.append("    " + geom.replace(f'pos="{_f(body.shape.pos)}"', f'pos="{_f(at)}"', 1))
    cam = world.camera
    lines.append(f'    <camera name="view" pos="{_f(cam[:3, 3])}" xyaxes="{_f(cam[:3, 0])} {_f(cam[:3, 1])}" '
                 f'fovy="{world.yfov_deg:g}"/>')
    lines += ['  </worldbody>', '</mujoco>']
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")
    return path


def _mjcf_geom(body: Body) -> str:
    s = body.shape
    kind = {"box": "box", "sphere": "sphere", "capsule": "capsule", "plane": "plane"}[s.kind]
    size = s.size if s.kind != "plane" else (*s.size, 0.05)
    quat = (s.quat[3], *s.quat[:3])
    return (f'<geom name="{body.name}" type="{kind}" size="{_f(size)}" pos="{_f(s.pos)}" quat="{_f(quat)}" '
            f'material={quoteattr("m_" + body.name)} contype="0" conaffinity="0"/>')


def _f(values) -> str:  # noqa: ANN001
    return " ".join(f"{float(v):.6g}" for v in values)


# ---------------------------------------------------------------------------------------------

def main() -> None:
    ap = argparse.ArgumentParser(description="write the tabletop world: glTF (and MJCF for the "
                                 "primitives-only world)")
    ap.add_argument("--out", default="out/tabletop", help="folder (default out/tabletop)")
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--primitives", action="store_true",
                    help="boxes, spheres and capsules only (no sample models): also writes tabletop.xml")
    args = ap.parse_args()
    try:
        world = make_tabletop(args.seed, () if args.primitives else tuple(MODELS))
        print(write_gltf(world, args.out))
    except (FileNotFoundError, ValueError) as e:
        raise SystemExit(f"tabletop.py: {e}") from None
    if world.primitives_only:
        print(write_mjcf(world, Path(args.out) / "tabletop.xml"))


if __name__ == "__main__":
    main()
