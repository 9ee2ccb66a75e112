#include "util/cpu_features.h"

namespace shgi {

bool cpu_has_avx2() {
#if defined(__x86_64__) || defined(__i386__)
    // GCC's and Clang's check also asks the OS (xgetbv) whether it saves the YMM registers.
    // __builtin_cpu_init first: a first call during another file's static initialisation may
    // come before libgcc's own constructor has filled in what the check reads.
    static const bool avx2 = [] {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx2") != 0;
    }();
    return avx2;
#else
    return false;
#endif
}

}  // namespace shgi
