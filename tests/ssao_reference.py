"""A NumPy reference of the SSAO passes (shaders/ssao_gtao.comp, ssao_denoise.comp,
ssao_composite.comp), step for step in float32, vectorised over the pixels, and the analytic
test scene: a floor meeting a wall at a right angle, with a box on the floor and sky above."""

from __future__ import annotations

import math

import numpy as np

from ecs_engine.maths.camera import perspective
from ecs_engine.render.post.ssao import SsaoSettings

F = np.float32
BAYER = np.array([0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5])
HALF_PI = F(1.57079632679490)
PI = F(3.14159265358979)


def _dot(a, b):
    return (a * b).sum(axis=-1, dtype=F)


def _normalize(v):
    return v / np.sqrt(_dot(v, v))[..., None]


class Depth:
    """The depth image with the shaders' clamped fetch and view-space reconstruction."""

    def __init__(self, depth: np.ndarray, projection: np.ndarray) -> None:
        self.d = depth.astype(F)
        self.h, self.w = depth.shape
        self.inverse = np.linalg.inv(projection.astype(np.float64)).astype(F)

    def at(self, x, y):
        return self.d[np.clip(y, 0, self.h - 1), np.clip(x, 0, self.w - 1)]

    def position(self, x, y, d):
        ndc_x = (x.astype(F) + F(0.5)) / F(self.w) * F(2) - F(1)
        ndc_y = (y.astype(F) + F(0.5)) / F(self.h) * F(2) - F(1)
        clip = np.stack([ndc_x, ndc_y, d.astype(F), np.ones_like(ndc_x)], axis=-1)
        v = clip @ self.inverse.T
        with np.errstate(divide="ignore", invalid="ignore"):
            return v[..., :3] / v[..., 3:4]

    def tangent(self, x, y, c, ax, ay):
        xa, ya, xb, yb = x - ax, y - ay, x + ax, y + ay
        da, db = self.at(xa, ya), self.at(xb, yb)
        has_a = (xa >= 0) & (ya >= 0) & (da > 0)
        has_b = (xb < self.w) & (yb < self.h) & (db > 0)
        to_a = np.where(has_a[..., None], c - self.position(xa, ya, da), F(0))
        to_b = np.where(has_b[..., None], self.position(xb, yb, db) - c, F(0))
        pick_a = ~has_b | (has_a & (np.abs(to_a[..., 2]) < np.abs(to_b[..., 2])))
        return np.where(pick_a[..., None], to_a, to_b)


