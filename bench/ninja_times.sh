#!/usr/bin/env bash
# What a finished Ninja build spent, from its own log (no relaunch): the build's span, the sum
# of its steps' wall times (about the CPU it used: each step is one process), the sum per folder
# and the costliest steps. Steps ran two at a time on CI's 2 cores, so a step's wall time is
# close to its CPU time only when the machine had nothing else to do.
#   bench/ninja_times.sh BUILD_DIR [TOP]     e.g. after CI: bench/ninja_times.sh /tmp/ci/build-sanitize
set -euo pipefail
log="${1:?usage: bench/ninja_times.sh BUILD_DIR [TOP]}/.ninja_log"
top="${2:-15}"
[ -f "$log" ] || { echo "ninja_times: no $log (a Ninja build folder?)" >&2; exit 2; }
# .ninja_log v5: start_ms end_ms mtime output hash, after one header line.
awk 'NR > 1 { s += $2 - $1; if ($2 > span) span = $2 }
     END { printf "span %.0f s, steps %.0f s\n", span / 1000, s / 1000 }' "$log"
echo "by folder:"
awk 'NR > 1 { split($4, p, "/"); k = p[1]; if (k == "tests") k = "tests/" p[3]; t[k] += ($2 - $1) / 1000 }
     END { for (k in t) printf "  %7.1f s  %s\n", t[k], k }' "$log" | sort -rn | head -n "$top"
echo "costliest steps:"
awk 'NR > 1 { printf "  %7.1f s  %s\n", ($2 - $1) / 1000, $4 }' "$log" | sort -rn | head -n "$top"
