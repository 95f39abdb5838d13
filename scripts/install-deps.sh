#!/usr/bin/env bash
# Installs the Debian 12 packages fremen builds and tests with, when any is missing.
# Idempotent: does nothing (and needs no network) when everything is already there.
#   scripts/install-deps.sh        what the build and `make test` need
#   scripts/install-deps.sh fuzz   also clang and its libFuzzer runtime (`make fuzz`, fuzz/README.md)
#   scripts/install-deps.sh clang  also clang (`make thread-safety`: its thread-safety analysis)
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  liblmdb-dev lmdb-utils zlib1g-dev libxxhash-dev libeigen3-dev libspdlog-dev libfftw3-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcpp-httplib-dev libssl-dev prometheus-cpp-dev  # fremend's HTTP port: HTTP(S) and Prometheus metrics
  libpng-dev  # fremend's region.png (server/gateway/png_encode.cc)
  python3-grpcio python3-protobuf python3-numpy
  python3-setuptools python3-wheel python3-venv  # the Python package's wheel, built and installed by python.test_package
  mypy python3-pycodestyle  # the Python package's type and style checks (python.mypy, python.pycodestyle)
  openssl  # the tests make their TLS certificates with it
  prometheus  # e2e.HttpPrometheusTest: a real Prometheus scrapes fremend's /metrics
  libjs-chart.js  # Chart.js, embedded in fremend's dashboard at build time (docs/http.md, "Dashboard")
  chromium chromium-driver python3-selenium  # e2e.dashboard_browser: the dashboard in a real, headless browser
  nginx-light python3-yaml  # the fleet tests: a real nginx routes on x-fremen-map; the Kubernetes manifests parsed
)
case "${1:-}" in
  fuzz) packages+=(clang-14 libclang-rt-14-dev) ;;  # libclang_rt.fuzzer, asan and ubsan for clang
  clang) packages+=(clang-14) ;;
esac

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
