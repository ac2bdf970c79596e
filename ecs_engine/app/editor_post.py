"""The editor's post-effect toggles: one checkbox per registered effect (render/post/registry.py,
so a new effect gets its toggle with no change here), its description as the tooltip. The
names on go into the requested Settings; the session applies them with the renderer's one call
(`Renderer.set_post_effects`), as the command line's --post and the App's plugins do."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


def post_toggles(imgui: Any, post: frozenset[str], remember: Callable[[str], None]) -> frozenset[str]:
    """Draw the checkboxes; the effects on after this frame's clicks. `remember(label)` keeps
    each checkbox's place ("post NAME": where tests click)."""
    from ..render.post.registry import kinds

    on = set(post)
    imgui.separator()
    imgui.text("post effects")
    for name, kind in kinds().items():
        _, checked = imgui.checkbox(name, name in on)
        remember(f"post {name}")
        if kind.description and imgui.is_item_hovered():
            imgui.set_tooltip(kind.description)
        (on.add if checked else on.discard)(name)
    return frozenset(on)
