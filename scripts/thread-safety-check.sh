#!/usr/bin/env bash
# Compiles the libraries that share state between threads — storage (with its test environment),
# server and the C++ client — and the locks' own unit test with clang's thread-safety analysis as
# an error, in their own tree:
#   scripts/thread-safety-check.sh BUILD_DIR JOBS
# The analysis checks the ABSL_GUARDED_BY / ABSL_EXCLUSIVE_LOCKS_REQUIRED / ... annotations
# (absl/base/thread_annotations.h): a guarded member touched without its mutex, a "Locked" helper
# called without the lock, a lock taken twice. It only understands annotated lock types, which is
# why the code locks base::Mutex and friends (base/mutex.h), not bare std::mutex. g++ ignores the
# annotations, so only this build enforces them. Nothing is linked but the small base test, and
# nothing is run: -O0.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=$1 jobs=$2

cxx=${TSA_CXX:-clang++-14}
cmake -S . -B "$build_dir" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-O0 \
  -DCMAKE_CXX_FLAGS="-Wthread-safety -Werror=thread-safety" -DFREMEN_NATIVE=OFF >/dev/null
cmake --build "$build_dir" -j"$jobs" --target fremen_storage fremen_storage_testing fremen_server fremen_client \
  fremen_base_test
echo "thread-safety: the storage, server and client libraries pass clang's thread-safety analysis"
