"""The files a run writes (`--screenshot`, `--perf-json`, `--trace`, `--record-input`, `--audio-out`),
checked before its first frame, so a long run never ends by failing to write, and never by destroying a user's file.

Each output is refused, in one line naming it, when: its path is empty or a folder; its folder
does not exist or cannot be written; a screenshot's name does not end in .png (it is always
written as PNG); it is also one of the run's inputs (a model, a sky, a scene file, the input
script: a run never writes over what it reads) or another of its outputs; or a file is there
that is not of the kind written (a PNG for the screenshot, a perf log for --perf-json, a trace
for --trace, an input script for --record-input, a WAV file for --audio-out): a scene, a script
or a photo is not replaced without `--force`.
An empty file is replaced: nothing is lost; a device or a pipe (/dev/null) never is.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import UsageError
from .scenes import is_scene_file

if TYPE_CHECKING:
    from .settings import RunOptions

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def is_png(path: Path) -> bool:
    with open(path, "rb") as f:
        return f.read(len(PNG_SIGNATURE)) == PNG_SIGNATURE


def is_perf_log(path: Path) -> bool:
    """A file `--perf-json` wrote (app/perf.py's document)."""
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except (ValueError, UnicodeDecodeError):
        return False
    return isinstance(doc, dict) and {"schema_version", "meta", "frames"} <= doc.keys()


def is_trace(path: Path) -> bool:
    """A file `--trace` wrote (app/trace.py's Chrome trace-event document)."""
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except (ValueError, UnicodeDecodeError):
        return False
    return isinstance(doc, dict) and "traceEvents" in doc


def is_wav(path: Path) -> bool:
    """A RIFF/WAVE file (what --audio-out writes)."""
    with open(path, "rb") as f:
        head = f.read(12)
    return head[:4] == b"RIFF" and head[8:12] == b"WAVE"


def is_input_script(path: Path) -> bool:
    """A file of input events (app/input_script.py's format) with at least one event, or a
    recording (which may have none)."""
    from .input_script import InputRecorder, read_script

    try:
        script = read_script(path)
        with open(path, encoding="utf-8") as f:
            first = f.readline().rstrip("\n")
    except (UsageError, OSError, UnicodeDecodeError):
        return False
    return bool(script.events) or first == InputRecorder(path).lines[0]  # the recorder's header


# flag -> (what it writes, in words; how to recognise a file of that kind; the kind, in words)
OUTPUTS: dict[str, tuple[str, Callable[[Path], bool], str]] = {
    "--screenshot": ("the screenshot", is_png, "a PNG image"),
    "--perf-json": ("the performance log", is_perf_log, "a --perf-json log"),
    "--trace": ("the trace", is_trace, "a --trace file"),
    "--record-input": ("the input recording", is_input_script, "an input script"),
    "--audio-out": ("the sound capture", is_wav, "a WAV file"),
}


def check_outputs(outputs: dict[str, str | None], inputs: dict[str, str | None], force: bool = False) -> None:
    """UsageError, in one line naming the flag and the path, for the first output that cannot
    or must not be written. `outputs`: flag -> path or None; `inputs`: what the file is ("the
    model") -> path or None."""
    written: dict[str, str] = {}
    for flag, path in outputs.items():
        if path is None:
            continue
        what, _, _ = OUTPUTS[flag]
        if not str(path):
            raise UsageError(f"{flag}: the path for {what} is empty")
        for other, other_path in [*inputs.items(), *((f"the {f}", p) for f, p in written.items())]:
            if other_path is not None and same_file(path, other_path):
                raise UsageError(f"{flag} {path} is also {other}: a run does not write over a file it uses")
        check_writable(flag, Path(path), force)
        written[flag] = path


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """The same file, by resolved path or (both existing) by device and inode (a link, a
    second name)."""
    if Path(a).resolve() == Path(b).resolve():
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def check_writable(flag: str, target: Path, force: bool) -> None:
    what, is_kind, kind = OUTPUTS[flag]
    if target.is_dir():
        raise UsageError(f"{flag} {target}: is a directory, not a file to write {what} to")
    if flag == "--screenshot" and target.suffix.lower() != ".png":
        raise UsageError(f"{flag} {target}: screenshots are written as PNG; give a name ending in .png")
    if not target.parent.is_dir():
        raise UsageError(f"{flag} {target}: cannot write {what} there: folder {target.parent} does not exist")
    if target.exists():
        # a device or a pipe (/dev/null) would be replaced by a file: the perf log is renamed over its target
        if not target.is_file():
            raise UsageError(f"{flag} {target}: not a regular file; {what} is written as one")
        if not os.access(target, os.W_OK):
            raise UsageError(f"{flag} {target}: cannot write {what} there: the file is read-only")
        if not force and target.stat().st_size and not _is(is_kind, target):
            raise UsageError(
                f"{flag} {target}: the file there is not {kind}; not replacing it with {what} "
                "(choose another path, or add --force)"
            )
    probe_write(target, f"{flag} {target}", what)


def probe_write(target: Path, label: str, what: str) -> None:
    """Refuse (one line starting with `label`) a path whose folder a file cannot be made in: a
    probe file is made and removed beside it, the target itself left as it is."""
    probe = target.with_name(f".{target.name}.{os.getpid()}.probe")
    try:
        with open(probe, "w"):
            pass
        probe.unlink()
    except OSError as exc:
        raise UsageError(f"{label}: cannot write {what} there: {exc.strerror or exc}") from None


def write_json_file(target: Path, document: Any, label: str, what: str) -> None:
    """`document` as JSON, written to a temporary file beside `target` and renamed over it (a
    reader or a crash never sees half a file); an OSError is one line starting with `label`."""
    tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            json.dump(document, f, allow_nan=False)
        os.replace(tmp, target)
    except BaseException as exc:
        try:
            tmp.unlink()
        except OSError:
            pass
        if isinstance(exc, OSError):
            raise UsageError(f"{label}: cannot write {what}: {exc.strerror or exc}") from None
        raise


def _is(is_kind: Callable[[Path], bool], target: Path) -> bool:
    try:
        return is_kind(target)
    except OSError:  # unreadable: not known to be of the kind, so not replaced
        return False


def check_run_files(options: RunOptions) -> None:
    """The run's outputs against each other, its inputs and what is on disk (check_outputs)."""
    scene_files = [s for s in (options.scene, *options.scenes) if is_scene_file(s)]
    path_is = {"model": "the model", "environment": "the sky"}.get(options.scene, "the scene's PATH")
    inputs = {"the --input-script": options.input_script, path_is: options.path}
    inputs.update({f"the scene file {s}": s for s in scene_files})
    outputs = {
        "--screenshot": options.screenshot,
        "--perf-json": options.perf_json,
        "--trace": options.trace,
        "--record-input": options.record_input,
        "--audio-out": options.audio_out,
    }
    check_outputs(outputs, inputs, options.force)
