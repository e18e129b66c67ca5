#!/bin/sh
# Runs test programs one after another and adds up their closing lines
# ("N passed, N failed"). A program that crashes, times out or prints no closing
# line counts as one failure. Prints the total alone on the last line and exits
# non-zero when anything failed.
set -u
limit=${TEST_TIMEOUT:-900}
passed=0
failed=0
log=$(mktemp)
for prog in "$@"; do
    name=$(basename "$prog")
    echo "== $name"
    timeout "$limit" "$prog" >"$log" 2>&1
    status=$?
    cat "$log"
    line=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' "$log" | tail -n 1)
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
done
rm -f "$log"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
