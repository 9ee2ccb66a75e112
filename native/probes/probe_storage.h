// Probe grids on disk: the compact fp16 packing of seed 002 §5.2, SHGI's versioned binary cache,
// and an EXR + JSON export that other tools can read.
//
// Packing: a probe's (order + 1)^2 RGB coefficients as IEEE half floats (Imath::half),
// coefficient-major [coeff][rgb] like docs/architecture.md's float layout, zero-padded to a
// multiple of 4 bytes: L2 = 27 halves = 54 bytes -> 56 (seed 002 §5.2: "a 10^3 grid of L2 probes
// ... roughly 56 kilobytes"), L1 = 24, L3 = 96, L4 = 152. Values beyond half's range (|x| > 65504)
// are clamped to it; each coefficient keeps a relative error <= 2^-11 (half's 11-bit significand)
// above half's smallest normal number 6.1e-5, and an absolute error <= 2^-25 below it.
//
// Binary cache (.shprobes), little-endian, version 1:
//   "SHGIPRB\0" | u32 version | u32 order | u32 volumes | u32 visibility_resolution |
//   u32 includes_direct | u64 passes | u64 probes |
//   per volume: f32[16] world_from_volume (column-major), i32[3] resolution |
//   f32[3] position per probe | u8 active per probe | f32 variance per probe |
//   packed SH per probe | f32[2] visibility moments per texel, probe by probe.
// The SH is stored at half precision (the compact form); everything else in full.
//
// EXR + JSON export (<stem>.json beside one or two EXR files per volume): see export_probe_grid.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "probes/probe_field.h"
#include "sh/sh_coeffs.h"

namespace shgi {

inline constexpr uint32_t kProbeFileVersion = 1;

// Bytes of one packed probe of `order` (56 for L2).
size_t packed_probe_bytes(int order);
// Writes packed_probe_bytes(sh.order) bytes.
void pack_probe_sh(const ShRgb& sh, uint8_t* out);
ShRgb unpack_probe_sh(const uint8_t* in, int order);

// The binary cache. save throws IoError naming the path when it cannot write; load throws
// IoError for a missing, truncated or foreign file or an unknown version, and InvalidArgument
// (from validate_probe_grid_data) for inconsistent contents.
void save_probe_grid(const std::string& path, const ProbeGridData& data);
ProbeGridData load_probe_grid(const std::string& path);

// Writes <stem>.json and, per volume v, <stem>_volume<v>.exr and <stem>_volume<v>_visibility.exr
// (`json_path` must end in .json). The SH EXR of a volume with resolution (nx, ny, nz) is nx
// pixels wide and ny * nz high; probe (i, j, k) is pixel (i, j + ny * k), row 0 the file's first
// row. Its float channels: sh<ii>.R/G/B for coefficient ii = l(l+1)+m (two digits), Position.X/Y/Z
// (relocated probe, world), Active.V (0 or 1), Variance.V. The visibility EXR tiles each probe's
// octahedral map (res x res) at (i * res, (j + ny * k) * res): Distance.Mean, Distance.MeanSquare
// (m, m^2). The JSON states the format, version, SH basis, normalisation and units, the frame,
// every volume's transform and resolution and file names, and the layout above.
void export_probe_grid(const std::string& json_path, const ProbeGridData& data);
// Reads what export_probe_grid wrote (IoError naming the file and the problem).
ProbeGridData import_probe_grid(const std::string& json_path);

}  // namespace shgi
