#include "probes/probe_storage.h"

#include <Imath/half.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>
#include <type_traits>
#include <vector>

#include "io/exr_image.h"
#include "io/image.h"
#include "util/binary_file.h"
#include "util/error.h"
#include "util/memory.h"

namespace shgi {
namespace {

constexpr char kMagic[8] = {'S', 'H', 'G', 'I', 'P', 'R', 'B', '\0'};
constexpr float kHalfMax = 65504.0f;
constexpr const char* kFormatName = "shgi-probe-grid";

std::string two_digits(int i) {
    std::ostringstream s;
    s << std::setw(2) << std::setfill('0') << i;
    return s.str();
}

std::string file_name(const std::string& path) {
    return std::filesystem::path(path).filename().string();
}

std::string json_stem(const std::string& json_path) {
    std::filesystem::path path(json_path);
    if (path.extension() != ".json" || path.stem().empty())
        throw InvalidArgument(format_message("probe export path \"", json_path,
                                             "\" must end in .json"));
    return path.replace_extension().string();
}

// validate_probe_volumes for volumes read from `path`: a refusal is a file error naming it.
size_t checked_volumes(const std::vector<ProbeVolume>& volumes, const std::string& path) {
    try {
        return validate_probe_volumes(volumes, "volumes");
    } catch (const InvalidArgument& e) {
        throw IoError(format_message("\"", path, "\": ", e.what()));
    }
}

}  // namespace

size_t packed_probe_bytes(int order) {
    check_sh_order(order, "packed probe order");
    const size_t halves = size_t(3 * sh_num_coefficients(order));
    return (halves * sizeof(uint16_t) + 3) / 4 * 4;
}

void pack_probe_sh(const ShRgb& sh, uint8_t* out) {
    const size_t bytes = packed_probe_bytes(sh.order);
    std::memset(out, 0, bytes);
    const int values = 3 * sh.num_coefficients();
    for (int i = 0; i < values; ++i) {
        const float v = std::clamp(sh.data()[i], -kHalfMax, kHalfMax);
        const uint16_t bits = Imath::half(std::isnan(v) ? 0.0f : v).bits();
        std::memcpy(out + 2 * i, &bits, sizeof(bits));
    }
}

ShRgb unpack_probe_sh(const uint8_t* in, int order) {
    ShRgb sh(order);
    const int values = 3 * sh.num_coefficients();
    for (int i = 0; i < values; ++i) {
        uint16_t bits;
        std::memcpy(&bits, in + 2 * i, sizeof(bits));
        Imath::half h;
        h.setBits(bits);
        sh.data()[i] = float(h);
    }
    return sh;
}

void save_probe_grid(const std::string& path, const ProbeGridData& data) {
    validate_probe_grid_data(data);
    write_file_atomically(path, [&](const std::string& temp) {
        std::ofstream out(temp, std::ios::binary | std::ios::trunc);
        BinaryWriter w(out);
        w.header(kMagic, kProbeFileVersion);
        w.put(uint32_t(data.order));
        w.put(uint32_t(data.volumes.size()));
        w.put(uint32_t(data.visibility_resolution));
        w.put(uint32_t(data.includes_direct ? 1 : 0));
        w.put(uint64_t(data.passes));
        w.put(uint64_t(data.probe_count()));
        for (const ProbeVolume& v : data.volumes) {
            w.bytes(&v.world_from_volume[0][0], 16 * sizeof(float));
            w.bytes(&v.resolution[0], 3 * sizeof(int32_t));
        }
        w.bytes(data.positions.data(), data.positions.size() * sizeof(vec3));
        w.bytes(data.active.data(), data.active.size());
        w.bytes(data.variance.data(), data.variance.size() * sizeof(float));
        std::vector<uint8_t> packed(packed_probe_bytes(data.order));
        for (const ShRgb& sh : data.sh) {
            pack_probe_sh(sh, packed.data());
            w.bytes(packed.data(), packed.size());
        }
        w.bytes(data.visibility.data(), data.visibility.size() * sizeof(vec2));
        out.flush();
        if (!out) throw IoError(format_message("cannot write probe file \"", path, "\""));
    });
}

ProbeGridData load_probe_grid(const std::string& path) {
    require_readable_file(path, "probe file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(format_message("cannot open probe file \"", path, "\""));
    BinaryReader r(in, path, "probe file");
    r.header(kMagic, kProbeFileVersion, kProbeFileVersion);
    ProbeGridData data;
    data.order = int(r.get<uint32_t>("the header"));
    const uint32_t volumes = r.get<uint32_t>("the header");
    data.visibility_resolution = int(r.get<uint32_t>("the header"));
    data.includes_direct = r.get<uint32_t>("the header") != 0;
    data.passes = r.get<uint64_t>("the header");
    const uint64_t probes = r.get<uint64_t>("the header");
    if (data.order < 1 || data.order > kMaxShOrder || volumes == 0 || volumes > kMaxProbeVolumes ||
        data.visibility_resolution < 1 || data.visibility_resolution > 64)
        throw IoError(format_message("probe file \"", path, "\" has an invalid header (order ",
                                     data.order, ", ", volumes, " volumes, visibility ",
                                     data.visibility_resolution, ")"));
    data.volumes.resize(volumes);
    for (ProbeVolume& v : data.volumes) {
        r.bytes(&v.world_from_volume[0][0], 16 * sizeof(float), "a volume");
        r.bytes(&v.resolution[0], 3 * sizeof(int32_t), "a volume");
    }
    const uint64_t expected = checked_volumes(data.volumes, path);
    if (probes != expected)
        throw IoError(format_message("probe file \"", path, "\" says ", probes,
                                     " probes; its volumes hold ", expected));
    // The rest of the file must hold exactly those probes. Checked before anything is allocated,
    // so that a damaged header cannot make a small file ask for gigabytes.
    const uint64_t probe_bytes = sizeof(vec3) + 1 + sizeof(float) +
                                 packed_probe_bytes(data.order) +
                                 uint64_t(data.visibility_resolution) *
                                     uint64_t(data.visibility_resolution) * sizeof(vec2);
    const uint64_t remaining = r.remaining_bytes();
    if (remaining % probe_bytes != 0 || remaining / probe_bytes != probes)
        throw IoError(format_message("probe file \"", path, "\" says ", probes, " probes of ",
                                     probe_bytes, " bytes, but ", remaining,
                                     " bytes follow its header (truncated or damaged?)"));
    require_memory(saturating_mul(probes, sizeof(vec3) + 1 + sizeof(float) + sizeof(ShRgb) +
                                              uint64_t(data.visibility_resolution) *
                                                  data.visibility_resolution * sizeof(vec2)),
                   format_message("probe file \"", path, "\" with ", probes,
                                  " probes (visibility_resolution ", data.visibility_resolution,
                                  ")"),
                   "load it in a process with more memory, or re-bake with fewer probes");
    data.positions.resize(probes);
    r.bytes(data.positions.data(), probes * sizeof(vec3), "the positions");
    data.active.resize(probes);
    r.bytes(data.active.data(), probes, "the active flags");
    data.variance.resize(probes);
    r.bytes(data.variance.data(), probes * sizeof(float), "the variances");
    std::vector<uint8_t> packed(packed_probe_bytes(data.order));
    data.sh.reserve(probes);
    for (uint64_t i = 0; i < probes; ++i) {
        r.bytes(packed.data(), packed.size(), "the SH coefficients");
        data.sh.push_back(unpack_probe_sh(packed.data(), data.order));
    }
    data.visibility.resize(probes * uint64_t(data.visibility_resolution) *
                           data.visibility_resolution);
    r.bytes(data.visibility.data(), data.visibility.size() * sizeof(vec2), "the visibility maps");
    if (in.peek() != std::ifstream::traits_type::eof())
        throw IoError(format_message("probe file \"", path, "\" has data after its end"));
    validate_probe_grid_data(data);
    return data;
}

