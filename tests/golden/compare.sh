#!/usr/bin/env bash
# Compare two folders written by tests/golden/outputs.sh (or two results/ folders) byte for
# byte but for provenance lines (the version and commit, the command line, the BLAS and
# LAPACK paths, the process count) and wall-clock times, which are blanked. Prints each file
# that differs and exits 1 if any does.
#
#   tests/golden/compare.sh BEFORE_DIR AFTER_DIR
set -uo pipefail
before="$1"; after="$2"
provenance='(commit|^# command:|^command:|"command":|^blas:|^lapack:|"blas":|"lapack":|^processes:)'
# Wall-clock times: "wall_time_s: 0.12", "... in 0.3 s on ...", "..., 0.1 s" at a line's end.
times='s/(wall_time_s"?: )[0-9.e+-]+/\1T/; s/ in [0-9.]+ s on / in T s on /; s/, [0-9.]+ s$/, T s/'
normal() { grep -Ev "$provenance" "$1" | sed -E "$times"; }
status=0
files="$( (cd "$before" && find . -type f ! -name '*.png'; cd "$after" && find . -type f ! -name '*.png') | sort -u)"
for f in $files; do
  if [[ ! -f "$before/$f" || ! -f "$after/$f" ]]; then
    echo "only in one: $f"; status=1; continue
  fi
  if ! diff -q <(normal "$before/$f") <(normal "$after/$f") >/dev/null; then
    echo "differs: $f"
    diff <(normal "$before/$f") <(normal "$after/$f") | head -6
    status=1
  fi
done
n="$(echo "$files" | wc -l)"
[[ $status == 0 ]] && echo "identical but for provenance: $n files"
exit $status
