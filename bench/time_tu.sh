#!/usr/bin/env bash
# Compiler and linker launcher that logs what each step costs (bench/compile_times.sh sets it
# through CMake's CMAKE_CXX_COMPILER_LAUNCHER and CMAKE_CXX_LINKER_LAUNCHER). Each compile or
# link appends one line to $CABLECAL_TU_LOG:
#   <user+sys CPU s> <wall s> <peak RSS kB> <compile|link> <folder it ran in> <output file> <start> <end>
# (start and end in seconds since the epoch, for how many ran at once). CPU time is the figure
# to compare: wall time on a shared machine depends on the load.
set -u
log="${CABLECAL_TU_LOG:?set CABLECAL_TU_LOG to the log file}"
out="?" kind="link" prev=""
for a in "$@"; do
  if [ "$prev" = "-o" ]; then out="$a"; fi
  if [ "$a" = "-c" ]; then kind="compile"; fi
  prev="$a"
done
case "$PWD" in */CMakeScratch/*|*/CMakeTmp*) exec "$@" ;; esac  # CMake's own compiler checks
t="$(mktemp)"
start="$(date +%s.%N)"
/usr/bin/time -f '%U %S %e %M' -o "$t" "$@"
rc=$?
read -r user sys wall rss < <(tail -n 1 "$t")
rm -f "$t"
printf '%s %s %s %s %s %s %s %s\n' "$(echo "$user + $sys" | bc)" "$wall" "$rss" "$kind" "$PWD" "$out" "$start" "$(date +%s.%N)" >> "$log"
exit $rc
