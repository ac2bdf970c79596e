"""One render configuration: `RenderConfig`, a frozen value of every setting the renderer is
drawn with, and `RULES`, the one table of which combinations a device supports and why not.

```python
config = RenderConfig.from_strings(mode="indirect", culling="occlusion")
check(config, Caps.of(device))          # UsageError naming every refusal, or nothing
validate(config.replace(msaa=4, shadows="raytraced"), Caps(ray_tracing=False))  # the reasons
```

A rule is data: the configurations it is about, what they need (of the configuration itself,
or of the device's `Caps`), the reason, and the flag that would do instead. The modules'
check_* functions, the CLI's flags (config_flags.py) and the editor's lists ask this module,
so a name or a refusal is written once. Without caps (`caps=None`: no device open yet) the
device's rules wait; the configuration's own apply at once.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any, Final

from ...errors import UsageError
from .choices import (
    ANISOTROPY_CHOICES,
    MAX_EXPOSURE,
    MSAA_COUNTS,
    Caps,
    Choice,
    Culling,
    Fill,
    Form,
    LightCulling,
    Mode,
    Recorder,
    Shadows,
    ToneMap,
    Transparency,
    post_effects,
)

__all__ = [
    "ANISOTROPY_CHOICES",
    "CHOICES",
    "INERT",
    "MAX_EXPOSURE",
    "MSAA_COUNTS",
    "RULES",
    "Caps",
    "Culling",
    "Fill",
    "Form",
    "LightCulling",
    "Mode",
    "Recorder",
    "RenderConfig",
    "Rule",
    "Shadows",
    "ToneMap",
    "Transparency",
    "applies",
    "check",
    "inert_refusal",
    "validate",
]

# the settings picked by name: field -> (its enum, how a message names it)
CHOICES: Final[dict[str, tuple[type[Choice], str]]] = {
    "mode": (Mode, "render mode"),
    "recorder": (Recorder, "recorder"),
    "culling": (Culling, "culling"),
    "light_culling": (LightCulling, "light culling"),
    "shadows": (Shadows, "shadow method"),
    "transparency": (Transparency, "transparency"),
    "tone_map": (ToneMap, "tone map"),
    "fill": (Fill, "fill"),
}
_BOOLS = ("lod", "shadow_denoise")


def choice(field: str, value: Any) -> Any:
    """The member of `field`'s enum named `value`; UsageError naming the choices."""
    kind, label = CHOICES[field]
    return kind.parse(value, label)


_WORDS = {"true": True, "on": True, "yes": True, "1": True, "false": False, "off": False, "no": False, "0": False}


