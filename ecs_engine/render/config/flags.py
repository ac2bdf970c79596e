"""The render configuration's command-line flags, made from its enums (config_support.py): the
choices, the defaults (RenderConfig's) and the help, which describes each name. A name added
to an enum needs its line in DESCRIPTIONS (tests/test_render_config.py checks), and then is a
choice of the flag and of the editor's list at once.

Each flag's `dest` is the run option's field (app/settings.py RunOptions): the same name as the
configuration's field but for `--shadows`, whose run option is `shadow_method` (`shadows` is
the shadows scene's own switch there).
"""

from __future__ import annotations

import argparse
from typing import Final

from ...errors import UsageError
from . import ANISOTROPY_CHOICES, CHOICES, MSAA_COUNTS, RenderConfig
from .choices import Choice, Culling, Fill, LightCulling, Mode, Recorder, Shadows, ToneMap, Transparency

# RenderConfig field -> the run option (and argparse dest) where they differ
RUN_FIELDS: Final = {"shadows": "shadow_method"}

DESCRIPTIONS: Final[dict[Choice, str]] = {
    Mode.INSTANCED: "one draw per mesh per chunk",
    Mode.PER_ENTITY: "one draw per entity (the seed's way)",
    Mode.INDIRECT: "the GPU culls and writes the draws (compute + vkCmdDrawIndexedIndirectCount)",
    Recorder.NATIVE: "numba loop without the GIL (default when numba is installed)",
    Recorder.PYTHON: "the binding, call by call",
    Culling.FRUSTUM: "every row tested each frame",
    Culling.TEMPORAL: "a row tested again only when the camera's and its own speed limits say it could have "
    "changed side (not with --mode indirect)",
    Culling.OCCLUSION: "--mode indirect only, the frustum and then what last frame's visible rows hide and what "
    "covers no pixel, on the GPU (two-phase, a depth pyramid; the image is frustum culling's)",
    Culling.NONE: "draw everything",
    LightCulling.AUTO: "from 16 bounded lights, clusters and the opaque meshes lit in compute (deferred)",
    LightCulling.LOOP: "every fragment over every light",
    LightCulling.CLUSTERED: "clusters, lit in the fragment shader",
    LightCulling.DEFERRED: "clusters, and the opaque meshes always lit in compute (with --msaa: forward)",
    Shadows.MAPS: "shadow maps",
    Shadows.RAYTRACED: "ray-traced (needs a GPU with ray-tracing pipelines; drawn in the deferred form)",
    Transparency.SORTED: "sorted back to front per object",
    Transparency.WEIGHTED: "weighted blended order-independent transparency (drawn in the deferred form)",
    ToneMap.CLAMP: "min(c, 1), the colour as drawn",
    ToneMap.ACES: "filmic (Narkowicz's ACES fit)",
    ToneMap.REINHARD: "c / (1 + c)",
    Fill.SOLID: "filled triangles",
    Fill.WIREFRAME: "the triangles' edges (where the device has fillModeNonSolid)",
    Fill.POINTS: "the vertices (where the device has fillModeNonSolid)",
}

# (flag, RenderConfig field, what it picks), in the help's order
CHOICE_FLAGS: Final = (
    ("--mode", "mode", "how mesh rows are drawn"),
    ("--recorder", "recorder", "what records the CPU modes' draws"),
    ("--culling", "culling", "which rows a view skips"),
    ("--fill", "fill", "how meshes are rasterised"),
    ("--tone-map", "tone_map", "how the HDR colour maps to the display"),
    ("--light-culling", "light_culling", "how fragments find their lights"),
    ("--transparency", "transparency", "how blended materials are drawn"),
    ("--shadows", "shadows", "how lights with a Shadow cast"),
)


def choice_help(field: str, what: str) -> str:
    """`what` the flag picks, then each name with its description; the default marked."""
    kind, _ = CHOICES[field]
    default = getattr(RenderConfig(), field)
    names = [f"{m}{' (default)' if m == default else ''}: {DESCRIPTIONS[m]}" for m in kind]
    return f"{what}. " + "; ".join(names)


def post_list(text: str) -> frozenset[str]:
    """`--post bloom,fxaa`: the post effects' names (post/registry.py), commas or spaces between."""
    from ..post.registry import ordered

    names = frozenset(w for w in text.replace(",", " ").split() if w)
    try:
        ordered(names)
    except UsageError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return names


def post_help() -> str:
    from ..post.registry import kinds

    effects = "; ".join(f"{name}: {kind.description}" for name, kind in kinds().items())
    return f"post effects to run, comma-separated (default none). {effects}"


def add_config_flags(parser: argparse.ArgumentParser) -> None:
    """The render configuration's flags, with RenderConfig's defaults; argparse refuses a name
    no enum has (one line: app/cli.py's OneLineParser), config.check the combinations."""
    defaults = RenderConfig()
    for flag, field, what in CHOICE_FLAGS:
        kind, _ = CHOICES[field]
        default = getattr(defaults, field)
        where = parser.add_mutually_exclusive_group() if field == "culling" else parser  # vs --no-culling
        where.add_argument(
            flag,
            dest=RUN_FIELDS.get(field, field),
            choices=kind.names(),
            default=None if default is None else default.value,
            help=choice_help(field, what),
        )
        if field == "culling":  # --culling X --no-culling: which one was meant?
            where.add_argument(
                "--no-culling",
                dest="culling",
                action="store_const",
                const="none",
                help="draw everything (--culling none)",
            )
    parser.add_argument(
        "--no-lod",
        dest="lod",
        action="store_false",
        help="--mode indirect draws every mesh in full, not at the coarsest level of detail its size on screen allows",
    )
    parser.add_argument(
        "--exposure",
        type=float,
        default=defaults.exposure,
        help="stops: the scene's colour times 2^EV before the tone map",
    )
    parser.add_argument(
        "--msaa", type=int, choices=MSAA_COUNTS, default=defaults.msaa, help="samples per pixel (default 1: no MSAA)"
    )
    parser.add_argument(
        "--anisotropy",
        type=int,
        choices=ANISOTROPY_CHOICES,
        help="textures' anisotropic filtering, at most this many samples (1: off; default: the GPU's best, up to 16)",
    )
    parser.add_argument("--post", type=post_list, default=frozenset(), metavar="EFFECT[,EFFECT]", help=post_help())
    parser.add_argument(
        "--no-shadow-denoise",
        dest="shadow_denoise",
        action="store_false",
        help="--shadows raytraced: leave area lights' soft shadows unfiltered (4 rays a pixel: noisy)",
    )
