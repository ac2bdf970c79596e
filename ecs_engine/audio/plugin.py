"""AudioPlugin: the Audio resource, opened with the run, and AudioSystem after the hierarchy.

    app.add_plugins(DefaultPlugins, AudioPlugin())

The output is the default sound device, or the null output with one line when there is none;
`--audio-out out.wav` (or AudioPlugin(output="out.wav")) captures the sound to a file instead.
The device is closed, and a capture's file completed, when the run ends."""

from __future__ import annotations

import os
from typing import Any

from ..app.plugins import Plugin
from .audio import Audio
from .system import AudioSystem


class AudioPlugin(Plugin):
    def __init__(
        self, output: str | os.PathLike[str] | None = None, sample_rate: int = 48_000, doppler_factor: float = 1.0
    ) -> None:
        self.output = output
        self.sample_rate, self.doppler_factor = sample_rate, doppler_factor

    def build(self, app: Any) -> None:
        app.add_systems("post_update", AudioSystem())

        def open_audio(world: Any, session: Any) -> None:
            chosen = getattr(session.options, "audio_out", None) or self.output or "device"
            audio = Audio(chosen, self.sample_rate, self.doppler_factor)
            if not getattr(session.options, "quiet", False):
                audio.notice = audio.output.fallback  # said by the first frame, after the run's own first line
            world.resources[Audio] = audio

        def close_audio(world: Any) -> None:
            audio = world.resources.get(Audio)
            if audio is not None:
                audio.close()

        app.on_open(open_audio)
        app.on_close(close_audio)
