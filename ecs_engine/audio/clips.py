"""Sound files decoded into clips: WAV, FLAC, MP3 and Ogg Vorbis through miniaudio, to float32 at
the mixer's rate, keeping mono as mono and anything wider as stereo. A file is read once; asking
for it again gives the same clip. Errors name the file and say what is wrong in one line."""

from __future__ import annotations

import array
import os
from pathlib import Path

import numpy as np

from ..errors import UsageError
from .library import load

FORMATS = "WAV, FLAC, MP3 or Ogg Vorbis"


def decode(path: str | os.PathLike[str], sample_rate: int) -> np.ndarray:
    """The file's samples, (frames, channels) float32 at `sample_rate`; UsageError in one line for
    a missing, unreadable, empty or undecodable file."""
    miniaudio = load()
    name = os.fspath(path)
    if not Path(name).is_file():
        raise UsageError(f"sound file {name}: no such file")
    try:
        info = miniaudio.get_file_info(name)
        channels = 1 if info.nchannels == 1 else 2
        sound = miniaudio.decode_file(name, miniaudio.SampleFormat.FLOAT32, channels, sample_rate)
    except (miniaudio.DecodeError, miniaudio.MiniaudioError) as error:
        raise UsageError(f"sound file {name}: not a {FORMATS} file miniaudio can decode ({error})") from None
    except OSError as error:
        raise UsageError(f"sound file {name}: cannot be read ({error.strerror or error})") from None
    samples = np.frombuffer(sound.samples, np.float32) if isinstance(sound.samples, array.array) else None
    if samples is None or samples.size == 0:
        raise UsageError(f"sound file {name}: it holds no samples")
    if not np.isfinite(samples).all():
        raise UsageError(f"sound file {name}: it holds samples that are not finite numbers")
    return samples.reshape(-1, channels).copy()


def checked_samples(samples: np.ndarray, name: str) -> np.ndarray:
    """Samples made by a game (a synthesised clip) as the mixer holds them: (frames, 1 or 2)
    float32, finite; UsageError otherwise."""
    data = np.asarray(samples, np.float32)
    if data.ndim == 1:
        data = data[:, None]
    if data.ndim != 2 or data.shape[1] not in (1, 2) or data.shape[0] == 0:
        raise UsageError(f"clip {name}: samples must be (frames,) or (frames, 1 or 2), got shape {np.shape(samples)}")
    if not np.isfinite(data).all():
        raise UsageError(f"clip {name}: its samples hold NaN or infinity")
    return np.ascontiguousarray(data)
