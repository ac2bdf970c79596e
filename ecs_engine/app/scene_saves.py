"""`SceneFiles`: saving the world from a game's own systems. `World.save` refuses to run inside a
system (structural changes queued by the frame's systems would be half in the file), so a game
that saves on a key press asks this resource instead: outside a system it saves at once, inside
one the save waits for the end of the frame, when every queued change is applied. ScenePlugin puts
one in an App's world; the App's session calls `flush` after each frame that asked for one.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..ecs.world import World


class SceneFiles:
    def __init__(self, world: World) -> None:
        self.world = world
        self.pending: list[Path] = []  # asked for inside a system: saved when the frame is done

    def save(self, path: str | os.PathLike[str]) -> None:
        """`world.save(path)` now, or at the end of this frame when called from a system."""
        if self.world.deferring:
            self.pending.append(Path(path))
        else:
            self.world.save(path)

    def flush(self) -> None:
        """Write what the frame asked for, in order (a failing save is the run's error, as a
        failing system is: one line naming the file)."""
        pending, self.pending = self.pending, []
        for path in pending:
            self.world.save(path)
