"""The render configuration (render/config/__init__.py): the enums are the flags' words, the one table of
rules refuses each combination a device cannot draw with its reason, from_strings names every bad
value in one error, and the CLI's flags and the editor's lists come from the enums."""

from __future__ import annotations

import dataclasses
import sys

import pytest

from ecs_engine.errors import UsageError
from ecs_engine.render.config import (
    CHOICES,
    RULES,
    Caps,
    Culling,
    Fill,
    LightCulling,
    Mode,
    Recorder,
    RenderConfig,
    Shadows,
    ToneMap,
    Transparency,
    applies,
    check,
    inert_refusal,
    validate,
)
from ecs_engine.render.config.flags import CHOICE_FLAGS, DESCRIPTIONS, RUN_FIELDS

NOTHING = Caps(
    name="Bare GPU",
    ray_tracing=False,
    draw_indirect_count=False,
    multi_draw_indirect=False,
    draw_indirect_first_instance=False,
    fill_mode_non_solid=False,
    sample_counts=(1,),
    max_anisotropy=1.0,
    fragment_subgroup_arithmetic=False,
    independent_blend=False,
)


def test_the_defaults_are_todays_and_pass_on_any_device():
    c = RenderConfig()
    assert (c.mode, c.culling, c.light_culling, c.shadows, c.transparency, c.tone_map, c.fill) == (
        "instanced",
        "frustum",
        "auto",
        "maps",
        "sorted",
        "clamp",
        "solid",
    )
    numbers = (c.msaa, c.exposure, c.lod, c.shadow_denoise, c.anisotropy, c.post)
    assert numbers == (1, 0.0, True, True, None, frozenset())
    assert validate(c) == [] and validate(c, Caps()) == [] and validate(c, NOTHING) == []
    assert check(c, NOTHING) is c


@pytest.mark.parametrize(
    "changes, caps, reason",
    [
        ({"culling": "temporal", "mode": "indirect"}, None, "--culling temporal is for the CPU-culled modes"),
        ({"culling": "occlusion"}, None, "--culling occlusion needs --mode indirect: the depth pyramid"),
        ({"culling": "occlusion", "mode": "per_entity"}, None, "needs --mode indirect"),
        ({"mode": "indirect"}, Caps(draw_indirect_count=False), "lacks drawIndirectCount: the indirect mode needs it"),
        ({"mode": "indirect"}, Caps(multi_draw_indirect=False), "lacks multiDrawIndirect"),
        ({"mode": "indirect"}, Caps(draw_indirect_first_instance=False), "lacks drawIndirectFirstInstance"),
        (
            {"shadows": "raytraced"},
            Caps(name="Bare GPU", ray_tracing=False),
            "needs ray-tracing pipelines (VK_KHR_ray_tracing_pipeline and VK_KHR_acceleration_structure), "
            "which Bare GPU lacks: use --shadows maps",
        ),
        ({"shadows": "raytraced", "msaa": 4}, None, "one-sample G-buffer: it cannot draw with --msaa 4"),
        ({"fill": "wireframe"}, Caps(name="G", fill_mode_non_solid=False), "G cannot draw wireframe (it lacks fill"),
        ({"fill": "points"}, Caps(fill_mode_non_solid=False), "fillModeNonSolid): use --fill solid"),
        ({"msaa": 8}, Caps(name="G", sample_counts=(1, 4)), "--msaa 8: G offers 1, 4"),
        ({"msaa": 3}, None, "--msaa 3: one of 1, 2, 4, 8"),
        ({"exposure": float("nan")}, None, "exposure must be a number of stops in [-20, 20], got nan"),
        ({"exposure": 21}, None, "got 21"),
        ({"anisotropy": 3}, None, "--anisotropy 3: one of 1, 2, 4, 8, 16 (1: off)"),
        ({"anisotropy": 8}, Caps(name="G", max_anisotropy=4.0), "--anisotropy 8: G offers at most 4"),
        ({"anisotropy": 2}, Caps(name="G", max_anisotropy=1.0), "G offers no anisotropic filtering (use 1)"),
        ({"post": {"sparkles"}}, None, "unknown post effect in sparkles"),
    ],
)
def test_the_table_refuses_each_bad_combination_with_its_reason(changes, caps, reason):
    config = RenderConfig().replace(**changes)
    refusals = validate(config, caps)
    assert len(refusals) == 1 and reason in refusals[0], refusals
    with pytest.raises(UsageError) as err:
        check(config, caps)
    assert reason in str(err.value)
    # the same configuration without the device's part, or on a device that offers everything
    device_rule = caps is not None
    assert (validate(config) == []) == device_rule
    assert (validate(config, Caps()) == []) == device_rule


