"""Write shaders/layouts.glsl from ecs_engine/render/layouts.py, compile shaders/*.vert|frag|comp
to SPIR-V with glslc and record shaders/manifest.json.

The manifest holds, per shader, the sha256 of its source together with the shared includes
(*.glsl) and of the SPIR-V written; tests/test_shaders.py fails when a source no longer matches
its manifest entry (a stale .spv), without depending on the exact glslc version, and when
layouts.glsl differs from what the dtypes give.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path

SHADERS = Path(__file__).resolve().parent.parent / "shaders"
STAGES = (".vert", ".frag", ".comp", ".rgen", ".rmiss", ".rchit", ".rahit")
LAYOUTS = SHADERS / "layouts.glsl"


def source_digest(src: Path) -> str:
    h = hashlib.sha256(src.read_bytes())
    for include in sorted(SHADERS.glob("*.glsl")):
        h.update(include.name.encode())
        h.update(include.read_bytes())
    return h.hexdigest()


def main() -> int:
    try:
        version = subprocess.run(
            ["glslc", "--version"], capture_output=True, text=True, check=True
        ).stdout.splitlines()[0]
    except (OSError, subprocess.CalledProcessError):
        print("compile_shaders: glslc not found: sudo apt-get install -y glslc", file=sys.stderr)
        return 2
    from ecs_engine.render import layouts

    LAYOUTS.write_text(layouts.glsl())
    manifest = {"glslc": version, "shaders": {}}
    for src in sorted(p for p in SHADERS.iterdir() if p.suffix in STAGES):
        out = src.with_name(src.name + ".spv")
        subprocess.run(["glslc", "--target-env=vulkan1.2", "-O", str(src), "-o", str(out)], check=True)
        manifest["shaders"][src.name] = {
            "source_sha256": source_digest(src),
            "spirv_sha256": hashlib.sha256(out.read_bytes()).hexdigest(),
        }
    (SHADERS / "manifest.json").write_text(json.dumps(manifest, indent=2) + "\n")
    print(f"compiled {len(manifest['shaders'])} shaders with {version}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
