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

bool cpu_has_avx512dq_vl() {
#if defined(__x86_64__) || defined(__i386__)
    static const bool avx512 = [] {
        __builtin_cpu_init();  // as cpu_has_avx2; the checks include the OS's (xgetbv ZMM state)
        return cpu_has_avx2() && __builtin_cpu_supports("avx512f") != 0 &&
               __builtin_cpu_supports("avx512dq") != 0 && __builtin_cpu_supports("avx512vl") != 0;
    }();
    return avx512;
#else
    return false;
#endif
}

bool cpu_has_avx512dq_vl_gfni() {
#if defined(__x86_64__) || defined(__i386__)
    static const bool gfni = cpu_has_avx512dq_vl() && __builtin_cpu_supports("gfni") != 0;
    return gfni;
#else
    return false;
#endif
}

}  // namespace shgi
