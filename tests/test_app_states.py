"""The App's thin wrappers over the ECS core's game structure (ecs/states.py, observers.py):
init_state, systems that run in a state, on_enter / on_exit, observers, and replacing an
on_enter system by name; bad input as one UsageError. A pure simulation: no GPU."""

from __future__ import annotations

from enum import Enum, auto

import numpy as np
import pytest

from ecs_engine import App, Component, Field, MinimalPlugins, OnAdd, Time, in_state, request_state
from ecs_engine.errors import UsageError


class Game(Enum):
    MENU = auto()
    PLAYING = auto()
    PAUSED = auto()
    OVER = auto()


class Enemy(Component):
    hp = Field(np.float32, default=2.0)


def test_menu_playing_paused_over_through_the_app():
    app = App(title="States").add_plugins(MinimalPlugins).init_state(Game.MENU)
    log: list[str] = []

    def spawn_enemies(world, dt):
        log.append("enter playing")
        world.spawn_batch(3, Enemy())

    def fight(world, dt):
        log.append("fight")
        for batch in world.query(Enemy):
            batch[Enemy].hp -= 1.0

    def director(world, dt):
        step = world.resources[Time].steps
        wanted = {1: Game.PLAYING, 2: Game.PAUSED, 4: Game.PLAYING}.get(step)
        if wanted is not None:
            request_state(world, wanted)
        if (world.query(Enemy).column(Enemy.hp) <= 0).all() and world.query(Enemy).count():
            request_state(world, Game.OVER)

    app.on_enter(Game.MENU, lambda world, dt: log.append("enter menu"))
    app.on_enter(Game.PLAYING, spawn_enemies)
    app.on_exit(Game.PLAYING, lambda world, dt: log.append("exit playing"))
    app.on_enter(Game.OVER, lambda world, dt: log.append("game over"))
    app.add_systems("update", fight, run_if=in_state(Game.PLAYING))
    app.add_systems("update", director)
    counted = []
    app.add_observer(OnAdd(Enemy), lambda world, trigger: counted.append(len(trigger.entities)))
    app.run(frames=8)
    assert log == [
        "enter menu",  # frame 1
        "enter playing",  # frame 2 (requested in frame 1)
        "fight",
        "exit playing",  # frame 3: paused, no fight
        "enter playing",  # frame 5: 3 more enemies at 2 hp
        "fight",
        "fight",
        "exit playing",  # frame 7: the first three are at 0 hp: game over
        "game over",
    ]
    assert counted == [3, 3]  # in bulk, once per spawn_batch
    assert app.systems()["spawn_enemies"] == "on_enter Game.PLAYING"


def test_an_on_enter_system_is_replaced_by_name():
    app = App(title="Swap").add_plugins(MinimalPlugins).init_state(Game.MENU)
    seen = []

    def greet(world, dt):
        seen.append("old")

    app.on_enter(Game.MENU, greet)

    def greet_again(world, dt):
        seen.append("new")

    app.replace_system("greet", greet_again)
    app.run(frames=2)
    assert seen == ["new"] and app.systems()["greet_again"] == "on_enter Game.MENU" and "greet" not in app.systems()


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda app: app.init_state(3), "takes a member of an Enum class (a state), got int 3"),
        (lambda app: app.on_enter("menu", print), "on_enter takes a member of an Enum class"),
        (lambda app: app.on_exit(Game.MENU), "on_exit(<Game.MENU: 1>) was given no systems"),
        (lambda app: app.add_observer(Enemy, print), "OnAdd"),
    ],
)
def test_bad_game_structure_input_is_one_usage_error(build, message):
    app = App(title="Bad").add_plugins(MinimalPlugins)
    with pytest.raises(UsageError) as caught:
        build(app)
    assert message in str(caught.value) and "\n" not in str(caught.value)
    assert app.systems().keys() <= {
        "snapshot",
        "orbit",
        "motion",
        "spring",
        "animation",
        "animation_layers",
        "render_origin",
        "transform",
        "hierarchy",
        "skins",
    }
