#!/usr/bin/env bash
# expect_failure.sh PATTERN COMMAND...: the command must exit non-zero (not
# by a signal) and print PATTERN.
pattern="$1"; shift
out=$("$@" 2>&1); rc=$?
echo "$out"
if [ $rc -eq 0 ]; then echo "expected failure, got exit 0"; exit 1; fi
if [ $rc -gt 128 ]; then echo "terminated by signal $((rc-128))"; exit 1; fi
echo "$out" | grep -q -- "$pattern" || { echo "message does not match '$pattern'"; exit 1; }
echo "failed as expected (exit $rc)"
