#!/usr/bin/env bash
# Runs every test of the project on a fresh machine: formatting, lints, the unit and
# integration tests, and a build of the benchmarks. This is the README's test command;
# CI (.ci/run) calls it. Everything it needs comes from crates.io through cargo.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== cargo fmt --check"
cargo fmt --check
echo "== cargo clippy"
cargo clippy --all-targets --locked -- -D warnings
echo "== cargo test"
cargo test --locked
echo "== cargo bench --no-run"
cargo bench --no-run --locked
