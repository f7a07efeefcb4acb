"""The built-in physically based sky (Preetham, Shirley and Smits 1999), in NumPy.

The GPU makes the sky cube from the same numbers (shaders/sky.comp): `SkyModel.coefficients`
are the Perez coefficients and zenith values that this module computes once per sun, and
`sky_radiance` is the shader's formula, vectorised, for the tests. `sun_radiometry` gives the
automatic directional light that matches the sky's sun (same turbidity, same air mass).

Model (Preetham et al., "A Practical Analytic Model for Daylight", SIGGRAPH 1999):
- sky luminance Y and chromaticity x, y per direction: the Perez function
  F(theta, gamma) = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma), with
  coefficients linear in the turbidity T (the paper's Appendix A.2), scaled by the zenith
  values (A.2, eq. for Y_z, x_z, y_z) as Y = Y_z F(theta, gamma) / F(0, theta_s);
- xyY -> CIE XYZ -> linear Rec. 709 (sRGB primaries), negatives clipped;
- the sun: extraterrestrial illuminance E0 attenuated by Rayleigh and aerosol (Angstrom)
  transmittance at 680, 550 and 440 nm over the Kasten-Young air mass (the paper's
  Appendix A.1 formulas, ozone and water vapour left out);
- the ground (below the horizon): a Lambertian plane of albedo `GROUND_ALBEDO` lit by the sun
  and by the sky's horizontal illuminance.

Units: renderer radiance 1 = `SKY_UNIT` cd/m^2 (20 kcd/m^2), chosen so that the sky is
around 1 (zenith 0.4, horizon 0.8 for the default sun and T = 3) as HDR environments are in
the glTF-Sample-Viewer, so exposure 0 with the pbr-neutral tone map looks right; the sun's
illuminance is in the same unit (lux / SKY_UNIT), about 4.3 at 50 degrees of elevation. The
sun disc itself is not in the sky cube: the directional light carries it (no double count).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vkpbr.shading import SUN_DIRECTION

__all__ = ["SKY_UNIT", "TURBIDITY", "GROUND_ALBEDO", "SkyModel", "sky_model", "sky_radiance",
           "sun_radiometry", "XYZ_TO_LINEAR_SRGB"]

SKY_UNIT = 20000.0  # cd/m^2 (and lux per unit of illuminance) of renderer radiance 1
TURBIDITY = 3.0  # a clear day
GROUND_ALBEDO = (0.30, 0.27, 0.24)  # dry earth, slightly warm
E0_LUX = 128000.0  # extraterrestrial solar illuminance, lux
MAX_SUN_ZENITH = np.radians(88.0)  # the model is fitted for a sun above the horizon

XYZ_TO_LINEAR_SRGB = np.array([[3.2404542, -1.5371385, -0.4985314],
                               [-0.9692660, 1.8760108, 0.0415560],
                               [0.0556434, -0.2040259, 1.0572252]])
_LUMA = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 luminance of linear RGB

# Perez coefficients (A..E) as (slope, intercept) in T: Preetham 1999, Appendix A.2.
_PEREZ = {
    "Y": ((0.1787, -1.4630), (-0.3554, 0.4275), (-0.0227, 5.3251), (0.1206, -2.5771),
          (-0.0670, 0.3703)),
    "x": ((-0.0193, -0.2592), (-0.0665, 0.0008), (-0.0004, 0.2125), (-0.0641, -0.8989),
          (-0.0033, 0.0452)),
    "y": ((-0.0167, -0.2608), (-0.0950, 0.0092), (-0.0079, 0.2102), (-0.0441, -1.6537),
          (-0.0109, 0.0529)),
}
_ZENITH_X = np.array([[0.00166, -0.00375, 0.00209, 0.0],
                      [-0.02903, 0.06377, -0.03202, 0.00394],
                      [0.11693, -0.21196, 0.06052, 0.25886]])
_ZENITH_Y = np.array([[0.00275, -0.00610, 0.00317, 0.0],
                      [-0.04214, 0.08970, -0.04153, 0.00516],
                      [0.15346, -0.26756, 0.06670, 0.26688]])


@dataclass(frozen=True)
class SkyModel:
    """Everything the sky shader needs, computed once per sun (pushed to sky.comp).

    perez : (3, 5) float64, rows Y, x, y; columns A..E.
    zenith : (3,) Y_z / F(0, theta_s) (in SKY_UNIT), x_z / F_x(0, theta_s), y_z / F_y(...).
    to_sun : (3,) unit vector towards the sun (minus the light's travel direction).
    ground : (3,) ground radiance, renderer units.
    """

    perez: np.ndarray
    zenith: np.ndarray
    to_sun: np.ndarray
    ground: np.ndarray

    @property
    def coefficients(self) -> np.ndarray:
        """(28,) float32 in sky.comp's push-constant order: perez (15), zenith (3) + pad,
        to_sun (3) + pad, ground (3) + pad. Tail padded to vec4 boundaries."""
        out = np.zeros(28, np.float32)
        out[:15] = self.perez.reshape(-1)
        out[16:19] = self.zenith
        out[20:23] = self.to_sun
        out[24:27] = self.ground
        return out


def _perez(theta_cos: np.ndarray, gamma: np.ndarray, c: np.ndarray) -> np.ndarray:
    a, b, cc, d, e = (c[..., k] for k in range(5))
    cos_g = np.cos(gamma)
    return (1.0 + a * np.exp(b / theta_cos)) * (1.0 + cc * np.exp(d * gamma) + e * cos_g * cos_g)


def _to_sun(sun_direction: np.ndarray) -> tuple[np.ndarray, float]:
    d = -np.asarray(sun_direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    return d, float(np.arccos(np.clip(d[1], -1.0, 1.0)))


def _sky_xyY(model: SkyModel, d: np.ndarray) -> np.ndarray:
    """(..., 3) Y, x, y of directions above the horizon (d.y clamped to a small cosine)."""
    cos_t = np.maximum(d[..., 1], 0.01)  # at the horizon the model's e^(B / cos) -> 0
    gamma = np.arccos(np.clip(d @ model.to_sun, -1.0, 1.0))
    return np.stack([model.zenith[k] * _perez(cos_t, gamma, model.perez[k]) for k in range(3)],
                    axis=-1)


def _xyY_to_rgb(xyY: np.ndarray) -> np.ndarray:
    Y, x, y = xyY[..., 0], xyY[..., 1], xyY[..., 2]
    X = x / y * Y
    Z = (1.0 - x - y) / y * Y
    return np.maximum(np.stack([X, Y, Z], axis=-1) @ XYZ_TO_LINEAR_SRGB.T, 0.0)


def sky_model(sun_direction: np.ndarray | tuple = SUN_DIRECTION,
              turbidity: float = TURBIDITY) -> SkyModel:
    """The sky's coefficients for a sun whose light travels along `sun_direction`."""
    T = float(turbidity)
    to_sun, theta_s = _to_sun(np.asarray(sun_direction))
    theta_s = min(theta_s, float(MAX_SUN_ZENITH))
    perez = np.array([[s * T + i for s, i in _PEREZ[k]] for k in "Yxy"])
    chi = (4.0 / 9.0 - T / 120.0) * (np.pi - 2.0 * theta_s)
    y_z = ((4.0453 * T - 4.9710) * np.tan(chi) - 0.2155 * T + 2.4192) * 1000.0 / SKY_UNIT
    th = np.array([theta_s**3, theta_s**2, theta_s, 1.0])
    tt = np.array([T * T, T, 1.0])
    x_z, yc_z = tt @ _ZENITH_X @ th, tt @ _ZENITH_Y @ th
    f0 = _perez(np.array(1.0), np.array(theta_s), perez)  # F(0, theta_s) per row
    zenith = np.array([y_z, x_z, yc_z]) / f0
    partial = SkyModel(perez, zenith, to_sun, np.zeros(3))
    # The ground: Lambertian, lit by the sun and the sky's horizontal illuminance.
    rgb, e_sun = sun_radiometry(sun_direction, turbidity)
    e = _horizontal_sky_illuminance(partial) + np.asarray(rgb) * e_sun * max(to_sun[1], 0.0)
    ground = np.asarray(GROUND_ALBEDO) / np.pi * e
    return SkyModel(perez, zenith, to_sun, ground)


def _horizontal_sky_illuminance(model: SkyModel, n: int = 96) -> np.ndarray:
    """(3,) RGB irradiance of the sky on a horizontal plane (midpoint rule in (cos t, phi))."""
    mu = (np.arange(n) + 0.5) / n  # cos theta: d omega = d mu d phi
    phi = (np.arange(2 * n) + 0.5) / (2 * n) * 2.0 * np.pi
    mu, phi = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1.0 - mu * mu)
    d = np.stack([s * np.cos(phi), mu, s * np.sin(phi)], axis=-1)
    rgb = _xyY_to_rgb(_sky_xyY(model, d))
    return (rgb * mu[..., None]).sum(axis=(0, 1)) * (1.0 / n) * (2.0 * np.pi / (2 * n))


