"""NumPy reference of the bloom passes (shaders/bloom_downsample.comp, bloom_upsample.comp,
ecs_engine/render/post/bloom.py): the same taps, weights, clamp-to-edge bilinear sampling at the
same half-texel positions, and a float16 store after every pass, so the GPU's result differs from
it only by float32 arithmetic and the sampler's filtering precision.

Images are (height, width, 4) arrays; every stored level is rounded to float16 as the GPU's
R16G16B16A16_SFLOAT images are."""

from __future__ import annotations

import numpy as np

from ecs_engine.render.post.bloom_settings import BloomSettings, blend_weights, chain_extents

LUMA = np.array([0.2126, 0.7152, 0.0722])
HALF_MAX = 65504.0


def sample(image: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Bilinear samples of `image` at normalised coordinates (u, v), clamp-to-edge addressing:
    what a LINEAR, CLAMP_TO_EDGE sampler returns at LOD 0."""
    h, w = image.shape[:2]
    x, y = u * w - 0.5, v * h - 0.5
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    x0, y0 = x0.astype(np.int64), y0.astype(np.int64)
    xs = np.clip(x0, 0, w - 1), np.clip(x0 + 1, 0, w - 1)
    ys = np.clip(y0, 0, h - 1), np.clip(y0 + 1, 0, h - 1)
    top = image[ys[0], xs[0]] * (1 - fx) + image[ys[0], xs[1]] * fx
    bottom = image[ys[1], xs[0]] * (1 - fx) + image[ys[1], xs[1]] * fx
    return top * (1 - fy) + bottom * fy


def _grid(width: int, height: int, source: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float]:
    """The output pixels' centres in normalised coordinates, and the source's texel size."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    uu, vv = np.meshgrid(u, v)
    return uu, vv, 1.0 / source.shape[1], 1.0 / source.shape[0]


def downsample(source: np.ndarray, size: tuple[int, int], first: bool, settings: BloomSettings) -> np.ndarray:
    """One 13-tap step into an image of `size` (width, height); Karis-weighted when `first`."""
    src = source[..., :3].astype(np.float64)
    uu, vv, tx, ty = _grid(*size, src)

    def tap(x: float, y: float) -> np.ndarray:
        return sample(src, uu + x * tx, vv + y * ty)

    a, b, c = tap(-2, -2), tap(0, -2), tap(2, -2)
    d, e, f = tap(-2, 0), tap(0, 0), tap(2, 0)
    g, h, i = tap(-2, 2), tap(0, 2), tap(2, 2)
    j, k, l_, m = tap(-1, -1), tap(1, -1), tap(-1, 1), tap(1, 1)
    boxes = [(a + b + d + e) / 4, (b + c + e + f) / 4, (d + e + g + h) / 4, (e + f + h + i) / 4, (j + k + l_ + m) / 4]
    weights = [np.full(a.shape[:2] + (1,), w) for w in (0.125, 0.125, 0.125, 0.125, 0.5)]
    if first:
        weights = [w / (1 + box @ LUMA)[..., None] for w, box in zip(weights, boxes)]
    color = sum(w * box for w, box in zip(weights, boxes)) / sum(weights)
    if first:
        color = np.clip(color, 0.0, HALF_MAX)
        if settings.threshold > 0:
            color = soft_threshold(color, settings)
    out = np.ones(color.shape[:2] + (4,))
    out[..., :3] = color
    return out.astype(np.float16)


def soft_threshold(color: np.ndarray, settings: BloomSettings) -> np.ndarray:
    t, knee = settings.threshold, settings.threshold * settings.threshold_softness
    brightness = color.max(axis=-1, keepdims=True)
    soft = np.clip(brightness - (t - knee), 0.0, 2 * knee) ** 2 * (0.25 / (knee + 1e-5))
    return color * np.maximum(brightness - t, soft) / np.maximum(brightness, 1e-5)


def upsample(source: np.ndarray, target: np.ndarray, src_weight: float, dst_weight: float) -> np.ndarray:
    """The 3x3 tent over `source` (the smaller level), blended into `target` in place."""
    src = source[..., :3].astype(np.float64)
    h, w = target.shape[:2]
    uu, vv, tx, ty = _grid(w, h, src)
    tent = np.zeros((h, w, 3))
    for y in (-1, 0, 1):
        for x in (-1, 0, 1):
            weight = (0.5 if x == 0 else 0.25) * (0.5 if y == 0 else 0.25)
            tent += sample(src, uu + x * tx, vv + y * ty) * weight
    out = target.astype(np.float64)
    out[..., :3] = out[..., :3] * dst_weight + tent * src_weight
    return out.astype(np.float16)


def bloom(hdr: np.ndarray, settings: BloomSettings) -> np.ndarray:
    """`hdr` (height, width, 4) after the whole bloom, as float16."""
    hdr = hdr.astype(np.float16)
    extents = chain_extents((hdr.shape[1], hdr.shape[0]), settings)
    levels = []
    for k, size in enumerate(extents):
        levels.append(downsample(hdr if k == 0 else levels[k - 1], size, k == 0, settings))
    weights = blend_weights(settings, len(extents))
    for k in range(len(extents) - 1, 0, -1):
        levels[k - 1] = upsample(levels[k], levels[k - 1], *weights[k])
    return upsample(levels[0], hdr, *weights[0])
