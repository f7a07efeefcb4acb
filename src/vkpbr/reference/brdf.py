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
from vkpbr.shading import (
    AMBIENT,
    MIN_ROUGHNESS,
    MIN_SHEEN_ROUGHNESS,
    SHEEN_ALBEDO_FIT,
    SHEEN_FIT_MIN_N_DOT_V,
    Brdf,
    Tonemap,
)

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
    "max3",
    "dielectric_f0",
    "d_charlie",
    "sheen_lambda",
    "v_charlie",
    "sheen_albedo",
    "sheen_albedo_integral",
    "volume_transmittance",
    "Layers",
    "LayeredTerms",
    "evaluate_layered_brdf",
    "shade_layered",
    "specular_glossiness",
    "d_ggx_anisotropic",
    "v_ggx_anisotropic",
    "anisotropic_alphas",
    "anisotropy_frame",
    "ibl_reflection",
    "eval_iridescence",
    "iridescence_fresnel",
    "dispersion_iors",
    "AMBIENT",
    "MIN_ROUGHNESS",
    "MIN_SHEEN_ROUGHNESS",
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
    """Schlick: F0 + (1 - F0)(1 - h.v)^5 (the base kept >= 0, as brdf.glsl keeps it: h.v
    rounds above 1 where l = v)."""
    return f0 + (1.0 - f0) * np.power(np.maximum(1.0 - v_dot_h, 0.0), 5.0)[..., None]


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


# --- The KHR_materials_* layers (brdf.glsl's second half; shade.glsl's composition) ---------


def max3(x: np.ndarray) -> np.ndarray:
    """Largest component of (..., 3) -> (...)."""
    return np.max(np.asarray(x, dtype=np.float64), axis=-1)


def dielectric_f0(ior: np.ndarray, specular_color: np.ndarray) -> np.ndarray:
    """min(((ior - 1) / (ior + 1))^2 * specular colour, 1), (..., 3)."""
    r = (np.asarray(ior, dtype=np.float64) - 1.0) / (np.asarray(ior, dtype=np.float64) + 1.0)
    return np.minimum((r * r)[..., None] * np.asarray(specular_color, dtype=np.float64), 1.0)


def d_charlie(n_dot_h: np.ndarray, alpha_g: np.ndarray) -> np.ndarray:
    """Charlie sheen distribution: (2 + 1/a) sin(theta_h)^(1/a) / (2 pi)."""
    inv_r = 1.0 / np.asarray(alpha_g, dtype=np.float64)
    sin2h = np.maximum(1.0 - n_dot_h * n_dot_h, 0.0)
    return (2.0 + inv_r) * np.power(sin2h, inv_r * 0.5) / (2.0 * PI)


def _sheen_l(x: np.ndarray, alpha_g: np.ndarray) -> np.ndarray:
    w = (1.0 - alpha_g) ** 2
    a = 21.5473 + (25.3245 - 21.5473) * w
    b = 3.82987 + (3.32435 - 3.82987) * w
    c = 0.19823 + (0.16801 - 0.19823) * w
    d = -1.97760 + (-1.27393 + 1.97760) * w
    e = -4.32054 + (-4.85967 + 4.32054) * w
    return a / (1.0 + b * np.power(x, c)) + d * x + e


def sheen_lambda(cos_theta: np.ndarray, alpha_g: np.ndarray) -> np.ndarray:
    """The Charlie visibility's lambda (KHR_materials_sheen README)."""
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    low = np.exp(_sheen_l(np.minimum(cos_theta, 0.5), alpha_g))
    high = np.exp(2.0 * _sheen_l(0.5, alpha_g) - _sheen_l(np.maximum(1.0 - cos_theta, 0.0), alpha_g))
    return np.where(cos_theta < 0.5, low, high)


def v_charlie(n_dot_l: np.ndarray, n_dot_v: np.ndarray, alpha_g: np.ndarray) -> np.ndarray:
    """1 / ((1 + lambda(n.v) + lambda(n.l)) 4 n.v n.l); 0 below the horizon."""
    ok = (n_dot_l > 0.0) & (n_dot_v > 0.0)
    nl, nv = np.where(ok, n_dot_l, 1.0), np.where(ok, n_dot_v, 1.0)
    val = 1.0 / ((1.0 + sheen_lambda(nv, alpha_g) + sheen_lambda(nl, alpha_g)) * (4.0 * nv * nl))
    return np.where(ok, val, 0.0)


