#!/usr/bin/env bash
# The planted suite: problems where IoU 1 is reachable by construction (`bsa plant`: a
# random contact-free launch whose shadow becomes the target, hints placed from the
# target as a user would), solved with the scenes' defaults, no per-problem settings.
#
#     bash scripts/planted-suite.sh [FIRST_SEED] [PER_CLASS]     # defaults: 1000 6
#
# Five classes, PER_CLASS problems each, seeds FIRST_SEED, FIRST_SEED + 1, ...:
#   spheres   3 to 6 spheres, radius 0.12 to 0.36 m, 4 m picture, light 6 m up
#   boxes     4 to 8 maple blocks of three sizes, 1.6 m picture
#   boxes12   8 to 12 such blocks, 2 m picture
#   chess     6 chess pieces (scenes/thinker/pieces), 0.96 m picture, light 3 m up
#   mix       2 or 3 spheres and 2 or 3 blocks, 1.6 m picture
# ROUTE=new takes the user's way instead: `bsa new` designs a scene from the planted
# target and the same objects (its own launch positions, hints, heights and trial solves),
# then `bsa solve` solves it; the wall time is then that of both commands.
# Problems and solves go to $ROOT/<class>-<seed>/ (ROOT defaults to /tmp/bsa-planted);
# CLASSES="chess mix" runs only those classes;
# BSA=PATH runs another binary (e.g. an older build, for a side-by-side comparison); prints one line per problem
# and a table per class: IoU (min / median / max), solves with a contact before t,
# samples and wall time (median). Every solve is also a row of results/planted.csv
# (scripts/ledger.sh: set_or_seed the draw's first seed, item "<class> <seed>", route
# plant or new; LEDGER_COMMIT=<commit> with BSA=..., LEDGER=0 for none).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ledger.sh
first=${1:-1000}
per=${2:-6}
if [ -z "${BSA:-}" ]; then cargo build --release --locked --quiet; fi
bsa=${BSA:-./target/release/bsa}
root=${ROOT:-/tmp/bsa-planted}
mkdir -p "$root"
results=$root/results.tsv
: >"$results"
pieces=scenes/thinker/pieces
inventory() { # class seed -> "objects width light"
    python3 - "$1" "$2" "$pieces" <<'PY'
import random, sys
cls, seed, pieces = sys.argv[1], int(sys.argv[2]), sys.argv[3]
r = random.Random(seed)
blocks = ["box:0.14x0.07x0.035", "box:0.28x0.07x0.035", "box:0.07x0.035x0.035"]
if cls == "spheres":
    n = r.randint(3, 6)
    items = [f"sphere:{r.uniform(0.12, 0.36):.3f}" for _ in range(n)]
    print(",".join(items), 4.0, 6.0)
elif cls == "boxes":
    n = r.randint(4, 8)
    print(",".join(r.choice(blocks) for _ in range(n)), 1.6, 6.0)
elif cls == "boxes12":
    n = r.randint(8, 12)
    print(",".join(r.choice(blocks) for _ in range(n)), 2.0, 6.0)
elif cls == "chess":
    names = ["king", "queen", "rook", "bishop", "knight", "pawn"]
    print(",".join(f"mesh:{pieces}/{p}.obj/900" for p in names), 0.96, 3.0)
else:
    s = [f"sphere:{r.uniform(0.05, 0.1):.3f}" for _ in range(r.randint(2, 3))]
    b = [r.choice(blocks) for _ in range(r.randint(2, 3))]
    print(",".join(s + b), 1.6, 6.0)
PY
}
for class in ${CLASSES:-spheres boxes boxes12 chess mix}; do
    for ((k = 0; k < per; k++)); do
        seed=$((first + k))
        dir=$root/$class-$seed
        rm -rf "$dir"
        read -r objects width light <<<"$(inventory "$class" "$seed")"
        if ! $bsa plant "$dir" --objects "$objects" --seed "$seed" --width "$width" \
            --light-height "$light" >"$dir.plant.log" 2>&1; then
            echo "$class seed $seed: plant failed: $(tail -1 "$dir.plant.log")"
            continue
        fi
        scene=$dir
        started=$(date +%s.%N)
        if [ "${ROUTE:-plant}" = new ]; then
            scene=$dir/new
            $bsa new "$scene" --target "$dir/target.png" --objects "$objects" --width "$width" \
                --light-height "$light" >"$dir.new.log" 2>&1 ||
                { echo "$class seed $seed: new failed, see $dir.new.log"; continue; }
        fi
        $bsa solve "$scene" --out "$scene/out" -q >"$dir.solve.log" 2>&1 ||
            { echo "$class seed $seed: solve failed, see $dir.solve.log"; continue; }
        ended=$(date +%s.%N)
        python3 - "$scene/out/solution.json" "$class" "$seed" "${ROUTE:-plant}" "$started" "$ended" \
            >>"$results" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
# The plant route reports the solver's own wall time; the new route both commands'.
wall = s["wall_time_s"] if sys.argv[4] != "new" else float(sys.argv[6]) - float(sys.argv[5])
print("\t".join(map(str, [sys.argv[2], sys.argv[3], s["iou"], s["n_contacts"], s["samples"],
                          wall, len(s["occluders"])])))
PY
        IFS=$'\t' read -r _ _ iou contacts samples wall _ < <(tail -1 "$results")
        ledger_row planted "$first" "$class $seed" "${ROUTE:-plant}" "$(printf %.4f "$iou")" \
            "$contacts" "$samples" "$(printf %.2f "$wall")"
        tail -1 "$results" | awk -F'\t' '{printf "%s seed %s: %d objects, IoU %.4f, %d contacts, %d samples, %.2f s\n", $1, $2, $7, $3, $4, $5, $6}'
    done
done
python3 - "$results" <<'PY'
import statistics, sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1]) if l.strip()]
print(f"\n{'class':<9} {'n':>3} {'IoU min':>8} {'median':>8} {'max':>8} {'contact':>8} {'samples':>8} {'wall s':>7}")
every = []
for cls in ["spheres", "boxes", "boxes12", "chess", "mix"]:
    r = [x for x in rows if x[0] == cls]
    if not r:
        continue
    iou = sorted(float(x[2]) for x in r)
    every += iou
    print(f"{cls:<9} {len(r):>3} {iou[0]:>8.4f} {statistics.median(iou):>8.4f} {iou[-1]:>8.4f} "
          f"{sum(int(x[3]) > 0 for x in r):>8} {statistics.median(int(x[4]) for x in r):>8.0f} "
          f"{statistics.median(float(x[5]) for x in r):>7.2f}")
if every:
    every.sort()
    print(f"{'all':<9} {len(every):>3} {every[0]:>8.4f} {statistics.median(every):>8.4f} {every[-1]:>8.4f}")
PY
