"""The frame's chunk jobs, handed to the worker pool in one batch (not one for the camera and
one for the shadows: the threads would wait at a barrier in between).

With shadow views and a camera path that records culled rows (the CPU-recorded paths,
chunk_paths.py's record_keyed), a chunk is one job for every view: its rows are culled against
the camera and each shadow view in one pass over their model matrices (shadow_pass.py's
record_chunk, instance_rows.cull_views), then each view's visible rows are written and
recorded. Chunks tagged NotShadowCaster are camera jobs of their own. A path that culls on the
GPU (indirect) has its chunks' rows culled on the GPU per shadow view too (shadow_indirect.py):
its chunks are camera jobs alone. The set-aside rows that cast (SetAsideRows.casters) are
shadow-only jobs in every mode.
"""

from __future__ import annotations

from typing import Any

from ..draw.path import ChunkResult, FrameInputs, RenderPath
from ..extract.frame_data import NOT_CASTER, Chunk
from ..shadows.maps_pass import ShadowPass

CAMERA, SHADOWS, BOTH = "camera", "shadows", "camera and shadows"


class FrameJobs:
    def __init__(
        self, path: RenderPath, inputs: FrameInputs, shadows: ShadowPass, chunks: list[Chunk], aside: list[Chunk]
    ) -> None:
        """`aside`: the set-aside rows as shadow casters (SetAsideRows.casters), shadow-only jobs."""
        self.path, self.inputs, self.shadows = path, inputs, shadows
        self.work: list[tuple[str, Chunk]] = [(CAMERA, c) for c in chunks]
        if shadows.active:
            casters = [not c.flags & NOT_CASTER for c in chunks]
            if hasattr(path, "record_keyed"):
                self.work = [(BOTH if caster else CAMERA, c) for caster, c in zip(casters, chunks, strict=True)]
            elif not shadows.culls_on_gpu:  # (the indirect mode's views cull the chunks' rows on the GPU)
                self.work += [(SHADOWS, c) for caster, c in zip(casters, chunks, strict=True) if caster]
            self.work += [(SHADOWS, c) for c in aside if not c.flags & NOT_CASTER]

    def run(self, item: tuple[str, Chunk]) -> tuple[ChunkResult | None, list[ChunkResult]]:
        """One job: (the camera's result or None, the shadow views' results)."""
        kind, chunk = item
        if kind == CAMERA:
            return self.path.record_chunk(chunk, self.inputs), []
        return self.shadows.record_chunk(chunk, (self.path, self.inputs) if kind == BOTH else None)

    def results(self, results: list[tuple[ChunkResult | None, list[ChunkResult]]]) -> tuple[list[ChunkResult], Any]:
        """The camera's results in chunk order (what the path's finish and counts take) and,
        per shadow view, the secondaries to execute."""
        camera = [r for r, _ in results if r is not None]
        return camera, self.shadows.collect([views for _, views in results if views])


def job_name(item: tuple[str, Chunk]) -> str:
    """A job's name in errors: the chunk's, and which views it records."""
    kind, chunk = item
    return chunk.name if kind == CAMERA else f"{chunk.name} ({kind})"


def run_jobs(
    jobs: Any, path: RenderPath, inputs: FrameInputs, shadows: ShadowPass, chunks: list[Chunk], aside: list[Chunk]
) -> tuple[list[ChunkResult], Any]:
    """The frame's jobs on `jobs` (a JobPool, or None: on this thread): FrameJobs.results' pair.
    A frame without shadow views (most) runs its camera's chunks alone, without the batch's
    bookkeeping."""
    if not shadows.active:
        record = path.record_chunk
        if jobs is None:
            return [record(chunk, inputs) for chunk in chunks], []
        return jobs.map(lambda chunk: record(chunk, inputs), chunks, _chunk_name), []
    work = FrameJobs(path, inputs, shadows, chunks, aside)  # one batch: camera and shadows
    done = jobs.map(work.run, work.work, job_name) if jobs is not None else list(map(work.run, work.work))
    return work.results(done)


def _chunk_name(chunk: Chunk) -> str:
    return chunk.name