@dataclass(frozen=True)
class RenderConfig:
    """Every setting a frame is drawn with, today's defaults. Names may be given as strings
    (`RenderConfig(culling="none")`); an unknown one is a UsageError naming the choices."""

    mode: Mode = Mode.INSTANCED
    recorder: Recorder | None = None  # None: native where numba is (chunk_paths.default_recorder)
    culling: Culling = Culling.FRUSTUM
    light_culling: LightCulling = LightCulling.AUTO
    shadows: Shadows = Shadows.MAPS
    shadow_denoise: bool = True  # ray-traced soft shadows filtered (shadow_denoise.py)
    transparency: Transparency = Transparency.SORTED
    tone_map: ToneMap = ToneMap.CLAMP
    exposure: float = 0.0  # stops: the HDR colour times 2^exposure before the tone map
    msaa: int = 1  # samples per pixel of the scene
    fill: Fill = Fill.SOLID
    lod: bool = True  # the indirect mode picks levels of detail by projected size
    anisotropy: int | None = None  # textures' (1: off; None: the device's best, up to 16)
    post: frozenset[str] = field(default_factory=frozenset)  # post effects by name (post/registry.py)

    def __post_init__(self) -> None:
        # names given become members here, once (hence object.__setattr__ on a frozen value),
        # so the rules compare members and a bad name fails where it was given
        errors = []
        for name, (kind, label) in CHOICES.items():
            value = getattr(self, name)
            if value is None and name == "recorder":
                continue
            try:
                object.__setattr__(self, name, kind.parse(value, label))
            except UsageError as exc:
                errors.append(str(exc))
        if isinstance(self.post, str) or not isinstance(self.post, Iterable):
            errors.append(f"post effects are a set of names, got {self.post!r}")
        else:
            object.__setattr__(self, "post", frozenset(self.post))
        if errors:
            raise UsageError("; ".join(errors))

    @property
    def post_names(self) -> str:
        return ", ".join(sorted(self.post)) or "none"

    @property
    def depth_post(self) -> tuple[str, ...]:
        """The post effects on that read the scene's single-sample depth (post/registry.py)."""
        from ..post.registry import depth_readers

        return depth_readers(self.post)

    @property
    def depth_post_names(self) -> str:
        return ",".join(self.depth_post)

    @property
    def depth_post_labels(self) -> str:
        return ", ".join(name.upper() for name in self.depth_post)

    @property
    def post_choices(self) -> str:
        return ", ".join(sorted(post_effects())) or "none yet"

    def replace(self, **changes: Any) -> RenderConfig:
        """This configuration with `changes` (names or members), checked as a new one."""
        return dataclasses.replace(self, **changes)

    def changed(self, other: RenderConfig) -> frozenset[str]:
        """The fields whose values differ: what a switch from `other` to this one touches."""
        return frozenset(f.name for f in dataclasses.fields(self) if getattr(self, f.name) != getattr(other, f.name))

    @classmethod
    def from_strings(cls, **given: Any) -> RenderConfig:
        """A configuration from the words of flags or a settings file: names, numbers as text,
        booleans as words (on/off, true/false), `culling` True/False for frustum/none. Every bad
        value or unknown setting is named in ONE UsageError, with the choices."""
        fields = {f.name for f in dataclasses.fields(cls)}
        errors: list[str] = []
        values: dict[str, Any] = {}
        for name, value in given.items():
            if name not in fields:
                errors.append(f"unknown render setting {name!r}; settings: {', '.join(sorted(fields))}")
            elif name == "culling" and isinstance(value, bool):
                values[name] = Culling.FRUSTUM if value else Culling.NONE
            elif name in _BOOLS and isinstance(value, str):
                if value.lower() not in _WORDS:
                    errors.append(f"{name} is on or off, got {value!r}")
                values[name] = _WORDS.get(value.lower(), True)
            elif name in ("msaa", "anisotropy", "exposure") and isinstance(value, str):
                try:
                    values[name] = float(value) if name == "exposure" else int(value)
                except ValueError:
                    errors.append(f"{name} takes a number, got {value!r}")
            elif name == "post" and isinstance(value, str):
                values[name] = frozenset(w for w in value.replace(",", " ").split() if w)
            elif name in CHOICES and not (value is None and name == "recorder"):
                kind, label = CHOICES[name]
                try:
                    values[name] = kind.parse(value, label)
                except UsageError as exc:
                    errors.append(str(exc))
            else:
                values[name] = value
        if errors:
            raise UsageError("; ".join(errors))
        return cls(**values)


@dataclass(frozen=True)
class Rule:
    """`field` refused where `when(config)` holds but `needs(config, caps)` does not; a rule with
    `device=True` asks the device's caps and waits while there are none. `reason` is formatted
    with `c` (the configuration), `caps` and `suggest`; the suggestion follows as ": use ..."
    unless the reason names it."""

    field: str
    when: Callable[[RenderConfig], bool]
    needs: Callable[[RenderConfig, Caps], bool]
    reason: str
    suggest: str | None = None
    device: bool = False

    def refusal(self, config: RenderConfig, caps: Caps | None) -> str | None:
        """The message if this rule refuses `config` on `caps` (None: no device yet)."""
        if not self.when(config) or (self.device and caps is None):
            return None
        if self.needs(config, caps or Caps()):
            return None
        text = self.reason.format(c=config, caps=caps, suggest=self.suggest)
        if self.suggest is not None and "{suggest}" not in self.reason:
            text += f": use {self.suggest}"
        return text