def sheen_albedo(n_dot_v: np.ndarray, alpha_g: np.ndarray) -> np.ndarray:
    """E(n.v, alpha_g), the fitted polynomial vkpbr.shading.SHEEN_ALBEDO_FIT (as brdf.glsl)."""
    x = np.cbrt(np.clip(np.asarray(n_dot_v, dtype=np.float64), SHEEN_FIT_MIN_N_DOT_V, 1.0))
    y = np.sqrt(np.clip(np.asarray(alpha_g, dtype=np.float64), MIN_SHEEN_ROUGHNESS, 1.0))
    c = np.asarray(SHEEN_ALBEDO_FIT)
    e = sum(c[i, j] * x**i * y**j for i in range(c.shape[0]) for j in range(c.shape[1]))
    return np.clip(e, 0.0, 1.0)


def sheen_albedo_integral(n_dot_v: float, alpha_g: float, n_theta: int = 256,
                          n_phi: int = 128) -> float:
    """E(n.v, alpha_g) by quadrature: the integral over the hemisphere of the Charlie lobe
    D V (n.l) (white sheen), a midpoint rule in (theta, phi) of l; the fit's reference."""
    theta = (np.arange(n_theta) + 0.5) * (PI / 2) / n_theta
    phi = (np.arange(n_phi) + 0.5) * PI / n_phi  # half the circle: symmetric about v's plane
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    l = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1)
    d_omega = np.sin(th) * (PI / 2 / n_theta) * (PI / n_phi) * 2.0
    v = np.array([np.sqrt(1.0 - n_dot_v**2), 0.0, n_dot_v])
    h = _normalize(l + v)
    f = d_charlie(h[..., 2], alpha_g) * v_charlie(l[..., 2], np.full(th.shape, n_dot_v), alpha_g)
    return float(np.sum(f * l[..., 2] * d_omega))


def volume_transmittance(dist: np.ndarray, attenuation_color: np.ndarray,
                         attenuation_distance: float) -> np.ndarray:
    """attenuation colour ^ (dist / attenuation distance), (..., 3); distance 0: infinite."""
    dist = np.asarray(dist, dtype=np.float64)
    color = np.asarray(attenuation_color, dtype=np.float64)
    if attenuation_distance <= 0.0:
        return np.ones(dist.shape + (3,))
    return np.where((dist > 0.0)[..., None], np.power(color, (dist / attenuation_distance)[..., None]),
                    1.0)


def d_ggx_anisotropic(n_dot_h, t_dot_h, b_dot_h, at, ab):  # noqa: ANN001, ANN201
    """Anisotropic GGX D (KHR_materials_anisotropy): a2 w2^2 / pi with a2 = at ab and
    w2 = a2 / |(ab t.h, at b.h, a2 n.h)|^2."""
    a2 = at * ab
    f2 = (ab * t_dot_h) ** 2 + (at * b_dot_h) ** 2 + (a2 * n_dot_h) ** 2
    w2 = a2 / f2
    return a2 * w2 * w2 / PI


def v_ggx_anisotropic(n_dot_l, n_dot_v, b_dot_v, t_dot_v, t_dot_l, b_dot_l, at, ab):  # noqa: ANN001, ANN201
    """Anisotropic height-correlated Smith V: 0.5 / (n.l |(at t.v, ab b.v, n.v)| +
    n.v |(at t.l, ab b.l, n.l)|), clamped to [0, 1] (the Sample Viewer's)."""
    ggx_v = n_dot_l * np.sqrt((at * t_dot_v) ** 2 + (ab * b_dot_v) ** 2 + n_dot_v**2)
    ggx_l = n_dot_v * np.sqrt((at * t_dot_l) ** 2 + (ab * b_dot_l) ** 2 + n_dot_l**2)
    with np.errstate(divide="ignore"):
        return np.clip(0.5 / (ggx_v + ggx_l), 0.0, 1.0)


def anisotropic_alphas(alpha, strength):  # noqa: ANN001, ANN201
    """(alpha_t, alpha_b) = (mix(alpha, 1, s^2), clamp(alpha, 0.001, 1))."""
    alpha = np.asarray(alpha, dtype=np.float64)
    return alpha + (1.0 - alpha) * strength * strength, np.clip(alpha, 0.001, 1.0)


