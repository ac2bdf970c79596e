"""Radiance .hdr files (RGBE, flat or new-style run-length scanlines, "-Y h +X w"), read as
linear float32 RGB (an EXPOSURE line is ignored, as most readers do): the environment maps'
one reader of their own, apart from environment_maps.py's cube maths. Every bad file is one
UsageError naming it; the size is checked from the header before the pixels are decoded."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from ...errors import UsageError
from ...user_files import IMAGE, UserFileError, read_user_file

#: The most texels an environment's source may have: an 8192 x 4096 equirectangular map, or six
#: faces of up to 2364 x 2364 (files and arrays, in code or in a scene file). Checked from an
#: image file's header before its pixels are decoded; about 400 MiB as float32 RGB.
MAX_SOURCE_TEXELS = 1 << 25
_RESOLUTION = re.compile(rb"([-+])([XY]) +(\d+) +([-+])([XY]) +(\d+)")
_HEADER_LIMIT = 1 << 16  # bytes: a Radiance header longer than this is not one


def _hdr_error(path: Path, why: str) -> UsageError:
    return UsageError(f"environment map {path}: {why}")


def read_rgbe(path: str | os.PathLike[str], max_texels: int = MAX_SOURCE_TEXELS) -> np.ndarray:
    """(H, W, 3) float32 linear radiance of a Radiance .hdr file: flat or new-style run-length
    scanlines, "-Y h +X w" orientation (rows top to bottom, columns left to right). Anything else,
    a missing file or a broken or truncated one, or one of more than `max_texels` (checked before
    the pixels are decoded), is a UsageError naming the file."""
    file = Path(path)
    try:
        data = read_user_file(file, IMAGE)
    except FileNotFoundError:
        raise _hdr_error(file, "no such file") from None
    except UserFileError as exc:
        raise _hdr_error(file, exc.why) from None
    except OSError as exc:
        raise _hdr_error(file, f"cannot be read ({exc.strerror or exc})") from None
    if not data.startswith(b"#?"):
        raise _hdr_error(file, "not a Radiance .hdr file (it does not start with '#?')")
    end = data.find(b"\n\n", 0, _HEADER_LIMIT)
    if end < 0:
        raise _hdr_error(file, "broken .hdr header (no blank line ends it)")
    for line in data[:end].split(b"\n")[1:]:
        if line.startswith(b"FORMAT=") and line.strip() != b"FORMAT=32-bit_rle_rgbe":
            raise _hdr_error(file, f"unsupported .hdr pixel format {line[7:].decode('latin-1').strip()!r}")
    line_end = data.find(b"\n", end + 2)
    if line_end < 0:
        raise _hdr_error(file, "truncated .hdr file (no resolution line)")
    resolution = data[end + 2 : line_end].strip()
    match = _RESOLUTION.fullmatch(resolution)
    if match is None:
        raise _hdr_error(file, f"broken .hdr resolution line {resolution.decode('latin-1')!r}")
    if (match[1], match[2], match[4], match[5]) != (b"-", b"Y", b"+", b"X"):
        raise _hdr_error(
            file, f"unsupported .hdr orientation {resolution.decode('latin-1')!r} (only '-Y h +X w' is read)"
        )
    h, w = int(match[3]), int(match[6])
    if h < 1 or w < 1:
        raise _hdr_error(file, f"empty .hdr image ({w} x {h})")
    if h * w > max_texels:
        raise _hdr_error(file, f"{w} x {h} is more than the {max_texels:,} texels an environment map may have")
    rgbe = _rgbe_scanlines(data, line_end + 1, h, w, file)
    exponent = rgbe[..., 3:4].astype(np.int32)
    scale = np.where(exponent > 0, np.ldexp(1.0, exponent - 136), 0.0)  # Radiance's colr_color
    return ((rgbe[..., :3] + 0.5) * scale).astype(np.float32)


def _rgbe_scanlines(data: bytes, pos: int, h: int, w: int, file: Path) -> np.ndarray:
    """(h, w, 4) uint8 RGBE pixels from `pos` on: each scanline flat, or run-length encoded (it
    starts 2, 2, then the width; each channel in turn as runs: a count above 128 repeats the next
    byte count - 128 times, a count up to 128 copies that many bytes)."""
    out = np.empty((h, w, 4), dtype=np.uint8)
    size = len(data)
    for row in range(h):
        rle = 8 <= w < 0x8000 and pos + 4 <= size and data[pos] == 2 and data[pos + 1] == 2 and data[pos + 2] < 128
        if not rle:
            if pos + 4 * w > size:
                raise _hdr_error(file, f"truncated .hdr file (scanline {row} of {h} is incomplete)")
            out[row] = np.frombuffer(data, np.uint8, 4 * w, pos).reshape(w, 4)
            pos += 4 * w
            continue
        if (data[pos + 2] << 8 | data[pos + 3]) != w:
            raise _hdr_error(file, f"broken .hdr scanline {row}: its length is not the image width {w}")
        pos += 4
        for channel in range(4):
            line = bytearray()
            while len(line) < w:
                if pos >= size:
                    raise _hdr_error(file, f"truncated .hdr file (scanline {row} of {h} is incomplete)")
                count = data[pos]
                if count > 128:
                    if pos + 1 >= size:
                        raise _hdr_error(file, f"truncated .hdr file (scanline {row} of {h} is incomplete)")
                    line += data[pos + 1 : pos + 2] * (count - 128)
                    pos += 2
                else:
                    if count == 0:
                        raise _hdr_error(file, f"broken .hdr scanline {row}: a run of length 0")
                    if pos + 1 + count > size:
                        raise _hdr_error(file, f"truncated .hdr file (scanline {row} of {h} is incomplete)")
                    line += data[pos + 1 : pos + 1 + count]
                    pos += 1 + count
            if len(line) != w:
                raise _hdr_error(file, f"broken .hdr scanline {row}: its runs overrun the image width {w}")
            out[row, :, channel] = np.frombuffer(bytes(line), np.uint8)
    return out
