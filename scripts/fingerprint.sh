#!/usr/bin/env bash
# Fingerprint of what `bsa` produces, to show that a change kept behaviour bit for bit:
#
#     bash scripts/fingerprint.sh BSA_BINARY OUT_DIR [seeds...]     # default seeds: 1 2 3
#     diff -r OUT_A OUT_B                                           # empty: identical
#
# For every scene under scenes/ and every seed it solves (on all cores), then keeps
# solution.json without its timing fields (wall times, time per phase, threads, the
# scene path), the SHA-256 of convergence.csv, shadow.png, overlay.png,
# launch.csv, trajectory.csv and the glb, and the output of `bsa eval` and `bsa check`.
# It also keeps `--help` of bsa and of every subcommand. Timing lines are dropped from
# what the commands print; everything else is compared as is.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "$1")
out=$2
shift 2
seeds=("$@")
[ ${#seeds[@]} -eq 0 ] && seeds=(1 2 3)
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# clap prints the binary's file name in its usage lines: call it `bsa` whatever its path.
ln -s "$bin" "$work/bsa"
bin=$work/bsa

"$bin" --help >"$out/help.txt"
for sub in check solve eval export validate video budget; do
    "$bin" "$sub" --help >"$out/help-$sub.txt"
done

# Lines that carry a wall time or a rate differ from run to run; the rest must not.
# The temporary output folder's name differs too.
untimed() { sed -E -e 's/[0-9][0-9.,]* ?(ms|us|µs|s|samples\/s|\/s)\b/<time>/g' -e "s|$work|<out>|g"; }

for dir in scenes/*/; do
    [ -f "$dir/scene.json" ] || continue
    name=$(basename "$dir")
    "$bin" check "$dir" 2>&1 | untimed >"$out/check-$name.txt"
    for seed in "${seeds[@]}"; do
        o=$work/$name-$seed
        "$bin" solve "$dir" --seed "$seed" --out "$o" -q >"$out/solve-$name-$seed.txt" 2>&1
        python3 - "$o/solution.json" >"$out/solution-$name-$seed.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
for k in ("wall_time_s", "time_per_term_us", "threads", "scene_file"):
    s.pop(k, None)
for st in s.get("stages", []):
    st.pop("wall_time_s", None)
print(json.dumps(s, indent=1, sort_keys=True))
PY
        (cd "$o" && sha256sum convergence.csv shadow.png overlay.png launch.csv trajectory.csv ./*.glb) \
            >"$out/files-$name-$seed.txt"
        "$bin" eval "$dir" --solution "$o/solution.json" 2>&1 | untimed >"$out/eval-$name-$seed.txt"
        untimed <"$out/solve-$name-$seed.txt" >"$out/solve-$name-$seed.tmp" &&
            mv "$out/solve-$name-$seed.tmp" "$out/solve-$name-$seed.txt"
        echo "$name seed $seed: $(grep -o '"iou": [0-9.]*' "$out/solution-$name-$seed.json" | tail -1)"
    done
done
