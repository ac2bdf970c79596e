"""The inner loop of the mixer: every playing voice added into one stereo block, compiled
(numba, without the GIL: the frame's threads run while the sound thread mixes).

A voice reads its clip at a fractional position that advances by its rate each output frame
(the clip's rate over the output's, times pitch and Doppler), linearly interpolated between
samples; a looping voice wraps, position and interpolation both, so a clip whose end meets its
start plays without a seam. Its gains move in a straight line from the last block's to this
block's targets over the block, so a sound that moves, fades or stops does not click.

Most output frames read two samples inside the clip. Those are mixed in three passes over the
run: where each frame reads (index and fraction, in float32 from the whole sample below the
position: 16 lanes to a vector instruction; a block spans a few thousand samples at most, where
float32 still places a read within a thousandth of a sample, and the position itself goes on in
float64), the interpolated samples (the reads), and the samples times each channel's gain added
into the block (vector instructions again). One loop doing all three ran about four times
slower: the reads' addresses come from the positions, which kept the compiler from vectorising
any of it. A block wholly inside the clip (nearly every voice's) is one such run; the frames
around a clip's end (wrapping, or running out) take the careful path, one at a time."""

from __future__ import annotations

import numpy as np
from numba import float32, njit, uint32, uint64


@njit(nogil=True, cache=True)
def _at_the_end(out, bank, base, n, ch, mono, looping, p, r, gl, gr, i):  # pragma: no cover (compiled)
    """Output frame `i` read at `p` where its second sample is past the clip's last: the clip's
    first (a loop) or silence. Its own function: kept in the kernel's loop, it slowed the runs
    inside the clip by half (measured), though few frames take it."""
    k = int(p)
    f = p - k
    k1 = k + 1
    if k1 >= n:
        k1 = 0 if looping else -1
    if ch == 1:
        a = bank[base + k]
        b = bank[base + k1] if k1 >= 0 else np.float32(0.0)
        sl = sr = a + f * (b - a)
    else:
        al, ar = bank[base + 2 * k], bank[base + 2 * k + 1]
        bl = bank[base + 2 * k1] if k1 >= 0 else np.float32(0.0)
        br = bank[base + 2 * k1 + 1] if k1 >= 0 else np.float32(0.0)
        sl = al + f * (bl - al)
        sr = ar + f * (br - ar)
        if mono:
            sl = sr = 0.5 * (sl + sr)
    out[0, i] += sl * gl
    out[1, i] += sr * gr
    return p + r


@njit(nogil=True, cache=True)
def mix_block(
    out: np.ndarray,  # (2, frames) float32, left then right, added into
    bank: np.ndarray,  # float32: every clip's samples, interleaved, one after another
    offset: np.ndarray,  # int64 per clip: its first sample in `bank`
    length: np.ndarray,  # int64 per clip: its frames
    channels: np.ndarray,  # int64 per clip: 1 or 2
    clip: np.ndarray,  # int64 per voice
    position: np.ndarray,  # float64 per voice: frames into its clip (advanced here)
    rate: np.ndarray,  # float64 per voice: clip frames per output frame
    gain_from: np.ndarray,  # (voices, 2) float32: the gains the last block ended on (set to `gain_to` here)
    gain_to: np.ndarray,  # (voices, 2) float32: this block's targets
    loop: np.ndarray,  # bool per voice
    live: np.ndarray,  # bool per voice: playing (cleared here when a clip that does not loop ends)
    mono: np.ndarray,  # bool per voice: a stereo clip heard as one point (spatial): its channels averaged
) -> None:  # pragma: no cover (compiled)
    frames = out.shape[1]
    at = np.empty(frames, np.uint32)
    frac, left, right = np.empty(frames, np.float32), np.empty(frames, np.float32), np.empty(frames, np.float32)
    for v in range(clip.shape[0]):
        if not live[v]:
            continue
        c = clip[v]
        base, n, ch = offset[c], length[c], channels[c]
        p, r = position[v], rate[v]
        g0l, g0r = np.float64(gain_from[v, 0]), np.float64(gain_from[v, 1])
        dl = (np.float64(gain_to[v, 0]) - g0l) / frames
        dr = (np.float64(gain_to[v, 1]) - g0r) / frames
        looping = loop[v]
        i = 0
        while i < frames:
            if p >= n:
                if not looping:
                    live[v] = False
                    break
                p -= n * np.floor(p / n)
            # frames whose both samples lie inside the clip: all but the last before index n - 1
            # (one kept back, so that rounding never reads past it)
            inside = int(np.ceil((n - 1 - p) / r)) - 1 if p < n - 1 else 0
            count = min(frames - i, inside)
            if count > 0:
                # the three passes (see the module), written out here: as functions of their own
                # they cost each voice about as much as 100 of its frames (measured)
                k0 = uint32(p)
                f0, step = float32(p - k0), float32(r)
                for j in range(count):  # where each frame reads
                    x = f0 + float32(j) * step
                    k = uint32(x)
                    at[j] = k + k0
                    frac[j] = x - float32(k)
                if ch == 1:  # the reads
                    for j in range(count):
                        k = uint64(base) + uint64(at[j])
                        a = bank[k]
                        left[j] = a + frac[j] * (bank[k + uint64(1)] - a)
                    heard = left
                else:
                    for j in range(count):
                        k = uint64(base) + uint64(2) * uint64(at[j])
                        al, ar = bank[k], bank[k + uint64(1)]
                        left[j] = al + frac[j] * (bank[k + uint64(2)] - al)
                        right[j] = ar + frac[j] * (bank[k + uint64(3)] - ar)
                    if mono[v]:
                        for j in range(count):
                            left[j] = right[j] = float32(0.5) * (left[j] + right[j])
                    heard = right
                a_l, a_r = float32(g0l + (i + 1) * dl), float32(g0r + (i + 1) * dr)
                d_l, d_r = float32(dl), float32(dr)
                out_left, out_right = out[0, i:], out[1, i:]
                for j in range(count):  # the gains, added into the block
                    out_left[j] += left[j] * (a_l + float32(j) * d_l)
                    out_right[j] += heard[j] * (a_r + float32(j) * d_r)
                p += count * r
                i += count
                continue
            # one frame at the end: its second sample is the clip's first (a loop) or silence
            p = _at_the_end(out, bank, base, n, ch, mono[v], looping, p, r, g0l + (i + 1) * dl, g0r + (i + 1) * dr, i)
            i += 1
        position[v] = p
        gain_from[v, 0] = gain_to[v, 0]
        gain_from[v, 1] = gain_to[v, 1]
