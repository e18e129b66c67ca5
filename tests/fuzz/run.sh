#!/bin/sh
# Runs libFuzzer programs one after another (make fuzz):
#
#   tests/fuzz/run.sh SECONDS BUILD_DIR build/fuzz/fuzz_NAME...
#
# Each program fuzz_NAME mutates the committed seeds tests/fuzz/corpus/NAME
# (read only) and the inputs it found interesting in earlier runs,
# BUILD_DIR/fuzz/corpus/NAME (where it adds new ones), for SECONDS seconds.
# A crash, leak, timeout (10 s for one input) or out-of-memory stops that
# program and leaves its input in BUILD_DIR/fuzz/findings/NAME/. Every run adds a line
# to BUILD_DIR/fuzz/history.tsv; the table printed at the end gives this run's
# figures and the executions of all runs so far. Exits non-zero when any
# program found something. Several runs may go on at once (on other targets,
# or on one target: they share its corpus directory).
set -u
seconds=$1
build=$2
shift 2
history="$build/fuzz/history.tsv"
mkdir -p "$build/fuzz"
[ -f "$history" ] || printf 'date\ttarget\tseconds\texecutions\texec_per_s\tcov\tft\tcorpus\tstatus\n' >"$history"
found=0
summary=$(mktemp)
for prog in "$@"; do
    name=$(basename "$prog")
    name=${name#fuzz_}
    work="$build/fuzz/corpus/$name"
    findings="$build/fuzz/findings/$name"
    log="$build/fuzz/logs/$name-$(date -u +%Y%m%dT%H%M%S)-$$.log"   # one per run: runs may overlap
    mkdir -p "$work" "$findings" "$build/fuzz/logs"
    echo "== fuzz_$name: $seconds s"
    "$prog" -max_total_time="$seconds" -timeout=10 -print_final_stats=1 \
        -artifact_prefix="$findings/" "$work" "tests/fuzz/corpus/$name" >"$log" 2>&1
    status=$?
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
    last=$(grep -aE '^#[0-9]+' "$log" | tail -n 1)
    cov=$(echo "$last" | sed -n 's/.* cov: \([0-9]*\).*/\1/p')
    ft=$(echo "$last" | sed -n 's/.* ft: \([0-9]*\).*/\1/p')
    corp=$(echo "$last" | sed -n 's/.* corp: \([0-9]*\).*/\1/p')
    if [ "$status" -ne 0 ]; then
        found=1
        echo "   fuzz_$name FOUND SOMETHING (status $status): see $log; reproduce with"
        for f in "$findings"/*; do [ -f "$f" ] && echo "     $build/fuzz/replay_$name $f"; done
        grep -aE '^(==[0-9]+==ERROR|SUMMARY|fuzz_)' "$log" | head -n 5 | sed 's/^/     /'
        result=finding
    else
        result=clean
    fi
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$(date -u +%Y-%m-%dT%H:%M:%SZ)" "$name" "$seconds" \
        "${runs:-0}" "${rate:-0}" "${cov:-?}" "${ft:-?}" "${corp:-?}" "$result" >>"$history"
    total=$(awk -F'\t' -v t="$name" '$2 == t { s += $4 } END { printf "%.0f", s }' "$history")
    printf '%-12s %12s %8s %8s %8s %8s %14s  %s\n' "$name" "${runs:-0}" "${rate:-0}" "${cov:-?}" "${ft:-?}" \
        "${corp:-?}" "$total" "$result" >>"$summary"
done
echo
printf '%-12s %12s %8s %8s %8s %8s %14s  %s\n' target executions exec/s cov ft corpus "all runs" result
cat "$summary"
rm -f "$summary"
exit $found
