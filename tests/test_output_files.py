"""What a run may write over (app/output_files.py): its outputs never replace a file of another
kind or one of its inputs, and a path that cannot be written is refused before the first frame.
(The CLI's side of it, exit 2 and the file as it was: tests/test_cli_render.py.)"""

from __future__ import annotations

import json
import os

import pytest

from ecs_engine.errors import UsageError


def check_outputs(outputs, inputs, force=False):
    from ecs_engine.app.output_files import check_outputs

    check_outputs(outputs, inputs, force)


PNG = b"\x89PNG\r\n\x1a\n" + b"\x00" * 32


def refused(outputs, inputs=None, force=False, match=""):
    with pytest.raises(UsageError, match=match) as caught:
        check_outputs(outputs, inputs or {}, force)
    assert "\n" not in str(caught.value)
    return str(caught.value)


def test_a_file_of_the_kind_written_is_replaced_another_kind_only_with_force(tmp_path):
    png, perf, script, recording, empty = (tmp_path / n for n in ("a.png", "p.json", "s.txt", "r.txt", "e.txt"))
    png.write_bytes(PNG)
    perf.write_text(json.dumps({"schema_version": 1, "meta": {}, "frames": []}))
    script.write_text("# a hand-written script\n10 down w\n")
    recording.write_text("# recorded by ecs-engine --record-input: frame action arguments\n")  # a run without input
    empty.write_text("")
    check_outputs({"--screenshot": str(png), "--perf-json": str(perf), "--record-input": str(script)}, {})
    check_outputs({"--record-input": str(recording)}, {})
    check_outputs({"--perf-json": str(empty)}, {})  # nothing to lose
    text_png, scene = tmp_path / "notes.png", tmp_path / "level.scene"
    text_png.write_text("not an image")
    scene.write_bytes(b"PK\x03\x04 a saved scene")
    for flag, path, kind in (
        ("--screenshot", text_png, "a PNG image"),
        ("--perf-json", script, "a --perf-json log"),
        ("--record-input", scene, "an input script"),
        ("--record-input", perf, "an input script"),
    ):
        message = refused({flag: str(path)}, match=f"the file there is not {kind}")
        assert message.startswith(f"{flag} {path}:") and "--force" in message
        check_outputs({flag: str(path)}, {}, force=True)
    assert text_png.read_text() == "not an image" and scene.read_bytes() == b"PK\x03\x04 a saved scene"


def test_an_output_is_never_an_input_or_another_output(tmp_path):
    script = tmp_path / "s.txt"
    script.write_text("10 down w\n")
    link = tmp_path / "link.txt"
    link.symlink_to(script)
    inputs = {"the --input-script": str(script)}
    refused({"--record-input": str(script)}, inputs, force=True, match="is also the --input-script")
    refused({"--record-input": str(link)}, inputs, force=True, match="is also the --input-script")  # by inode
    relative = os.path.relpath(script)
    refused({"--perf-json": relative}, inputs, force=True, match="is also the --input-script")
    both = str(tmp_path / "out.png")
    refused({"--screenshot": both, "--perf-json": both}, match="--perf-json .* is also the --screenshot")
    refused({"--screenshot": str(tmp_path / "sky.png")}, {"the sky": str(tmp_path / "sky.png")}, match="the sky")


def test_a_folder_a_missing_folder_a_device_a_read_only_file_and_a_non_png_name(tmp_path):
    refused({"--perf-json": str(tmp_path)}, match="is a directory, not a file to write the performance log to")
    refused({"--record-input": str(tmp_path / "no" / "r.txt")}, match="folder .* does not exist")
    refused({"--screenshot": str(tmp_path / "shot.jpg")}, match="screenshots are written as PNG")
    refused({"--screenshot": ""}, match="the path for the screenshot is empty")
    refused({"--perf-json": os.devnull}, force=True, match="not a regular file")  # never renamed over
    png = tmp_path / "old.png"
    png.write_bytes(PNG)
    png.chmod(0o444)
    if os.geteuid() != 0:  # root may write anything
        refused({"--screenshot": str(png)}, force=True, match="the file is read-only")
        folder = tmp_path / "locked"
        folder.mkdir(mode=0o555)
        refused({"--perf-json": str(folder / "p.json")}, match="cannot write the performance log there")
