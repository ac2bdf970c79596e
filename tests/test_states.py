"""States (ecs/states.py): an Enum value in a resource, systems that run only in a state, OnEnter
and OnExit systems run once per transition at the start of the frame after the request, bad
values refused, and the same in a parallel schedule."""

from __future__ import annotations

from enum import Enum, auto

import numpy as np
import pytest

from ecs_engine import (
    AccessError,
    Component,
    EcsError,
    Field,
    NextState,
    Schedule,
    State,
    World,
    any_with,
    current_state,
    in_state,
    init_state,
    request_state,
    system,
)
from ecs_engine.ecs.timestep import FixedTimestep
from ecs_engine.jobs import JobPool


class GameState(Enum):
    MENU = auto()
    PLAYING = auto()
    PAUSED = auto()
    GAME_OVER = auto()


class Other(Enum):
    A = auto()


class Enemy(Component):
    hp = Field(np.float32, default=3.0)


class Key:
    """Which key the 'player' pressed this frame (a resource)."""

    def __init__(self) -> None:
        self.pressed = ""


def game(parallel: bool = False) -> tuple[World, Schedule, list]:
    """menu -> playing -> paused -> playing -> game over, driven by the Key resource."""
    world, log = World(), []
    world.resources[Key] = Key()
    init_state(world, GameState.MENU)
    schedule = Schedule(parallel=parallel)
    go = {"enter": GameState.PLAYING, "p": GameState.PAUSED, "r": GameState.PLAYING, "dead": GameState.GAME_OVER}

    @system(reads=[Key, State[GameState]], writes=[NextState[GameState]])
    def controls(world, dt):
        key = world.resources[Key].pressed
        if key in go:
            request_state(world, go[key])
        log.append(("frame", current_state(world, GameState).name))

    @system(writes=[Enemy])
    def fight(world, dt):
        for batch in world.query(Enemy):
            batch[Enemy].hp -= 1.0
        log.append("fight")

    schedule.add(controls)
    schedule.add(fight, run_if=in_state(GameState.PLAYING))
    schedule.on_enter(GameState.MENU, lambda w, dt: log.append("enter menu"))
    schedule.on_exit(GameState.MENU, lambda w, dt: log.append("exit menu"))

    @system(writes=[Enemy])
    def spawn_level(world, dt):
        log.append(("enter playing", world.query(Enemy).count()))
        if not world.query(Enemy).count():
            world.spawn_batch(3, Enemy())

    @system(writes=[Enemy])
    def clear_level(world, dt):
        log.append("game over: clear")
        for batch in world.query(Enemy):
            world.destroy(batch.entities)

    schedule.on_enter(GameState.PLAYING, spawn_level)
    schedule.on_exit(GameState.GAME_OVER, lambda w, dt: log.append("never"))
    schedule.on_enter(GameState.GAME_OVER, clear_level)  # not on pause: the level stays
    schedule.on_enter(GameState.PAUSED, lambda w, dt: log.append("enter paused"))
    schedule.on_exit(GameState.PAUSED, lambda w, dt: log.append("exit paused"))
    return world, schedule, log


def play(world: World, schedule: Schedule, keys: list[str]) -> None:
    for key in keys:
        world.resources[Key].pressed = key
        schedule.run(world, 1 / 60)


def test_menu_playing_paused_game_over_with_enter_and_exit_systems_once_each():
    world, schedule, log = game()
    play(world, schedule, ["", "enter", "", "p", "", "r", "dead", ""])
    assert log == [
        "enter menu",  # the initial state is entered at the first frame
        ("frame", "MENU"),
        ("frame", "MENU"),  # requested this frame: applies at the start of the next
        "exit menu",
        ("enter playing", 0),
        ("frame", "PLAYING"),
        "fight",
        ("frame", "PLAYING"),
        "fight",
        "enter paused",
        ("frame", "PAUSED"),  # fight does not run while paused
        ("frame", "PAUSED"),
        "exit paused",
        ("enter playing", 3),  # the level kept while paused
        ("frame", "PLAYING"),
        "fight",
        "game over: clear",  # OnEnter(GAME_OVER); its destroys applied before the frame's systems
        ("frame", "GAME_OVER"),
    ]
    assert world.query(Enemy).count() == 0 and current_state(world, GameState) is GameState.GAME_OVER
    assert world.resources[State[GameState]].previous is GameState.PLAYING


