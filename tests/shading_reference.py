"""An independent NumPy evaluation of the shading models, written from their published formulas in
float64 (not from the shader): ray-cast a camera's pixels onto an analytic plane or sphere and
shade each hit. tests/test_shading_models.py compares it with what the GPU draws.

Conventions (components/light.py): a light delivers E = I * window(d) / d^2 (point, spot; the
window is (1 - (d/r)^4)^2 clamped, 1 when r = 0; a spot's cone factor is KHR_lights_punctual's)
or E = illuminance (directional); radiance = ambient * base + sum E (n.wi) pi f(wi, v) + emissive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

PI = np.pi


def srgb8(linear: np.ndarray) -> np.ndarray:
    """Linear [0, 1] to 8-bit sRGB, rounded as the R8G8B8A8_SRGB store does."""
    c = np.clip(linear, 0.0, 1.0)
    encoded = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.round(encoded * 255.0)


@dataclass
class Light:
    kind: str  # point, spot, directional
    color: tuple[float, float, float]
    intensity: float  # directional: illuminance
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    direction: tuple[float, float, float] = (0.0, 0.0, -1.0)  # where it shines
    radius: float = 0.0
    inner: float = 0.0
    outer: float = np.pi / 4


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def irradiance(light: Light, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(E, unit direction to the light) at points p (..., 3)."""
    if light.kind == "directional":
        d = -_unit(np.asarray(light.direction, float))
        return np.full(p.shape[:-1], light.intensity), np.broadcast_to(d, p.shape)
    to_light = np.asarray(light.position, float) - p
    d2 = (to_light**2).sum(-1)
    window = np.ones_like(d2)
    if light.radius > 0:
        window = np.clip(1 - (d2 / light.radius**2) ** 2, 0, 1) ** 2
    wi = to_light / np.sqrt(d2)[..., None]
    e = light.intensity * window / d2
    if light.kind == "spot":
        cos_angle = (-wi * _unit(np.asarray(light.direction, float))).sum(-1)
        cos_outer, cos_inner = np.cos(light.outer), np.cos(light.inner)
        e = e * np.clip((cos_angle - cos_outer) / (cos_inner - cos_outer), 0, 1) ** 2
    return e, wi


def brdf_pi(model: str, m: dict, n: np.ndarray, wi: np.ndarray, v: np.ndarray) -> np.ndarray:
    """pi * f(wi, v) (..., 3) for unit vectors (..., 3), where n.wi > 0."""
    base = np.asarray(m["base_color"][:3], float)
    nl = (n * wi).sum(-1)[..., None]
    nv = np.clip((n * v).sum(-1), 0, 1)[..., None]
    if model == "lambert":
        return np.broadcast_to(base, n.shape)
    if model == "oren_nayar":
        # Oren & Nayar 1994, qualitative model: A + B max(0, cos(phi_i - phi_r)) sin(alpha) tan(beta)
        sigma2 = m["roughness"] ** 2
        a = 1 - 0.5 * sigma2 / (sigma2 + 0.33)
        b = 0.45 * sigma2 / (sigma2 + 0.09)
        theta_i, theta_r = np.arccos(np.clip(nl, -1, 1)), np.arccos(nv)
        alpha, beta = np.maximum(theta_i, theta_r), np.minimum(theta_i, theta_r)
        li, vi = wi - n * nl, v - n * nv  # projections onto the tangent plane
        norms = np.linalg.norm(li, axis=-1, keepdims=True) * np.linalg.norm(vi, axis=-1, keepdims=True)
        cos_phi = np.where(norms > 1e-12, (li * vi).sum(-1, keepdims=True) / np.maximum(norms, 1e-300), 0.0)
        return base * (a + b * np.maximum(cos_phi, 0) * np.sin(alpha) * np.tan(beta))
    if model == "phong":
        e = m["shininess"]
        r = 2 * nl * n - wi
        rv = np.clip((r * v).sum(-1), 0, None)[..., None]
        return base + m["specular"] * (e + 2) / (2 * PI) * rv**e * PI
    if model == "blinn_phong":
        e = m["shininess"]
        h = _unit(wi + v)
        nh = np.clip((n * h).sum(-1), 0, None)[..., None]
        return base + m["specular"] * (e + 8) / (8 * PI) * nh**e * PI
    if model == "cook_torrance":
        # glTF 2.0 appendix B's specular: GGX D, height-correlated Smith V, Schlick F; alpha = roughness^2
        metallic = m["metallic"]
        alpha = max(m["roughness"], 0.045) ** 2
        h = _unit(wi + v)
        nh = np.clip((n * h).sum(-1), 0, None)[..., None]
        vh = np.clip((v * h).sum(-1), 0, None)[..., None]
        nv = np.maximum(nv, 1e-4)
        a2 = alpha**2
        d = a2 / (PI * (nh**2 * (a2 - 1) + 1) ** 2)
        vis = 0.5 / (nl * np.sqrt(nv**2 * (1 - a2) + a2) + nv * np.sqrt(nl**2 * (1 - a2) + a2))
        f0 = 0.04 * (1 - metallic) + base * metallic
        f = f0 + (1 - f0) * (1 - vh) ** 5
        # the diffuse lobe weighted by 1 - F(n.v), what the specular one leaves (not glTF's 1 - F(v.h))
        diffuse = (1 - (f0 + (1 - f0) * (1 - nv) ** 5)) * (1 - metallic) * base / PI
        return PI * (diffuse + f * d * vis)
    raise ValueError(model)


