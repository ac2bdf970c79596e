"""Textures: images that materials name by handle, kept on the CPU until the renderer uploads them.

A `Textures` registry belongs to a world's `Materials` (`materials(world).textures`): `add` takes
pixels, `load` reads an image file. A file that is missing or cannot be decoded does not stop a
model from loading: `load` logs one warning naming the file and returns the fallback texture, a
magenta and black checkerboard that shows where it is used.

`color` says how the texels are encoded: sRGB for colours (base colour, emissive), linear for
data (normal maps, metallic-roughness, occlusion); the GPU decodes sRGB before filtering.

How the GPU holds them (render/assets/texture_pages.py): each texture is resized to a square power of two
between MIN_TEXTURE_SIZE and MAX_TEXTURE_SIZE, its size class, and becomes one layer of that
class's array image, with a full mip chain made here (`mip_chain`: box-filtered, in linear light
for sRGB textures).

Render targets (`Textures.render_target(name, width, height)`): textures whose texels a camera
draws each frame (the RenderTexture component names one: a security monitor, a minimap). A
material samples one by its handle, as any texture: `Material("screen", "unlit",
base_color_texture=textures.render_target("monitor", 320, 240))`; the camera with
`RenderTexture(name="monitor", width=320, height=240)` draws it; both refuse a side over
MAX_RENDER_TEXTURE_SIDE (components/camera.py: one limit, one message). On the CPU it is one
black texel (it has no pixels of its own: a saved scene keeps its name and size, scene_assets.py);
on the GPU it is a layer of the page of `size_class(width, height)`, sRGB, opaque black until a
frame draws into it (render/passes/render_texture.py copies the camera's image in and makes its
mips).
"""

from __future__ import annotations

import logging
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Final

import numpy as np

from ...components.camera import render_texture_size_error
from ...errors import UsageError
from ...user_files import IMAGE, UserFileError, open_user_file

__all__ = [
    "MAX_TEXTURE_PIXELS",
    "MAX_TEXTURE_SIZE",
    "MIN_TEXTURE_SIZE",
    "RenderTarget",
    "Texture",
    "Textures",
    "mip_chain",
    "size_class",
]

log = logging.getLogger("ecs_engine")

MIN_TEXTURE_SIZE: Final = 16
MAX_TEXTURE_SIZE: Final = 4096
#: the size classes, smallest first: 16, 32, ..., 4096
CLASS_SIZES: Final[tuple[int, ...]] = tuple(
    1 << k for k in range(int(math.log2(MIN_TEXTURE_SIZE)), int(math.log2(MAX_TEXTURE_SIZE)) + 1)
)
#: The most texels a texture may have (8192 x 8192, 256 MiB of RGBA8), from a file, a model or a
#: scene file: the GPU holds at most MAX_TEXTURE_SIZE a side, so more only costs memory, and an
#: image file's header is checked against it before its pixels are decoded.
MAX_TEXTURE_PIXELS: Final = 1 << 26
#: The longest side a texture may have (the largest maxImageDimension2D of common GPUs).
MAX_TEXTURE_SIDE: Final = 16384


@dataclass(frozen=True, eq=False)
class Texture:
    """RGBA8 pixels (height, width, 4), row 0 at the top (glTF's and Vulkan's origin)."""

    name: str
    pixels: np.ndarray
    color: bool = True  # sRGB-encoded colour; False: linear data
    source: str | None = None  # the image file it was read from (saved scenes name it); None: pixels only

    def __post_init__(self) -> None:
        pixels = np.asarray(self.pixels)
        if pixels.ndim == 2:
            pixels = np.repeat(pixels[:, :, None], 3, axis=2)
        if pixels.ndim != 3 or pixels.shape[2] not in (1, 2, 3, 4) or 0 in pixels.shape:
            raise ValueError(f"texture {self.name!r}: pixels must be (height, width, 1-4), got {pixels.shape}")
        too_large = texture_size_error(pixels.shape[1], pixels.shape[0])
        if too_large:
            raise ValueError(f"texture {self.name!r}: {too_large}")
        if pixels.dtype != np.uint8:
            if not np.issubdtype(pixels.dtype, np.floating) or not np.isfinite(pixels).all():
                raise ValueError(f"texture {self.name!r}: pixels must be uint8, or finite floats in [0, 1]")
            pixels = np.round(np.clip(pixels, 0.0, 1.0) * 255.0).astype(np.uint8)
        channels = pixels.shape[2]
        if channels < 4:  # grey, grey + alpha, RGB -> RGBA
            rgb = pixels[:, :, :1].repeat(3, axis=2) if channels <= 2 else pixels[:, :, :3]
            alpha = pixels[:, :, 1:2] if channels == 2 else np.full(pixels.shape[:2] + (1,), 255, np.uint8)
            pixels = np.concatenate([rgb, alpha], axis=2)
        pixels = np.ascontiguousarray(pixels)
        pixels.flags.writeable = False
        object.__setattr__(self, "pixels", pixels)

    @property
    def size(self) -> tuple[int, int]:
        """(width, height)"""
        return int(self.pixels.shape[1]), int(self.pixels.shape[0])


