"""Sound as components: `AudioSource` on anything that makes a sound, `AudioListener` on the
entity that hears (usually the camera). The `Audio` resource (ecs_engine.audio) holds the clips,
the buses and the mixer; AudioSystem hands every source's gains and pitch to it once a frame.

A source plays its `clip` (a handle from `audio.load(path)` or `audio.clip(samples)`) from the
frame it appears when `autoplay` is set. `playing` says whether it plays: AudioSystem sets it
when the source starts and clears it when a clip that does not loop ends; a system sets it to
start the clip again from its beginning and clears it to stop it (with a short fade). `paused`
holds the clip where it is. A `spatial` source is heard from its entity's world position
(attenuated by distance with `model` between `min_distance` and `max_distance`, shaped by its
cone around its forward axis -z, panned, Doppler-shifted by its and the listener's Velocity); a
source that is not spatial plays as it is (music, the interface)."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field

from .transform import LIMIT

MASTER, MUSIC, EFFECTS = 0, 1, 2  # the Audio resource's first buses; audio.add_bus makes more
INVERSE, LINEAR, EXPONENTIAL = 0, 1, 2  # distance models (OpenAL's clamped ones: ecs_engine/audio/spatial.py)

__all__ = ["EFFECTS", "EXPONENTIAL", "INVERSE", "LINEAR", "MASTER", "MUSIC", "AudioListener", "AudioSource"]


class AudioSource(Component):
    """A sound an entity makes (see the module)."""

    clip = Field(np.int64, default=-1, minimum=-1, doc="a clip handle of the Audio resource (-1: none)")
    volume = Field(np.float64, default=1.0, finite=True, minimum=0.0, maximum=LIMIT)
    pitch = Field(np.float64, default=1.0, finite=True, minimum=0.0, min_exclusive=True, maximum=64.0)
    loop = Field(np.bool_, default=False)
    autoplay = Field(np.bool_, default=True)
    playing = Field(np.bool_, default=False)
    paused = Field(np.bool_, default=False)
    spatial = Field(np.bool_, default=True)
    min_distance = Field(np.float64, default=1.0, finite=True, minimum=0.0, min_exclusive=True, maximum=LIMIT)
    max_distance = Field(np.float64, default=1000.0, finite=True, minimum=0.0, min_exclusive=True, maximum=LIMIT)
    rolloff = Field(np.float64, default=1.0, finite=True, minimum=0.0, maximum=LIMIT)
    model = Field(np.int8, default=INVERSE, minimum=0, maximum=2, doc="INVERSE, LINEAR or EXPONENTIAL")
    cone_inner = Field(np.float64, default=360.0, finite=True, minimum=0.0, maximum=360.0, doc="degrees, full angle")
    cone_outer = Field(np.float64, default=360.0, finite=True, minimum=0.0, maximum=360.0, doc="degrees, full angle")
    cone_outer_gain = Field(np.float64, default=0.0, finite=True, minimum=0.0, maximum=1.0)
    bus = Field(np.int64, default=EFFECTS, minimum=0, doc="MASTER, MUSIC, EFFECTS or one of audio.add_bus")


class AudioListener(Component):
    """Tag: the entity whose world position, axes and Velocity the sound is heard from. With none,
    the active camera hears; with no camera either, the origin looking down -z."""