def test_device_rules_wait_for_a_device_and_every_refusal_is_named_at_once():
    config = RenderConfig.from_strings(mode="indirect", culling="temporal", shadows="raytraced", fill="points", msaa=4)
    assert validate(config) == [
        "--culling temporal is for the CPU-culled modes; the indirect mode culls on the GPU: use --culling frustum",
        "--shadows raytraced traces from the one-sample G-buffer: it cannot draw with --msaa 4",
    ]
    refusals = validate(config, NOTHING)
    assert len(refusals) == 8  # two of the configuration, three indirect features, rays, fill, msaa
    with pytest.raises(UsageError) as err:
        check(config, NOTHING)
    assert str(err.value) == "; ".join(refusals) and "\n" not in str(err.value)
    fill = "Bare GPU cannot draw points (it lacks fillModeNonSolid): use --fill solid"
    assert validate(config, NOTHING, only=("fill",)) == [fill]


def test_every_rule_is_about_a_field_and_can_refuse():
    names = {f.name for f in dataclasses.fields(RenderConfig)}
    assert all(rule.field in names for rule in RULES)
    # each rule refuses one of these configurations (none is dead)
    bad = [
        RenderConfig(mode="indirect", culling="temporal", shadows="raytraced", fill="points", msaa=4),
        RenderConfig(culling="occlusion", exposure=99, anisotropy=3, msaa=3, post={"x"}),
        RenderConfig(anisotropy=16, msaa=8, post={"ssao"}),  # SSAO reads single-sample depth
    ]
    fired = {id(r) for r in RULES for c in bad if r.refusal(c, NOTHING) is not None}
    assert fired == {id(r) for r in RULES}


def test_from_strings_gives_one_error_naming_each_bad_value_and_the_choices():
    with pytest.raises(UsageError) as err:
        RenderConfig.from_strings(culling="sideways", tone_map="filmic", msaa="many", colour="red")
    text = str(err.value)
    assert "\n" not in text
    assert "unknown culling 'sideways'; choices: frustum, temporal, occlusion, none" in text
    assert "unknown tone map 'filmic'; choices: clamp, aces, reinhard" in text
    assert "msaa takes a number, got 'many'" in text
    assert "unknown render setting 'colour'" in text
    with pytest.raises(UsageError, match="unknown render mode 'fast'; choices: instanced, per_entity, indirect"):
        RenderConfig.from_strings(mode="fast")
    with pytest.raises(UsageError, match="lod is on or off, got 'maybe'"):
        RenderConfig.from_strings(lod="maybe")
    with pytest.raises(UsageError, match="unknown shadow method 'soft'"):
        RenderConfig(shadows="soft")  # type: ignore[arg-type]  # the constructor takes names too


def test_from_strings_reads_the_words_of_flags_and_files():
    words = {"mode": "indirect", "culling": "occlusion", "msaa": "4", "exposure": "-1.5", "lod": "off"}
    c = RenderConfig.from_strings(**words, anisotropy="8", post="", recorder=None)
    assert c.mode is Mode.INDIRECT and c.culling is Culling.OCCLUSION
    assert (c.msaa, c.exposure, c.lod, c.anisotropy, c.recorder, c.post) == (4, -1.5, False, 8, None, frozenset())
    assert RenderConfig.from_strings(culling=True).culling is Culling.FRUSTUM
    assert RenderConfig.from_strings(culling=False).culling is Culling.NONE


def test_replace_checks_names_and_is_frozen():
    c = RenderConfig()
    d = c.replace(tone_map="aces", exposure=1.0)
    assert d.tone_map is ToneMap.ACES and c.tone_map is ToneMap.CLAMP
    assert d.changed(c) == {"tone_map", "exposure"} and c.changed(c) == frozenset()
    with pytest.raises(UsageError, match="unknown fill 'dots'"):
        c.replace(fill="dots")
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.mode = Mode.INDIRECT  # type: ignore[misc]
    assert hash(c) == hash(RenderConfig())  # a value: a cache key


@pytest.mark.parametrize("kind", [Mode, Recorder, Culling, LightCulling, Shadows, Transparency, ToneMap, Fill])
def test_enums_round_trip_the_cli_strings(kind):
    for member in kind:
        assert kind(member.value) is member and member == member.value and f"{member}" == member.value
        assert member in DESCRIPTIONS  # the flag's help describes every name
    assert kind.names() == tuple(m.value for m in kind)


def test_the_implementations_know_every_name():
    """The modules that draw a setting map the same names (their tables stay theirs)."""
    from ecs_engine.render.draw.chunk_paths import RECORDERS
    from ecs_engine.render.draw.path import FILL_MODES
    from ecs_engine.render.extract.frame_data import CULLING
    from ecs_engine.render.frame.renderer import MODES, PATHS
    from ecs_engine.render.lighting.clusters import LIGHT_MODES
    from ecs_engine.render.passes.oit import TRANSPARENCY_MODES
    from ecs_engine.render.passes.tone_map import TONE_MAPS
    from ecs_engine.render.raytracing.shadows import SHADOW_METHODS

    assert MODES == tuple(PATHS) == Mode.names()
    assert tuple(RECORDERS) == Recorder.names()
    assert CULLING == Culling.names() and LIGHT_MODES == LightCulling.names()
    assert TRANSPARENCY_MODES == Transparency.names() and SHADOW_METHODS == Shadows.names()
    assert tuple(TONE_MAPS) == ToneMap.names() and tuple(FILL_MODES) == Fill.names()


