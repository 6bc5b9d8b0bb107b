#!/usr/bin/env bash
# Compare two folders written by tests/golden/outputs.sh (or two results/ folders) byte for
# byte but for provenance lines: the version and commit, the command line, the BLAS and
# LAPACK paths and the process count. Prints each file that differs and exits 1 if any does.
#
#   tests/golden/compare.sh BEFORE_DIR AFTER_DIR
set -uo pipefail
before="$1"; after="$2"
provenance='(commit|^# command:|^command:|"command":|^blas:|^lapack:|"blas":|"lapack":|^processes:)'
status=0
files="$( (cd "$before" && find . -type f ! -name '*.png'; cd "$after" && find . -type f ! -name '*.png') | sort -u)"
for f in $files; do
  if [[ ! -f "$before/$f" || ! -f "$after/$f" ]]; then
    echo "only in one: $f"; status=1; continue
  fi
  if ! diff -q <(grep -Ev "$provenance" "$before/$f") <(grep -Ev "$provenance" "$after/$f") >/dev/null; then
    echo "differs: $f"
    diff <(grep -Ev "$provenance" "$before/$f") <(grep -Ev "$provenance" "$after/$f") | head -6
    status=1
  fi
done
n="$(echo "$files" | wc -l)"
[[ $status == 0 ]] && echo "identical but for provenance: $n files"
exit $status
