"""The inner loop of the mixer: every playing voice added into one stereo block, compiled
(numba, without the GIL: the frame's threads run while the sound thread mixes).

A voice reads its clip at a fractional position that advances by its rate each output frame
(the clip's rate over the output's, times pitch and Doppler), linearly interpolated between
samples; a looping voice wraps, position and interpolation both, so a clip whose end meets its
start plays without a seam. Its gains move in a straight line from the last block's to this
block's targets over the block, so a sound that moves, fades or stops does not click.

Most output frames read two samples inside the clip: those run in a loop without the end's
checks (`_run_mono`, `_run_stereo`), as many as fit before the last sample; the frames around
the end (wrapping or running out) take the careful path, one at a time."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(nogil=True, cache=True, inline="always")
def _run_mono(out, bank, base, p, r, gl, gr, dl, dr, i, count):  # pragma: no cover (compiled)
    for j in range(i, i + count):
        k = int(p)
        f = p - k
        a = bank[base + k]
        s = a + f * (bank[base + k + 1] - a)
        gl += dl
        gr += dr
        out[j, 0] += s * gl
        out[j, 1] += s * gr
        p += r
    return p, gl, gr


@njit(nogil=True, cache=True, inline="always")
def _run_stereo(out, bank, base, p, r, gl, gr, dl, dr, i, count, mono):  # pragma: no cover (compiled)
    for j in range(i, i + count):
        k = int(p)
        f = p - k
        al, ar = bank[base + 2 * k], bank[base + 2 * k + 1]
        sl = al + f * (bank[base + 2 * k + 2] - al)
        sr = ar + f * (bank[base + 2 * k + 3] - ar)
        if mono:
            sl = sr = 0.5 * (sl + sr)
        gl += dl
        gr += dr
        out[j, 0] += sl * gl
        out[j, 1] += sr * gr
        p += r
    return p, gl, gr


@njit(nogil=True, cache=True)
def mix_block(
    out: np.ndarray,  # (frames, 2) float32, added into
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
    frames = out.shape[0]
    for v in range(clip.shape[0]):
        if not live[v]:
            continue
        c = clip[v]
        base, n, ch = offset[c], length[c], channels[c]
        p, r = position[v], rate[v]
        gl, gr = np.float64(gain_from[v, 0]), np.float64(gain_from[v, 1])
        dl = (np.float64(gain_to[v, 0]) - gl) / frames
        dr = (np.float64(gain_to[v, 1]) - gr) / frames
        looping = loop[v]
        i = 0
        while i < frames:
            if p >= n:
                if not looping:
                    live[v] = False
                    break
                p -= n * np.floor(p / n)
            # frames whose both samples lie inside the clip: all but the last before index n - 1
            # (one kept back, so that rounding in the sum never reads past it)
            inside = int(np.ceil((n - 1 - p) / r)) - 1 if p < n - 1 else 0
            count = min(frames - i, inside)
            if count > 0:
                if ch == 1:
                    p, gl, gr = _run_mono(out, bank, base, p, r, gl, gr, dl, dr, i, count)
                else:
                    p, gl, gr = _run_stereo(out, bank, base, p, r, gl, gr, dl, dr, i, count, mono[v])
                i += count
                continue
            # one frame at the end: its second sample is the clip's first (a loop) or silence
            k = int(p)
            f = p - k
            k1 = k + 1
            if k1 >= n:
                k1 = 0 if looping else -1
            gl += dl
            gr += dr
            if ch == 1:
                a = bank[base + k]
                b = bank[base + k1] if k1 >= 0 else np.float32(0.0)
                s = a + f * (b - a)
                out[i, 0] += s * gl
                out[i, 1] += s * gr
            else:
                al, ar = bank[base + 2 * k], bank[base + 2 * k + 1]
                bl = bank[base + 2 * k1] if k1 >= 0 else np.float32(0.0)
                br = bank[base + 2 * k1 + 1] if k1 >= 0 else np.float32(0.0)
                sl = al + f * (bl - al)
                sr = ar + f * (br - ar)
                if mono[v]:
                    sl = sr = 0.5 * (sl + sr)
                out[i, 0] += sl * gl
                out[i, 1] += sr * gr
            p += r
            i += 1
        position[v] = p
        gain_from[v, 0] = gain_to[v, 0]
        gain_from[v, 1] = gain_to[v, 1]
