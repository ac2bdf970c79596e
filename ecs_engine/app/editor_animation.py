"""The editor's Animation window, shown while the selected entity is (or belongs to) a character
with an AnimationPlayer: its clips to pick from (cross-faded over `fade` seconds), play and
pause, loop, speed, a scrubber over the clip's time, the clip's marks, and the character's
skeleton drawn over the scene (a line from each joint to its parent joint)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..animation import AnimationClips
from ..animation.player import crossfade
from ..animation.skins import Skins
from ..components import active_camera
from ..components.animation import AnimationPlayer, AnimationTarget
from ..components.hierarchy import Parent, WorldMatrix
from ..ecs.gather import gather
from .editor_physics import draw_segments

COLOUR = 0xFFFFC040  # ImGui's ABGR: a light blue


def player_of(world: Any, entity: int | None) -> int | None:
    """The entity with the AnimationPlayer that moves `entity` (itself, or its AnimationTarget's
    player), or None."""
    if entity is None or not world.is_alive(entity):
        return None
    if world.has(entity, AnimationPlayer):
        return int(entity)
    if world.has(entity, AnimationTarget):
        player = int(world.get(entity, AnimationTarget).player)
        return player if world.is_alive(player) and world.has(player, AnimationPlayer) else None
    return None


def skeleton_segments(world: Any, player: int) -> np.ndarray:
    """Lines (S, 2, 3) from each joint of `player`'s skinned character to its parent joint, in
    world space: the joints of the skin copies whose first joint `player` animates."""
    skins = world.resources.get(Skins)
    if skins is None:
        return np.zeros((0, 2, 3))
    out = []
    for skin in skins.skins:
        if not skin.copies:
            continue
        owners, found = gather(world, skin.joints[:, 0], AnimationTarget, "player", fill=-1)
        for copy in np.flatnonzero(found & (owners == player)).tolist():
            joints = skin.joints[copy]
            parents, _ = gather(world, joints, Parent, "entity", fill=-1)
            matrices, alive = gather(world, joints, WorldMatrix, "matrix")
            at = matrices[:, :3, 3]
            index = {int(e): k for k, e in enumerate(joints) if alive[k]}
            out += [(at[index[int(p)]], at[k]) for k, p in enumerate(parents) if alive[k] and int(p) in index]
    return np.array(out, np.float64).reshape(-1, 2, 3)


class AnimationPanel:
    """The Animation window and the skeleton's lines (see the module)."""

    def __init__(self) -> None:
        self.fade = 0.3  # seconds a picked clip cross-fades in
        self.show_skeleton = False

    def draw(self, imgui: Any, world: Any, selected: int | None) -> int | None:
        """The window for the selected entity's character; the player it shows, or None."""
        player = player_of(world, selected)
        clips = world.resources.get(AnimationClips)
        if player is None or clips is None or not len(clips):
            return None
        p = world.get(player, AnimationPlayer)
        imgui.set_next_window_pos((680, 10), imgui.Cond_.first_use_ever.value)
        if imgui.begin("Animation")[0]:
            names = [c.name for c in clips.clips]
            current = int(p.clip)
            label = names[current] if 0 <= current < len(names) else "(none)"
            if imgui.begin_combo("clip", label):
                for handle, name in enumerate(names):
                    if imgui.selectable(f"{name}##{handle}", handle == current)[0] and handle != current:
                        crossfade(world, player, handle, self.fade)
                imgui.end_combo()
            _, self.fade = imgui.slider_float("fade (s)", self.fade, 0.0, 2.0)
            edits: dict[str, Any] = {}
            changed, value = imgui.checkbox("playing", bool(p.playing))
            if changed:
                edits["playing"] = value
            imgui.same_line()
            changed, value = imgui.checkbox("looping", bool(p.looping))
            if changed:
                edits["looping"] = value
            changed, value = imgui.slider_float("speed", float(p.speed), -2.0, 2.0)
            if changed:
                edits["speed"] = value
            if 0 <= current < len(names):
                clip = clips[current]
                changed, value = imgui.slider_float("time (s)", float(p.time), 0.0, max(clip.duration, 1e-6))
                if changed:  # scrubbing holds the pose where the slider is
                    edits.update(time=value, playing=False)
                marks = ", ".join(f"{e.name} {e.time:g}" for e in clip.events)
                imgui.text(f"marks: {marks or 'none'}")
            if edits:
                world.set(player, AnimationPlayer, **edits)
            _, self.show_skeleton = imgui.checkbox("show skeleton", self.show_skeleton)
        imgui.end()
        return player

    def draw_skeleton(self, imgui: Any, world: Any, player: int | None, rect: tuple, drawlist: Any) -> int:
        """The player's skeleton over the scene in `rect`: how many lines were drawn."""
        if not self.show_skeleton or player is None:
            return 0
        segments = skeleton_segments(world, player)
        if not len(segments):
            return 0
        try:
            cam = active_camera(world)
        except Exception:  # no camera: nothing to draw it from
            return 0
        return draw_segments(imgui, world, cam, segments, rect, drawlist, COLOUR, 2.0)
