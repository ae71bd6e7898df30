#!/usr/bin/env bash
# Sets up (scripts/setup.sh) and renders the demo scene scenes/demo.xml into out/demo.png
# on the default device (the first GPU, else PoCL's CPU device).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
./build/clrt render scenes/demo.xml -o out "$@"
echo "demo: wrote out/demo.png"
