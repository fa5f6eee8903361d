#!/usr/bin/env python3
"""What each pass of the solver drew and gained over the solves of a suite, as a markdown
table, from the `passes` of every `solution.json` under the folders given:

    python3 scripts/passes-table.py /tmp/bsa-planted [/tmp/bsa-planted-new ...]

(the ROOT folders of scripts/planted-suite.sh or scripts/new-suite.sh). A pass "paid"
where it raised its stage's IoU by 0.001 or more; "in the kept attempt" counts those of
the attempt whose picture the solve kept. Passes of the last stage are listed apart.
A second table lists the moves the passes took (each pass's `moves`), by the pass that
took them (`moves`, `runs` before a restart, `trades`, `polish`) and the move's name."""
import collections
import glob
import json
import sys

MIN_GAIN = 0.001
rows = collections.defaultdict(lambda: {"samples": 0, "time": 0.0, "gain": 0.0, "ran": 0,
                                        "paid": 0, "kept": 0})
moves = collections.defaultdict(lambda: {"taken": 0, "paid": 0, "gain": 0.0, "solves": set()})
solutions = 0
for root in sys.argv[1:]:
    for path in sorted(glob.glob(f"{root}/**/solution.json", recursive=True)):
        s = json.load(open(path))
        passes = s.get("passes") or []
        if not passes:
            continue
        solutions += 1
        last = max(p["stage"] for p in passes)
        kept = next((k for k, a in enumerate(s.get("attempts") or []) if a["kept"]), 0)
        for p in passes:
            r = rows[("last stage: " if p["stage"] == last else "") + p["pass"]]
            gain = p["iou_after"] - p["iou_before"]
            r["samples"] += p["samples"]
            r["time"] += p["wall_time_s"]
            r["gain"] += gain
            r["ran"] += 1
            r["paid"] += gain >= MIN_GAIN
            r["kept"] += gain >= MIN_GAIN and p["attempt"] == kept
            for m in p.get("moves") or []:
                gain = m["iou_after"] - m["iou_before"]
                r = moves[(p["pass"], m["move"])]
                r["taken"] += 1
                r["paid"] += gain >= MIN_GAIN
                r["gain"] += gain
                r["solves"].add(path)
if not solutions:
    sys.exit("no solution.json with passes under " + " ".join(sys.argv[1:]))
samples = sum(r["samples"] for r in rows.values())
time = sum(r["time"] for r in rows.values())
print(f"{solutions} solves\n")
print("| pass | samples | time | ran | paid (IoU +0.001 or more) | of those, in the kept attempt | IoU gained, summed |")
print("|---|---|---|---|---|---|---|")
for name, r in sorted(rows.items(), key=lambda kv: -kv[1]["time"]):
    print(f"| {name} | {100 * r['samples'] / samples:.1f} % | {100 * r['time'] / time:.1f} % | "
          f"{r['ran']} | {r['paid']} | {r['kept']} | {r['gain']:.3f} |")

if moves:
    print("\n| pass | move | taken | paid (IoU +0.001 or more) | in solves | IoU gained, summed |")
    print("|---|---|---|---|---|---|")
    for (pass_, name), r in sorted(moves.items(), key=lambda kv: -kv[1]["gain"]):
        print(f"| {pass_} | {name} | {r['taken']} | {r['paid']} | {len(r['solves'])} | "
              f"{r['gain']:.3f} |")
