// The choice of the dense kernels (dense_kernels.hpp), compiled for the portable instruction set.
#include "adparm/dense_kernels.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace adparm {

#if defined(ADPARM_DENSE_KERNELS_X86)
namespace dense_kernels_avx2 {
const DenseKernels* table();
}
namespace dense_kernels_avx512 {
const DenseKernels* table();
}
#endif

namespace {

bool has_avx2() {
#if defined(ADPARM_DENSE_KERNELS_X86)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

bool has_avx512() {
#if defined(ADPARM_DENSE_KERNELS_X86)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f") && has_avx2();
#else
  return false;
#endif
}

const DenseKernels* avx2() {
#if defined(ADPARM_DENSE_KERNELS_X86)
  return dense_kernels_avx2::table();
#else
  return nullptr;
#endif
}

const DenseKernels* avx512() {
#if defined(ADPARM_DENSE_KERNELS_X86)
  return dense_kernels_avx512::table();
#else
  return nullptr;
#endif
}

}  // namespace

const DenseKernels* select_dense_kernels(bool blocks) {
  const char* variable = std::getenv("ADPARM_KERNELS");
  const std::string requested = variable == nullptr ? "" : variable;
  if (requested.empty() || requested == "auto") {  // dense_kernels.hpp: which set for which work
    if (blocks && has_avx512()) return avx512();
    if (has_avx2()) return avx2();
    return nullptr;
  }
  if (requested == "portable") return nullptr;
  if (requested == "avx2" || requested == "avx512") {
    const bool avx2_set = requested == "avx2";
    if (avx2_set ? !has_avx2() : !has_avx512())
      throw std::invalid_argument("ADPARM_KERNELS=" + requested + ": " +
                                  (avx2_set ? "this CPU (or this build) lacks AVX2 and FMA"
                                            : "this CPU (or this build) lacks AVX-512F") +
                                  "; use auto or portable");
    return avx2_set ? avx2() : avx512();
  }
  throw std::invalid_argument("ADPARM_KERNELS: unknown value '" + requested +
                              "' (auto, portable, avx2 or avx512)");
}

}  // namespace adparm
