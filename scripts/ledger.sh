# The results ledger (results/*.csv): sourced by the suites, which call ledger_row once
# per solve. Columns: commit, date, machine, suite, set_or_seed, item, route, iou,
# contacts, samples, seconds. The tables of docs/results.md are made from these files
# (`BSA_REGENERATE=1 cargo test --test integration ledger::`).
#
# LEDGER=0 appends nothing; LEDGER_COMMIT names the build measured when it is not this
# checkout's (a BSA=... binary); BSA_MACHINE names the machine (default: cores and
# architecture).
ledger_header="commit,date,machine,suite,set_or_seed,item,route,iou,contacts,samples,seconds"
ledger_commit() {
    if [ -n "${LEDGER_COMMIT:-}" ]; then
        echo "$LEDGER_COMMIT"
        return
    fi
    local c
    c=$(git rev-parse --short=7 HEAD 2>/dev/null || echo unknown)
    if ! git diff --quiet HEAD -- src Cargo.toml Cargo.lock 2>/dev/null; then c=$c-dirty; fi
    echo "$c"
}
# ledger_row SUITE SET_OR_SEED ITEM ROUTE IOU CONTACTS SAMPLES SECONDS, appended to
# results/SUITE.csv (written with its header when new).
ledger_row() {
    [ "${LEDGER:-1}" = 0 ] && return 0
    local suite=$1 file=results/$1.csv
    shift
    local field
    for field in "$@"; do
        case $field in *,* | *\"*) echo "ledger: a field with a comma or quote: $field" >&2; return 1 ;; esac
    done
    [ -s "$file" ] || echo "$ledger_header" >"$file"
    local machine=${BSA_MACHINE:-$(nproc)-core $(uname -m)}
    echo "$(ledger_commit),$(date -u +%Y-%m-%d),$machine,$suite,$(IFS=,; echo "$*")" >>"$file"
}
