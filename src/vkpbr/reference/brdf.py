"""NumPy mirror of shaders/brdf.glsl: the same functions, names and arguments, vectorised.

The GPU tests evaluate these at the same n, l, v as the shader and compare pixels. A change to
one file is a change to both. Inputs broadcast: directions are (..., 3) arrays of unit vectors,
scalars (...) arrays, colours (..., 3). Computation is in float64 (the shader's float32
differs by rounding only). The sRGB curve (`srgb_to_linear`, `linear_to_srgb`) is
vkpbr.scene.color's, re-exported here beside the functions it mirrors.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vkpbr.scene.color import linear_to_srgb, srgb_to_linear
from vkpbr.shading import AMBIENT, MIN_ROUGHNESS, Brdf, Tonemap

__all__ = [
    "d_ggx",
    "d_blinn_phong",
    "f_schlick",
    "g_cook_torrance",
    "diffuse_lambert",
    "f0_from_metallic",
    "BrdfTerms",
    "evaluate_brdf",
    "light_attenuation",
    "tonemap",
    "srgb_to_linear",
    "linear_to_srgb",
    "shade",
    "AMBIENT",
    "MIN_ROUGHNESS",
]

PI = np.pi
EPS = 1e-6


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sum(a * b, axis=-1)


def _normalize(x: np.ndarray) -> np.ndarray:
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def d_ggx(n_dot_h: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """GGX / Trowbridge-Reitz, alpha = r^2: alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2)."""
    a2 = alpha * alpha
    k = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0
    return a2 / (PI * k * k)


def d_blinn_phong(n_dot_h: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """The course's Blinn-Phong D: (ap + 2)/(2 pi) (n.h)^ap with ap = 2/alpha^2 - 2."""
    ap = 2.0 / (alpha * alpha) - 2.0
    return (ap + 2.0) / (2.0 * PI) * np.power(n_dot_h, ap)


def f_schlick(f0: np.ndarray, v_dot_h: np.ndarray) -> np.ndarray:
    """Schlick: F0 + (1 - F0)(1 - h.v)^5."""
    return f0 + (1.0 - f0) * np.power(1.0 - v_dot_h, 5.0)[..., None]


def g_cook_torrance(n_dot_h, n_dot_v, n_dot_l, v_dot_h):  # noqa: ANN001, ANN201
    """Cook-Torrance masking: min(1, 2(n.h)(n.v)/(v.h), 2(n.h)(n.l)/(v.h))."""
    k = 2.0 * n_dot_h / np.maximum(v_dot_h, EPS)
    return np.minimum(1.0, np.minimum(k * n_dot_v, k * n_dot_l))


def diffuse_lambert(c: np.ndarray, f: np.ndarray, metallic: np.ndarray) -> np.ndarray:
    """(c / pi)(1 - F)(1 - M)."""
    return c / PI * (1.0 - f) * (1.0 - np.asarray(metallic))[..., None]


def f0_from_metallic(c: np.ndarray, metallic: np.ndarray) -> np.ndarray:
    """F0 = (1 - M) 0.04 + M c."""
    m = np.asarray(metallic)[..., None]
    return (1.0 - m) * 0.04 + m * c


@dataclass
class BrdfTerms:
    D: np.ndarray  # (...)
    F: np.ndarray  # (..., 3)
    G: np.ndarray  # (...)
    specular: np.ndarray  # (..., 3): D F G / (4 (n.v)+ (n.l)+)
    diffuse: np.ndarray  # (..., 3)


def evaluate_brdf(n, v, l, c, metallic, roughness, brdf: int = Brdf.GGX) -> BrdfTerms:  # noqa: ANN001, E741
    """Every BRDF term at the given shading points (mirror of brdf.glsl evaluate_brdf)."""
    n, v, l, c = (np.asarray(x, dtype=np.float64) for x in (n, v, l, c))
    metallic = np.asarray(metallic, dtype=np.float64)
    roughness = np.asarray(roughness, dtype=np.float64)
    h = _normalize(l + v)
    n_dot_l = np.maximum(_dot(n, l), 0.0)
    n_dot_v = np.maximum(_dot(n, v), 0.0)
    n_dot_h = np.maximum(_dot(n, h), 0.0)
    v_dot_h = np.maximum(_dot(v, h), 0.0)
    alpha = roughness * roughness
    d = d_blinn_phong(n_dot_h, alpha) if brdf == Brdf.BLINN_PHONG else d_ggx(n_dot_h, alpha)
    f = f_schlick(f0_from_metallic(c, metallic), v_dot_h)
    g = g_cook_torrance(n_dot_h, n_dot_v, n_dot_l, v_dot_h)
    spec = (d * g / np.maximum(4.0 * n_dot_v * n_dot_l, EPS))[..., None] * f
    return BrdfTerms(D=d, F=f, G=g, specular=spec, diffuse=diffuse_lambert(c, f, metallic))


def light_attenuation(dist2: np.ndarray, falloff: int, light_range: float = 0.0) -> np.ndarray:
    """1 (the course) or inverse square with glTF's range window."""
    dist2 = np.asarray(dist2, dtype=np.float64)
    if falloff == 0:
        return np.ones_like(dist2)
    att = 1.0 / np.maximum(dist2, 1e-4)
    if light_range > 0.0:
        r = dist2 / (light_range * light_range)
        att = att * np.clip(1.0 - r * r, 0.0, 1.0)
    return att


def tonemap(x: np.ndarray, mode: int) -> np.ndarray:
    if mode == Tonemap.REINHARD:
        return x / (1.0 + x)
    if mode == Tonemap.ACES:
        return np.clip((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    return x


def shade(n, v, l, c, metallic, roughness, light_in, occlusion=1.0, emissive=0.0,  # noqa: ANN001, E741
          brdf: int = Brdf.GGX) -> dict[str, np.ndarray]:
    """The radiance terms pbr.frag writes: specular, diffuse, ambient and final, (..., 3)."""
    roughness = np.clip(roughness, MIN_ROUGHNESS, 1.0)
    t = evaluate_brdf(n, v, l, c, metallic, roughness, brdf)
    n_dot_l = np.maximum(_dot(np.asarray(n, float), np.asarray(l, float)), 0.0)[..., None]
    spec = t.specular * light_in * n_dot_l
    diff = t.diffuse * light_in * n_dot_l
    amb = AMBIENT * np.asarray(c, float) * np.asarray(occlusion, float)[..., None]
    final = emissive + amb + diff + spec
    return {"specular": spec, "diffuse": diff, "ambient": amb, "final": final, "terms": t}
