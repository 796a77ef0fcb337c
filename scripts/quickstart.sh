#!/usr/bin/env bash
# The main job, from a bare Debian 12 machine: install dependencies, build, and run the paper
# reproduction on the built-in simulated robot. Results go to ./errfield-out.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
./build/errfield reproduce --out errfield-out "$@"