void export_probe_grid(const std::string& json_path, const ProbeGridData& data) {
    validate_probe_grid_data(data);
    const std::string stem = json_stem(json_path);
    const int coefficients = sh_num_coefficients(data.order);
    const int res = data.visibility_resolution;
    nlohmann::json volumes = nlohmann::json::array();
    for (size_t v = 0; v < data.volumes.size(); ++v) {
        const ProbeVolume& volume = data.volumes[v];
        const ivec3 n = volume.resolution;
        const size_t offset = data.volume_offset(v);
        const size_t count = size_t(n.x) * n.y * n.z;
        Image sh_image(n.x, n.y * n.z);
        for (int c = 0; c < coefficients; ++c) {
            std::vector<float> pixels(count * 3);
            for (size_t p = 0; p < count; ++p)
                for (int k = 0; k < 3; ++k) pixels[3 * p + k] = data.sh[offset + p][c][k];
            sh_image.add_layer("sh" + two_digits(c), {"R", "G", "B"}, pixels);
        }
        std::vector<float> position(count * 3), active(count), variance(count);
        for (size_t p = 0; p < count; ++p) {
            for (int k = 0; k < 3; ++k) position[3 * p + k] = data.positions[offset + p][k];
            active[p] = data.active[offset + p] ? 1.0f : 0.0f;
            variance[p] = data.variance[offset + p];
        }
        sh_image.add_layer("Position", {"X", "Y", "Z"}, position);
        sh_image.add_layer("Active", {"V"}, active);
        sh_image.add_layer("Variance", {"V"}, variance);
        Image vis_image(n.x * res, n.y * n.z * res);
        std::vector<float> moments(size_t(vis_image.width()) * vis_image.height() * 2);
        for (size_t p = 0; p < count; ++p) {
            const size_t px = p % size_t(n.x), row = p / size_t(n.x);
            const vec2* map = data.visibility_map(offset + p);
            for (int y = 0; y < res; ++y)
                for (int x = 0; x < res; ++x) {
                    const size_t pixel = (row * res + y) * size_t(vis_image.width()) + px * res + x;
                    moments[2 * pixel] = map[y * res + x].x;
                    moments[2 * pixel + 1] = map[y * res + x].y;
                }
        }
        vis_image.add_layer("Distance", {"Mean", "MeanSquare"}, moments);
        const std::string sh_file = stem + "_volume" + std::to_string(v) + ".exr";
        const std::string vis_file = stem + "_volume" + std::to_string(v) + "_visibility.exr";
        write_exr(sh_file, sh_image);
        write_exr(vis_file, vis_image);
        nlohmann::json matrix = nlohmann::json::array();
        for (int col = 0; col < 4; ++col)
            for (int row = 0; row < 4; ++row) matrix.push_back(volume.world_from_volume[col][row]);
        volumes.push_back({{"world_from_volume", matrix},
                           {"resolution", {n.x, n.y, n.z}},
                           {"sh_file", file_name(sh_file)},
                           {"visibility_file", file_name(vis_file)}});
    }
    const nlohmann::json doc = {
        {"format", kFormatName},
        {"version", kProbeFileVersion},
        {"frame", "Blender world space: right-handed, Z up, metres"},
        {"sh",
         {{"order", data.order},
          {"coefficients", coefficients},
          {"quantity", data.includes_direct ? "incident radiance (direct and indirect)"
                                            : "indirect incident radiance (light that scattered "
                                              "at least once; add direct light separately)"},
          {"unit", "W m^-2 sr^-1, linear Rec.709 RGB"},
          {"basis",
           "real orthonormal spherical harmonics without the Condon-Shortley phase; coefficient "
           "index i = l(l+1)+m; Y00 = 0.282095, Y1-1 = 0.488603 y, Y10 = 0.488603 z, "
           "Y11 = 0.488603 x (Ramamoorthi-Hanrahan)"},
          {"normalisation",
           "L(w) = sum_i c_i Y_i(w); irradiance E(n) = sum_lm A_l c_lm Y_lm(n) with A_0..A_4 = "
           "pi, 2pi/3, pi/4, 0, -pi/24"},
          {"channels", "sh<ii>.R/G/B, ii = two-digit coefficient index"}}},
        {"layout",
         "per volume: probe (i, j, k) at cell centre -1 + (2 i + 1) / n of the volume's "
         "[-1,1]^3 (world = world_from_volume * local, column-major 4x4); in the SH EXR at pixel "
         "column i, row j + ny * k (row 0 first in the file); channels Position.X/Y/Z (probe "
         "after relocation), Active.V (0: inside geometry, unused), Variance.V (variance of the "
         "DC luminance estimate)"},
        {"visibility",
         {{"resolution", res},
          {"mapping", "octahedral (Cigolle et al. 2014): u, v in [0,1], texel centres; upper "
                      "hemisphere (+Z) in the inner diamond"},
          {"layout", "probe (i, j, k)'s res x res map at pixel (i * res, (j + ny * k) * res)"},
          {"channels", "Distance.Mean (m), Distance.MeanSquare (m^2) of hit distances around "
                       "each texel's direction; used with Chebyshev's inequality"}}},
        {"passes", data.passes},
        {"volumes", volumes}};
    write_file_atomically(json_path, [&](const std::string& temp) {
        std::ofstream out(temp, std::ios::trunc);
        out << doc.dump(2) << "\n";
        out.flush();
        if (!out) throw IoError(format_message("cannot write \"", json_path, "\""));
    });
}

