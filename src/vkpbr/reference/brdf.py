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
    "v_smith_ggx_correlated",
    "diffuse_lambert",
    "f0_from_metallic",
    "BrdfTerms",
    "evaluate_brdf",
    "light_attenuation",
    "tonemap",
    "tonemap_pbr_neutral",
    "tonemap_aces_hill",
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


def v_smith_ggx_correlated(n_dot_l, n_dot_v, alpha):  # noqa: ANN001, ANN201
    """Height-correlated Smith V = G / (4 n.l n.v) for GGX:
    0.5 / (n.l sqrt(n.v^2 (1 - a^2) + a^2) + n.v sqrt(n.l^2 (1 - a^2) + a^2))."""
    a2 = np.asarray(alpha, dtype=np.float64) ** 2
    gv = n_dot_l * np.sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2)
    gl = n_dot_v * np.sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2)
    s = gv + gl
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(s > 0.0, 0.5 / np.where(s > 0.0, s, 1.0), 0.0)


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
    if brdf == Brdf.GLTF:
        d = d_ggx(n_dot_h, alpha)
        f = f_schlick(f0_from_metallic(c, metallic), v_dot_h)
        vis = v_smith_ggx_correlated(n_dot_l, n_dot_v, alpha)
        diffuse = ((1.0 - metallic)[..., None] * (1.0 - f_schlick(np.full_like(c, 0.04), v_dot_h))
                   * c / PI)
        return BrdfTerms(D=d, F=f, G=vis * 4.0 * n_dot_l * n_dot_v, specular=f * (d * vis)[..., None],
                         diffuse=diffuse)
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


def tonemap_pbr_neutral(color: np.ndarray) -> np.ndarray:
    """Khronos PBR Neutral on (..., 3) linear colours (the specification's reference code)."""
    color = np.asarray(color, dtype=np.float64)
    start, desaturation = 0.8 - 0.04, 0.15
    x = color.min(axis=-1, keepdims=True)
    offset = np.where(x < 0.08, x - 6.25 * x * x, 0.04)
    color = color - offset
    peak = color.max(axis=-1, keepdims=True)
    d = 1.0 - start
    new_peak = 1.0 - d * d / (peak + d - start)
    with np.errstate(divide="ignore", invalid="ignore"):
        scaled = color * (new_peak / peak)
    g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0)
    compressed = scaled * (1.0 - g) + new_peak * g
    return np.where(peak < start, color, compressed)


_ACES_IN = np.array([[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566],
                     [0.02840, 0.13383, 0.83777]])
_ACES_OUT = np.array([[1.60475, -0.53108, -0.07367], [-0.10208, 1.10813, -0.00605],
                      [-0.00327, -0.07276, 1.07602]])


def tonemap_aces_hill(color: np.ndarray) -> np.ndarray:
    """Stephen Hill's ACES fit on (..., 3) linear colours: input matrix, RRT+ODT fit, output."""
    c = np.asarray(color, dtype=np.float64) @ _ACES_IN.T
    a = c * (c + 0.0245786) - 0.000090537
    b = c * (0.983729 * c + 0.4329510) + 0.238081
    return np.clip((a / b) @ _ACES_OUT.T, 0.0, 1.0)


def tonemap(x: np.ndarray, mode: int) -> np.ndarray:
    """The tone curve `mode` (vkpbr.shading.Tonemap) on (..., 3) linear colours."""
    if mode == Tonemap.REINHARD:
        return x / (1.0 + x)
    if mode == Tonemap.ACES:
        return np.clip((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    if mode == Tonemap.ACES_HILL:
        return tonemap_aces_hill(x)
    if mode == Tonemap.PBR_NEUTRAL:
        return tonemap_pbr_neutral(x)
    return x


def shade(n, v, l, c, metallic, roughness, light_in, occlusion=1.0, emissive=0.0,  # noqa: ANN001, E741
          brdf: int = Brdf.GGX, ambient: float = AMBIENT) -> dict[str, np.ndarray]:
    """The radiance terms pbr.frag writes for one light: specular, diffuse, ambient and
    final, (..., 3). `ambient`: the course's 0.02 (0 in the physically based mode)."""
    roughness = np.clip(roughness, MIN_ROUGHNESS, 1.0)
    t = evaluate_brdf(n, v, l, c, metallic, roughness, brdf)
    n_dot_l = np.maximum(_dot(np.asarray(n, float), np.asarray(l, float)), 0.0)[..., None]
    spec = t.specular * light_in * n_dot_l
    diff = t.diffuse * light_in * n_dot_l
    amb = ambient * np.asarray(c, float) * np.asarray(occlusion, float)[..., None]
    final = emissive + amb + diff + spec
    return {"specular": spec, "diffuse": diff, "ambient": amb, "final": final, "terms": t}
