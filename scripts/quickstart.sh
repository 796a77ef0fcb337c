#!/usr/bin/env bash
# The main job, from a bare Debian 12 machine: install dependencies, build, and run the paper
# reproduction on the built-in simulated robot. Results go to ./errfield-out.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# Only the command-line tool and the library it links: the tests, benchmarks and examples are
# built by scripts/test.sh (or a plain scripts/build.sh).
ERRFIELD_BUILD_TARGETS=errfield_cli bash scripts/build.sh
./build/errfield reproduce --out errfield-out "$@"