def _exposure_ok(c: RenderConfig, caps: Caps) -> bool:
    x = c.exposure
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and abs(x) <= MAX_EXPOSURE


def _indirect_needs(feature: str, name: str) -> Rule:
    """The indirect mode's need of one device feature (indirect_draws.FEATURES)."""
    return Rule(
        "mode",
        lambda c: c.mode is Mode.INDIRECT,
        lambda c, caps: bool(getattr(caps, feature)),
        "{caps.name} lacks " + name + ": the indirect mode needs it",
        "--mode instanced",
        device=True,
    )


def _one_of(choices: tuple[int, ...]) -> str:
    return "one of " + ", ".join(map(str, choices)) + " (1: off)"


# Every combination the renderer refuses, and why. The texts are the flags' words: the CLI
# prints them as they are, the editor shows them under its controls.
RULES: Final[tuple[Rule, ...]] = (
    # culling: the indirect mode culls in its compute shader; the depth pyramid is the GPU's
    Rule(
        "culling",
        lambda c: c.culling is Culling.TEMPORAL,
        lambda c, caps: c.mode is not Mode.INDIRECT,
        "--culling temporal is for the CPU-culled modes; the indirect mode culls on the GPU",
        "--culling frustum",
    ),
    Rule(
        "culling",
        lambda c: c.culling is Culling.OCCLUSION,
        lambda c, caps: c.mode is Mode.INDIRECT,
        "--culling occlusion needs {suggest}: the depth pyramid is tested on the GPU",
        "--mode indirect",
    ),
    # the indirect mode: counts, many draws and first instances in its indirect draws
    _indirect_needs("draw_indirect_count", "drawIndirectCount"),
    _indirect_needs("multi_draw_indirect", "multiDrawIndirect"),
    _indirect_needs("draw_indirect_first_instance", "drawIndirectFirstInstance"),
    # ray-traced shadows: pipelines that trace, from the one-sample G-buffer
    Rule(
        "shadows",
        lambda c: c.shadows is Shadows.RAYTRACED,
        lambda c, caps: caps.ray_tracing,
        "--shadows raytraced needs ray-tracing pipelines (VK_KHR_ray_tracing_pipeline and "
        "VK_KHR_acceleration_structure), which {caps.name} lacks",
        "--shadows maps",
        device=True,
    ),
    Rule(
        "shadows",
        lambda c: c.shadows is Shadows.RAYTRACED,
        lambda c, caps: c.msaa == 1,
        "--shadows raytraced traces from the one-sample G-buffer: it cannot draw with --msaa {c.msaa}",
    ),
    # wireframe and points: the polygon modes behind fillModeNonSolid
    Rule(
        "fill",
        lambda c: c.fill is not Fill.SOLID,
        lambda c, caps: caps.fill_mode_non_solid,
        "{caps.name} cannot draw {c.fill} (it lacks fillModeNonSolid)",
        "--fill solid",
        device=True,
    ),
    # numbers: the exposure's range; the sample counts and anisotropies there are, and offered
    Rule(
        "exposure",
        lambda c: True,
        _exposure_ok,
        f"exposure must be a number of stops in [-{MAX_EXPOSURE:g}, {MAX_EXPOSURE:g}], got {{c.exposure!r}}",
    ),
    Rule("msaa", lambda c: True, lambda c, caps: c.msaa in MSAA_COUNTS, "--msaa {c.msaa!r}: " + _one_of(MSAA_COUNTS)),
    Rule(
        "msaa",
        lambda c: c.msaa in MSAA_COUNTS,
        lambda c, caps: c.msaa in caps.sample_counts,
        "--msaa {c.msaa}: {caps.name} offers {caps.sample_list}",
        device=True,
    ),
    Rule(
        "anisotropy",
        lambda c: c.anisotropy is not None,
        lambda c, caps: c.anisotropy in ANISOTROPY_CHOICES,
        "--anisotropy {c.anisotropy!r}: " + _one_of(ANISOTROPY_CHOICES),
    ),
    Rule(
        "anisotropy",
        lambda c: c.anisotropy in ANISOTROPY_CHOICES,
        lambda c, caps: (c.anisotropy or 1) <= caps.max_anisotropy,
        "--anisotropy {c.anisotropy}: {caps.name} offers {caps.anisotropy_offer}",
        device=True,
    ),
    Rule(
        "post",
        lambda c: bool(c.post),
        lambda c, caps: c.post <= post_effects(),
        "unknown post effect in {c.post_names}; choices: {c.post_choices}",
    ),
    # the effects that sample depth (SSAO) read one sample a pixel; resolving a multisampled
    # depth would be a pass of its own (the render pass's depth resolve needs render passes 2)
    Rule(
        "post",
        lambda c: isinstance(c.msaa, int) and c.msaa > 1 and bool(c.depth_post),
        lambda c, caps: False,
        "--post {c.depth_post_names} cannot draw with --msaa {c.msaa}: {c.depth_post_labels} reads "
        "single-sample depth (use {suggest})",
        "--msaa 1",
    ),
)


