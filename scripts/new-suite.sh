#!/usr/bin/env bash
# The held-out pictures of `bsa new`: for every picture of
# tools/test-pictures/set-NN/manifest.json (drawn by `cargo run --release --example
# test_pictures`, each with its objects stated there before any solve), `bsa new` then `bsa solve`, no edits in between, and a
# table: picture, objects, start IoU, final IoU, contacts before t, wall time (new + solve,
# whole processes). The overlays are tiled into docs/images/new-suite[-auto].png.
#
#     bash scripts/new-suite.sh [SEED] [auto]      # defaults: seed 1, the stated boxes
#     SET=2 bash scripts/new-suite.sh 1             # set 2 (tools/test-pictures/set-02), or any other set-NN
#
# With `auto`, every picture gets one automatic item of its kind instead (auto:box of the
# unit block for the block pictures, auto:sphere for the sphere one, auto:chess for the
# chess ones) and the table gives the count chosen.
# Scenes and solves go to /tmp/bsa-new-suite[-2][-auto]/<picture>/ and <picture>-out/
# (with <picture>-new.log, what `bsa new` printed);
# the contact sheet to docs/images/new-suite[-2][-auto].png.
# OBJECTS="..." gives every picture these objects instead of its stated ones (ROUTE names
# them in the ledger, default "objects"; ROOT moves the scenes and solves).
# Every picture is also a row of results/new-suite.csv (scripts/ledger.sh: set_or_seed
# "set-NN/seed-S", item the picture, route stated or auto, seconds new + solve).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ledger.sh
seed=${1:-1}
mode=${2:-given}
cargo build --release --locked --quiet --bin bsa --example contact_sheet
bsa=$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')/release
sheet=$bsa/examples/contact_sheet
bsa=${BSA:-$bsa/bsa}
set_=${SET:-1}
pics=tools/test-pictures/set-$(printf %02d "$set_")
suffix=""
if [ "$set_" != 1 ]; then suffix=-$set_; fi
if [ "$mode" = auto ]; then suffix=$suffix-auto; fi
root=${ROOT:-/tmp/bsa-new-suite$suffix}
mkdir -p "$root"
rows=$root/results.tsv
: >"$rows"
overlays=()
while IFS=$'\t' read -r name objects options; do
    case "$name" in '#'*|'') continue ;; esac
    if [ "$mode" = auto ]; then
        case "$objects" in
            chess*) objects=auto:chess ;;
            sphere*) objects=auto:sphere ;;
            *) objects=auto:box:0.1397x0.06985x0.0349 ;;
        esac
    fi
    if [ -n "${OBJECTS:-}" ]; then objects=$OBJECTS; fi
    dir=$root/$name
    rm -rf "$dir" "$dir-out" "$dir-new.log"
    t0=$(date +%s.%N)
    # shellcheck disable=SC2086
    new=$("$bsa" new "$dir" --target "$pics/$name.png" --objects "$objects" --seed "$seed" $options)
    # What `bsa new` printed (its trial solves and the design kept), beside the solve's log.
    printf '%s\n' "$new" >"$dir-new.log"
    "$bsa" solve "$dir" -q --seed "$seed" --out "$dir-out" >"$dir-out.log"
    t1=$(date +%s.%N)
    start=$(sed -n 's/.*start guess IoU \([0-9.]*\).*/\1/p' <<<"$new")
    count=$(sed -n 's/^[^:]*: \([0-9]*\) objects\{0,1\} .*/\1/p' <<<"$new")
    python3 - "$dir-out/solution.json" "$name" "$objects" "$count" "$start" "$t0" "$t1" >>"$rows" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
name, objects, count, start, t0, t1 = sys.argv[2:8]
print("\t".join([name, objects, count, start, f"{s['iou']:.4f}", str(s["n_contacts"]),
                 f"{float(t1) - float(t0):.1f}"]))
PY
    tail -n 1 "$rows"
    IFS=$'\t' read -r _ _ _ _ final contacts wall < <(tail -n 1 "$rows")
    samples=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["samples"])' "$dir-out/solution.json")
    route=stated
    if [ "$mode" = auto ]; then route=auto; fi
    if [ -n "${OBJECTS:-}" ]; then route=${ROUTE:-objects}; fi
    ledger_row new-suite "set-$(printf %02d "$set_")/seed-$seed" "$name" "$route" "$final" \
        "$contacts" "$samples" "$wall"
    overlays+=("$dir-out/overlay.png")
done < <(python3 - "$pics/manifest.json" <<'PY'
import json, sys
for p in json.load(open(sys.argv[1]))["pictures"]:
    print("\t".join([p["name"], p["objects"], p.get("options", "")]))
PY
)
python3 - "$rows" <<'PY'
import statistics, sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1]) if l.strip()]
print()
print("| picture | objects | count | start IoU | final IoU | contacts before t | wall time (s) |")
print("|---|---|---|---|---|---|---|")
for r in rows:
    print("| " + " | ".join(r) + " |")
ious = [float(r[4]) for r in rows]
print()
print(f"final IoU: median {statistics.median(ious):.4f}, min {min(ious):.4f}, "
      f">= 0.90: {sum(i >= 0.90 for i in ious)} of {len(ious)}; "
      f"solves with a contact: {sum(r[5] != '0' for r in rows)}; "
      f"start IoU median {statistics.median(float(r[3]) for r in rows):.4f}")
PY
"$sheet" "${SHEET:-docs/images/new-suite$suffix.png}" 4 320 "${overlays[@]}"