def test_the_cli_flags_come_from_the_enums():
    from ecs_engine.app.cli import render_flags

    parser = render_flags()
    actions = {a.option_strings[0]: a for a in parser._actions if a.option_strings}
    assert {field for _, field, _ in CHOICE_FLAGS} == set(CHOICES)
    for flag, field, _ in CHOICE_FLAGS:
        kind, _ = CHOICES[field]
        action = actions[flag]
        assert action.dest == RUN_FIELDS.get(field, field)
        assert tuple(action.choices) == kind.names()
        assert all(name in action.help for name in kind.names())
    defaults = vars(parser.parse_args([]))
    options = RenderConfig.from_strings(**{k: defaults[k] for k in ("mode", "culling", "fill", "tone_map", "msaa")})
    assert options == RenderConfig()


def test_run_options_refuse_a_combination_before_a_device_opens():
    from ecs_engine.app.settings import RunOptions

    with pytest.raises(UsageError, match="--culling occlusion needs --mode indirect"):
        RunOptions(culling="occlusion")
    assert RunOptions(mode="indirect", culling="occlusion").render_config().culling is Culling.OCCLUSION


def test_flags_that_change_nothing():
    instanced, indirect = RenderConfig(), RenderConfig(mode="indirect")
    assert applies("recorder", instanced) and not applies("recorder", indirect)
    assert applies("lod", indirect) and not applies("lod", instanced)
    assert not applies("shadow_denoise", instanced)
    assert applies("shadow_denoise", instanced.replace(shadows="raytraced"))
    assert applies("tone_map", instanced)  # a field without an entry always applies
    refusal = inert_refusal("recorder", indirect)
    assert refusal == "--recorder does not apply to --mode indirect: the GPU writes its draws"
    assert inert_refusal("lod", instanced) is None  # hidden in the editor, not refused


def test_caps_of_a_stand_in_device_offer_what_it_has():
    class Traces:  # a device that traces rays and has nothing else to say
        ray_tracing = object()

    caps = Caps.of(Traces())
    assert caps.ray_tracing and not caps.draw_indirect_count and caps.sample_counts == (1,)
    assert caps.name == "this device" and caps.max_anisotropy == 1.0


def test_caps_of_the_test_device(monkeypatch):
    from gpu_context import shared_device

    device = shared_device()
    caps = Caps.of(device)
    assert caps.name == device.info.name and 1 in caps.sample_counts
    assert caps.ray_tracing == (device.ray_tracing is not None)
    monkeypatch.setitem(device.features, "fillModeNonSolid", False)  # read now, not kept
    assert not Caps.of(device).fill_mode_non_solid


def test_the_renderer_refuses_every_setting_the_device_lacks_at_once_and_reports_its_config(monkeypatch):
    from gpu_context import headless_gpu

    from ecs_engine.render.draw.chunk_paths import default_recorder
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(32, 24) as gpu:
        monkeypatch.setitem(gpu.device.features, "drawIndirectCount", False)
        monkeypatch.setitem(gpu.device.features, "fillModeNonSolid", False)
        with pytest.raises(UsageError) as err:
            Renderer(gpu.device, gpu.target, gpu.meshes, mode="indirect", fill="points")
        assert "lacks drawIndirectCount" in str(err.value) and "cannot draw points" in str(err.value)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, tone_map="aces", culling=False, light_culling="loop")
        try:
            wanted = RenderConfig(tone_map="aces", culling="none", light_culling="loop", recorder=default_recorder())
            assert renderer.config == wanted.replace(msaa=gpu.target.samples)
            renderer.light_culling = "clustered"
            assert renderer.config.changed(wanted) == {"light_culling"}
        finally:
            renderer.destroy()


def test_a_bad_flag_is_one_line_and_exit_2():
    from test_cli_render import cli, one_line_error

    proc = cli("cube", "--headless", "--tone-map", "filmic")
    one_line_error(proc, "invalid choice: 'filmic'", "'clamp', 'aces', 'reinhard'")
    proc = cli("cube", "--headless", "--culling", "occlusion", "--width", "32", "--height", "24")
    one_line_error(proc, "--culling occlusion needs --mode indirect: the depth pyramid is tested on the GPU")
    assert "headless" not in proc.stdout  # refused before the scene started


if __name__ == "__main__":
    sys.exit(pytest.main([__file__]))
