"""The editor's sound: the inspector's AudioSource section (the clip, play and stop, pause, every
setting of the source) and the Sound window, shown while the world has the Audio resource: each
bus's volume and mute, and what the mixer costs (the perf line's figures). Each edit of a source
goes through `Editor.set` (the world's checks: a refused value is shown, the source stays)."""

from __future__ import annotations

from typing import Any

from ..audio import Audio
from ..components.audio import AudioSource
from ..ecs.world import World
from .editor_layout import button_width, same_line_if_fits
from .editor_lights import Editor

MODELS = ("inverse", "linear", "exponential")  # AudioSource.model's values, in order
RANGES = {"volume": (0.0, 2.0), "pitch": (0.25, 4.0), "rolloff": (0.0, 8.0), "cone_outer_gain": (0.0, 1.0)}
ANGLES = ("cone_inner", "cone_outer")
DISTANCES = ("min_distance", "max_distance")
SOURCE_LABELS = (*RANGES, "model", "bus", *DISTANCES, *(f"{name} (deg)" for name in ANGLES))

rects: dict[str, tuple[float, float, float, float]] = {}  # the last UI's buttons, by label (tests click them)


def _remember(imgui: Any, label: str) -> None:
    lo, hi = imgui.get_item_rect_min(), imgui.get_item_rect_max()
    rects[label] = (lo.x, lo.y, hi.x, hi.y)


def source_section(editor: Editor, world: World, eid: int) -> None:
    """The inspector's AudioSource section (see the module)."""
    imgui = editor.imgui
    source = world.get(eid, AudioSource)
    audio = world.resources.get(Audio)
    imgui.separator_text("AudioSource")
    clip = int(source.clip)
    imgui.text(f"clip {audio.clip_name(clip) if audio is not None else clip}")
    label = "stop" if source.playing else "play"
    if imgui.button(label):
        editor.set(world, eid, AudioSource, playing=not bool(source.playing))
    _remember(imgui, "play")
    same_line_if_fits(imgui, button_width(imgui, "paused") + 20)
    for flag in ("paused", "loop", "spatial"):
        changed, value = imgui.checkbox(flag, bool(getattr(source, flag)))
        if changed:
            editor.set(world, eid, AudioSource, **{flag: value})
        if flag != "spatial":
            imgui.same_line()
    for name, (low, high) in RANGES.items():
        if name == "rolloff" and not source.spatial:
            continue
        changed, value = imgui.slider_float(name, float(getattr(source, name)), low, high)
        if changed:
            editor.set(world, eid, AudioSource, **{name: value})
    if audio is not None:
        changed, bus = imgui.combo("bus", min(int(source.bus), len(audio.buses) - 1), audio.buses)
        if changed:
            editor.set(world, eid, AudioSource, bus=bus)
    if not source.spatial:
        return
    changed, model = imgui.combo("model", int(source.model), list(MODELS))
    if changed:
        editor.set(world, eid, AudioSource, model=model)
    for name in DISTANCES:
        changed, value = imgui.drag_float(name, float(getattr(source, name)), 0.1, 0.01, 1e6)
        if changed:
            editor.set(world, eid, AudioSource, **{name: value})
    for name in ANGLES:
        changed, value = imgui.slider_float(f"{name} (deg)", float(getattr(source, name)), 0.0, 360.0)
        if changed:
            editor.set(world, eid, AudioSource, **{name: value})


class AudioPanel:
    """The Sound window (see the module): a tab beside Perf in the default layout."""

    def __init__(self) -> None:
        self.focus = False  # bring the window forward next frame (`show`)

    def show(self) -> None:
        self.focus = True

    def draw(self, imgui: Any, world: Any) -> None:
        audio = world.resources.get(Audio)
        if audio is None:
            return
        if self.focus:
            imgui.set_next_window_focus()
            self.focus = False
        if imgui.begin("Sound")[0]:
            imgui.text(f"output  {audio.output.backend}")
            imgui.text("mute, volume")
            for bus in audio.buses:  # the box first: the rows' boxes line up whatever the names
                changed, muted = imgui.checkbox(f"##mute {bus}", audio.muted(bus))
                if changed:
                    audio.mute(bus, muted)
                _remember(imgui, f"mute {bus}")
                imgui.same_line()
                changed, volume = imgui.slider_float(f"{bus}##volume", audio.volume(bus), 0.0, 2.0)
                if changed:
                    audio.set_volume(bus, max(volume, 0.0))
            _limiter(imgui, audio)
            imgui.text_wrapped(audio.perf_line())
        imgui.end()


def _limiter(imgui: Any, audio: Audio) -> None:
    """The master limiter (audio/limiter.py): on or off, its ceiling in dB."""
    on = audio.limiting is not None
    changed, on = imgui.checkbox("##limiter", on)
    _remember(imgui, "limiter")
    if changed:
        audio.limit(-1.0 if on else None)
    imgui.same_line()
    if audio.limiting is None:
        imgui.text("limiter off")
        return
    ceiling, release = audio.limiting
    changed, ceiling = imgui.slider_float("limiter", ceiling, -24.0, 0.0, "ceiling %.1f dB")
    if changed:
        audio.limit(min(max(ceiling, -24.0), 0.0), release)
