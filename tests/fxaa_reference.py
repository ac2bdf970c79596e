"""FXAA 3.11 PC quality, preset 39, in NumPy (float64), pixel by pixel: the same steps as
shaders/fxaa.frag (see ecs_engine/render/post/fxaa.py), in texel units instead of normalised
coordinates (the shader's distances enter only as ratios). Texel reads clamp to the edge; the
search and the final read are bilinear with clamp-to-edge addressing, as the sampler's.

Clean synthetic edges make exact ties in FXAA's comparisons: where a search sample straddles a
rectangle's corner it averages three texels of one colour and one of the other, which is exactly
a quarter of the gradient from the pair's mean, the threshold itself; float rounding decides
such a comparison on a GPU, differently on different ones. `fxaa_outcomes` therefore follows
both ways of every comparison within TIE of equality and returns each outcome the algorithm
allows; `fxaa` is the one without any flipped.
"""

from __future__ import annotations

import numpy as np

STEPS = (1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 4.0, 8.0)
WEIGHTS = np.array([0.299, 0.587, 0.114])
TIE = 1e-4  # luma difference counted as equality (8-bit steps are 0.004 apart)


class Decisions:
    """The comparisons of one pixel's run; the near-ties among them numbered in order, those in
    `flips` taken the other way."""

    def __init__(self, flips=frozenset(), tie=TIE):
        self.flips, self.ties, self.tie = flips, 0, tie

    def ge(self, a, b):
        """a >= b"""
        if abs(a - b) > self.tie:
            return a >= b
        self.ties += 1
        return (a >= b) != (self.ties - 1 in self.flips)

    def lt(self, a, b):
        return not self.ge(a, b)


