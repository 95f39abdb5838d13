#include "storage/model/kernels/cpu_dispatch.h"

namespace fremen::model {

const char* KernelDispatchPath() {
#if FREMEN_KERNEL_CLONES_ENABLED
  // The test the clones' resolver makes (GCC's ifunc resolvers read the same cpu model).
  return __builtin_cpu_supports("avx2") ? "avx2" : "default";
#else
  return "none";
#endif
}

}  // namespace fremen::model
