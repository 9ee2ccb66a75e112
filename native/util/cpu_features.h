// What the CPU running SHGI can do beyond the build's baseline (x86-64: SSE2), for the few hot
// loops that have a wider clone compiled with __attribute__((target(...))) and choose it at run
// time. Each answer is found once (cpuid) and kept.
#pragma once

namespace shgi {

// True when the CPU and the operating system support AVX2 (256-bit integer SIMD); false on
// other architectures.
bool cpu_has_avx2();
// True when the CPU and the operating system support AVX2 and AVX-512 F, DQ and VL (64-bit
// integer multiplies on 256-bit registers); false on other architectures.
bool cpu_has_avx512dq_vl();
// True when cpu_has_avx512dq_vl() and the CPU has GFNI (Galois-field affine transforms of bytes:
// a byte's bits reversed in one instruction); false on other architectures.
bool cpu_has_avx512dq_vl_gfni();

}  // namespace shgi
