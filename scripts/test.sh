#!/usr/bin/env bash
# Runs every test of the project on a fresh machine: it first installs what the tests
# need (the Khronos glTF validator from npm, Blender's bpy module from PyPI in a local
# virtualenv, Chromium from Debian's packages), then formatting, lints, the unit and
# integration tests (including the ignored ones: the validator, the Blender cross-check
# and video, the report page in headless Chromium) and a build of the benchmarks. This is the README's test command; CI (.ci/run) calls it.
set -euo pipefail
cd "$(dirname "$0")/.."

# The builds and bpy need about 7 GB (README); a full disk would otherwise show only as a
# failed link a quarter of an hour in. What is already built or installed here counts.
need_kb=$((7 * 1024 * 1024))
free_kb=$(df -Pk . | awk 'NR == 2 { print $4 }')
built_kb=$({ du -sk target .venv-blender 2>/dev/null || true; } | awk '{ s += $1 } END { print s + 0 }')
have_kb=$((free_kb + built_kb))
if [ "$have_kb" -lt "$need_kb" ]; then
    echo "scripts/test.sh: $(pwd) has $((have_kb / 1024)) MB free (counting target/ and .venv-blender/)," \
        "and the tests need about $((need_kb / 1024)) MB; free some disk and run again" >&2
    exit 1
fi

echo "== setup: Khronos glTF validator (npm, pinned by tools/gltf-validator/package-lock.json)"
(cd tools/gltf-validator && npm ci --no-audit --no-fund --loglevel=error)
echo "== setup: Blender bpy in .venv-blender (PyPI, pinned by blender/requirements.txt)"
bash blender/setup_venv.sh

echo "== setup: Chromium (Debian's package) for the report page's browser test"
if ! command -v chromium >/dev/null; then
    if [ "$(id -u)" -eq 0 ]; then
        apt-get update && apt-get install -y chromium
    else
        sudo apt-get update && sudo apt-get install -y chromium
    fi
fi

echo "== cargo fmt --check"
cargo fmt --check
echo "== cargo clippy"
cargo clippy --all-targets --locked -- -D warnings
echo "== cargo doc (its links checked)"
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --locked --document-private-items
# The tests that need the validator or bpy are #[ignore]d so that a plain `cargo test`
# lists them as ignored; --include-ignored runs them too, for real (a missing tool fails).
echo "== cargo test (with the ignored Blender and validator tests: --include-ignored)"
cargo test --locked -- --include-ignored --skip fuzz::
# The fuzz harness on its own, with its output, so that its "N/M handled cleanly" lines
# show in the log.
echo "== fuzz harness"
cargo test --locked --test integration fuzz:: -- --nocapture --test-threads 1
echo "== cargo bench --no-run"
cargo bench --no-run --locked