def sky_radiance(directions: np.ndarray, model: SkyModel | None = None) -> np.ndarray:
    """Linear RGB radiance (..., 3) float64 of the sky (above the horizon) or the ground
    (below) along unit `directions` (..., 3); sky.comp's formula."""
    model = sky_model() if model is None else model
    d = np.asarray(directions, dtype=np.float64)
    rgb = _xyY_to_rgb(_sky_xyY(model, d))
    return np.where(d[..., 1:2] >= 0.0, rgb, model.ground)


def sun_radiometry(sun_direction: np.ndarray | tuple = SUN_DIRECTION,
                   turbidity: float = TURBIDITY) -> tuple[tuple[float, float, float], float]:
    """The sky's sun as a directional light.

    Returns
    -------
    color : (r, g, b) linear, luminance 1 (the atmosphere's transmittance, reddening with
        the air mass).
    illuminance : on a plane facing the sun, in the sky's unit (lux / SKY_UNIT); 0 for a sun
        at or below the horizon. Light intensity = illuminance, colour = color.
    """
    to_sun, theta_s = _to_sun(np.asarray(sun_direction))
    if to_sun[1] <= 0.0:
        return (1.0, 1.0, 1.0), 0.0
    deg = np.degrees(theta_s)
    air_mass = 1.0 / (np.cos(theta_s) + 0.50572 * (96.07995 - deg) ** -1.6364)  # Kasten-Young
    lam = np.array([0.680, 0.550, 0.440])  # micrometres: R, G, B
    beta = 0.04608 * turbidity - 0.04586  # Angstrom turbidity from T (Preetham A.1)
    tau = np.exp(-air_mass * (0.008735 * lam**-4.08 + beta * lam**-1.3))
    lum = float(tau @ _LUMA)
    color = tau / lum
    return (float(color[0]), float(color[1]), float(color[2])), E0_LUX * lum / SKY_UNIT
