#!/usr/bin/env bash
# The test fuzz_corpus: replays each corpus folder through its harness.
# Usage: replay_all.sh HARNESS CORPUS [HARNESS CORPUS ...]
set -u
status=0
while [ $# -ge 2 ]; do
  printf '%s: ' "$(basename "$1")"
  "$1" "$2" || { echo "FAILED: $1 $2"; status=1; }
  shift 2
done
exit $status