def anisotropy_frame(t, b, n, ng, rotation: float, texel=None):  # noqa: ANN001, ANN201
    """KHR_materials_anisotropy's direction in world space and its cross direction, (..., 3)
    each, and the strength's texel factor: the direction (texel RG * 2 - 1, else (1, 0))
    rotated by `rotation` (radians, towards b), in the frame (t, b, n); b_a = ng x t_a."""
    t, b, n, ng = (np.asarray(x, dtype=np.float64) for x in (t, b, n, ng))
    direction, scale = np.array([1.0, 0.0]), 1.0
    if texel is not None:
        direction, scale = np.asarray(texel[:2], np.float64) * 2.0 - 1.0, float(texel[2])
    c, s_ = np.cos(rotation), np.sin(rotation)
    d = np.array([c * direction[0] - s_ * direction[1], s_ * direction[0] + c * direction[1]])
    d = d / np.linalg.norm(d)
    at = t * d[0] + b * d[1]
    return at, np.cross(ng, at), scale


def ibl_reflection(n, v, roughness, strength, ab):  # noqa: ANN001, ANN201
    """The direction the environment is read along (shade.glsl ibl_reflection): reflect(-v,
    n), or for strength > 0 about the bent normal normalize(mix(cross(cross(b_a, v), b_a), n,
    (1 - s (1 - r))^4)) (the Sample Viewer's getIBLRadianceAnisotropy)."""
    n, v = np.asarray(n, dtype=np.float64), np.asarray(v, dtype=np.float64)
    bent = n
    if strength > 0.0:
        ab = np.asarray(ab, dtype=np.float64)
        normal = np.cross(np.cross(ab, v), ab)
        k = (1.0 - strength * (1.0 - np.asarray(roughness, dtype=np.float64))) ** 4
        bent = _normalize(normal + (n - normal) * np.asarray(k)[..., None])
    return _normalize(2.0 * _dot(bent, v)[..., None] * bent - v)


_XYZ_TO_REC709 = np.array([[3.2404542, -1.5371385, -0.4985314],
                           [-0.9692660, 1.8760108, 0.0415560],
                           [0.0556434, -0.2040259, 1.0572252]])


