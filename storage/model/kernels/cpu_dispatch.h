// Run-time dispatch of the hot kernels' entry points (README, "Portable binaries").
//
// The default build is portable (-march=x86-64-v2: SSE4.2, 128-bit vectors), which cost the scan
// update kernels 8-30 % against -march=native (docs/performance.md, "Portable binaries").
// FREMEN_KERNEL_CLONES on a function definition makes GCC compile it twice, for AVX2 and for the
// build's own target, and pick one when the binary is loaded (an ifunc resolver: no cost per call).
// The whole kernel must be inside the cloned function to profit: [[gnu::flatten]] inlines the
// helpers it calls (FoldObservation, the prefetches) into each clone. Used on ApplyScan,
// ApplyDenseScan, WideBodies::Fold, the lossless estimator's AddApproximate, and the ingest's
// conversion of cells to keys (server/convert/ingest_convert.cc). Region prediction over records
// is scalar per cell (its loop over a state's few components is a dependent sum) and measured no
// better as an AVX2 clone; PredictColumns, the region kernel over a brick's models as columns, has
// its own AVX-512 and AVX2 paths written with intrinsics and chosen at run time (region_predict.cc).
//
// The clone is "avx2", deliberately not "arch=x86-64-v3": that one includes FMA, and with FMA the
// compiler fuses a·b + c into one rounding (C++'s default -ffp-contract=fast), so the AVX2 path would
// round differently from the default path and from the same inline code elsewhere (FoldObservation
// in BasicSpectrum): a map's records would then depend on which node ingested or replayed its log.
// Without FMA both paths do the same IEEE operations per element, in the same order, and give
// bit-identical records (cpu_dispatch_test.cc); only the vector width differs.
//
// Empty where it would add nothing or is not supported: a build whose target already has AVX2
// (FREMEN_MARCH=native on such a machine), other architectures, compilers other than GCC, and
// sanitizer builds.
#pragma once

#if defined(__x86_64__) && !defined(__AVX2__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define FREMEN_KERNEL_CLONES [[gnu::target_clones("avx2", "default"), gnu::flatten]]
#define FREMEN_KERNEL_CLONES_ENABLED 1
#else
#define FREMEN_KERNEL_CLONES
#define FREMEN_KERNEL_CLONES_ENABLED 0
#endif

// FREMEN_FMA_CLONES: the same for code whose arithmetic is written with explicit std::fma (the
// lossless history's bin predictor, lossless/bin_model.cc). On a target without FMA, std::fma is a
// call into libm per operation, four per slot and component (7 % of a lossless update's instructions
// as calls, and the loop around them not optimised across the calls); the "fma" clone makes each one
// vfmadd. IEEE-754 defines fma's result exactly, so libm's and the instruction's agree to the bit;
// the file is compiled with -ffp-contract=off, so the clone fuses nothing the source did not ask for.
#if defined(__x86_64__) && !defined(__FMA__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define FREMEN_FMA_CLONES [[gnu::target_clones("fma", "default"), gnu::flatten]]
#else
#define FREMEN_FMA_CLONES
#endif

namespace fremen::model {

// Which clone the loader chose in this process: "avx2", "default" (the build's own target), or
// "none" (no clones in this build). For logs and tests.
const char* KernelDispatchPath();

}  // namespace fremen::model
