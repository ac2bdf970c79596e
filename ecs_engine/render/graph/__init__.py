"""The frame graph: passes declare the images and buffers they read and write; the graph orders
them, culls what no output needs, allocates transient resources (aliasing memory where lifetimes
do not overlap) and records the barriers between them. See docs/frame-graph.md."""

from .barriers import Barrier
from .builder import SETUP_EACH_COMPILE, UNREPLAYABLE, Pass, PassBuilder
from .context import PassContext
from .graph import FrameGraph
from .resources import Access, BufferDesc, GraphBuffer, GraphImage, ImageDesc, Load

__all__ = [
    "SETUP_EACH_COMPILE",
    "UNREPLAYABLE",
    "Access",
    "Barrier",
    "BufferDesc",
    "FrameGraph",
    "GraphBuffer",
    "GraphImage",
    "ImageDesc",
    "Load",
    "Pass",
    "PassBuilder",
    "PassContext",
]
