// Whether the AVX2 lane kernel (element_batch_avx2.cpp) was built and can run on this processor.

#include "sim/element_batch.hpp"

namespace tetcut::sim::detail {

bool element_lanes_available() {
#if defined(TETCUT_AVX2_KERNEL)
  static const bool available = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return available;
#else
  return false;
#endif
}

#if !defined(TETCUT_AVX2_KERNEL)
// Built without the kernel: every lane goes to the scalar kernel.
void element_hessian_lanes(const LaneMaterial&, LaneBatch* batch, int count) {
  for (int lane = 0; lane < count; ++lane) batch->fallback[lane] = true;
}
#endif

}  // namespace tetcut::sim::detail