@dataclass(frozen=True)
class RenderTarget:
    """A texture a camera draws (Textures.render_target): its handle and the size asked for."""

    name: str
    handle: int
    width: int
    height: int

    @property
    def side(self) -> int:
        """The side of its square layer on the GPU (its size class's)."""
        return CLASS_SIZES[size_class(self.width, self.height)]


def _fallback_pixels() -> np.ndarray:
    cell = (np.indices((MIN_TEXTURE_SIZE, MIN_TEXTURE_SIZE)) // 4).sum(axis=0) % 2
    out = np.zeros((MIN_TEXTURE_SIZE, MIN_TEXTURE_SIZE, 4), np.uint8)
    out[..., 3] = 255
    out[cell == 0, 0] = 255
    out[cell == 0, 2] = 255
    return out


class Textures:
    """Textures by handle. Handles are never reused; `version` counts additions, `edits`
    replacements (hot reload: a file changed on disk)."""

    def __init__(self) -> None:
        self._textures: list[Texture] = []
        self._fallback: int | None = None
        self._by_file: dict[tuple[str, bool], int] = {}
        self._targets: dict[str, RenderTarget] = {}  # render targets by name
        self._target_handles: dict[int, RenderTarget] = {}  # and by handle
        self.version = 0
        self.edits = 0

    def add(self, texture: Texture) -> int:
        if not isinstance(texture, Texture):
            raise TypeError(f"Textures.add takes a Texture, got {type(texture).__name__}")
        self._textures.append(texture)
        self.version += 1
        return len(self._textures) - 1

    @property
    def fallback(self) -> int:
        """The checkerboard drawn where a texture could not be read (added on first use)."""
        if self._fallback is None:
            self._fallback = self.add(Texture("fallback", _fallback_pixels(), color=True))
        return self._fallback

    def load(self, path: str | os.PathLike[str], *, color: bool = True, named_by: str | None = None) -> int:
        """The texture in an image file (PNG, JPEG, ... what Pillow reads), loaded once per file
        and colour space. A missing or unreadable file (or a FIFO, a device, one over the size
        limits) logs one warning, naming the file and `named_by` (the file that named it), and
        gives the fallback."""
        file = Path(path)
        key = (str(file.resolve()) if file.exists() else str(file), color)
        found = self._by_file.get(key)
        if found is not None:
            return found
        try:
            pixels = read_image(file)
        except ImageError as exc:
            by = f" (named by {named_by})" if named_by else ""
            log.warning("%s%s: %s; drawn with the fallback texture", file, by, exc)
            handle = self.fallback
        else:
            handle = self.add(Texture(file.name, pixels, color, str(file.resolve())))
        self._by_file[key] = handle
        return handle

    def render_target(self, name: str, width: int, height: int) -> int:
        """The handle of the texture a camera with `RenderTexture(name, width, height)` draws,
        added on first use (opaque black until drawn); the same name gives the same handle. A
        name asked for again at another size is a UsageError (one name, one image)."""
        if not isinstance(name, str) or not name:
            raise UsageError(f"a render texture needs a name (a non-empty string), not {name!r}")
        refused = render_texture_size_error(name, width, height)  # the RenderTexture component's limit
        if refused:
            raise UsageError(refused)
        width, height = int(width), int(height)
        found = self._targets.get(name)
        if found is not None:
            if (found.width, found.height) != (width, height):
                raise UsageError(
                    f"render texture {name!r} is {found.width} x {found.height} pixels and was asked for again at "
                    f"{width} x {height}: one name is one image (give the other camera's RenderTexture another name)"
                )
            return found.handle
        black = np.zeros((1, 1, 4), np.uint8)
        black[..., 3] = 255
        handle = self.add(Texture(name, black, color=True))
        self._targets[name] = self._target_handles[handle] = RenderTarget(name, handle, width, height)
        return handle

    def render_target_handle(self, name: str) -> int | None:
        """The handle of render target `name`, or None when none has that name."""
        found = self._targets.get(name)
        return None if found is None else found.handle

    def render_target_of(self, handle: int) -> RenderTarget | None:
        """The render target with this handle, or None for a texture with pixels of its own."""
        return self._target_handles.get(int(handle))

    @property
    def render_targets(self) -> tuple[RenderTarget, ...]:
        """Every render target, in the order they were added."""
        return tuple(self._targets.values())

    def replace(self, handle: int, texture: Texture) -> None:
        """`texture` under `handle`, where another was: materials naming it draw the new one
        from the next frame (the GPU copy is made again). A render target's texels come from its
        camera: replacing one is a UsageError."""
        if not isinstance(texture, Texture):
            raise TypeError(f"Textures.replace takes a Texture, got {type(texture).__name__}")
        self[handle]  # a handle that exists
        target = self._target_handles.get(int(handle))
        if target is not None:
            raise UsageError(f"texture {handle} is render texture {target.name!r}, drawn by its camera: not replaced")
        self._textures[int(handle)] = texture
        self.edits += 1

    def __getitem__(self, handle: int) -> Texture:
        if not isinstance(handle, (int, np.integer)) or not 0 <= handle < len(self._textures):
            raise KeyError(f"no texture {handle!r}; there are {len(self._textures)}")
        return self._textures[int(handle)]

    def __len__(self) -> int:
        return len(self._textures)


class ImageError(Exception):
    """An image file that cannot be used as a texture (the message says why)."""


def texture_size_error(width: int, height: int, max_pixels: int = MAX_TEXTURE_PIXELS) -> str | None:
    """Why an image of this size is refused (None: it is not)."""
    if max(width, height) > MAX_TEXTURE_SIDE or width * height > max_pixels:
        limit = f"{MAX_TEXTURE_SIDE} a side and {max_pixels:,} pixels ({math.isqrt(max_pixels)} squared)"
        return f"{width} x {height} pixels is larger than an image may be (at most {limit})"
    return None


def read_image(file: Path, max_pixels: int = MAX_TEXTURE_PIXELS) -> np.ndarray:
    """RGBA8 pixels of an image file, or ImageError. Only a regular file is opened (user_files),
    and its size is checked from its header before its pixels are decoded."""
    import warnings

    from PIL import Image, UnidentifiedImageError

    try:
        with open_user_file(file, IMAGE) as raw, warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(raw) as image:  # reads the header only
                too_large = texture_size_error(image.width, image.height, max_pixels)
                if too_large:
                    raise ImageError(too_large)
                return np.asarray(image.convert("RGBA"))
    except FileNotFoundError:
        raise ImageError("no such file") from None
    except UserFileError as exc:
        raise ImageError(exc.why) from None
    except UnidentifiedImageError:
        raise ImageError("not an image Pillow can read") from None
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:  # Pillow's limit, met first
        claimed = re.search(r"\((\d+) pixels\)", str(exc))
        size = f"{int(claimed[1]):,} pixels" if claimed else "it"
        raise ImageError(f"{size} is larger than an image may be (at most {max_pixels:,} pixels)") from None
    except (OSError, ValueError, SyntaxError) as exc:  # truncated or corrupt data
        raise ImageError(f"cannot be decoded ({exc})") from None


def pixels_of(image: object) -> np.ndarray:
    """RGBA8 pixels of a PIL image (what trimesh hands over for glTF textures), its size checked
    before it is decoded."""
    convert = getattr(image, "convert", None)
    if convert is None:
        raise ImageError(f"not an image ({type(image).__name__})")
    size = getattr(image, "size", (0, 0))
    too_large = texture_size_error(int(size[0]), int(size[1]))
    if too_large:
        raise ImageError(too_large)
    return np.asarray(convert("RGBA"))


def size_class(width: int, height: int) -> int:
    """Index into CLASS_SIZES: the power of two nearest the larger side (in log scale), clamped."""
    side = max(width, height, 1)
    k = round(math.log2(side)) - int(math.log2(MIN_TEXTURE_SIZE))
    return min(max(k, 0), len(CLASS_SIZES) - 1)


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    c = np.clip(c, 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1 / 2.4) - 0.055)


