"""Image-based lighting by Monte Carlo integration of the glTF 2.0 BRDF, in NumPy: the
independent reference for shaders/ibl.glsl (which uses the split-sum approximation), and
`split_sum_ibl`, the mirror of ibl.glsl's own formula from the texels it reads.

    L_o(v) = integral over the hemisphere of f(v, l) L_env(l) (n.l) dl
           + multiple-scattering compensation (Fdez-Aguera 2019) of the specular lobe,

with f the glTF 2.0 specification's BRDF (Appendix B: GGX D, height-correlated Smith V,
Schlick F, `fresnel_mix` of the dielectric with ior 1.5, `conductor_fresnel` of the metal,
mixed by metallic). The integral is estimated by one-sample multiple importance sampling: each
direction comes from the GGX lobe or the cosine lobe with probability 1/2, weighted by the
mixture's pdf (the balance heuristic), so that neither smooth nor rough lobes are noisy.

The compensation term needs the lobe's single-scattering albedo E_ss(n.v) and F-weighted
albedo; both are integrated here by Monte Carlo too (not read from the GPU's table). In a
uniform white environment a white metal then returns exactly 1, a white dielectric 1 up to
the spec's `fresnel_mix` (which is not exactly energy conserving: within 2%), and every mix
of the two (Appendix B mixes the dielectric and metal BRDFs, each compensated) 1 as well.

`d_ggx` and `f_schlick` are reference/brdf.py's; the height-correlated Smith V is a private
copy (`_v_smith_ggx_correlated`) until brdf.py has `v_smith_ggx_correlated`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from vkpbr.reference.brdf import d_ggx

__all__ = ["gltf_brdf", "mc_ibl", "Environment", "uniform_environment", "two_tone_environment",
           "ggx_albedo", "ibl_lobe", "split_sum_ibl"]

PI = np.pi
Environment = Callable[[np.ndarray], np.ndarray]  # unit directions (..., 3) -> RGB (..., 3)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sum(a * b, axis=-1)


def _v_smith_ggx_correlated(n_dot_l: np.ndarray, n_dot_v: np.ndarray,
                            alpha: np.ndarray) -> np.ndarray:
    """glTF 2.0 B.3.2: V = 0.5 / (n.l sqrt(n.v^2 (1 - a^2) + a^2) + n.v sqrt(n.l^2 (1 - a^2) + a^2))."""
    a2 = alpha * alpha
    gv = n_dot_l * np.sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2)
    gl = n_dot_v * np.sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2)
    s = gv + gl
    return np.where(s > 0.0, 0.5 / np.maximum(s, 1e-12), 0.0)


def gltf_brdf(n: np.ndarray, v: np.ndarray, l: np.ndarray, c: np.ndarray,
              metallic: np.ndarray, roughness: np.ndarray) -> np.ndarray:
    """The glTF 2.0 BRDF f(v, l) (Appendix B.3), (..., 3); zero below the horizon."""
    n_dot_l = _dot(n, l)
    n_dot_v = _dot(n, v)
    h = l + v
    h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-12)
    v_dot_h = np.abs(_dot(v, h))
    n_dot_h = np.clip(_dot(n, h), 0.0, 1.0)
    alpha = np.asarray(roughness, dtype=np.float64) ** 2
    spec = (_v_smith_ggx_correlated(np.maximum(n_dot_l, 0.0), np.maximum(n_dot_v, 0.0), alpha)
            * d_ggx(n_dot_h, alpha))[..., None]
    fc = (np.maximum(1.0 - v_dot_h, 0.0) ** 5)[..., None]
    c = np.asarray(c, dtype=np.float64)
    dielectric_f = 0.04 + 0.96 * fc
    dielectric = (1.0 - dielectric_f) * c / PI + dielectric_f * spec  # fresnel_mix(1.5, ...)
    metal = spec * (c + (1.0 - c) * fc)  # conductor_fresnel(c, ...)
    m = np.asarray(metallic, dtype=np.float64)[..., None]
    f = (1.0 - m) * dielectric + m * metal
    ok = ((n_dot_l > 0.0) & (n_dot_v > 0.0))[..., None]
    return np.where(ok, f, 0.0)


def _frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tangent and bitangent (..., 3) around unit n (Duff et al. 2017)."""
    s = np.where(n[..., 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (s + n[..., 2])
    b = n[..., 0] * n[..., 1] * a
    t = np.stack([1.0 + s * n[..., 0] ** 2 * a, s * b, -s * n[..., 0]], axis=-1)
    bt = np.stack([b, s + n[..., 1] ** 2 * a, -n[..., 1]], axis=-1)
    return t, bt


# Points evaluated at once: chunks of ~64K (point, sample) pairs keep each temporary at a
# few MB, in cache and without fresh pages (4096 samples of 1,500 points in one piece made
# arrays of 150 MB; the sum is the same: each point's own values, summed in the same order).
CHUNK_PAIRS = 1 << 16


def _draws(shape: tuple[int, ...], rng: np.random.Generator
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The uniform numbers `_sample` turns into directions: u1, u2 and the lobe pick."""
    return rng.random(shape), rng.random(shape), rng.random(shape) < 0.5


def _chunks(points: int, samples: int) -> list[slice]:
    step = max(1, CHUNK_PAIRS // max(samples, 1))
    return [slice(i, i + step) for i in range(0, points, step)]


def _sample(n: np.ndarray, v: np.ndarray, alpha: np.ndarray,
            draws: tuple[np.ndarray, np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Directions per point (..., count, 3) from the GGX/cosine mixture, one for each of
    `draws` (`_draws` of shape (..., count)), and their mixture pdf (..., count)."""
    u1, u2, pick = draws
    shape = u1.shape
    t, bt = _frame(n)
    t, bt, nn, vv = t[..., None, :], bt[..., None, :], n[..., None, :], v[..., None, :]
    a = np.asarray(alpha, dtype=np.float64)[..., None]
    a = np.broadcast_to(a, shape)
    phi = 2.0 * PI * u1
    # GGX half vector (Walter et al. 2007), reflected about it.
    cos_h = np.sqrt((1.0 - u2) / (1.0 + (a * a - 1.0) * u2))
    sin_h = np.sqrt(np.maximum(1.0 - cos_h * cos_h, 0.0))
    h = (t * (sin_h * np.cos(phi))[..., None] + bt * (sin_h * np.sin(phi))[..., None]
         + nn * cos_h[..., None])
    l_ggx = 2.0 * _dot(vv, h)[..., None] * h - vv
    # Cosine lobe.
    r = np.sqrt(u2)
    l_cos = (t * (r * np.cos(phi))[..., None] + bt * (r * np.sin(phi))[..., None]
             + nn * np.sqrt(np.maximum(1.0 - u2, 0.0))[..., None])
    l = np.where(pick[..., None], l_ggx, l_cos)
    # The mixture's pdf at l.
    hh = l + vv
    hh = hh / np.maximum(np.linalg.norm(hh, axis=-1, keepdims=True), 1e-12)
    n_dot_h = np.clip(_dot(nn, hh), 0.0, 1.0)
    v_dot_h = np.maximum(np.abs(_dot(vv, hh)), 1e-12)
    pdf_ggx = d_ggx(n_dot_h, a) * n_dot_h / (4.0 * v_dot_h)
    pdf_cos = np.maximum(_dot(nn, l), 0.0) / PI
    return l, 0.5 * pdf_ggx + 0.5 * pdf_cos


def ggx_albedo(n_dot_v: np.ndarray, roughness: np.ndarray, f0: np.ndarray | float = 1.0,
               samples: int = 4096, seed: int = 1) -> np.ndarray:
    """Directional albedo of the glTF specular lobe with Schlick F of `f0` (..., K when f0
    has K channels, a colour or several stacked; else ...): integral of V D F (n.l) dl by
    Monte Carlo (E_ss for f0 = 1)."""
    rng = np.random.default_rng(seed)
    n_dot_v = np.asarray(n_dot_v, dtype=np.float64)
    lead = n_dot_v.shape
    draws = [d.reshape(-1, samples) for d in _draws(lead + (samples,), rng)]
    alpha = np.broadcast_to(np.asarray(roughness, dtype=np.float64) ** 2, lead).reshape(-1)
    f0 = np.asarray(f0, dtype=np.float64)
    if f0.ndim:
        f0 = np.broadcast_to(f0, lead + f0.shape[-1:]).reshape(-1, f0.shape[-1])
    mu = n_dot_v.reshape(-1)
    out = np.empty(mu.shape + f0.shape[1:])
    for part in _chunks(len(mu), samples):
        out[part] = _albedo(mu[part], alpha[part], f0 if f0.ndim == 0 else f0[part],
                            [d[part] for d in draws])
    return out.reshape(lead + f0.shape[1:])


def _albedo(n_dot_v: np.ndarray, alpha: np.ndarray, f0: np.ndarray,
            draws: list[np.ndarray]) -> np.ndarray:
    """ggx_albedo of points (P,) from their draws (P, samples)."""
    nrm = np.zeros(n_dot_v.shape + (3,))
    nrm[..., 2] = 1.0
    v = np.stack([np.sqrt(1.0 - n_dot_v**2), np.zeros_like(n_dot_v), n_dot_v], axis=-1)
    l, pdf = _sample(nrm, v, alpha, tuple(draws))
    nl = l[..., 2]
    h = l + v[..., None, :]
    h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-12)
    vh = np.abs(_dot(v[..., None, :], h))
    a = np.broadcast_to(alpha[..., None], nl.shape)
    spec = _v_smith_ggx_correlated(np.maximum(nl, 0.0), n_dot_v[..., None], a) * d_ggx(
        np.clip(h[..., 2], 0.0, 1.0), a)
    w = np.where(nl > 0.0, spec * nl / np.maximum(pdf, 1e-12), 0.0)
    fc = (1.0 - vh) ** 5
    if f0.ndim == 0:
        return np.mean(w * (f0 + (1.0 - f0) * fc), axis=-1)
    f = f0[..., None, :] + (1.0 - f0[..., None, :]) * fc[..., None]
    return np.mean(w[..., None] * f, axis=-2)


def ibl_lobe(f0: np.ndarray, weight: np.ndarray | float, n_dot_v: np.ndarray,
             roughness: np.ndarray, a: np.ndarray, b: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """Mirror of ibl.glsl ibl_lobe: one specular lobe's split-sum weights (FssEss, FmsEms),
    each (..., 3), for Schlick's F of `f0` (..., 3) scaled by `weight`, from the split-sum
    table's A and B (...) at (n.v, roughness) (Fdez-Aguera 2019, listing 3)."""
    f0 = np.asarray(f0, dtype=np.float64)
    weight = np.asarray(weight, dtype=np.float64)[..., None]
    rough = np.asarray(roughness, dtype=np.float64)[..., None]
    mu = np.asarray(n_dot_v, dtype=np.float64)[..., None]
    a, b = np.asarray(a, dtype=np.float64)[..., None], np.asarray(b, dtype=np.float64)[..., None]
    fr = np.maximum(1.0 - rough, f0) - f0
    k_s = f0 + fr * (1.0 - mu) ** 5
    fss_ess = weight * (k_s * a + b)
    ems = 1.0 - (a + b)
    f_avg = weight * (f0 + (1.0 - f0) / 21.0)
    return fss_ess, ems * fss_ess * f_avg / (1.0 - ems * f_avg)


def split_sum_ibl(n_dot_v: np.ndarray, c: np.ndarray, metallic: np.ndarray,
                  roughness: np.ndarray, a: np.ndarray, b: np.ndarray, radiance: np.ndarray,
                  irradiance: np.ndarray, f0_dielectric: np.ndarray | float = 0.04,
                  specular_weight: np.ndarray | float = 1.0, iridescence: float = 0.0,
                  iridescence_fresnel: tuple | None = None, diffuse_transmission: float = 0.0,
                  diffuse_transmission_color: tuple = (1.0, 1.0, 1.0),
                  irradiance_behind: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mirror of ibl.glsl ibl_evaluate from the texels it reads: the split-sum table's A, B
    (...), the pre-filtered `radiance` along the reflection and the `irradiance` about n
    (..., 3, already scaled by the environment's intensity). glTF Appendix B's mix: the
    dielectric BRDF (its lobe of F0 `f0_dielectric` x `specular_weight` over the diffuse c,
    weighted by what that lobe leaves) and the metal BRDF (its lobe of F0 c), each with its
    own compensation, mixed by metallic. KHR_materials_iridescence (factor `iridescence`,
    `iridescence_fresnel` the film's Fresnel over the dielectric and over c, brdf.py
    `iridescence_fresnel`): each lobe mixed by the factor with the film's Fresnel (no
    multiple scattering), the dielectric's diffuse with 1 - max3 of it (the Sample Viewer's
    composition). KHR_materials_diffuse_transmission: the diffuse mixed by its factor with
    the same weight times the transmission colour and the `irradiance_behind` (about -n).
    Returns (diffuse, specular, k_d), each (..., 3)."""
    c = np.asarray(c, dtype=np.float64)
    m = np.asarray(metallic, dtype=np.float64)[..., None]
    mu = np.clip(np.asarray(n_dot_v, dtype=np.float64), 1e-4, 1.0)
    f0_d = np.broadcast_to(np.asarray(f0_dielectric, dtype=np.float64), c.shape)
    d_ss, d_ms = ibl_lobe(f0_d, specular_weight, mu, roughness, a, b)
    m_ss, m_ms = ibl_lobe(c, 1.0, mu, roughness, a, b)
    leaves = 1.0 - d_ss - d_ms
    if iridescence > 0.0 and iridescence_fresnel is not None:
        k = iridescence
        fi_d, fi_m = (np.asarray(x, dtype=np.float64) for x in iridescence_fresnel)
        leaves = leaves + (1.0 - fi_d.max(axis=-1, keepdims=True) - leaves) * k
        d_ss, d_ms = d_ss + (fi_d - d_ss) * k, d_ms * (1.0 - k)
        m_ss, m_ms = m_ss + (fi_m - m_ss) * k, m_ms * (1.0 - k)
    fss_ess = (1.0 - m) * d_ss + m * m_ss
    fms_ems = (1.0 - m) * d_ms + m * m_ms
    k_d = (1.0 - m) * c * leaves
    radiance, irradiance = np.asarray(radiance), np.asarray(irradiance)
    diffuse = k_d * irradiance
    if diffuse_transmission > 0.0:
        behind = ((1.0 - m) * leaves * np.asarray(diffuse_transmission_color)
                  * np.asarray(irradiance if irradiance_behind is None else irradiance_behind))
        diffuse = diffuse + (behind - diffuse) * diffuse_transmission
    return diffuse, fss_ess * radiance + fms_ems * irradiance, k_d


def _schlick(f0: np.ndarray, fc: np.ndarray) -> np.ndarray:
    return f0 + (1.0 - f0) * fc


def mc_ibl(n: np.ndarray, v: np.ndarray, c: np.ndarray, metallic: np.ndarray,
           roughness: np.ndarray, environment: Environment, samples: int = 2048,
           seed: int = 0, multiple_scattering: bool = True,
           coupling: str = "fdez-aguera") -> np.ndarray:
    """Radiance (..., 3) reflected towards v by the glTF BRDF lit by `environment`.

    glTF 2.0 Appendix B's material: mix(dielectric BRDF, metal BRDF, metallic), each BRDF's
    specular lobe with its own multiple-scattering compensation.

    Parameters
    ----------
    n, v : (..., 3) unit normal and direction towards the viewer.
    c : (..., 3) base colour; metallic, roughness : (...).
    environment : radiance of unit directions, (..., 3) -> (..., 3).
    samples : Monte Carlo samples per point (standard error ~ 1 / sqrt(samples)).
    multiple_scattering : add Fdez-Aguera's compensation of each specular lobe's lost
        energy (the dielectric's of F0 0.04, the metal's of F0 c, mixed by metallic), with
        E_ss and the F-weighted albedos integrated here (`ggx_albedo`) and the irradiance
        (cosine-weighted mean radiance) integrated over the same samples.
    coupling : how the dielectric's diffuse lobe is weighted. "gltf": the specification's
        `fresnel_mix`, (1 - F(v.h)) per direction, which is not energy conserving at grazing
        angles (a white smooth dielectric in a white furnace returns 1.3 at n.v = 0.2);
        "fdez-aguera": the energy-conserving weight 1 - (FssEss + FmsEms) of the dielectric's
        own lobe (Fdez-Aguera's listing 3), which ibl.glsl (and the glTF Sample Renderer's
        f_dielectric_brdf_ibl) uses; its albedo terms integrated here by Monte Carlo.
    """
    if coupling not in ("gltf", "fdez-aguera"):
        raise ValueError(f"coupling {coupling!r}: expected 'gltf' or 'fdez-aguera'")
    rng = np.random.default_rng(seed)
    n, v, c = (np.asarray(x, dtype=np.float64) for x in (n, v, c))
    lead = n.shape[:-1]
    metallic = np.broadcast_to(np.asarray(metallic, dtype=np.float64), lead)
    roughness = np.broadcast_to(np.asarray(roughness, dtype=np.float64), lead)
    draws = _draws(lead + (samples,), rng)
    n_dot_v = np.clip(_dot(n, v), 1e-4, 1.0)
    m = metallic[..., None]
    # E_ss (F0 = 1) and the dielectric's and the metal's F-weighted albedos from one set of
    # samples: seven "channels" of F0.
    f0s = (np.full_like(c, 0.04), c)
    albedo = ggx_albedo(n_dot_v, roughness, np.concatenate([np.ones_like(c[..., :1]), *f0s], -1))
    ems = 1.0 - albedo[..., :1]
    lobes = []  # (FssEss, FmsEms) of the dielectric's lobe, then the metal's
    for k, f0 in enumerate(f0s):
        fss_ess = albedo[..., 1 + 3 * k:4 + 3 * k]
        f_avg = f0 + (1.0 - f0) / 21.0
        fms_ems = ems * fss_ess * f_avg / (1.0 - ems * f_avg)
        lobes.append((fss_ess, fms_ems if multiple_scattering else np.zeros_like(fms_ems)))
    (d_ss, d_ms), (_, m_ms) = lobes
    fms_ems = (1.0 - m) * d_ms + m * m_ms

    def points(x: np.ndarray, tail: tuple[int, ...] = ()) -> np.ndarray:
        return np.broadcast_to(x, lead + tail).reshape((-1,) + tail)

    per_point = [points(n, (3,)), points(v, (3,)), points(c, (3,)), points(metallic),
                 points(roughness), points(d_ss, (3,)), points(d_ms, (3,))]
    flat_draws = [d.reshape(-1, samples) for d in draws]
    single, irr = np.empty((2, len(per_point[0]), 3))
    for part in _chunks(len(single), samples):
        single[part], irr[part] = _mc_points(*(x[part] for x in per_point),
                                             [d[part] for d in flat_draws], environment, coupling)
    return single.reshape(lead + (3,)) + fms_ems * irr.reshape(lead + (3,))


def _mc_points(n: np.ndarray, v: np.ndarray, c: np.ndarray, metallic: np.ndarray,
               roughness: np.ndarray, d_ss: np.ndarray, d_ms: np.ndarray,
               draws: list[np.ndarray], environment: Environment, coupling: str
               ) -> tuple[np.ndarray, np.ndarray]:
    """mc_ibl's estimate at points (P,) from their draws (P, samples): the BRDF's integral
    and the irradiance / pi over the same directions, each (P, 3)."""
    l, pdf = _sample(n, v, roughness**2, tuple(draws))
    env = environment(l)
    nl = _dot(n[..., None, :], l)
    w = np.where(nl > 0.0, np.maximum(nl, 0.0) / np.maximum(pdf, 1e-12), 0.0)[..., None]
    m = metallic[..., None]
    if coupling == "gltf":
        f = gltf_brdf(n[..., None, :], v[..., None, :], l, c[..., None, :],
                      metallic[..., None], roughness[..., None])
    else:
        # Each BRDF's specular lobe: V D (n.l) with Schlick F of its F0; the dielectric's
        # diffuse weighted by what its own lobe (single and multiple scattering) leaves.
        f_spec = gltf_brdf(n[..., None, :], v[..., None, :], l, np.ones_like(c)[..., None, :],
                           np.ones_like(metallic)[..., None], roughness[..., None])
        vv = v[..., None, :]
        hh = l + vv
        hh = hh / np.maximum(np.linalg.norm(hh, axis=-1, keepdims=True), 1e-12)
        fc = ((1.0 - np.abs(_dot(vv, hh))) ** 5)[..., None]
        dielectric = f_spec * _schlick(0.04, fc) + np.where(
            (nl > 0.0)[..., None], (c * (1.0 - d_ss - d_ms))[..., None, :] / PI, 0.0)
        metal = f_spec * _schlick(c[..., None, :], fc)
        f = (1.0 - m[..., None]) * dielectric + m[..., None] * metal
    single = np.mean(f * env * w, axis=-2)
    # Irradiance (cosine-weighted mean radiance) over the same directions: E / pi.
    irr = np.mean(env * (w / PI), axis=-2)
    return single, irr


def uniform_environment(radiance: float | tuple = 1.0) -> Environment:
    rgb = np.broadcast_to(np.asarray(radiance, dtype=np.float64), (3,))
    return lambda d: np.broadcast_to(rgb, d.shape).copy()


def two_tone_environment(up: tuple = (1.0, 1.0, 1.0), down: tuple = (0.1, 0.1, 0.1),
                         axis: tuple = (0.0, 1.0, 0.0)) -> Environment:
    """`up` radiance where d.axis > 0, `down` elsewhere (a sky over a dark ground)."""
    up_, down_, ax = (np.asarray(x, dtype=np.float64) for x in (up, down, axis))
    return lambda d: np.where((d @ ax)[..., None] > 0.0, up_, down_)
