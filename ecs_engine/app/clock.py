"""`Time`: the run's simulated time as a world resource (TimePlugin puts it there).

Systems get their step as `dt`; `Time` answers the rest: how long the game has run, how many
fixed steps it has taken and how long one is. It reads the run's FixedTimestep, so it costs
nothing per frame. Headless and simulation runs step 1/60 s a frame (reproducible frame for
frame); a window steps 1/120 s on the wall clock, as many steps a frame as time has passed.
"""

from __future__ import annotations

from ..ecs.timestep import FixedTimestep


class Time:
    def __init__(self, clock: FixedTimestep) -> None:
        self.clock = clock

    @property
    def step(self) -> float:
        """Seconds of one fixed step (the `dt` of a system in the "fixed" stage)."""
        return self.clock.step

    @property
    def steps(self) -> int:
        """Fixed steps taken since the run began."""
        return self.clock.steps

    @property
    def elapsed(self) -> float:
        """Seconds of simulation since the run began: the steps taken and what is waiting for
        the next one."""
        return self.clock.steps * self.clock.step + self.clock.accumulator

    @property
    def alpha(self) -> float:
        """Where this frame lies between the last two fixed steps (0 to 1), for interpolation."""
        return self.clock.alpha

    def __repr__(self) -> str:
        return f"Time(elapsed={self.elapsed:.3f} s, steps={self.steps}, step={self.step:.5f} s)"
