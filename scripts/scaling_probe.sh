#!/usr/bin/env bash
# A first look at thread scaling of the render jobs (the full sweep is `python -m bench scaling`,
# to come): the scaling scene at a few sizes, modes, recorders and thread counts, headless.
# Prints each run's last summary line.
set -u
run() { echo "== $*"; ecs_demo scaling --headless --width 640 --height 360 "$@" 2>&1 | tail -1; }
ecs_demo() { python3 -m ecs_engine demo "$@"; }
for n in 100000 1000000; do
  for mode in per_entity instanced; do
    for t in 1 4 16; do run --entities $n --mode $mode --recorder native --threads $t --frames 30; done
  done
done
run --entities 100000 --mode per_entity --recorder python --threads 1 --frames 6
run --entities 100000 --mode per_entity --recorder python --threads 16 --frames 6