def test_the_last_request_wins_the_current_value_does_nothing_and_an_enter_system_s_waits_a_frame():
    world, schedule, log = World(), Schedule(), []
    init_state(world, GameState.MENU)
    schedule.on_enter(GameState.PLAYING, lambda w, dt: (log.append("playing"), request_state(w, GameState.PAUSED)))
    schedule.on_enter(GameState.PAUSED, lambda w, dt: log.append("paused"))
    schedule.on_exit(GameState.MENU, lambda w, dt: log.append("exit menu"))
    schedule.run(world, 0.0)
    request_state(world, GameState.MENU)  # the current value: no transition
    schedule.run(world, 0.0)
    assert log == []
    request_state(world, GameState.GAME_OVER)
    request_state(world, GameState.PLAYING)  # the last one wins
    schedule.run(world, 0.0)
    assert log == ["exit menu", "playing"] and current_state(world, GameState) is GameState.PLAYING
    schedule.run(world, 0.0)
    assert log[-1] == "paused"


def test_the_transition_is_the_first_thing_of_a_fixed_step_frame_too():
    world, schedule, log = World(), Schedule(("fixed", "update")), []
    init_state(world, GameState.MENU)
    schedule.add(lambda w, dt: log.append("step"), "fixed", run_if=in_state(GameState.PLAYING))
    schedule.on_enter(GameState.PLAYING, lambda w, dt: log.append("enter"))
    clock = FixedTimestep(1 / 120)
    request_state(world, GameState.PLAYING)
    schedule.run_frame(world, 1 / 60, clock)
    assert log == ["enter", "step", "step"]


def test_run_if_given_to_add_joins_the_system_s_own():
    world, schedule, ran = World(), Schedule(), []
    init_state(world, GameState.PLAYING)
    counted = system(reads=[Enemy], run_if=any_with(Enemy))(lambda w, dt: ran.append(1))
    schedule.add(counted, run_if=in_state(GameState.PLAYING))
    schedule.run(world, 0.0)  # playing, but no enemy
    world.spawn(Enemy())
    schedule.run(world, 0.0)
    request_state(world, GameState.PAUSED)
    schedule.run(world, 0.0)  # an enemy, but paused
    assert ran == [1]
    assert "any_with(Enemy) and in_state(GameState.PLAYING)" in repr(counted.run_if)


def test_bad_state_values_are_one_clear_error():
    world, schedule = World(), Schedule()
    with pytest.raises(TypeError, match="init_state takes a member of an Enum class \\(a state\\), got int 3"):
        init_state(world, 3)
    with pytest.raises(EcsError, match=r"in_state\(GameState.PLAYING\): the world has no GameState state"):
        in_state(GameState.PLAYING)(world)
    with pytest.raises(EcsError, match=r"request_state\(GameState.PLAYING\): the world has no GameState state"):
        request_state(world, GameState.PLAYING)
    init_state(world, GameState.MENU)
    with pytest.raises(EcsError, match="already has a GameState state \\(now MENU\\)"):
        init_state(world, GameState.PLAYING)
    with pytest.raises(TypeError, match=r"NextState\[GameState\].set takes a GameState member, got Other.A"):
        world.resources[NextState[GameState]].set(Other.A)
    with pytest.raises(TypeError, match="takes a GameState member, got 'PLAYING'"):
        world.resources[NextState[GameState]].set("PLAYING")
    with pytest.raises(TypeError, match=r"in_state takes a GameState member, got Other.A"):
        in_state(GameState.MENU, Other.A)
    with pytest.raises(TypeError, match="on_enter takes a member of an Enum class"):
        schedule.on_enter("PLAYING", lambda w, dt: None)
    with pytest.raises(TypeError, match=r"State\[...\] takes an Enum class"):
        State[int]
    with pytest.raises(TypeError, match="run_if must be a function of the world"):
        schedule.add(lambda w, dt: None, run_if=GameState.MENU)
    assert current_state(world, GameState) is GameState.MENU  # nothing changed


def test_a_system_requesting_a_transition_declares_it():
    world, schedule = World(), Schedule()
    init_state(world, GameState.MENU)
    schedule.add(system(reads=[State[GameState]])(lambda w, dt: request_state(w, GameState.PLAYING)))
    with pytest.raises(AccessError, match="does not declare writes=\\[NextState\\[GameState\\]\\]"):
        schedule.run(world, 0.0)


def _played(parallel: bool) -> tuple[list, list]:
    world, schedule, log = game(parallel)
    pool = world.resources[JobPool] = JobPool(4)
    try:
        # a second requester in the same stage: the declared order decides which request wins
        schedule.add(system(writes=[NextState[GameState]])(lambda w, dt: request_state(w, GameState.MENU)))
        play(world, schedule, ["enter", "", "p", "r", "dead"])
        return log, world.entities().tolist()
    finally:
        pool.close()


def test_a_parallel_schedule_makes_the_same_transitions():
    sequential = _played(parallel=False)
    assert ("frame", "PLAYING") not in sequential[0]  # the later requester always won
    assert _played(parallel=True) == sequential