def resized(pixels: np.ndarray, side: int) -> np.ndarray:
    """The image scaled to side x side (Lanczos; a no-op at that size already)."""
    if pixels.shape[0] == side and pixels.shape[1] == side:
        return pixels
    from PIL import Image

    return np.asarray(Image.fromarray(pixels, "RGBA").resize((side, side), Image.Resampling.LANCZOS))


def mip_chain(pixels: np.ndarray, color: bool) -> list[np.ndarray]:
    """Level 0 (square, power-of-two side) and each half-size level down to 1 x 1, each texel the
    mean of the 2 x 2 above it: in linear light for sRGB colour (averaging encoded values darkens),
    colour weighted by alpha so transparent texels do not bleed their colour; data (normal
    maps, metallic-roughness) plainly averaged."""
    side = pixels.shape[0]
    if pixels.shape[:2] != (side, side) or side & (side - 1):
        raise ValueError(f"mip_chain needs a square power-of-two image, got {pixels.shape[:2]}")
    values = pixels.astype(np.float64) / 255.0
    if color:
        values[..., :3] = srgb_to_linear(values[..., :3])
    levels = [pixels]
    while values.shape[0] > 1:
        h = values.shape[0] // 2
        quads = values.reshape(h, 2, h, 2, 4)
        alpha = quads[..., 3].mean(axis=(1, 3))
        rgb = quads[..., :3].mean(axis=(1, 3))
        if color:  # weighted by alpha; where all four are transparent, the plain mean
            weights = quads[..., 3:4]
            total = weights.sum(axis=(1, 3))
            weighted = (quads[..., :3] * weights).sum(axis=(1, 3)) / np.maximum(total, 1e-8)
            rgb = np.where(total > 1e-8, weighted, rgb)
        values = np.concatenate([rgb, alpha[..., None]], axis=2)
        encoded = values.copy()
        if color:
            encoded[..., :3] = linear_to_srgb(encoded[..., :3])
        levels.append(np.round(encoded * 255.0).astype(np.uint8))
    return levels
