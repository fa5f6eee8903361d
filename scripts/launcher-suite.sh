#!/usr/bin/env bash
# Designs a launcher can hit, measured: for the four examples' pictures with their objects
# (and any set of test pictures), `bsa new --launcher`, `bsa solve`, then `bsa budget` twice
# (P(IoU >= 0.9), and P(IoU >= IoU - 0.05) with the tolerance search). One row per picture
# is appended to results/launcher/suite.csv (a folder of its own: its columns are not the
# ledger's of results/*.csv):
#
#     bash scripts/launcher-suite.sh [SET]     # SET: also the pictures of tools/test-pictures/set-SET
#
# Env: BSA (the binary, default ./target/release/bsa, built), ROOT (the work folder, default
# a fresh temporary one, kept), LEDGER=0 (append nothing).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ledger.sh
if [ -z "${BSA:-}" ]; then cargo build --release --locked --quiet; fi
bsa=${BSA:-./target/release/bsa}
root=${ROOT:-$(mktemp -d)}
mkdir -p "$root"
unit=0.1397x0.06985x0.0349
double=0.2794x0.06985x0.0349
half=0.06985x0.0349x0.0349
run() { # name set target objects [options...]
    local name=$1 set=$2 target=$3 objects=$4
    shift 4
    local dir=$root/$name out=$root/$name-out t0 t1
    rm -rf "$dir" "$out"
    t0=$(date +%s.%N)
    "$bsa" new "$dir" --target "$target" --objects "$objects" "$@" --launcher >"$root/$name.new.log"
    t1=$(date +%s.%N)
    "$bsa" solve "$dir" --out "$out" -q >"$root/$name.solve.log"
    "$bsa" budget "$out" -q --search-samples 0 >"$root/$name.budget.log"
    cp "$out/budget.json" "$out/budget-0.9.json"
    local nominal
    nominal=$(python3 -c "import json; print(round(json.load(open('$out/solution.json'))['iou'] - 0.05, 4))")
    "$bsa" budget "$out" -q --iou-threshold "$nominal" >>"$root/$name.budget.log"
    python3 - "$dir" "$out" "$set" "$name" "$(python3 -c "print(f'{$t1 - $t0:.2f}')")" "$(ledger_commit)" "${LEDGER:-1}" <<'PY'
import csv, json, os, sys
scene, out, set_, name, seconds, commit, ledger = sys.argv[1:]
s = json.load(open(f"{out}/solution.json"))
b09 = json.load(open(f"{out}/budget-0.9.json"))
b = json.load(open(f"{out}/budget.json"))
needs = json.load(open(f"{out}/launcher.json"))
front = list(csv.DictReader(open(f"{scene}/frontier.csv")))
standard = max((r for r in front if r["posed"] == "false" and r["clear"] == "true"),
               key=lambda r: float(r["iou"]))
row = {
    "commit": commit, "set": set_, "item": name, "t_s": s["t_s"],
    "standard_iou": f"{float(standard['iou']):.4f}", "iou": f"{s['iou']:.4f}",
    "contacts": s["n_contacts"],
    "p_nominal_minus_0.05": f"{b['monte_carlo']['p_iou_at_least_threshold']:.4f}",
    "p_0.9": f"{b09['monte_carlo']['p_iou_at_least_threshold']:.4f}",
    "mean_iou_at_launcher": f"{b['monte_carlo']['mean']:.4f}",
    "launcher_factor": f"{needs['scale']:.4f}", "new_seconds": seconds,
}
print(" ".join(f"{k}={v}" for k, v in row.items()))
if ledger != "0":
    path = "results/launcher/suite.csv"
    new = not os.path.exists(path)
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(row))
        if new:
            w.writeheader()
        w.writerow(row)
PY
}
run mickey - scenes/mickey/target.png sphere:0.6,sphere:0.35*2 --width 4
run fly - scenes/fly/target.png "box:$double*2,box:$unit*4"
run tbc - scenes/tbc/target.png "box:$unit*6,box:$half*6"
run thinker - scenes/thinker/target.png chess --width 0.96 --light-height 3
if [ -n "${1:-}" ]; then
    set_dir=tools/test-pictures/set-$1
    python3 -c "
import json
for p in json.load(open('$set_dir/manifest.json'))['pictures']:
    print(p['name'], p['objects'], p.get('options', ''))" | while read -r name objects options; do
        # shellcheck disable=SC2086
        run "$name" "$1" "$set_dir/$name.png" "$objects" $options
    done
fi
echo "work folder: $root"
