#!/usr/bin/env bash
# Wall time of the example solves, the paper's Table 3 "total running time":
#
#     bash scripts/bench-solves.sh [seeds...]      # default seeds: 1 2 3
#
# Builds the release binary, then solves every scene under scenes/ and the hand-made
# examples under benches/hand-made/ (named <scene>-hand-made; "Pay only for what varies"
# set its wall-time targets on them, before `bsa new` designed the examples) once per
# seed on all cores (results in /tmp/bsa-bench/<scene>-<seed>/, not in export/) and prints one line
# per solve: IoU at t, contacts, samples, iterations and the solver's own wall time.
# SCENES="mickey fly" solves only those (labels as printed, e.g. fly-hand-made).
# Targets (issue "four examples"): mickey <= 5 s, fly <= 10 s, tbc <= 27 s,
# thinker <= 4 min on 2 cores. Every solve is also a row of results/bench.csv
# (scripts/ledger.sh: set_or_seed the seed, item the scene, route solve).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ledger.sh
seeds=("$@")
[ ${#seeds[@]} -eq 0 ] && seeds=(1 2 3)
cargo build --release --locked --quiet
mkdir -p /tmp/bsa-bench
for dir in scenes/*/ benches/hand-made/*/; do
    [ -f "$dir/scene.json" ] || continue
    name=$(basename "$dir")
    case $dir in benches/*) label=$name-hand-made ;; *) label=$name ;; esac
    if [ -n "${SCENES:-}" ] && [[ " $SCENES " != *" $label "* ]]; then continue; fi
    for seed in "${seeds[@]}"; do
        out=/tmp/bsa-bench/$label-$seed
        ./target/release/bsa solve "$dir" --seed "$seed" --out "$out" -q --report >"$out.log" 2>&1 ||
            { echo "$name seed $seed: solve failed, see $out.log"; exit 1; }
        echo "seed $seed  $label$(grep -E "^$name: IoU" "$out.log" | sed "s/^$name//")"
        python3 - "$out/solution.json" <<'PY' | { read -r iou contacts samples wall
import json, sys
s = json.load(open(sys.argv[1]))
print(f"{s['iou']:.4f} {s['n_contacts']} {s['samples']} {s['wall_time_s']:.2f}")
PY
            ledger_row bench "$seed" "$label" solve "$iou" "$contacts" "$samples" "$wall"; }
    done
done
