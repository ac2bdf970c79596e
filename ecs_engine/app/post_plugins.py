"""Post effects as App plugins: one line turns one on.

    app.add_plugins(DefaultPlugins, SsaoPlugin(), BloomPlugin(), FxaaPlugin())
    app.add_plugins(BloomPlugin(BloomSettings(intensity=0.3)))
    app.add_plugins(PostEffectPlugin("ssao"))      # any registered effect by name (one such plugin an App)

When the run opens, the plugin adds its effect to the renderer's (`Renderer.set_post_effects`,
render/post/effects.py), with its settings; the command line's `--post` and the editor's
toggles go through the same call. Without RenderPlugin nothing is drawn, and nothing is added.
"""

from __future__ import annotations

from typing import Any

from .plugins import App, Plugin, Session


class PostEffectPlugin(Plugin):
    """The post effect `effect` (render/post/registry.py's name) with `settings` (None: its
    defaults); an unknown name or settings of another class is a UsageError when built."""

    effect: str = ""

    def __init__(self, effect: str | None = None, settings: Any = None) -> None:
        self.effect = effect if effect is not None else type(self).effect
        self.settings = settings

    def build(self, app: App) -> None:
        from ..render.post.registry import kind

        name = self.effect
        settings = kind(name).check_settings(self.settings)

        def turn_on(world: Any, session: Session) -> None:
            if app.renders:
                renderer = session.renderer
                renderer.set_post_effects({*renderer.post_effects, name}, {name: settings})

        app.on_open(turn_on)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.effect!r})"


class BloomPlugin(PostEffectPlugin):
    """Physically based bloom (render/post/bloom.py): `BloomPlugin(BloomSettings(...))`."""

    effect = "bloom"

    def __init__(self, settings: Any = None) -> None:
        super().__init__("bloom", settings)


class FxaaPlugin(PostEffectPlugin):
    """FXAA on the tone-mapped image, before the UI (render/post/fxaa.py): `FxaaPlugin(FxaaSettings(...))`."""

    effect = "fxaa"

    def __init__(self, settings: Any = None) -> None:
        super().__init__("fxaa", settings)


class SsaoPlugin(PostEffectPlugin):
    """Screen-space ambient occlusion from the scene's depth, before bloom (render/post/ssao.py):
    `SsaoPlugin(SsaoSettings(...))`; refused with MSAA (it reads single-sample depth)."""

    effect = "ssao"

    def __init__(self, settings: Any = None) -> None:
        super().__init__("ssao", settings)
