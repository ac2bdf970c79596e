"""The inner loop of the mixer: every playing voice added into one stereo block, compiled
(numba, without the GIL: the frame's threads run while the sound thread mixes).

A voice reads its clip at a fractional position that advances by its rate each output frame
(the clip's rate over the output's, times pitch and Doppler), linearly interpolated between
samples; a looping voice wraps, position and interpolation both, so a clip whose end meets its
start plays without a seam. Its gains move in a straight line from the last block's to this
block's targets over the block, so a sound that moves, fades or stops does not click."""

from __future__ import annotations

import numpy as np
from numba import njit


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
) -> None:
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
        for i in range(frames):
            if p >= n:
                if not looping:
                    live[v] = False
                    break
                p -= n * np.floor(p / n)
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
                    s = 0.5 * (sl + sr)
                    sl, sr = s, s
                out[i, 0] += sl * gl
                out[i, 1] += sr * gr
            p += r
        position[v] = p
        gain_from[v, 0] = gain_to[v, 0]
        gain_from[v, 1] = gain_to[v, 1]
