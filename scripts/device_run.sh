#!/bin/bash
# The GPU host run for issue 14 (device tool): A/B of e7d674c against the working tree, the
# texture/material/HDR/cluster tests on NVIDIA, the materials demo under validation, bench lights. Prepare here, once:
#   .gl/  the Vulkan loader and validation layers as .deb files (the device README: apt-get download
#         libvulkan1 ... vulkan-validationlayers), .whl/ wheels of vulkan cffi pycparser glfw trimesh
#         imgui-bundle esper for Python 3.12, .ab/base = `git archive e7d674c` unpacked;
# then run `bash scripts/device_run.sh all` with carry [".gl", ".whl", ".ab/base"]. Results in $OUT.
set -u
export PYTHONUNBUFFERED=1
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export VK_LAYER_PATH=/usr/share/vulkan/explicit_layer.d
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 1
export PYTHONPATH=/tmp/site
python3 -m pip install -q --no-deps --no-build-isolation --no-index --target /tmp/new . >/dev/null 2>&1 || { echo "install new failed"; exit 1; }
python3 -m pip install -q --no-deps --no-build-isolation --no-index --target /tmp/old .ab/base >/dev/null 2>&1 || { echo "install old failed"; exit 1; }
{ nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; date -u +%FT%TZ; python3 --version; } > $OUT/machine.txt
cat $OUT/machine.txt
MODES=" ${*:-all} "  # any of: tests lights ab (or all)
want() { [[ "$MODES" == *" $1 "* || "$MODES" == *" all "* ]]; }
REPO=$PWD
if want tests; then
  # from a copy outside the checkout: in its root, `ecs_engine` would be the source folder, not the
  # installed package (whose components/ and systems/ live inside it)
  rm -rf /tmp/t && cp -r tests /tmp/t && cd /tmp
  PYTHONPATH=/tmp/new:/tmp/site timeout 400 python3 -m pytest -q -p no:cacheprovider /tmp/t/test_textures.py /tmp/t/test_model_loading.py /tmp/t/test_shading_models.py /tmp/t/test_materials.py /tmp/t/test_render.py /tmp/t/test_light_rows.py /tmp/t/test_primitives.py /tmp/t/test_fill.py /tmp/t/test_double_sided.py /tmp/t/test_hdr.py /tmp/t/test_light_clusters.py /tmp/t/test_deferred.py /tmp/t/test_transparency.py /tmp/t/test_editor.py > $OUT/gpu_tests.txt 2>&1
  tail -3 $OUT/gpu_tests.txt
  PYTHONPATH=/tmp/new:/tmp/site timeout 60 python3 -m ecs_engine demo materials --headless --frames 30 --width 1280 --height 720 --validate --screenshot $OUT/materials-h100.png 2>&1 | tail -3
  cd $REPO
fi
if want lights; then
  (cd /tmp && PYTHONPATH=/tmp/new:/tmp/site timeout 560 python3 -m ecs_engine.bench lights --out $OUT --machine h100-16c 2>&1 | grep -v "^\[lights" | tail -14)
fi
if want ab; then
  for rep in 1 2 3 4; do
    if [ $((rep % 2)) = 1 ]; then order="new old"; else order="old new"; fi
    for v in $order; do
      (cd /tmp && PYTHONPATH=/tmp/$v:/tmp/site timeout 150 python3 $REPO/scripts/ab_frames.py $v $rep 1280x720 >> $OUT/ab.jsonl 2>> $OUT/ab.err)
    done
  done
  wc -l $OUT/ab.jsonl
fi
