#!/usr/bin/env bash
# Design the examples fly, tbc and THE THINKER with `bsa new`, from their target pictures
# and the objects of their boxes, with no hand work:
#
#     bash scripts/make-examples.sh [BSA_BINARY]      # about a minute on 2 cores
#
# Writes scenes/{fly,tbc,thinker}/{scene.json,start.png} in place (the targets stay; THE
# THINKER's pieces are the built-in chess set, the same files). `bsa new` is deterministic,
# so the committed scenes are what this prints. The objects are the ones the hand-made
# scenes had (benches/hand-made/, kept for the benchmarks of "Pay only for what varies"):
#   fly      two double units and four units (maple blocks, 2 3/4 x 1 3/8 inch section)
#   tbc      six units and six half pillars
#   thinker  one side of the chess set (16 pieces), a 0.96 m picture, the light 3 m up
# Mickey keeps the paper's geometry (scenes/mickey, written by hand).
# Every design is also a row of results/make-examples.csv (scripts/ledger.sh: item the
# scene, route new, iou the start guess's, contacts 0 when it has none before t,
# seconds those of `bsa new` with its trial solves).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ledger.sh
if [ -z "${1:-}" ]; then cargo build --release --locked --quiet; fi
bsa=${1:-./target/release/bsa}
unit=0.1397x0.06985x0.0349
double=0.2794x0.06985x0.0349
half=0.06985x0.0349x0.0349
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
design() { # name target objects [options...]
    local name=$1 target=$2 objects=$3
    shift 3
    # Into a fresh folder first: `bsa new` refuses to overwrite a scene.
    local t0 t1 printed
    t0=$(date +%s.%N)
    printed=$("$bsa" new "$work/$name" --target "$target" --objects "$objects" "$@")
    t1=$(date +%s.%N)
    printf '%s\n' "$printed"
    local contacts=""
    if grep -q "no contact before t" <<<"$printed"; then contacts=0; fi
    ledger_row make-examples - "$name" new \
        "$(sed -n 's/.*start guess IoU \([0-9.]*\).*/\1/p' <<<"$printed" | tail -1)" "$contacts" "" \
        "$(python3 -c "print(f'{$t1 - $t0:.2f}')")"
    cp "$work/$name/scene.json" "$work/$name/start.png" "scenes/$name/"
}
design fly scenes/fly/target.png "box:$double*2,box:$unit*4"
design tbc scenes/tbc/target.png "box:$unit*6,box:$half*6"
design thinker scenes/thinker/target.png chess --width 0.96 --light-height 3
