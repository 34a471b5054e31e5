#!/usr/bin/env bash
# Instruction-count regression check of the per-window path (streaming MAV D1D2+P update + 100-tree forest
# prediction) under callgrind: builds crackbot-research's example `per_window_instructions` in release,
# trains the forest natively (fixed data and seed), then counts only `per_window_loop` over N windows
# (--collect-atstart=no --toggle-collect) and compares instructions per window with
# benches/baselines/per_window_instructions.txt. Fails when more than 10 % above the baseline.
#
#   bash scripts/callgrind_check.sh            # check (run by .ci/run)
#   bash scripts/callgrind_check.sh --update   # write the measured count as the new baseline
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
N="${CALLGRIND_WINDOWS:-2000}"
baseline_file=benches/baselines/per_window_instructions.txt
command -v valgrind > /dev/null || { echo "callgrind check: valgrind is not installed (apt-get install valgrind)" >&2; exit 1; }

bin=$(cargo build --release --locked -p crackbot-research --example per_window_instructions --message-format=json \
    | grep -o '"executable":"[^"]*per_window_instructions"' | sed 's/"executable":"//; s/"$//' | tail -n 1)
[ -x "$bin" ] || { echo "callgrind check: no executable found for the example" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$bin" prepare "$work"
valgrind --tool=callgrind --callgrind-out-file="$work/callgrind.out" \
    --collect-atstart=no --toggle-collect='*per_window_loop*' \
    "$bin" measure "$work" "$N" 2> "$work/valgrind.log" || { cat "$work/valgrind.log" >&2; exit 1; }
total=$(sed -n 's/^totals: *\([0-9]*\).*/\1/p' "$work/callgrind.out" | head -n 1)
[ -n "$total" ] && [ "$total" -gt 0 ] || { echo "callgrind check: no instructions counted (did per_window_loop get renamed?)" >&2; exit 1; }
per_window=$(( total / N ))

if [ "${1:-}" = "--update" ]; then
    echo "$per_window" > "$baseline_file"
    echo "callgrind: $per_window instructions per window ($total over $N windows); baseline written to $baseline_file"
    exit 0
fi
baseline=$(tr -dc '0-9' < "$baseline_file")
limit=$(( baseline + baseline / 10 ))
echo "callgrind: $per_window instructions per window ($total over $N windows); baseline $baseline, limit $limit (+10 %)"
if [ "$per_window" -gt "$limit" ]; then
    echo "callgrind check FAILED: $per_window > $limit instructions per window. If the increase is intended, run" >&2
    echo "  bash scripts/callgrind_check.sh --update" >&2
    exit 1
fi
