#include "util/cpu_features.h"

namespace shgi {

bool cpu_has_avx2() {
#if defined(__x86_64__) || defined(__i386__)
    // GCC's and Clang's check also asks the OS (xgetbv) whether it saves the YMM registers.
    static const bool avx2 = __builtin_cpu_supports("avx2");
    return avx2;
#else
    return false;
#endif
}

}  // namespace shgi
