#!/bin/bash
# fuzz_replay.sh — every libFuzzer target builds with the ordinary
# compiler and passes its property on each of its seeds and on every
# input a fuzzing run once found (tests/fuzz/seeds/NAME; a crash that was
# fixed gets its input added there), replayed through the plain driver
# tests/fuzz/replay.c. `make fuzz` does the fuzzing itself.
. "$(dirname "$0")/lib.sh" "$@"

n=0
for src in tests/fuzz/fuzz_*.c; do
    name=$(basename "$src" .c)
    bin="$BUILD/fuzz-replay/$name"
    seeds="tests/fuzz/seeds/$name"
    n=$((n + 1))
    check "$name: built" test -x "$bin"
    check "$name: has seeds" test -d "$seeds"
    [ -x "$bin" ] && [ -d "$seeds" ] || continue
    out=$(TMPDIR="$T" timeout 120 "$bin" "$seeds" 2>"$T/$name.err")
    rc=$?
    check "$name: replays its $(ls "$seeds" | wc -l) seeds ($out)" \
        test "$rc" -eq 0 -a "$out" = "$(ls "$seeds" | wc -l) inputs"
    [ "$rc" -eq 0 ] || tail -n 20 "$T/$name.err"
done
check "found the fuzz targets" test "$n" -ge 13
finish
