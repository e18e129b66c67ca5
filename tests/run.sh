#!/bin/sh
# Runs test programs, up to TEST_JOBS at once (default: the number of cores, at
# most 4; TEST_JOBS=1 runs them one after another), and adds up their closing
# lines ("N passed, N failed"). Each program's output is kept whole and printed
# as one block when it ends: "== name", the output, the program's wall time.
# A program that crashes, times out (TEST_TIMEOUT seconds, default 900), prints
# no closing line, or exits non-zero after reporting no failure counts as one
# failure. Prints the total alone on the last line and exits non-zero when
# anything failed.
#
# The programs known to run longest start first, longest first, so that the
# last to end is a short one and no core idles while a long program runs
# alone. Wall seconds in a whole make test, 2 at once, at load about 2:
# test_radinterp 152, ref_radinterp_glass 69, test_radinterp-clang-ubsan 65,
# test_radinterp_visibility 60, ref_radinterp_building 60 (on a pool),
# test_walkthrough_daylight 48, test_lightvec_cache 46, test_radinterp_glass
# 40, test_walkthrough 38, test_walkthrough_building 35, the clang-ubsan
# builds of the walkthrough and lightvec cache tests 13-33, tsan_lightvec and
# the BVH tests 10-20. A
# program missing here only starts later; one that grows belongs here.
set -u
LONG_FIRST="test_radinterp ref_radinterp_glass test_radinterp-clang-ubsan test_radinterp_visibility ref_radinterp_building \
test_walkthrough_daylight test_lightvec_cache test_radinterp_glass test_walkthrough test_walkthrough_building \
test_walkthrough_radiosity \
test_walkthrough_building-clang-ubsan test_walkthrough_daylight-clang-ubsan test_lightvec_cache-clang-ubsan \
tsan_lightvec test_bvh_scalar test_bvh"

limit=${TEST_TIMEOUT:-900}
jobs=${TEST_JOBS:-$(nproc 2>/dev/null || echo 1)}
[ -n "${TEST_JOBS:-}" ] || [ "$jobs" -le 4 ] || jobs=4
case $jobs in '' | *[!0-9]* | 0) echo "run.sh: TEST_JOBS must be a positive number, not '$jobs'" >&2; exit 2 ;; esac

dir=$(mktemp -d) || exit 2
# A pipe the runs write their number to when they end: reading it waits for
# the next program to end, whichever it is (POSIX sh has no wait -n).
mkfifo "$dir/ended" || exit 2
exec 3<>"$dir/ended"
rm -f "$dir/ended"

now_ns() { date +%s%N; }
seconds() { printf '%d.%d' $(($1 / 1000000000)) $(($1 / 100000000 % 10)); }

# On INT or TERM: ends the runs (their shells, then timeout, which passes the
# signal on to its program) and leaves nothing behind.
stop() {
    for runner in "$dir"/*.runner; do
        [ -f "$runner" ] || continue
        kill "$(cat "$runner")" 2>/dev/null
        [ -f "${runner%.runner}.pid" ] && kill "$(cat "${runner%.runner}.pid")" 2>/dev/null
    done
    rm -rf "$dir"
    exit 130
}
trap stop INT TERM
trap 'rm -rf "$dir"' EXIT

# run_one N PROG: runs PROG under timeout, its output into N.out; writes its
# status and wall time in nanoseconds into N.end, then N into the pipe.
run_one() {
    start=$(now_ns)
    timeout "$limit" "$2" >"$dir/$1.out" 2>&1 3>&- &
    echo $! >"$dir/$1.pid"
    wait $! 2>>"$dir/$1.out"   # the shell's word on a crash: "Segmentation fault"
    status=$?
    echo "$status $(($(now_ns) - start))" >"$dir/$1.end"
    echo "$1" >&3
}

passed=0
failed=0
started=0
running=0

# report N: prints program N's block and adds its closing line to the totals.
report() {
    name=$(cat "$dir/$1.name")
    read -r status ns <"$dir/$1.end"
    echo "== $name"
    cat "$dir/$1.out"
    line=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' "$dir/$1.out" | tail -n 1)
    if [ -n "$line" ]; then
        p=${line%% passed*}
        f=${line#*passed, }; f=${f%% failed*}
        passed=$((passed + p))
        failed=$((failed + f))
        if [ "$status" -ne 0 ] && [ "$f" -eq 0 ]; then
            echo "   $name exited with status $status after reporting no failure"
            failed=$((failed + 1))
        fi
    else
        echo "   $name ended without a closing line (status $status)"
        failed=$((failed + 1))
    fi
    echo "   $name: $(seconds "$ns") s"
    rm -f "$dir/$1".*
}

wait_one() {
    read -r n <&3
    wait "$(cat "$dir/$n.runner")" 2>/dev/null
    report "$n"
    running=$((running - 1))
}

launch() {
    [ "$running" -lt "$jobs" ] || wait_one
    started=$((started + 1))
    echo "${1##*/}" >"$dir/$started.name"
    run_one "$started" "$1" &
    echo $! >"$dir/$started.runner"
    running=$((running + 1))
}

t0=$(now_ns)
# (the loops' variables are named apart from the functions': sh has no locals)
for first in $LONG_FIRST; do
    for prog in "$@"; do
        [ "${prog##*/}" = "$first" ] && launch "$prog"
    done
done
for prog in "$@"; do
    case " $LONG_FIRST " in
        *" ${prog##*/} "*) ;;
        *) launch "$prog" ;;
    esac
done
while [ "$running" -gt 0 ]; do wait_one; done
echo "   $started programs, $jobs at once: $(seconds $(($(now_ns) - t0))) s"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
