"""The editor's sound (app/editor_audio.py): the inspector's AudioSource section plays and stops
the selected source with its button, and the Sound window (a tab beside Perf) mutes a bus with
its box and turns the master's limiter off and on."""

from __future__ import annotations

import numpy as np
from test_editor import Scene

from ecs_engine.app import editor_audio
from ecs_engine.audio import Audio, AudioSystem
from ecs_engine.components import Transform
from ecs_engine.components.audio import AudioSource


def _click(scene, label: str) -> None:
    x0, y0, x1, y1 = editor_audio.rects[label]
    at = ((x0 + x1) / 2, (y0 + y1) / 2)
    scene.frame(mouse=at)
    scene.frame(down=True)
    scene.frame(down=False)


def test_play_stop_and_mute_from_the_editor():
    scene = Scene("cube")
    try:
        world, editor = scene.state.world, scene.session.editor
        audio = world.resources[Audio] = Audio("null")
        scene.state.schedule.add(AudioSystem(), "post_update")
        clip = audio.clip(np.sin(np.arange(4800) / 8.0), name="hum")
        source = world.spawn(Transform(), AudioSource(clip=clip, loop=True, autoplay=False))
        editor.selected = source
        for _ in range(3):
            scene.frame()
        assert not world.get(source, AudioSource).playing and audio.owner == {}
        _click(scene, "play")
        assert world.get(source, AudioSource).playing
        scene.frame()
        assert list(audio.owner.values()) == [source]  # AudioSystem started its voice
        _click(scene, "play")  # now the stop button
        assert not world.get(source, AudioSource).playing
        editor.audio.show()  # its tab, in front of Perf's
        scene.frame()
        _click(scene, "mute music")
        assert audio.muted("music") and not audio.muted("effects")
        assert audio.bus_gains()[audio.bus("music")] == 0.0
        assert audio.limiting == (0.0, 0.1)  # on by default
        _click(scene, "limiter")
        assert audio.limiting is None
        audio.mixer.render(16)  # (the mixer takes the setting at its next block)
        assert audio.mixer.limiter is None
        _click(scene, "limiter")
        assert audio.limiting == (-1.0, 0.1)
    finally:
        world.resources[Audio].close()
        scene.close()