def shade(
    model: str, m: dict, p: np.ndarray, n: np.ndarray, eye: np.ndarray, lights: list[Light], ambient
) -> np.ndarray:
    """Linear radiance (..., 3) at points p with unit normals n seen from eye."""
    base = np.asarray(m["base_color"][:3], float)
    if model == "unlit":
        return np.broadcast_to(base + np.asarray(m["emissive"]), p.shape).copy()
    v = _unit(eye - p)
    color = np.broadcast_to(np.asarray(ambient[:3]) * ambient[3] * base, p.shape).copy()
    for light in lights:
        e, wi = irradiance(light, p)
        nl = (n * wi).sum(-1)
        lit = (nl > 0) & (e > 0)
        term = np.asarray(light.color) * (e * np.maximum(nl, 0))[..., None] * brdf_pi(model, m, n, wi, v)
        color += np.where(lit[..., None], term, 0.0)
    return color + np.asarray(m["emissive"])


def pixel_rays(projection: np.ndarray, rotation: np.ndarray, eye: np.ndarray, width: int, height: int):
    """Unit world-space ray directions (h, w, 3) through pixel centres (Vulkan: y down)."""
    x = (np.arange(width) + 0.5) / width * 2 - 1
    y = (np.arange(height) + 0.5) / height * 2 - 1
    ndc = np.stack(np.broadcast_arrays(x[None, :], y[:, None], np.ones((height, width))), -1)
    inverse = np.linalg.inv(projection.astype(np.float64))
    clip = np.concatenate([ndc, np.ones((height, width, 1))], -1) @ inverse.T
    view_dir = clip[..., :3] / clip[..., 3:]
    return _unit(view_dir @ rotation[:3, :3].T.astype(np.float64))


def hit_plane(origin, rays, point, normal):
    t = ((np.asarray(point) - origin) @ normal) / (rays @ normal)
    return t, origin + rays * t[..., None]


def hit_sphere(origin, rays, center, radius):
    oc = origin - np.asarray(center)
    b = rays @ oc
    disc = b * b - (oc @ oc - radius * radius)
    t = -b - np.sqrt(np.maximum(disc, 0))
    return np.where(disc > 0, t, np.nan), origin + rays * t[..., None]


def lobe_integral(faces: np.ndarray, normals: np.ndarray, roughness: float) -> np.ndarray:
    """sum over texels l of L(l) D(h) (n.l) dw / the same without L, h = (n + l) / |n + l|: the
    prefilter's definition with n = v (the importance sampler's pdf of l is D(h) / 4)."""
    side = faces.shape[1]
    from ecs_engine.render.lighting.environment_maps import _texel_solid_angles, cube_directions

    light = cube_directions(side).reshape(-1, 3)
    solid_angle = np.tile(_texel_solid_angles(side).ravel(), 6)
    a2 = roughness**4
    h = normals[:, None, :] + light[None]
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    nh = np.einsum("ijk,ik->ij", h, normals)
    nl = normals @ light.T
    d = a2 / (math.pi * (nh * nh * (a2 - 1.0) + 1.0) ** 2)
    weight = np.where(nl > 0.0, d * nl * solid_angle[None], 0.0)
    return (weight @ faces.reshape(-1, 3)) / weight.sum(axis=1, keepdims=True)
