"""The renderer's post effects (a part of Renderer, through render/frame/target_forms.py's base):
which are on, their settings, and the effect objects the output passes run.

    renderer.set_post_effects({"bloom", "fxaa"})                   # from the next frame
    renderer.set_post_effects({"bloom"}, {"bloom": BloomSettings(intensity=0.3)})
    renderer.post_settings["bloom"] = BloomSettings(intensity=0.05)  # the effect made again if on

The names are post/registry.py's; a frame runs the "hdr" stage's effects on the HDR colour
before the tone map (OutputPasses.post) and the "ldr" stage's after it (render/passes/output_graph.py), each
stage in registration order. Any effect on needs the HDR colour, so the target's form follows
(target_forms._wanted_form). Frame replay's key holds each effect's key (`post_key`): a frame
recorded with other effects or settings is never submitted again.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Mapping
from typing import Any

from ...errors import UsageError
from ..config import RenderConfig, check
from .registry import kind, ordered


class PostSettings(dict[str, Any]):
    """`renderer.post_settings`: effect name -> its settings (absent: the defaults). Setting one
    checks its class and, if the effect is on, makes it again with them."""

    def __init__(self, owner: PostEffects) -> None:
        super().__init__()
        self._owner = owner

    def __setitem__(self, name: str, value: Any) -> None:
        self._owner.set_post_effects(self._owner.post_effects, {name: value})

    def __delitem__(self, name: str) -> None:
        self._owner.set_post_effects(self._owner.post_effects, {name: None})


def _split(post: Iterable[str] | Mapping[str, Any]) -> tuple[set[str], dict[str, Any]]:
    """Names and settings from a set of names or a mapping name -> settings (None: defaults)."""
    if isinstance(post, str):
        raise UsageError(f"post effects are a set of names, got {post!r}")
    if isinstance(post, Mapping):
        return set(post), {n: s for n, s in post.items() if s is not None}
    return set(post), {}


class PostEffects:
    """Renderer's post-effect methods; `device`, `output`, `target` and `ensure_output` are the
    renderer's."""

    device: Any
    output: Any
    target: Any
    post_effects: tuple[str, ...] = ()  # on, in the order a frame runs them
    post_settings: PostSettings
    _post_made: dict[str, Any]

    def ensure_output(self) -> None:
        raise NotImplementedError  # target_forms.py's

    def _post_init(self, post: Iterable[str] | Mapping[str, Any]) -> None:
        """The effects asked for when the renderer is made, checked before anything is (the
        target's first form follows them); made by `_post_make` once the output passes are."""
        self.post_settings = PostSettings(self)
        self._post_made = {}
        names, settings = _split(post)
        wanted = ordered(names)
        self._post_check(wanted)
        for name, value in settings.items():
            dict.__setitem__(self.post_settings, name, kind(name).check_settings(value))
        self.post_effects = wanted

    def _post_check(self, wanted: tuple[str, ...]) -> None:
        """The config table's refusals of these effects on this target (SSAO with MSAA)."""
        check(RenderConfig(post=frozenset(wanted), msaa=self.target.samples), only=("post",))

    def _post_make(self) -> None:
        self._post_apply(self.post_effects, ())

    def set_post_effects(
        self, names: Iterable[str] | Mapping[str, Any], settings: Mapping[str, Any] | None = None
    ) -> None:
        """Run the post effects `names` (a set, or a mapping name -> settings) from the next
        frame, with `settings` by name (None: the defaults; kept for later). An unknown name or
        settings of another class: UsageError, nothing changed."""
        wanted_names, given = _split(names)
        given.update(settings or {})
        wanted = ordered(wanted_names)
        self._post_check(wanted)
        checked = {name: kind(name).check_settings(value) for name, value in given.items()}
        changed = {n for n, v in checked.items() if self.post_settings.get(n, kind(n).settings()) != v}
        for name, value in given.items():
            if value is None:
                dict.pop(self.post_settings, name, None)
            else:
                dict.__setitem__(self.post_settings, name, checked[name])
        if wanted == self.post_effects and not changed & set(wanted):
            return
        self._post_apply(wanted, changed)
        self.ensure_output()  # the hdr form while any is on

    def _post_apply(self, wanted: tuple[str, ...], remake: Iterable[str]) -> None:
        made = self._post_made
        going = [n for n in made if n not in wanted or n in remake]
        if going:
            self.device.wait_idle()  # frames in flight may use them
        kept = {n: e for n, e in made.items() if n not in going}
        try:
            for name in wanted:
                if name not in kept:
                    effect_kind = kind(name)
                    kept[name] = effect_kind.make(self.device, self.post_settings.get(name) or effect_kind.settings())
        except BaseException:
            for name, effect in kept.items():
                if name not in made:
                    effect.destroy()
            raise
        hdr, ldr = ([kept[n] for n in wanted if kind(n).stage == stage] for stage in ("hdr", "ldr"))
        self.output.set_post(hdr, ldr)
        for name in going:
            made[name].destroy()
        self._post_made = {n: kept[n] for n in wanted}
        self.post_effects = wanted

    def post_key(self) -> Hashable:
        """What the post effects recorded into a frame depend on (frame_replay.py): each effect's
        key of this frame's inputs (OutputPasses.begin_post: SSAO's holds the projection)."""
        made, inputs = self._post_made, self.output.inputs
        return tuple((name, made[name].key(inputs)) for name in self.post_effects if name in made)
