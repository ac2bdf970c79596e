"""Materials: shared assets that entities name by handle (`Mesh.material`), like meshes.

A world's materials live in its `Materials` resource (`materials(world)` makes it on first use);
handles 0-5 are the default palette, the six looks every scene had before materials, so scenes
that set `Mesh.material` to 0-5 look as they did. `Materials.add` returns a handle; `update`
changes a material in place and the renderer uploads the table again (the editor edits live).

Shading models (the `model` field), each a branch of one fragment shader that a pipeline
specialisation constant keeps only when some material uses it (see shaders/shading.glsl):

- `unlit`: the base colour, as is;
- `lambert`: ideal diffuse;
- `oren_nayar`: rough diffuse (Oren-Nayar's qualitative model, sigma = `roughness` radians);
- `phong`: Lambert plus normalised Phong, (s + 2) / (2 pi) (r.v)^s times `specular`;
- `blinn_phong`: Lambert plus normalised Blinn-Phong, (s + 8) / (8 pi) (n.h)^s times `specular`;
- `cook_torrance`: glTF's metallic-roughness BRDF: GGX, height-correlated Smith, Schlick Fresnel,
  with the diffuse lobe weighted by 1 - F(n.v) so that it reflects no more than it receives.

Colours are linear RGB (the render target's sRGB encoding happens on write).

Textures (glTF's set): `*_texture` fields hold handles into the same `Materials.textures`
registry. The base colour texture multiplies `base_color` (alpha too); metallic-roughness reads
roughness from G and metallic from B, multiplying `roughness` and `metallic`; the normal map is
tangent-space (+Y up the image, glTF's convention), its xy scaled by `normal_scale`; emissive
multiplies `emissive`; occlusion (R) darkens the ambient light by `occlusion_strength`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, fields, replace
from typing import Any, Final

import numpy as np

from ...ecs.world import World
from ..layouts import (
    ALPHA_BLEND,
    ALPHA_MASK,
    ALPHA_OPAQUE,
    FEATURE_ALPHA_MASK,
    FEATURE_BLEND,
    FEATURE_DOUBLE_SIDED,
    FEATURE_EMISSIVE,
    FEATURE_TEXTURES,
    MATERIAL,
    MODEL_BLINN_PHONG,
    MODEL_COOK_TORRANCE,
    MODEL_LAMBERT,
    MODEL_OREN_NAYAR,
    MODEL_PHONG,
    MODEL_UNLIT,
    NO_TEXTURE,
)
from .textures import Textures

__all__ = ["ALPHA_MODES", "DEFAULT_PALETTE", "SHADING_MODELS", "TEXTURE_FIELDS", "Material", "Materials", "materials"]

#: name -> the shader's MODEL_* value
SHADING_MODELS: Final[dict[str, int]] = {
    "unlit": MODEL_UNLIT,
    "lambert": MODEL_LAMBERT,
    "oren_nayar": MODEL_OREN_NAYAR,
    "phong": MODEL_PHONG,
    "blinn_phong": MODEL_BLINN_PHONG,
    "cook_torrance": MODEL_COOK_TORRANCE,
}
#: name -> the shader's ALPHA_* value. `blend`: drawn after the opaque rows, back to front, with
#: alpha blending and no depth writes (set_aside_pass.py).
ALPHA_MODES: Final[dict[str, int]] = {"opaque": ALPHA_OPAQUE, "mask": ALPHA_MASK, "blend": ALPHA_BLEND}
MAX_SHININESS: Final = 1e4
#: a material's fill: index 0 is the global --fill's look, the others are drawn apart
FILLS: Final = ("solid", "wireframe", "points")
#: the texture fields, in the order of the row's `textures` then `textures2.x`
TEXTURE_FIELDS: Final = (
    "base_color_texture",
    "metallic_roughness_texture",
    "normal_texture",
    "emissive_texture",
    "occlusion_texture",
)


@dataclass(frozen=True)
class Material:
    """One look. Immutable: change a registered one with `Materials.update(handle, ...)`."""

    name: str = "material"
    model: str = "cook_torrance"
    base_color: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)  # linear RGBA
    metallic: float = 0.0  # cook_torrance
    roughness: float = 0.5  # cook_torrance (perceptual, alpha = roughness^2); oren_nayar: sigma
    shininess: float = 32.0  # phong, blinn_phong: the exponent
    specular: float = 0.5  # phong, blinn_phong: the specular colour's strength (white)
    emissive: tuple[float, float, float] = (0.0, 0.0, 0.0)  # linear RGB radiance added as is
    alpha_mode: str = "opaque"  # opaque or mask (alpha below alpha_cutoff is not drawn)
    alpha_cutoff: float = 0.5
    double_sided: bool = False  # back faces drawn too, lit with the normal reversed (glTF)
    fill: str = "solid"  # solid, wireframe or points (where the device has fillModeNonSolid)
    base_color_texture: int | None = None  # sRGB
    metallic_roughness_texture: int | None = None  # linear: G roughness, B metallic
    normal_texture: int | None = None  # linear, tangent space
    emissive_texture: int | None = None  # sRGB
    occlusion_texture: int | None = None  # linear: R
    normal_scale: float = 1.0
    occlusion_strength: float = 1.0
    # the world's Environment seen in the surface (environment.glsl), any shading model: a mirror
    # image weighted by Schlick's Fresnel with `reflectivity` at normal incidence, and a refracted
    # image (glass) by `refraction`, bent by `ior` and mixed with its reflection by Fresnel. Blurred
    # by roughness. Such materials are drawn forward, after the chunks (set_aside_pass.py).
    reflectivity: float = 0.0
    refraction: float = 0.0
    ior: float = 1.5

    def __post_init__(self) -> None:
        for name, size in (("base_color", 4), ("emissive", 3)):
            value = getattr(self, name)
            try:
                values = tuple(float(v) for v in value)
            except (TypeError, ValueError):
                raise ValueError(f"material {self.name!r}: {name} must be {size} numbers, got {value!r}") from None
            if len(values) != size or not all(math.isfinite(v) and v >= 0 for v in values):
                raise ValueError(
                    f"material {self.name!r}: {name} must be {size} finite numbers of at least 0, got {value!r}"
                )
            object.__setattr__(self, name, values)
        if self.model not in SHADING_MODELS:
            raise ValueError(
                f"material {self.name!r}: unknown shading model {self.model!r}; models: {', '.join(SHADING_MODELS)}"
            )
        if self.alpha_mode not in ALPHA_MODES:
            raise ValueError(
                f"material {self.name!r}: alpha_mode must be one of {', '.join(ALPHA_MODES)}, got {self.alpha_mode!r}"
            )
        if self.base_color[3] > 1:
            raise ValueError(f"material {self.name!r}: base_color's alpha must be at most 1, got {self.base_color[3]}")
        for name, low, high in (
            ("metallic", 0.0, 1.0),
            ("roughness", 0.0, 1.0),
            ("shininess", 1.0, MAX_SHININESS),
            ("specular", 0.0, math.inf),
            ("alpha_cutoff", 0.0, 1.0),
            ("normal_scale", -1e3, 1e3),
            ("occlusion_strength", 0.0, 1.0),
            ("reflectivity", 0.0, 1.0),
            ("refraction", 0.0, 1.0),
            ("ior", 1.0, 3.0),
        ):
            value = getattr(self, name)
            if not isinstance(value, (int, float, np.number)) or not (math.isfinite(value) and low <= value <= high):
                raise ValueError(
                    f"material {self.name!r}: {name} must be a finite number in [{low}, {high}], got {value!r}"
                )
            object.__setattr__(self, name, float(value))
        if self.fill not in FILLS:
            raise ValueError(f"material {self.name!r}: fill must be one of {', '.join(FILLS)}, got {self.fill!r}")
        if not isinstance(self.double_sided, (bool, np.bool_)):
            raise ValueError(f"material {self.name!r}: double_sided must be True or False, got {self.double_sided!r}")
        object.__setattr__(self, "double_sided", bool(self.double_sided))
        for name in TEXTURE_FIELDS:
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0):
                raise ValueError(f"material {self.name!r}: {name} must be a texture handle (an int >= 0) or None")
            if value is not None:
                object.__setattr__(self, name, int(value))

    @property
    def textured(self) -> bool:
        return any(getattr(self, name) is not None for name in TEXTURE_FIELDS)

    @property
    def normalisation(self) -> float:
        """The specular lobe's energy normalisation (times pi, as the shader's BRDFs are): Phong
        (s + 2) / 2, Blinn-Phong (s + 8) / 8 (Akenine-Moeller et al.); 1 for the other models."""
        s = self.shininess
        return {"phong": (s + 2.0) / 2.0, "blinn_phong": (s + 8.0) / 8.0}.get(self.model, 1.0)

    def row(self) -> np.ndarray:
        """This material as one MATERIAL row, as the shader reads it."""
        out = np.zeros((), MATERIAL.dtype)
        out["base_color"] = self.base_color
        out["emissive"][:3] = self.emissive
        # the specular strength times the model's normalisation, once here and not per light in
        # the shader (measured on the H100: that product cost the 100-cube seed scene 0.007 ms)
        out["surface"] = (self.metallic, self.roughness, self.shininess, self.specular * self.normalisation)
        out["params"] = (self.alpha_cutoff, self.normal_scale, self.occlusion_strength, 0.0)
        out["kind"] = (SHADING_MODELS[self.model], ALPHA_MODES[self.alpha_mode], int(self.double_sided), 0)
        handles = [NO_TEXTURE if (h := getattr(self, name)) is None else h for name in TEXTURE_FIELDS]
        out["textures"] = handles[:4]
        out["textures2"] = (handles[4], NO_TEXTURE, NO_TEXTURE, NO_TEXTURE)
        out["environment"] = (self.reflectivity, self.refraction, self.ior, 0.0)
        return out

    @property
    def mirrors(self) -> bool:
        """Whether the environment shows in it (reflection or refraction)."""
        return self.reflectivity > 0 or self.refraction > 0


def _palette_entry(name: str, color: tuple[float, float, float], strength: float, shininess: float) -> Material:
    # Before materials, specular was pow(n.h, s) * strength; normalised Blinn-Phong multiplies by
    # (s + 8) / 8, so the palette's strengths are divided by it to keep the seed scenes' highlights.
    return Material(
        name, "blinn_phong", (*color, 1.0), shininess=shininess, specular=strength * 8.0 / (shininess + 8.0)
    )


#: The looks of handles 0-5 (linear RGB, specular strength and shininess as before materials)
DEFAULT_PALETTE: Final[tuple[Material, ...]] = (
    _palette_entry("grey", (0.80, 0.80, 0.80), 0.5, 32.0),
    _palette_entry("red", (0.85, 0.35, 0.25), 0.6, 48.0),
    _palette_entry("blue", (0.25, 0.55, 0.85), 0.6, 48.0),
    _palette_entry("green", (0.35, 0.75, 0.35), 0.5, 32.0),
    _palette_entry("gold", (0.90, 0.75, 0.30), 0.7, 64.0),
    _palette_entry("purple", (0.65, 0.40, 0.80), 0.5, 32.0),
)


class Materials:
    """A world's materials by handle, and the table the renderer uploads (`table`, rewritten on
    every change; `version` counts the changes)."""

    def __init__(self, palette: tuple[Material, ...] = DEFAULT_PALETTE) -> None:
        self._materials: list[Material] = []
        self.textures = Textures()  # what the materials' *_texture handles name
        self.table = np.zeros(max(len(palette), 1), MATERIAL.dtype)
        self.blend = np.zeros(len(self.table), bool)  # per handle: alpha-blended
        self.fills = np.zeros(len(self.table), np.uint8)  # per handle: index into FILLS
        self.mirrors = np.zeros(len(self.table), bool)  # per handle: reflects or refracts the environment
        self._aside = 0  # materials whose rows are drawn apart (blended, not solid, or mirroring)
        self.blends = False  # some material is alpha-blended
        self.version = 0
        self.features = 0  # what the shader needs: bit per shading model some material uses, FEATURE_*
        for material in palette:
            self.add(material)

    def add(self, material: Material) -> int:
        if not isinstance(material, Material):
            raise TypeError(f"Materials.add takes a Material, got {type(material).__name__}")
        self._check_textures(material)
        handle = len(self._materials)
        if handle >= len(self.table):
            grown = np.zeros(2 * len(self.table), MATERIAL.dtype)
            grown[:handle] = self.table[:handle]
            self.table = grown
            self.blend = np.concatenate([self.blend, np.zeros(len(grown) - len(self.blend), bool)])
            self.fills = np.concatenate([self.fills, np.zeros(len(grown) - len(self.fills), np.uint8)])
            self.mirrors = np.concatenate([self.mirrors, np.zeros(len(grown) - len(self.mirrors), bool)])
        self._materials.append(material)
        self._write(handle)
        return handle

    def update(self, handle: int, **changes: Any) -> Material:
        """Replace fields of the material at `handle` (checked like a new one); returns it."""
        old = self[handle]
        known = {f.name for f in fields(Material)}
        unknown = set(changes) - known
        if unknown:
            raise TypeError(f"Material has no field(s) {sorted(unknown)}; its fields are {sorted(known)}")
        new = replace(old, **changes)
        self._check_textures(new)
        self._materials[handle] = new
        self._write(handle)
        return new

    def _check_textures(self, material: Material) -> None:
        for name in TEXTURE_FIELDS:
            h = getattr(material, name)
            if h is not None and h >= len(self.textures):
                raise ValueError(
                    f"material {material.name!r}: {name} {h} is not a texture of this registry "
                    f"({len(self.textures)} textures; add them with Materials.textures)"
                )

    def _write(self, handle: int) -> None:
        self.table[handle] = self._materials[handle].row()
        material = self._materials[handle]
        self.blend[handle] = material.alpha_mode == "blend"
        self.fills[handle] = FILLS.index(material.fill)
        self.mirrors[handle] = material.mirrors
        n = len(self._materials)
        self._aside = int(self._aside_mask(n).sum())
        self.blends = bool(self.blend[:n].any())  # some material is alpha-blended
        self.features |= 1 << SHADING_MODELS[material.model]
        if material.alpha_mode == "mask":
            self.features |= FEATURE_ALPHA_MASK
        if material.textured:
            self.features |= FEATURE_TEXTURES
        if material.double_sided:
            self.features |= FEATURE_DOUBLE_SIDED
        if any(material.emissive) or material.emissive_texture is not None:
            self.features |= FEATURE_EMISSIVE
        if material.alpha_mode == "blend":
            self.features |= FEATURE_BLEND
        self.version += 1

    def __getitem__(self, handle: int) -> Material:
        if not isinstance(handle, (int, np.integer)) or not 0 <= handle < len(self._materials):
            raise KeyError(f"no material {handle!r}; materials are 0 to {len(self._materials) - 1}")
        return self._materials[int(handle)]

    def __len__(self) -> int:
        return len(self._materials)

    def __iter__(self) -> Iterator[Material]:
        return iter(self._materials)

    def set_aside(self) -> np.ndarray | None:
        """Per material, whether its rows are drawn apart from the chunks (blended, a fill of its
        own, or mirroring the environment; set_aside_pass.py); None when none is (the usual case)."""
        if not self._aside:
            return None
        return self._aside_mask(len(self._materials))

    def _aside_mask(self, n: int) -> np.ndarray:
        # mirroring materials are drawn forward even in the deferred form: their surface mixes
        # the lit colour with the environment, after every light (set_aside_pass.py)
        return self.blend[:n] | (self.fills[:n] != 0) | self.mirrors[:n]

    def rows(self) -> np.ndarray:
        """The table's used rows (a view)."""
        return self.table[: len(self._materials)]


def materials(world: World) -> Materials:
    """The world's materials, made (with the default palette) on first use."""
    found = world.resources.get(Materials)
    if found is None:
        found = world.resources[Materials] = Materials()
    return found
