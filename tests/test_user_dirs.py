"""Where the engine keeps its own files (user_dirs.py): a relative XDG_CACHE_HOME or
XDG_CONFIG_HOME is ignored, as the XDG spec says, and a headless editor never rewrites the
user's editor.ini."""

from __future__ import annotations


def test_a_relative_xdg_folder_is_ignored(tmp_path, monkeypatch):
    from ecs_engine.app.editor_dock import config_dir
    from ecs_engine.user_dirs import cache_home, config_home

    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CACHE_HOME", "cache")
    monkeypatch.setenv("XDG_CONFIG_HOME", "config")
    assert cache_home() == tmp_path / "home" / ".cache"
    assert config_home() == tmp_path / "home" / ".config" and config_dir() == config_home() / "ecs_engine"
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "abs"))
    assert cache_home() == tmp_path / "abs"


def test_the_pipeline_cache_ignores_a_relative_xdg_cache_home(tmp_path, monkeypatch):
    """XDG says a relative value is to be ignored: the cache goes to ~/.cache, never under the
    folder the command runs in."""
    from gpu_context import shared_device

    from ecs_engine.gpu.pipeline_cache import PipelineCache

    device = shared_device()
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("XDG_CACHE_HOME", "relative-cache")
    monkeypatch.chdir(tmp_path)
    cache = PipelineCache(device.vk, device.handle, device.info)
    cache.destroy()  # saves it
    assert cache.path.parent == tmp_path / "home" / ".cache" / "ecs_engine" and cache.path.is_file()
    assert not (tmp_path / "relative-cache").exists()


def test_a_headless_editor_leaves_the_users_layout_file_alone(config_home):
    from ecs_engine.app.editor_dock import layout_file
    from ecs_engine.app.loop import run
    from ecs_engine.app.settings import RunOptions

    mine = "[Window][Scene and render]\nPos=0,19\nSize=500,700\n"
    ini = layout_file()
    assert str(ini).startswith(str(config_home))  # the test's folder, never the real one
    ini.parent.mkdir(parents=True, exist_ok=True)
    ini.write_text(mine)
    before = ini.stat().st_mtime_ns
    options = RunOptions(scene="cube", editor=True, frames=2, width=96, height=64, quiet=True, threads=2)
    result = run(options)
    assert result.frames == 2 and result.validation_messages == []
    assert ini.read_text() == mine and ini.stat().st_mtime_ns == before