def gtao(depth: np.ndarray, projection: np.ndarray, settings: SsaoSettings) -> np.ndarray:
    """ssao_gtao.comp: (h, w, 4) float32 of visibility and view-space normal (unrounded)."""
    img = Depth(depth, projection)
    h, w = depth.shape
    y, x = np.mgrid[0:h, 0:w]
    d = img.at(x, y)
    drawn = d > 0
    c = img.position(x, y, d)
    c = np.where(drawn[..., None], c, F(1))  # the background is written as 1 below
    view_vec = _normalize(-c)
    normal = np.cross(img.tangent(x, y, c, 0, 1), img.tangent(x, y, c, 1, 0)).astype(F)
    length = np.sqrt(_dot(normal, normal))
    with np.errstate(divide="ignore", invalid="ignore"):
        normal = np.where((length > 0)[..., None], normal / length[..., None], view_vec)

    p = projection.astype(np.float64)
    lens_x, lens_y, lens_z = F(0.5 * p[0, 0] * w), F(p[3, 2]), F(p[3, 3])
    radius, falloff = F(settings.radius), F(settings.falloff)
    pixel_radius = radius * lens_x / (lens_y * c[..., 2] + lens_z)
    c = c * F(0.99999)
    falloff_range = falloff * radius
    falloff_mul = F(-1) / falloff_range
    falloff_add = radius * (F(1) - falloff) / falloff_range + F(1)
    min_s = F(1.3) / pixel_radius
    slice_noise = (BAYER[(y & 3) * 4 + (x & 3)].astype(F) + F(0.5)) / F(16)
    step_noise = (BAYER[(x & 3) * 4 + (y & 3)].astype(F) + F(0.5)) / F(16)

    def horizon(qx, qy, low):
        inside = (qx >= 0) & (qy >= 0) & (qx < w) & (qy < h)
        qx, qy = np.clip(qx, 0, w - 1), np.clip(qy, 0, h - 1)
        dq = np.where(inside, img.at(qx, qy), F(0))
        delta = img.position(qx, qy, np.where(dq > 0, dq, F(1))) - c
        dist = np.sqrt(_dot(delta, delta))
        weight = np.clip(dist * falloff_mul + falloff_add, 0, 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            cos = _dot(delta / dist[..., None], view_vec)
        return np.where(dq > 0, low + (cos - low) * weight, low)

    slices, steps = settings.slices, settings.steps
    visibility = np.zeros((h, w), F)
    for sl in range(slices):
        phi = (F(sl) + slice_noise) * (PI / F(slices))
        omega = np.stack([np.cos(phi), np.sin(phi)], axis=-1).astype(F)
        direction = np.stack([omega[..., 0], -omega[..., 1], np.zeros_like(phi)], axis=-1)
        ortho = direction - _dot(direction, view_vec)[..., None] * view_vec
        axis = _normalize(np.cross(ortho, view_vec).astype(F))
        projected = normal - axis * _dot(normal, axis)[..., None]
        projected_length = np.sqrt(_dot(projected, projected))
        cos_n = np.clip(_dot(projected, view_vec) / np.maximum(projected_length, F(1e-6)), 0, 1)
        n = np.sign(_dot(ortho, projected)) * np.arccos(cos_n)
        low0, low1 = np.cos(n + HALF_PI), np.cos(n - HALF_PI)
        cos0, cos1 = low0.copy(), low1.copy()
        for i in range(steps):
            jitter = step_noise + F(sl + i * steps) * F(0.618034)
            jitter = jitter - np.floor(jitter)
            s = (F(i) + jitter) / F(steps)
            s = s * s + min_s
            offset = np.floor((s * pixel_radius)[..., None] * omega + F(0.5)).astype(np.int64)
            ox, oy = offset[..., 0], offset[..., 1]
            cos0 = np.maximum(cos0, horizon(x + ox, y + oy, low0))
            cos1 = np.maximum(cos1, horizon(x - ox, y - oy, low1))
        projected_length = projected_length + (F(1) - projected_length) * F(0.05)
        h0 = -np.arccos(np.clip(cos1, -1, 1))
        h1 = np.arccos(np.clip(cos0, -1, 1))
        h0 = n + np.clip(h0 - n, -HALF_PI, HALF_PI)
        h1 = n + np.clip(h1 - n, -HALF_PI, HALF_PI)
        arc0 = (cos_n + F(2) * h0 * np.sin(n) - np.cos(F(2) * h0 - n)) / F(4)
        arc1 = (cos_n + F(2) * h1 * np.sin(n) - np.cos(F(2) * h1 - n)) / F(4)
        visibility += projected_length * (arc0 + arc1)
    visibility = np.clip(visibility / F(slices), 0.03, 1.0) ** F(settings.intensity)
    out = np.concatenate([visibility[..., None], normal], axis=-1).astype(F)
    out[~drawn] = (1, 0, 0, 0)
    return out


EDGE = np.array([0.5, 1.0, 1.0, 1.0, 0.5], F)
TOLERANCE = F(0.05)


def denoise(depth: np.ndarray, projection: np.ndarray, noisy: np.ndarray) -> np.ndarray:
    """ssao_denoise.comp over `noisy` as the GPU stores it (float16 rounded)."""
    img = Depth(depth, projection)
    h, w = depth.shape
    y, x = np.mgrid[0:h, 0:w]
    noisy = noisy.astype(np.float16).astype(F)
    d = img.at(x, y)
    c = img.position(x, y, np.where(d > 0, d, F(1)))
    tolerance = np.maximum(TOLERANCE * np.abs(c[..., 2]), F(1e-6))
    total = np.zeros((h, w), F)
    acc = np.zeros((h, w), F)
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            qx, qy = np.clip(x + dx, 0, w - 1), np.clip(y + dy, 0, h - 1)
            dq = img.at(qx, qy)
            off = np.abs(_dot(noisy[..., 1:], img.position(qx, qy, np.where(dq > 0, dq, F(1))) - c))
            weight = EDGE[dx + 2] * EDGE[dy + 2] * np.maximum(F(1) - off / tolerance, F(0))
            weight = np.where(dq > 0, weight, F(0))
            acc += weight * noisy[qy, qx, 0]
            total += weight
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(d > 0, acc / total, noisy[..., 0]).astype(F)


def ssao(depth: np.ndarray, projection: np.ndarray, settings: SsaoSettings) -> np.ndarray:
    """The "ao" image the passes make (before its R16 rounding)."""
    return denoise(depth, projection, gtao(depth, projection, settings))


# ------------------------------------------------------------------ the analytic scene
NEAR = 0.1
EYE_HEIGHT = 1.5
PITCH = math.radians(25.0)  # looking down
WALL_Z = -3.5  # world: the wall's face, facing +z
WALL_TOP = 1.8
BOX_CORNERS = ((0.5, 0.0, -2.4), (1.3, 0.7, -1.6))  # world min, max corner
SKY, FLOOR, WALL, BOX = 0, 1, 2, 3


def scene(w: int = 48, h: int = 32, fov_y: float = math.radians(60.0)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(depth (h, w) float32 reverse-Z with an infinite far plane, projection, surface labels):
    a camera at (0, EYE_HEIGHT, 0) looking down -z pitched down by PITCH over the floor y = 0
    (label FLOOR), which meets the wall z = WALL_Z (WALL, up to WALL_TOP; sky above it: depth 0,
    SKY), and a box on the floor (BOX)."""
    projection = perspective(fov_y, w / h, NEAR)
    inverse = np.linalg.inv(projection.astype(np.float64))
    y, x = np.mgrid[0:h, 0:w]
    ndc = np.stack([(x + 0.5) / w * 2 - 1, (y + 0.5) / h * 2 - 1, np.ones((h, w)), np.ones((h, w))], -1)
    v = ndc @ inverse.T
    ray = v[..., :3] / v[..., 3:4]  # view space, on the near plane: z = -NEAR
    cp, sp = math.cos(PITCH), math.sin(PITCH)
    to_world = np.array([[1, 0, 0], [0, cp, sp], [0, -sp, cp]])  # pitched down about x
    direction = ray @ to_world.T
    eye = np.array([0.0, EYE_HEIGHT, 0.0])
    t = np.full((h, w), np.inf)
    label = np.full((h, w), SKY)
    with np.errstate(divide="ignore", invalid="ignore"):
        floor = -eye[1] / direction[..., 1]
        floor_hit = eye + floor[..., None] * direction
        hit = (floor > 0) & (floor_hit[..., 2] > WALL_Z)
        t, label = np.where(hit, floor, t), np.where(hit, FLOOR, label)
        wall = (WALL_Z - eye[2]) / direction[..., 2]
        wall_hit = eye + wall[..., None] * direction
        hit = (wall > 0) & (wall_hit[..., 1] >= 0) & (wall_hit[..., 1] <= WALL_TOP) & (wall < t)
        t, label = np.where(hit, wall, t), np.where(hit, WALL, label)
        lo, hi = np.array(BOX_CORNERS[0]), np.array(BOX_CORNERS[1])
        t0 = (lo - eye) / direction
        t1 = (hi - eye) / direction
        near_t = np.minimum(t0, t1).max(axis=-1)
        far_t = np.maximum(t0, t1).min(axis=-1)
        hit = (near_t <= far_t) & (near_t > 0) & (near_t < t)
        t, label = np.where(hit, near_t, t), np.where(hit, BOX, label)
    distance = t * NEAR  # the ray's view-space depth: it reaches z = -NEAR at t = 1
    depth = np.where(np.isfinite(t), NEAR / distance, 0.0)
    return depth.astype(np.float32), projection, label