def validate(config: RenderConfig, caps: Caps | None = None, only: Iterable[str] | None = None) -> list[str]:
    """Every refusal of `config` on a device with `caps` (None: the configuration's own rules
    alone); `only`: the rules about these fields."""
    fields = None if only is None else frozenset(only)
    found = (r.refusal(config, caps) for r in RULES if fields is None or r.field in fields)
    return [text for text in found if text is not None]


def check(config: RenderConfig, caps: Caps | None = None, only: Iterable[str] | None = None) -> RenderConfig:
    """`config`, or one UsageError naming every refusal (validate)."""
    refusals = validate(config, caps, only)
    if refusals:
        raise UsageError("; ".join(refusals))
    return config


# Settings that change nothing in some configurations: field -> (whether it applies, and the
# CLI's refusal of a flag given where it does not; None: not refused, the editor hides it)
INERT: Final[dict[str, tuple[Callable[[RenderConfig], bool], str | None]]] = {
    "recorder": (
        lambda c: c.mode is not Mode.INDIRECT,
        "--recorder does not apply to --mode {c.mode}: the GPU writes its draws",
    ),
    "shadow_denoise": (
        lambda c: c.shadows is Shadows.RAYTRACED,
        "--no-shadow-denoise applies to --shadows raytraced; shadow maps have no denoiser",
    ),
    "lod": (lambda c: c.mode is Mode.INDIRECT, None),  # the indirect mode's compute shaders pick levels
}


def applies(field: str, config: RenderConfig) -> bool:
    """Whether `field` changes anything drawn with `config` (the editor shows only those)."""
    entry = INERT.get(field)
    return entry is None or entry[0](config)


def inert_refusal(field: str, config: RenderConfig) -> str | None:
    """The CLI's refusal of a flag for `field` given where it changes nothing, or None."""
    entry = INERT.get(field)
    if entry is None or entry[1] is None or entry[0](config):
        return None
    return entry[1].format(c=config)


def __getattr__(name: str) -> Any:
    if name == "POST_EFFECTS":  # config_support's, read from the post effects' registry when asked
        return post_effects()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def check_samples(device: Any, samples: int) -> None:
    """UsageError unless the device renders the scene with `samples` (--msaa): the table's rule,
    checked where a target is made (here and not in gpu/: the Vulkan layer imports no render
    module)."""
    check(RenderConfig.from_strings(msaa=samples), Caps.of(device), only=("msaa",))