def _eval_sensitivity(opd: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """The XYZ sensitivity's Fourier transform at optical path difference opd (nm, (...)),
    phase `shift` (..., 3), as linear Rec. 709 (brdf.glsl eval_sensitivity)."""
    phase = 2.0 * PI * np.asarray(opd)[..., None] * 1.0e-9
    val = np.array([5.4856e-13, 4.4201e-13, 5.2481e-13])
    pos = np.array([1.6810e06, 1.7953e06, 2.2084e06])
    var = np.array([4.3278e09, 9.3046e09, 6.6121e09])
    xyz = val * np.sqrt(2.0 * PI * var) * np.cos(pos * phase + shift) * np.exp(-(phase**2) * var)
    xyz[..., 0] += (9.7470e-14 * np.sqrt(2.0 * PI * 4.5282e09) * np.cos(2.2399e06 * phase[..., 0]
                    + shift[..., 0]) * np.exp(-4.5282e09 * phase[..., 0] ** 2))
    return (xyz / 1.0685e-7) @ _XYZ_TO_REC709.T


def eval_iridescence(outside_ior: float, eta2: float, cos_theta1, thickness: float,  # noqa: ANN001
                     base_f0) -> np.ndarray:  # noqa: ANN001
    """KHR_materials_iridescence's thin-film Fresnel (..., 3) at cos(theta1) (...), film index
    eta2 and thickness (nm) over a base of reflectance base_f0 (3,) or (..., 3): Belcour and
    Barla 2017's two-order airy sum, as the extension's README and the Sample Viewer."""
    cos1 = np.asarray(cos_theta1, dtype=np.float64)
    t = float(np.clip(thickness / 0.03, 0.0, 1.0))
    film = outside_ior + (eta2 - outside_ior) * t * t * (3.0 - 2.0 * t)  # smoothstep
    cos2_sq = 1.0 - (outside_ior / film) ** 2 * (1.0 - cos1**2)
    cos2 = np.sqrt(np.maximum(cos2_sq, 0.0))
    r0 = ((film - outside_ior) / (film + outside_ior)) ** 2
    r12 = (r0 + (1.0 - r0) * (1.0 - cos1) ** 5)[..., None]
    t121 = 1.0 - r12
    phi21 = PI - (PI if film < outside_ior else 0.0)
    f0 = np.clip(np.asarray(base_f0, dtype=np.float64), 0.0, 0.9999)
    base_ior = (1.0 + np.sqrt(f0)) / (1.0 - np.sqrt(f0))
    r1 = ((base_ior - film) / (base_ior + film)) ** 2
    r23 = r1 + (1.0 - r1) * ((1.0 - cos2) ** 5)[..., None]
    phi = phi21 + np.where(base_ior < film, PI, 0.0) * np.ones_like(r23)
    opd = 2.0 * film * thickness * cos2
    r123 = np.clip(r12 * r23, 1e-5, 0.9999)
    rs = t121**2 * r23 / (1.0 - r123)
    out = r12 + rs
    cm = rs - t121
    for m in (1, 2):
        cm = cm * np.sqrt(r123)
        out = out + cm * 2.0 * _eval_sensitivity(m * opd, m * phi)
    out = np.maximum(out, 0.0)
    return np.where((cos2_sq < 0.0)[..., None], 1.0, out)


def iridescence_fresnel(m: Layers, n_dot_v, c) -> tuple | None:  # noqa: ANN001
    """(film Fresnel over the dielectric's F0, over the base colour c) at n.v, for `m`'s film;
    None without one (factor or thickness 0), as shade.glsl iridescence_fresnel."""
    if m.iridescence <= 0.0 or m.iridescence_thickness <= 0.0:
        return None
    f0 = dielectric_f0(m.ior, m.specular_color)
    return (eval_iridescence(1.0, m.iridescence_ior, n_dot_v, m.iridescence_thickness, f0),
            eval_iridescence(1.0, m.iridescence_ior, n_dot_v, m.iridescence_thickness, c))


@dataclass(frozen=True)
class Layers:
    """A material's KHR_materials_* parameters (brdf.glsl `Layers`; shade.glsl clamps them
    the same way in `material_layers`, and so does `Layers.of`)."""

    ior: float = 1.5
    specular_color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    specular: float = 1.0
    clearcoat: float = 0.0
    clearcoat_roughness: float = MIN_ROUGHNESS
    sheen_color: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sheen_roughness: float = MIN_SHEEN_ROUGHNESS
    transmission: float = 0.0
    thickness: float = 0.0
    attenuation_color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    attenuation_distance: float = 0.0
    anisotropy: float = 0.0  # strength, times the texture's B
    anisotropy_rotation: float = 0.0
    iridescence: float = 0.0  # factor, times the texture's R
    iridescence_ior: float = 1.3
    iridescence_thickness: float = 400.0  # nm: mix(minimum, maximum, texel G), else maximum
    diffuse_transmission: float = 0.0
    diffuse_transmission_color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    dispersion: float = 0.0

    @classmethod
    def of(cls, material: object, model_scale: float = 1.0) -> Layers:
        """The layers of a vkpbr.scene.types.Material, clamped as the shader clamps them;
        `model_scale`: the node's scale (the length of its model matrix's first column), by
        which KHR_materials_volume's thickness, given in the mesh's space, is scaled."""
        m = material
        return cls(
            ior=max(float(m.ior), 1.0), specular_color=tuple(m.specular_color_factor),
            specular=float(np.clip(m.specular_factor, 0.0, 1.0)),
            clearcoat=float(np.clip(m.clearcoat_factor, 0.0, 1.0)),
            clearcoat_roughness=float(np.clip(m.clearcoat_roughness_factor, MIN_ROUGHNESS, 1.0)),
            sheen_color=tuple(m.sheen_color_factor),
            sheen_roughness=float(np.clip(m.sheen_roughness_factor, MIN_SHEEN_ROUGHNESS, 1.0)),
            transmission=float(np.clip(m.transmission_factor, 0.0, 1.0)),
            thickness=max(float(m.thickness_factor), 0.0) * float(model_scale),
            attenuation_color=tuple(m.attenuation_color),
            attenuation_distance=float(m.attenuation_distance),
            anisotropy=float(np.clip(m.anisotropy_strength, 0.0, 1.0)),
            anisotropy_rotation=float(m.anisotropy_rotation),
            iridescence=float(np.clip(m.iridescence_factor, 0.0, 1.0)),
            iridescence_ior=max(float(m.iridescence_ior), 1.0),
            iridescence_thickness=max(float(m.iridescence_thickness_maximum), 0.0),
            diffuse_transmission=float(np.clip(m.diffuse_transmission_factor, 0.0, 1.0)),
            diffuse_transmission_color=tuple(np.clip(m.diffuse_transmission_color_factor, 0, 1)),
            dispersion=max(float(m.dispersion), 0.0))


@dataclass
class LayeredTerms:
    base: BrdfTerms  # specular and diffuse include n.l here (brdf.glsl LayeredTerms)
    transmission: np.ndarray  # (..., 3)
    sheen: np.ndarray  # (..., 3)
    diffuse_transmission: np.ndarray  # (..., 3), also in base.diffuse
    clearcoat: np.ndarray  # (...)


def evaluate_layered_brdf(n, nc, v, l, c, metallic, roughness, m: Layers,  # noqa: ANN001, E741
                          frame=None, iridescence=None) -> LayeredTerms:  # noqa: ANN001
    """Mirror of brdf.glsl evaluate_layered_brdf: the glTF BRDF with the KHR_materials_*
    layers for one light (before its radiance and shadow). `frame`: (t_a, b_a), the
    anisotropy's directions (`anisotropy_frame`), needed when m.anisotropy > 0;
    `iridescence`: `iridescence_fresnel`'s pair, None without a film."""
    n, nc, v, l, c = (np.asarray(x, dtype=np.float64) for x in (n, nc, v, l, c))
    metallic = np.asarray(metallic, dtype=np.float64)
    alpha = np.asarray(roughness, dtype=np.float64) ** 2
    h = _normalize(l + v)
    n_dot_l = np.maximum(_dot(n, l), 0.0)
    n_dot_v = np.maximum(_dot(n, v), 0.0)
    n_dot_h = np.maximum(_dot(n, h), 0.0)
    v_dot_h = np.maximum(_dot(v, h), 0.0)
    d = d_ggx(n_dot_h, alpha)
    vis = v_smith_ggx_correlated(n_dot_l, n_dot_v, alpha)
    if m.anisotropy > 0.0:
        at, ab = (np.asarray(x, dtype=np.float64) for x in frame)
        a_t, a_b = anisotropic_alphas(alpha, m.anisotropy)
        d = d_ggx_anisotropic(np.clip(_dot(n, h), 0.001, 1.0), _dot(at, h), _dot(ab, h), a_t, a_b)
        vis = v_ggx_anisotropic(n_dot_l, n_dot_v, _dot(ab, v), _dot(at, v), _dot(at, l),
                                _dot(ab, l), a_t, a_b)
    f_dielectric = m.specular * f_schlick(dielectric_f0(m.ior, m.specular_color), v_dot_h)
    f_metal = f_schlick(c, v_dot_h)
    f_max = max3(f_dielectric)
    if iridescence is not None:
        k = m.iridescence
        f_dielectric = f_dielectric + (iridescence[0] - f_dielectric) * k
        f_metal = f_metal + (iridescence[1] - f_metal) * k
        f_max = f_max + (max3(iridescence[0]) - f_max) * k
    f = (1.0 - metallic)[..., None] * f_dielectric + metallic[..., None] * f_metal
    specular = f * (d * vis * n_dot_l)[..., None]
    diffuse_weight = (1.0 - metallic) * (1.0 - f_max)
    diffuse = (diffuse_weight * (1.0 - m.transmission) / PI * n_dot_l)[..., None] * c
    diffuse_transmission = np.zeros_like(diffuse)
    if m.diffuse_transmission > 0.0:
        # KHR_materials_diffuse_transmission: mix(Lambert of c, Lambert of the transmission
        # colour about -n, factor), the volume's transmittance on the latter.
        btdf = (np.asarray(m.diffuse_transmission_color) / PI
                * np.maximum(-_dot(n, l), 0.0)[..., None]
                * volume_transmittance(np.asarray(m.thickness), m.attenuation_color,
                                       m.attenuation_distance))
        diffuse_transmission = ((diffuse_weight * (1.0 - m.transmission)
                                 * m.diffuse_transmission)[..., None] * btdf)
        diffuse = diffuse * (1.0 - m.diffuse_transmission) + diffuse_transmission
    base = BrdfTerms(D=d, F=f, G=vis * 4.0 * n_dot_l * n_dot_v, specular=specular, diffuse=diffuse)
    transmission = np.zeros_like(specular)
    if m.transmission > 0.0:
        l_mirror = _normalize(l - 2.0 * n * _dot(l, n)[..., None])
        ht = _normalize(l_mirror + v)
        alpha_t = alpha * np.clip(m.ior * 2.0 - 2.0, 0.0, 1.0)
        d_t = d_ggx(np.maximum(_dot(n, ht), 0.0), alpha_t)
        v_t = v_smith_ggx_correlated(np.maximum(_dot(n, l_mirror), 0.0), n_dot_v, alpha_t)
        transmission = ((diffuse_weight * m.transmission * d_t * v_t)[..., None] * c
                        * volume_transmittance(np.asarray(m.thickness), m.attenuation_color,
                                               m.attenuation_distance))
    sheen = np.zeros_like(specular)
    if max(m.sheen_color) > 0.0:
        sheen = np.asarray(m.sheen_color) * (d_charlie(n_dot_h, m.sheen_roughness)
                                             * v_charlie(n_dot_l, n_dot_v, m.sheen_roughness)
                                             * n_dot_l)[..., None]
    clearcoat = np.zeros_like(n_dot_l)
    if m.clearcoat > 0.0:
        a_c = m.clearcoat_roughness**2
        nc_dot_l = np.maximum(_dot(nc, l), 0.0)
        clearcoat = (d_ggx(np.maximum(_dot(nc, h), 0.0), a_c)
                     * v_smith_ggx_correlated(nc_dot_l, np.maximum(_dot(nc, v), 0.0), a_c) * nc_dot_l)
    return LayeredTerms(base=base, transmission=transmission, sheen=sheen, clearcoat=clearcoat,
                        diffuse_transmission=diffuse_transmission)


def dispersion_iors(m: Layers) -> tuple[float, float, float]:
    """The index each channel refracts at (shade.glsl refracted_behind): KHR_materials_
    dispersion's spread s = (ior - 1) 0.025 dispersion, red ior - s, green ior, blue ior + s
    (at least 1), in a volume (thickness > 0); the material's ior for all three otherwise."""
    if m.dispersion <= 0.0 or m.thickness <= 0.0:
        return (m.ior, m.ior, m.ior)
    s = (m.ior - 1.0) * 0.025 * m.dispersion
    return (max(m.ior - s, 1.0), m.ior, m.ior + s)


def transmission_exit(p, n, v, m: Layers) -> np.ndarray:  # noqa: ANN001
    """Mirror of shade.glsl's refracted ray: where the light a transmissive surface at `p`
    lets through leaves it (..., 3): `p` itself for a thin wall, `thickness` along
    refract(-v, n, 1 / ior) into a volume; the opaque copy is sampled where it projects
    (render/transmission.py)."""
    p, n, v = (np.asarray(x, dtype=np.float64) for x in (p, n, v))
    if m.thickness <= 0.0:
        return p
    eta = 1.0 / m.ior
    cos_i = _dot(n, v)
    k = 1.0 - eta * eta * (1.0 - cos_i * cos_i)
    d = np.where((k >= 0.0)[..., None],
                 -eta * v + (eta * cos_i - np.sqrt(np.maximum(k, 0.0)))[..., None] * n, -v)
    return p + _normalize(d) * m.thickness


def shade_layered(n, v, l, c, metallic, roughness, light_in, m: Layers, emissive=0.0,  # noqa: ANN001, E741
                  nc=None, env_radiance: float | None = None,  # noqa: ANN001
                  ibl_diffuse_weight=None, behind=None,  # noqa: ANN001
                  frame=None) -> dict[str, np.ndarray]:  # noqa: ANN001
    """The views shade.glsl writes for a layered glTF material lit by one light (`l`,
    `light_in`; light_in 0 for none) and optionally a uniform environment of radiance
    `env_radiance` (already scaled by its intensity), for the layers' environment terms:
    the coat's reflection, sheen and refraction (each sees `env_radiance` in every
    direction). `ibl_diffuse_weight`: the split sum's k_d (..., 3), needed for refraction.
    `behind` (..., 3): the radiance refraction brings (the opaque copy's where the exit point
    projects, `transmission_exit`); None: `env_radiance`.
    Returns the radiance views "specular", "diffuse", "transmission", "sheen", "clearcoat",
    the scalars "sheen_scaling" and "coat_blend", the data views "ior", "dielectric_f0" and
    "volume", and "final" (the point light's and these environment terms only: the split
    sum's own diffuse and specular are not mirrored here), each (..., 3).
    `frame`: the anisotropy's (t_a, b_a) (`anisotropy_frame`) when m.anisotropy > 0."""
    roughness = np.clip(roughness, MIN_ROUGHNESS, 1.0)
    n = np.asarray(n, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    nc = n if nc is None else np.asarray(nc, dtype=np.float64)
    light_in = np.asarray(light_in, dtype=np.float64)
    irid = iridescence_fresnel(m, np.clip(_dot(n, v), 0.0, 1.0), np.asarray(c, dtype=np.float64))
    t = evaluate_layered_brdf(n, nc, v, l, c, metallic, roughness, m, frame, irid)
    out = {"specular": t.base.specular * light_in, "diffuse": t.base.diffuse * light_in,
           "diffuse_transmission": t.diffuse_transmission * light_in,
           "transmission": t.transmission * light_in, "sheen": t.sheen * light_in,
           "clearcoat": t.clearcoat[..., None] * light_in, "terms": t}
    n_dot_v = np.clip(_dot(n, v), 1e-4, 1.0)
    if env_radiance is not None:
        if m.transmission > 0.0:
            out["transmission"] = out["transmission"] + (
                m.transmission * np.asarray(ibl_diffuse_weight)
                * (env_radiance if behind is None else np.asarray(behind))
                * volume_transmittance(np.asarray(m.thickness), m.attenuation_color,
                                       m.attenuation_distance))
        if max(m.sheen_color) > 0.0:
            out["sheen"] = out["sheen"] + (np.asarray(m.sheen_color) * env_radiance
                                           * sheen_albedo(n_dot_v, m.sheen_roughness)[..., None])
        if m.clearcoat > 0.0:
            out["clearcoat"] = out["clearcoat"] + env_radiance
    scaling = 1.0 - max(m.sheen_color) * sheen_albedo(n_dot_v, m.sheen_roughness)
    nc_dot_v = np.clip(_dot(nc, v), 0.0, 1.0)
    blend = m.clearcoat * (0.04 + 0.96 * (1.0 - nc_dot_v) ** 5)
    out["clearcoat"] = out["clearcoat"] * blend[..., None]
    base = out["diffuse"] + out["specular"] + out["transmission"]
    out["final"] = ((emissive + out["sheen"] + base * scaling[..., None]) * (1.0 - blend)[..., None]
                    + out["clearcoat"])
    shape = n.shape
    out["sheen_scaling"], out["coat_blend"] = scaling, blend
    out["ior"] = np.full(shape, min(m.ior - 1.0, 1.0))
    out["dielectric_f0"] = np.broadcast_to(dielectric_f0(m.ior, m.specular_color) * m.specular, shape)
    out["iridescence"] = (np.zeros(shape) if irid is None
                          else np.broadcast_to(irid[0] * m.iridescence, shape))
    out["volume"] = np.broadcast_to(volume_transmittance(np.asarray(m.thickness), m.attenuation_color,
                                                         m.attenuation_distance), shape)
    return out


def specular_glossiness(diffuse, specular, glossiness) -> tuple:  # noqa: ANN001
    """KHR_materials_pbrSpecularGlossiness (archived) as the glTF BRDF's inputs, as the glTF
    Sample Viewer shades it (getSpecularGlossinessInfo, getBaseColor): a dielectric whose base
    colour is the diffuse colour, whose F0 is the specular colour and whose perceptual
    roughness is 1 - glossiness. Returns (c (..., 3), metallic, roughness, Layers): the
    roughness before the punctual floor (`shade_layered` clamps it), the Layers' dielectric F0
    (`dielectric_f0`, ior 1.5: 0.04 x specular colour) the specular colour. Inputs are texel x
    factor already (diffuse RGB, specular RGB, glossiness)."""
    specular = np.asarray(specular, dtype=np.float64)
    c = np.asarray(diffuse, dtype=np.float64)[..., :3]
    roughness = 1.0 - np.asarray(glossiness, dtype=np.float64)
    f0_ior = ((1.5 - 1.0) / (1.5 + 1.0)) ** 2
    layers = Layers(ior=1.5, specular_color=tuple(specular / f0_ior), specular=1.0)
    return c, np.zeros_like(roughness), roughness, layers
