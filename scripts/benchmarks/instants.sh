#!/usr/bin/env bash
# The cost and the figures of several shadows per sample (issue #16), as docs/results.md
# reports them:
#
#     bash scripts/benchmarks/instants.sh [BSA_BINARY] [OUT_DIR]    # about 10 minutes
#
# For each use it solves (seed 1, all cores) and prints one line: the scene, the options,
# samples, shadows per sample, wall time (the solver's own, solution.json) and the IoU
# figures (worst frame of a hold window, every picture of a sequence). Then today's
# solutions of Mickey and fly over the hold windows (their launch tables rendered in a
# copy of the scene with `hold`), the air solves against the compensated tables of
# `bsa budget`, and the robust solves' budgets.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=$(realpath "${1:-target/release/bsa}")
out=${2:-/tmp/bsa-instants}
# The figures of docs/results.md were measured on the hand-made fly, tbc and THE THINKER
# (benches/hand-made), kept for them.
fly=benches/hand-made/fly
mkdir -p "$out"

line() { # name dir
    python3 - "$1" "$2/solution.json" <<'PY'
import json, sys
name, path = sys.argv[1], sys.argv[2]
s = json.load(open(path))
frames = s.get("frames", [])
pics = {}
for f in frames:
    pics.setdefault(f["picture"], []).append(f["iou"])
figs = "; ".join(
    f"picture {p + 1}: at t {max(v) if len(v) == 1 else v[len(v) // 2]:.4f}, worst {min(v):.4f} of {len(v)} frames"
    for p, v in sorted(pics.items())
) or f"IoU at t {s['iou']:.4f}"
print(f"{name:<34} samples {s['samples']:>7}  shadows/sample {s.get('shadows_per_sample') or 1:>3}  "
      f"wall {s['wall_time_s']:7.2f} s  contacts {s['n_contacts']}  {figs}")
PY
}

solve() { # name scene args...
    local name=$1 scene=$2
    shift 2
    "$bin" solve "$scene" --seed 1 --out "$out/$name" --force -q "$@" >/dev/null 2>&1
    line "$name" "$out/$name"
}

# A scene folder with one field of scene.json changed (python expression on `s`).
variant() { # name scene python-statement
    local d=$out/scenes/$1
    rm -rf "$d" && mkdir -p "$d" && cp -r "$2"/* "$d"/
    python3 - "$d/scene.json" "$3" "$(realpath "$2")" <<'PY'
import json, os, sys
s = json.load(open(sys.argv[1]))
# The copy lives elsewhere: the target is taken from the scene's own folder.
s["target"] = os.path.join(sys.argv[3], s["target"])
exec(sys.argv[2])
json.dump(s, open(sys.argv[1], "w"), indent=1)
PY
    echo "$d"
}

echo "== hold"
solve mickey scenes/mickey
solve mickey+hold-at-1.2 "$(variant mickey_h scenes/mickey 's["hold"] = {"window": 0.1, "fps": 60}')"
solve mickey_hold scenes/mickey_hold
solve fly "$fly"
solve fly+hold-at-1.2 "$(variant fly_h "$fly" 's["hold"] = {"window": 0.05, "fps": 60}')"
solve fly_hold scenes/fly_hold
echo "today's solutions over the windows (launch tables rendered with hold):"
for s in mickey fly; do
    "$bin" render "$out/scenes/${s}_h" --solution "$out/$s/launch.csv" --out "$out/$s-window" |
        grep -E "worst|per frame" | sed "s/^/  $s: /"
done

echo "== sequence"
solve sequence scenes/sequence
solve sequence-H-only "$(variant seq_h scenes/sequence 's["targets"] = s["targets"][1:]')"

echo "== air in the loop"
for s in mickey fly tbc thinker; do
    scene=benches/hand-made/$s
    [ "$s" = mickey ] && scene=scenes/mickey
    [ "$s" = mickey ] || [ "$s" = fly ] || solve "$s" "$scene"
    solve "$s+air" "$scene" --air
    "$bin" budget "$out/$s" --samples 100 --search-samples 0 -q >/dev/null
    python3 - "$out/$s/launch_drag.csv" "$out/$s+air/launch.csv" "$s" <<'PY'
import csv, math, sys
comp = {r["name"]: r for r in csv.DictReader(open(sys.argv[1]))}
air = {r["name"]: r for r in csv.DictReader(open(sys.argv[2]))}
v = lambda r: [float(r[k]) for k in ("vx_m_s", "vy_m_s", "vz_m_s")]
c = lambda r: [float(r[k]) for k in ("com_at_t_x_m", "com_at_t_y_m", "com_at_t_z_m")]
dv = [math.dist(v(air[n]), v(comp[n])) for n in comp if comp[n]["launched"] == "true"]
dc = [math.dist(c(air[n]), c(comp[n])) for n in comp if comp[n]["launched"] == "true"]
print(f"  {sys.argv[3]}: air table vs compensated table: |dv| max {max(dv):.2e} m/s, "
      f"centre of mass at t apart by up to {1000 * max(dc):.1f} mm")
PY
done

echo "== robust launches"
solve mickey+robust scenes/mickey --robust
solve mickey+robust+free scenes/mickey --robust --free-positions
solve fly+robust-dir0.09 "$fly" --robust --speed-tol 0 --spin-tol 0 --timing-tol 0 --direction-tol 0.09
solve fly+robust-dir0.09+free "$fly" --robust --speed-tol 0 --spin-tol 0 --timing-tol 0 --direction-tol 0.09 --free-positions
for d in mickey mickey+robust mickey+robust+free mickey_hold; do
    "$bin" budget "$out/$d" --search-samples 0 -q | grep -E "Monte" | sed "s/^/  $d:/"
done
for d in fly fly+robust-dir0.09 fly+robust-dir0.09+free fly_hold; do
    "$bin" budget "$out/$d" --iou-threshold 0.85 -q | grep -E "IoU at t|largest" | sed "s/^/  $d:/"
done
