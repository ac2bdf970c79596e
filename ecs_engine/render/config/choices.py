"""The render configuration's vocabulary (config.py holds the configuration and its rules): one
enum per setting that is picked by name, the numbers' choices, and `Caps`, what a device offers
that some setting needs.

The enums are `StrEnum`s: a member is the string the flags, the editor and the saved settings
use (`Culling("temporal") == "temporal"`), so code that still passes names keeps working. Each
name is spelled here once; the modules that implement a setting map these names to what they
draw (tone_map.py's operator numbers, path.py's polygon modes, renderer.PATHS' classes).
`Form`, the target's form the settings lead to, is not picked by name: gpu/scene_attachments.py
declares it (this module reads MSAA_COUNTS from there) and it is re-exported here.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Any, Final

from ...errors import UsageError
from ...gpu.array_image import ANISOTROPY_CHOICES
from ...gpu.scene_attachments import MSAA_COUNTS, Form

__all__ = [
    "ANISOTROPY_CHOICES",
    "MAX_EXPOSURE",
    "MSAA_COUNTS",
    "Caps",
    "Choice",
    "Culling",
    "Fill",
    "Form",
    "LightCulling",
    "Mode",
    "Recorder",
    "Shadows",
    "ToneMap",
    "Transparency",
    "post_effects",
]

MAX_EXPOSURE: Final = 20.0  # stops either way (tone_map.py: the colour times 2^exposure)


def post_effects() -> frozenset[str]:
    """The post effects a configuration may name: render/post/registry.py's, whose effect modules
    register themselves (imported on first use: this vocabulary stays light)."""
    from ..post.registry import names

    return names()


def __getattr__(name: str) -> Any:
    if name == "POST_EFFECTS":  # the names, read from the registry when asked
        return post_effects()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class Choice(StrEnum):
    """A setting picked by name. `label` is how a message names the setting."""

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The names in order, as plain strings (argparse choices, the editor's combo lists)."""
        return tuple(m.value for m in cls)

    @classmethod
    def parse(cls, value: Any, label: str) -> Any:
        """The member named `value` (a member passes through); UsageError naming the choices."""
        try:
            return cls(value)
        except ValueError:
            raise UsageError(f"unknown {label} {value!r}; choices: {', '.join(cls.names())}") from None


class Mode(Choice):
    """How mesh rows are drawn (renderer.PATHS)."""

    INSTANCED = "instanced"  # one draw per mesh per chunk, recorded on the CPU
    PER_ENTITY = "per_entity"  # one draw per entity (the seed's way)
    INDIRECT = "indirect"  # compute shaders cull and write the draws (vkCmdDrawIndexedIndirectCount)


class Recorder(Choice):
    """What records the CPU paths' secondaries (chunk_paths.RECORDERS)."""

    NATIVE = "native"  # a numba loop without the GIL
    PYTHON = "python"  # the binding, call by call


class Culling(Choice):
    """Which rows a view skips (frame_data.py, temporal_culling.py, occlusion.py)."""

    FRUSTUM = "frustum"  # every row tested each frame
    TEMPORAL = "temporal"  # a row tested again only when it could have changed side (CPU modes)
    OCCLUSION = "occlusion"  # the frustum, then a depth pyramid on the GPU (the indirect mode)
    NONE = "none"  # draw everything


class LightCulling(Choice):
    """How fragments find their lights (light_clusters.py)."""

    AUTO = "auto"
    LOOP = "loop"
    CLUSTERED = "clustered"
    DEFERRED = "deferred"


class Shadows(Choice):
    """How lights with a Shadow cast (shadow_pass.py, ray_shadows.py)."""

    MAPS = "maps"
    RAYTRACED = "raytraced"


class Transparency(Choice):
    """How blended materials are drawn (set_aside_pass.py, oit_pass.py)."""

    SORTED = "sorted"
    WEIGHTED = "weighted"


class ToneMap(Choice):
    """The tone map's operator (tone_map.py)."""

    CLAMP = "clamp"
    ACES = "aces"
    REINHARD = "reinhard"


class Fill(Choice):
    """How mesh triangles are rasterised (path.FILL_MODES; materials.FILLS)."""

    SOLID = "solid"
    WIREFRAME = "wireframe"
    POINTS = "points"


@dataclass(frozen=True)
class Caps:
    """What a device offers that a setting needs. `Caps.of(device)` reads a device; by hand (the
    defaults: everything offered) it stands for a device a test describes."""

    name: str = "this device"  # how refusals name the device
    ray_tracing: bool = True  # VK_KHR_ray_tracing_pipeline and VK_KHR_acceleration_structure
    draw_indirect_count: bool = True
    multi_draw_indirect: bool = True
    draw_indirect_first_instance: bool = True
    fill_mode_non_solid: bool = True
    sample_counts: tuple[int, ...] = MSAA_COUNTS  # the colour and depth sample counts both offered
    max_anisotropy: float = 16.0  # 1 without samplerAnisotropy; capped at 16
    fragment_subgroup_arithmetic: bool = True  # clustered lights' fragment shaders
    independent_blend: bool = True  # weighted transparency's two targets

    @classmethod
    def of(cls, device: Any) -> Caps:
        """A device's caps, read now (tests change a device's features to play another device).
        What a stand-in device lacks (no limits, no features) counts as not offered."""
        features = getattr(device, "features", None) or {}
        limits = getattr(device, "limits", None)
        samples: tuple[int, ...] = (1,)
        best = 1.0
        if limits is not None:
            from ...gpu.scene_attachments import supported_samples

            if hasattr(limits, "framebufferColorSampleCounts"):
                samples = supported_samples(device)
            if features.get("samplerAnisotropy"):
                best = min(16.0, float(limits.maxSamplerAnisotropy))
        info = getattr(device, "info", None)
        return cls(
            name=str(getattr(info, "name", "this device")),
            ray_tracing=getattr(device, "ray_tracing", None) is not None,
            draw_indirect_count=bool(features.get("drawIndirectCount")),
            multi_draw_indirect=bool(features.get("multiDrawIndirect")),
            draw_indirect_first_instance=bool(features.get("drawIndirectFirstInstance")),
            fill_mode_non_solid=bool(features.get("fillModeNonSolid")),
            sample_counts=samples,
            max_anisotropy=best,
            fragment_subgroup_arithmetic=bool(features.get("fragmentSubgroupArithmetic")),
            independent_blend=bool(features.get("independentBlend")),
        )

    # what the refusals' texts say (config.RULES formats them with the caps as `caps`)
    @property
    def sample_list(self) -> str:
        return ", ".join(str(n) for n in self.sample_counts)

    @property
    def anisotropy_offer(self) -> str:
        return f"at most {self.max_anisotropy:g}" if self.max_anisotropy > 1 else "no anisotropic filtering (use 1)"