def srgb_to_linear(c):
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c):
    c = np.clip(np.asarray(c, np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


def fxaa(image, subpix=0.75, edge_threshold=0.166, edge_threshold_min=0.0833, linear=False):
    """`image`: (h, w, 4) colour as the shader samples it (linear for an _SRGB source, then
    `linear=True`); the anti-aliased image, same shape."""
    return fxaa_outcomes(image, subpix, edge_threshold, edge_threshold_min, linear, ties=False)[0]


def fxaa_outcomes(
    image, subpix=0.75, edge_threshold=0.166, edge_threshold_min=0.0833, linear=False, ties=True, tie=TIE
):
    """(the image without flipped ties, {(y, x): [every outcome the pixel's ties allow]} for the
    pixels that have ties); with `ties` False, the image only (and an empty dict). `tie`: how
    near equality a comparison may go either way (TIE for exact ties; wider where the GPU's
    inputs are known only to a coarser step than float64's, such as an 8-bit sRGB image it
    decodes with its own precision)."""
    img = np.asarray(image, np.float64)
    h, w = img.shape[:2]
    luma_img = img[..., :3] @ WEIGHTS
    if linear:
        luma_img = np.sqrt(luma_img)

    def luma_of(rgb):
        y = float(np.dot(rgb, WEIGHTS))
        return float(np.sqrt(y)) if linear else y

    def texel_luma(x, y):
        return float(luma_img[min(max(y, 0), h - 1), min(max(x, 0), w - 1)])

    def bilinear(px, py):
        """The colour at (px, py) in texel units (centres at i + 0.5)."""
        fx, fy = px - 0.5, py - 0.5
        x0, y0 = int(np.floor(fx)), int(np.floor(fy))
        ax, ay = fx - x0, fy - y0
        xs = [min(max(x0, 0), w - 1), min(max(x0 + 1, 0), w - 1)]
        ys = [min(max(y0, 0), h - 1), min(max(y0 + 1, 0), h - 1)]
        top = img[ys[0], xs[0]] * (1 - ax) + img[ys[0], xs[1]] * ax
        bottom = img[ys[1], xs[0]] * (1 - ax) + img[ys[1], xs[1]] * ax
        return top * (1 - ay) + bottom * ay

    args = (img, texel_luma, bilinear, luma_of, subpix, edge_threshold, edge_threshold_min)
    out = img.copy()
    tied = {}
    for y in range(h):
        for x in range(w):
            d = Decisions(tie=tie)
            out[y, x] = _pixel(x, y, *args, d)
            if ties and d.ties:
                tied[(y, x)] = _every_outcome(x, y, args, frozenset(), [], tie)
    return out, tied


def _every_outcome(x, y, args, flips, outcomes, tie=TIE):
    """Runs with `flips`, then with each further tie (after the last flipped) flipped too."""
    d = Decisions(flips, tie)
    outcomes.append(_pixel(x, y, *args, d))
    for i in range(max(flips, default=-1) + 1, min(d.ties, 8)):
        _every_outcome(x, y, args, flips | {i}, outcomes, tie)
    return outcomes


def _pixel(x, y, img, L, bilinear, luma_of, subpix, edge_threshold, edge_threshold_min, d):
    m, n, s, e, wl = L(x, y), L(x, y - 1), L(x, y + 1), L(x + 1, y), L(x - 1, y)
    range_max = max(m, n, s, e, wl)
    range_ = range_max - min(m, n, s, e, wl)
    if d.lt(range_, max(edge_threshold_min, range_max * edge_threshold)):
        return img[y, x]
    nw, ne, sw, se = L(x - 1, y - 1), L(x + 1, y - 1), L(x - 1, y + 1), L(x + 1, y + 1)

    subpix_a = (n + s + wl + e) * 2.0 + nw + sw + ne + se
    c = min(max(abs(subpix_a / 12.0 - m) / range_, 0.0), 1.0)
    f = (-2.0 * c + 3.0) * c * c
    subpix_h = f * f * subpix

    edge_horz = abs(-2 * wl + nw + sw) + abs(-2 * m + n + s) * 2 + abs(-2 * e + ne + se)
    edge_vert = abs(-2 * s + sw + se) + abs(-2 * m + wl + e) * 2 + abs(-2 * n + nw + ne)
    horz = d.ge(edge_horz, edge_vert)
    if not horz:
        n, s = wl, e
    pair_n = d.ge(abs(n - m), abs(s - m))
    gradient = max(abs(n - m), abs(s - m))
    sign = -1.0 if pair_n else 1.0  # towards the paired neighbour, across the edge
    luma_nn = (n if pair_n else s) + m
    gradient_scaled = gradient * 0.25
    m_below = d.lt(m - luma_nn * 0.5, 0.0)

    # positions in texel units; along = the edge's axis, across = the other
    cx, cy = x + 0.5, y + 0.5
    along = np.array([1.0, 0.0]) if horz else np.array([0.0, 1.0])
    across = np.array([0.0, 1.0]) if horz else np.array([1.0, 0.0])
    pos_b = np.array([cx, cy]) + across * sign * 0.5

    def end_luma(p):
        return luma_of(bilinear(p[0], p[1])[:3]) - luma_nn * 0.5

    pos_n = pos_b - along * STEPS[0]
    pos_p = pos_b + along * STEPS[0]
    end_n, end_p = end_luma(pos_n), end_luma(pos_p)
    done_n, done_p = d.ge(abs(end_n), gradient_scaled), d.ge(abs(end_p), gradient_scaled)
    if not done_n:
        pos_n = pos_n - along * STEPS[1]
    if not done_p:
        pos_p = pos_p + along * STEPS[1]
    for step in STEPS[2:]:
        if done_n and done_p:
            break
        if not done_n:  # (the shader tests a finished side again: the same values, the same answer)
            end_n = end_luma(pos_n)
            done_n = d.ge(abs(end_n), gradient_scaled)
        if not done_p:
            end_p = end_luma(pos_p)
            done_p = d.ge(abs(end_p), gradient_scaled)
        if not done_n:
            pos_n = pos_n - along * step
        if not done_p:
            pos_p = pos_p + along * step

    k = 0 if horz else 1
    dst_n = (cx, cy)[k] - pos_n[k]
    dst_p = pos_p[k] - (cx, cy)[k]
    nearer_n = d.lt(dst_n, dst_p)
    good = (d.lt(end_n, 0.0) != m_below) if nearer_n else (d.lt(end_p, 0.0) != m_below)
    pixel_offset = 0.5 - min(dst_n, dst_p) / (dst_n + dst_p)
    offset = max(pixel_offset if good else 0.0, subpix_h)
    final = np.array([cx, cy]) + across * sign * offset
    rgb = bilinear(final[0], final[1])[:3]
    return np.array([*rgb, img[y, x, 3]])


def outcome_errors(gpu, reference, to_bytes):
    """Per pixel, the largest channel error in 1/255 of `gpu` (bytes) against `reference` (as
    fxaa_outcomes gives it); for a pixel with exact ties, against the nearest outcome they allow."""
    want, tied = reference
    err = np.abs(gpu.astype(np.float64) - to_bytes(want)).max(-1)
    for (y, x), outcomes in tied.items():
        err[y, x] = min(np.abs(gpu[y, x].astype(np.float64) - to_bytes(o)).max() for o in outcomes)
    return err