namespace {

// An integer field, exactly: nlohmann's get<int>() would truncate 1.5 to 1 and read true as 1.
template <typename T>
T json_integer(const nlohmann::json& value, const std::string& json_path, const char* key) {
    const bool fits = std::is_signed_v<T> ? value.is_number_integer() : value.is_number_unsigned();
    if (!fits)
        throw IoError(format_message("\"", json_path, "\": ", key, " is ", value.dump(),
                                     "; it must be ", std::is_signed_v<T> ? "an" : "a non-negative",
                                     " integer"));
    return value.get<T>();
}

}  // namespace

ProbeGridData import_probe_grid(const std::string& json_path) {
    require_readable_file(json_path, "probe grid JSON");
    std::ifstream in(json_path);
    if (!in) throw IoError(format_message("cannot open probe grid JSON \"", json_path, "\""));
    nlohmann::json doc;
    try {
        doc = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
        throw IoError(format_message("\"", json_path, "\" is not valid JSON: ", e.what()));
    }
    const std::filesystem::path folder = std::filesystem::path(json_path).parent_path();
    try {
        if (doc.value("format", "") != kFormatName)
            throw IoError(format_message("\"", json_path, "\" is not an SHGI probe grid (format \"",
                                         doc.value("format", ""), "\")"));
        const uint32_t version = json_integer<uint32_t>(doc.at("version"), json_path, "version");
        if (version != kProbeFileVersion)
            throw IoError(format_message("\"", json_path, "\" has version ", version,
                                         "; this SHGI reads ", kProbeFileVersion));
        ProbeGridData data;
        data.order = json_integer<int>(doc.at("sh").at("order"), json_path, "sh.order");
        check_sh_order(data.order, "sh.order");
        data.includes_direct =
            doc.at("sh").at("quantity").get<std::string>().find("direct and") != std::string::npos;
        data.visibility_resolution = json_integer<int>(doc.at("visibility").at("resolution"),
                                                       json_path, "visibility.resolution");
        data.passes = json_integer<uint64_t>(doc.at("passes"), json_path, "passes");
        const int res = data.visibility_resolution;
        if (res < 1 || res > 64)
            throw IoError(format_message("\"", json_path, "\": visibility resolution ", res));
        const int coefficients = sh_num_coefficients(data.order);
        // Every volume and the probe count first, before any EXR is read: a small JSON listing
        // many (or many large) volumes must not make the import ask for gigabytes.
        const nlohmann::json& entries = doc.at("volumes");
        const size_t listed = entries.is_array() ? entries.size() : 0;
        std::vector<ProbeVolume> volumes(listed);
        for (size_t v = 0; v < listed; ++v) {
            const nlohmann::json& entry = entries[v];
            ProbeVolume& volume = volumes[v];
            const auto matrix = entry.at("world_from_volume").get<std::vector<float>>();
            std::vector<int> resolution;
            for (const nlohmann::json& count : entry.at("resolution"))
                resolution.push_back(json_integer<int>(count, json_path, "a volume's resolution"));
            if (matrix.size() != 16 || resolution.size() != 3)
                throw IoError(format_message("\"", json_path, "\": a volume needs 16 matrix "
                                             "entries and 3 resolutions"));
            for (int i = 0; i < 16; ++i) volume.world_from_volume[i / 4][i % 4] = matrix[size_t(i)];
            volume.resolution = ivec3(resolution[0], resolution[1], resolution[2]);
        }
        checked_volumes(volumes, json_path);
        for (size_t v = 0; v < listed; ++v) {
            const nlohmann::json& entry = entries[v];
            const ProbeVolume& volume = volumes[v];
            const ivec3 n = volume.resolution;
            const size_t count = size_t(n.x) * n.y * n.z;
            const auto path_of = [&](const char* key) {
                return (folder / entry.at(key).get<std::string>()).string();
            };
            const std::string sh_path = path_of("sh_file");
            const std::string vis_path = path_of("visibility_file");
            // Any failure reading an EXR names it: a bare std::exception from the EXR library
            // would reach Python as a RuntimeError without the file's name.
            const auto read_named = [&](const std::string& path) {
                try {
                    return read_exr(path);
                } catch (const Error&) {
                    throw;
                } catch (const std::bad_alloc&) {
                    throw OutOfMemory(format_message("cannot read EXR \"", path, "\" (listed by \"",
                                                     json_path, "\"): out of memory"));
                } catch (const std::exception& error) {
                    throw IoError(format_message("cannot read EXR \"", path, "\" (listed by \"",
                                                 json_path, "\"): ", error.what()));
                }
            };
            const Image sh_image = read_named(sh_path);
            const Image vis_image = read_named(vis_path);
            if (sh_image.width() != n.x || sh_image.height() != n.y * n.z ||
                vis_image.width() != n.x * res || vis_image.height() != n.y * n.z * res)
                throw IoError(format_message("\"", sh_path, "\" or \"", vis_path,
                                             "\" does not match the volume's resolution"));
            const auto layer = [&](const Image& image, const std::string& name,
                                   const std::string& path) {
                try {
                    return image.layer_pixels(name);
                } catch (const InvalidArgument&) {
                    throw IoError(format_message("\"", path, "\" has no layer ", name));
                }
            };
            const size_t first = data.positions.size();
            data.sh.resize(first + count, ShRgb(data.order));
            for (int c = 0; c < coefficients; ++c) {
                const std::vector<float> pixels = layer(sh_image, "sh" + two_digits(c), sh_path);
                if (pixels.size() != count * 3)
                    throw IoError(format_message("\"", sh_path, "\": layer sh", two_digits(c),
                                                 " is not RGB"));
                for (size_t p = 0; p < count; ++p)
                    data.sh[first + p][c] =
                        vec3(pixels[3 * p], pixels[3 * p + 1], pixels[3 * p + 2]);
            }
            const std::vector<float> position = layer(sh_image, "Position", sh_path);
            const std::vector<float> active = layer(sh_image, "Active", sh_path);
            const std::vector<float> variance = layer(sh_image, "Variance", sh_path);
            const std::vector<float> moments = layer(vis_image, "Distance", vis_path);
            if (position.size() != count * 3 || active.size() != count ||
                variance.size() != count || moments.size() != count * res * res * 2)
                throw IoError(format_message("\"", sh_path, "\": unexpected channel counts"));
            for (size_t p = 0; p < count; ++p) {
                data.positions.push_back(vec3(position[3 * p], position[3 * p + 1],
                                              position[3 * p + 2]));
                data.active.push_back(active[p] > 0.5f ? 1 : 0);
                data.variance.push_back(variance[p]);
            }
            data.visibility.resize(data.positions.size() * size_t(res) * res);
            for (size_t p = 0; p < count; ++p) {
                const size_t px = p % size_t(n.x), row = p / size_t(n.x);
                vec2* map = data.visibility.data() + (first + p) * size_t(res) * res;
                for (int y = 0; y < res; ++y)
                    for (int x = 0; x < res; ++x) {
                        const size_t pixel = (row * res + y) * size_t(n.x) * res + px * res + x;
                        map[y * res + x] = vec2(moments[2 * pixel], moments[2 * pixel + 1]);
                    }
            }
            data.volumes.push_back(volume);
        }
        validate_probe_grid_data(data);
        return data;
    } catch (const nlohmann::json::exception& e) {
        throw IoError(format_message("\"", json_path, "\" is not a probe grid export: ", e.what()));
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw;
    } catch (const std::exception& e) {
        throw IoError(format_message("cannot import probe grid \"", json_path, "\": ", e.what()));
    }
}

}  // namespace shgi
