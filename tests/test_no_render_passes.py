"""Everything is drawn with dynamic rendering (vkCmdBeginRendering) between explicit barriers:
no source under ecs_engine/ makes a render pass or framebuffer or begins a render pass."""

from __future__ import annotations

from pathlib import Path

import ecs_engine

GONE = ("vkCreateRenderPass", "vkCreateFramebuffer", "vkCmdBeginRenderPass", "vkCmdNextSubpass")


def test_no_render_pass_or_framebuffer_is_made_or_begun():
    root = Path(ecs_engine.__file__).parent
    found = [
        f"{path.relative_to(root)}:{n}: {name}"
        for path in sorted(root.rglob("*.py"))
        for n, line in enumerate(path.read_text().splitlines(), 1)
        for name in GONE
        if name in line
    ]
    assert found == []
