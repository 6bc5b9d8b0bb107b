#!/usr/bin/env bash
# cmake --install of this build into a fresh prefix, then, against that prefix only: a C++
# project built with find_package(cablecal), the installed CLI drawing a figure (its plotting
# scripts found beside it, not in the source tree), and the installed Python module (a report's
# figures drawn with the scripts installed beside it).
#   consumer_test.sh BUILD_DIR SOURCE_DIR WORK_DIR PYTHON
set -euo pipefail
build="$1" source="$2" work="$3" python="$4"
rm -rf "$work" && mkdir -p "$work"
prefix="$work/prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
cmake -S "$source/tests/consumer" -B "$work/build" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/build" >/dev/null
"$work/build/consumer" "$prefix/share/cablecal/robots/planar3_suspended.yaml"
"$work/build/consumer" "$prefix/share/cablecal/robots/asymmetric.yaml"
# The installed CLI, run from elsewhere, with the source tree out of sight.
cd "$work"
env -u CABLECAL_SCRIPTS_DIR "$prefix/bin/cablecal" workspace --robot "$prefix/share/cablecal/robots/asymmetric.yaml" \
  --step 0.2 --out "$work/ws.csv" --plot "$work/ws.png"
test -s "$work/ws.png"
if strings "$prefix/bin/cablecal" | grep -F -q "$source/scripts"; then
  echo "the installed binary names the source tree's scripts folder" >&2
  exit 1
fi
if [ -n "$python" ]; then
  PYTHONPATH="$prefix/lib/python3/dist-packages" "$python" -c \
    "import cablecal, sys; r = cablecal.Robot.load('$prefix/share/cablecal/robots/planar3_suspended.yaml'); \
     p = cablecal.sample(r, 4); print(cablecal.__file__, r.num_cables, p.poses.shape); \
     sys.exit(0 if cablecal.__file__.startswith('$prefix') else 1)"
  # The installed module's report draws with the scripts installed beside it.
  env -u CABLECAL_SCRIPTS_DIR PYTHONPATH="$prefix/lib/python3/dist-packages" "$python" -c \
    "import cablecal; r = cablecal.Robot.load('$prefix/share/cablecal/robots/asymmetric.yaml'); \
     m = cablecal.simulate(r, cablecal.sample(r, 8, seed=5), seed=1).measurements; \
     print(cablecal.report(r, cablecal.identify(r, m), '$work/report'))"
  test -s "$work/report/residuals.png"
fi
echo "consumer test: passed"
