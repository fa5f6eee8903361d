#!/usr/bin/env bash
# Runs every test of the project on a fresh machine: it first installs what the tests
# need (the Khronos glTF validator from npm, Blender's bpy module from PyPI in a local
# virtualenv), then formatting, lints, the unit and integration tests (including the
# Blender cross-check and video) and a build of the benchmarks. This is the README's
# test command; CI (.ci/run) calls it.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== setup: Khronos glTF validator (npm, pinned by tools/gltf-validator/package-lock.json)"
(cd tools/gltf-validator && npm ci --no-audit --no-fund --loglevel=error)
echo "== setup: Blender bpy in .venv-blender (PyPI, pinned by blender/requirements.txt)"
bash blender/setup_venv.sh

echo "== cargo fmt --check"
cargo fmt --check
echo "== cargo clippy"
cargo clippy --all-targets --locked -- -D warnings
echo "== cargo test (with the Blender and validator tests: BSA_FULL_TESTS=1)"
BSA_FULL_TESTS=1 cargo test --locked
echo "== cargo bench --no-run"
cargo bench --no-run --locked
