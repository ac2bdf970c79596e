"""Sound: the `Audio` resource (clips, buses, one-shots, the output), `AudioSource` and
`AudioListener` components (ecs_engine.components.audio), AudioSystem and AudioPlugin. The mixer
runs on the sound device's thread; docs/audio.md says how and why miniaudio."""

from __future__ import annotations

from .audio import Audio
from .plugin import AudioPlugin
from .system import AudioSystem

__all__ = ["Audio", "AudioPlugin", "AudioSystem"]
