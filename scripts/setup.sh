#!/usr/bin/env bash
# Installs the Debian packages cablecal needs, and only those that are missing.
# Nothing else is downloaded: every dependency is a Debian package (see README, "Dependencies").
#   scripts/setup.sh          what the default build needs (scripts/run.sh)
#   scripts/setup.sh --tests  and what the whole test suite needs (scripts/test.sh)
#   scripts/setup.sh --sanitize  and clang for the instrumented stage (scripts/test.sh --sanitize)
#   scripts/setup.sh --bench  and what bench/'s scipy baseline needs (bench/identify_vs_scipy.sh)
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config git
  ninja-build            # builds in parallel across targets (scripts/build.sh; make works too)
  libeigen3-dev          # fixed-size 2-D/3-D geometry and small dense linear algebra
  libceres-dev           # identification (Levenberg-Marquardt, autodiff Jets, covariance)
  coinor-libipopt-dev    # experiment design NLP
  libblas3 liblapack3    # the reference BLAS/LAPACK, loaded for bit-reproducible designs (CMakeLists.txt)
  libyaml-cpp-dev        # robot files
  libcli11-dev           # command line
  libgtest-dev           # unit tests
  libbenchmark-dev       # bench/
  python3-matplotlib     # figures (scripts/*.py, run with /usr/bin/python3)
  python3-yaml           # bench/rounds.py reads result YAML
  pybind11-dev python3-dev python3-numpy  # the Python module (python/)
)
if [ "$#" -gt 1 ]; then
  echo "cablecal setup: one option at most (got $#: $*); use --tests, --sanitize, --bench or nothing" >&2
  exit 2
fi
case "${1:-}" in
  "") ;;
  -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
  --bench)
    PACKAGES+=(
      python3-scipy               # bench/scipy_identify.py, the independent baseline
    ) ;;
  --tests|--sanitize)
    PACKAGES+=(
      libopenmpi-dev openmpi-bin  # the CABLECAL_MPI build and its mpirun tests
      locales-all                 # a decimal-comma locale: number parsing must not depend on it
      python3-pytest              # the Python module's tests (tests/python)
    )
    if [ "$1" = --sanitize ]; then
      PACKAGES+=(
        clang libclang-rt-dev     # the sanitizer build and the libFuzzer targets of tests/fuzz
        libomp-dev                # OpenMP for clang
      )
    fi ;;
  *) echo "cablecal setup: unknown option '$1' (use --tests, --sanitize, --bench or nothing)" >&2; exit 2 ;;
esac

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "cablecal setup: installing missing Debian packages: ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "cablecal setup: need root (or sudo) to install: ${missing[*]}" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
