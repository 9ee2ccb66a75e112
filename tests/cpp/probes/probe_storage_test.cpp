// Probe storage: the fp16 packing's size and error bound, the binary cache and the EXR + JSON
// export round trips, and rejection of damaged files.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "probes/probe_storage.h"
#include "support/expect_error.h"
#include "support/test_folder.h"
#include "util/rng.h"

namespace shgi {
namespace {

using testing::expect_error;
using testing::test_file_path;

TEST(ProbeStorage, PackedSizes) {
    EXPECT_EQ(packed_probe_bytes(2), 56u);  // seed 002 §5.2
    EXPECT_EQ(packed_probe_bytes(1), 24u);
    EXPECT_EQ(packed_probe_bytes(3), 96u);
    EXPECT_EQ(packed_probe_bytes(4), 152u);
}

// Half floats keep 11 significant bits: relative error <= 2^-11 for normal values, absolute
// <= 2^-25 below the smallest normal half (6.1e-5); out-of-range values clamp to 65504.
TEST(ProbeStorage, Fp16PackingErrorBound) {
    Pcg32 rng(9, 0);
    for (int order = 1; order <= 4; ++order) {
        for (int trial = 0; trial < 200; ++trial) {
            ShRgb sh(order);
            for (int i = 0; i < 3 * sh.num_coefficients(); ++i) {
                const float magnitude = std::pow(10.0f, -6.0f + 10.0f * rng.next_float());
                sh.data()[i] = (rng.next_float() < 0.5f ? -1.0f : 1.0f) * magnitude;
            }
            std::vector<uint8_t> packed(packed_probe_bytes(order) + 4, 0xAB);
            pack_probe_sh(sh, packed.data());
            EXPECT_EQ(packed[packed_probe_bytes(order)], 0xAB);  // nothing written beyond
            const ShRgb back = unpack_probe_sh(packed.data(), order);
            for (int i = 0; i < 3 * sh.num_coefficients(); ++i) {
                const float v = sh.data()[i], u = back.data()[i];
                if (std::abs(v) > 65504.0f)
                    EXPECT_EQ(std::abs(u), 65504.0f);
                else if (std::abs(v) >= 6.103515625e-5f)
                    EXPECT_LE(std::abs(u - v), std::abs(v) * 0x1p-11f) << v;
                else
                    EXPECT_LE(std::abs(u - v), 0x1p-25f) << v;
            }
        }
    }
}

ProbeGridData sample_data() {
    ProbeGridData data;
    data.order = 2;
    ProbeVolume a;
    a.world_from_volume = glm::translate(mat4(1.0f), vec3(1.0f, 2.0f, 3.0f)) *
                          glm::scale(mat4(1.0f), vec3(2.0f, 1.0f, 0.5f));
    a.resolution = ivec3(3, 2, 2);
    ProbeVolume b;
    b.resolution = ivec3(1, 2, 1);
    data.volumes = {a, b};
    data.positions = probe_base_positions(data.volumes);
    const size_t n = data.positions.size();
    data.visibility_resolution = 4;
    Pcg32 rng(4, 0);
    for (size_t i = 0; i < n; ++i) {
        data.positions[i] += vec3(0.01f * float(i));
        data.active.push_back(i % 5 == 3 ? 0 : 1);
        ShRgb sh(2);
        for (int c = 0; c < 27; ++c) sh.data()[c] = rng.next_float() - 0.25f;
        data.sh.push_back(sh);
        data.variance.push_back(0.001f * float(i));
        for (int t = 0; t < 16; ++t) {
            const float d = 1.0f + rng.next_float();
            data.visibility.push_back(vec2(d, d * d + 0.1f));
        }
    }
    data.passes = 12;
    return data;
}

void expect_same_layout(const ProbeGridData& a, const ProbeGridData& b) {
    ASSERT_EQ(a.probe_count(), b.probe_count());
    EXPECT_EQ(a.order, b.order);
    EXPECT_EQ(a.passes, b.passes);
    ASSERT_EQ(a.volumes.size(), b.volumes.size());
    for (size_t v = 0; v < a.volumes.size(); ++v) {
        EXPECT_EQ(a.volumes[v].world_from_volume, b.volumes[v].world_from_volume);
        EXPECT_EQ(a.volumes[v].resolution, b.volumes[v].resolution);
    }
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.active, b.active);
    EXPECT_EQ(a.variance, b.variance);
    EXPECT_EQ(a.visibility, b.visibility);
}

TEST(ProbeStorage, BinaryCacheRoundTripsAtHalfPrecision) {
    const ProbeGridData data = sample_data();
    const std::string path = test_file_path("probes", "grid.shprobes");
    save_probe_grid(path, data);
    const auto size = std::filesystem::file_size(path);
    const ProbeGridData back = load_probe_grid(path);
    expect_same_layout(data, back);
    for (size_t i = 0; i < data.probe_count(); ++i)
        for (int c = 0; c < 27; ++c)
            EXPECT_NEAR(back.sh[i].data()[c], data.sh[i].data()[c],
                        std::abs(data.sh[i].data()[c]) * 0x1p-11f + 0x1p-25f);
    EXPECT_GE(size, data.probe_count() * 56u);

    // Truncated, foreign and future files are refused with their path named.
    std::filesystem::resize_file(path, size - 3);
    expect_error<IoError>([&] { load_probe_grid(path); }, {"grid.shprobes", "truncated"});
    testing::write_file(path, "PNG....................................");
    expect_error<IoError>([&] { load_probe_grid(path); }, {"not an SHGI probe file"});
    save_probe_grid(path, data);
    {
        std::fstream file(path, std::ios::binary | std::ios::in | std::ios::out);
        file.seekp(8);
        const uint32_t version = 99;
        file.write(reinterpret_cast<const char*>(&version), sizeof(version));
    }
    expect_error<IoError>([&] { load_probe_grid(path); }, {"version 99"});
    expect_error<IoError>([&] { load_probe_grid(path + ".missing"); }, {"cannot open"});

    // A header that promises more probes than the file holds is refused before anything that
    // size is allocated: both volumes claim `side`^3 probes. 64^3 each is ~0.1 GB of data in a
    // 1 KB file; 256^3 each is past the probe cap, refused by that.
    const auto claim = [&](int32_t side) {
        save_probe_grid(path, data);
        std::fstream file(path, std::ios::binary | std::ios::in | std::ios::out);
        const uint64_t probes = 2ull * uint64_t(side) * uint64_t(side) * uint64_t(side);
        file.seekp(36);  // after the magic (8), five uint32 fields and passes (8)
        file.write(reinterpret_cast<const char*>(&probes), sizeof(probes));
        const int32_t resolution[3] = {side, side, side};
        for (int v = 0; v < 2; ++v) {
            file.seekp(44 + v * (16 * 4 + 3 * 4) + 16 * 4);  // after the volume's matrix
            file.write(reinterpret_cast<const char*>(resolution), sizeof(resolution));
        }
    };
    claim(64);
    expect_error<IoError>([&] { load_probe_grid(path); },
                          {"grid.shprobes", "says 524288 probes", "truncated or damaged"});
    claim(256);
    expect_error<IoError>([&] { load_probe_grid(path); },
                          {"grid.shprobes", "volumes hold 33554432 probes",
                           "the limit is 2097152"});
}

TEST(ProbeStorage, ExrJsonExportRoundTrips) {
    const ProbeGridData data = sample_data();
    const std::string path = test_file_path("probes", "export.json");
    export_probe_grid(path, data);
    const ProbeGridData back = import_probe_grid(path);
    expect_same_layout(data, back);
    for (size_t i = 0; i < data.probe_count(); ++i)
        for (int c = 0; c < 27; ++c) EXPECT_EQ(back.sh[i].data()[c], data.sh[i].data()[c]);

    std::ifstream json(path);
    const std::string text((std::istreambuf_iterator<char>(json)), std::istreambuf_iterator<char>());
    for (const char* part : {"\"format\": \"shgi-probe-grid\"", "Condon-Shortley", "W m^-2 sr^-1",
                             "export_volume0.exr", "export_volume1_visibility.exr", "octahedral"})
        EXPECT_NE(text.find(part), std::string::npos) << part;

    std::filesystem::remove(test_file_path("probes", "export_volume1.exr"));
    expect_error<IoError>([&] { import_probe_grid(path); }, {"export_volume1.exr"});
    expect_error<InvalidArgument>([&] { export_probe_grid(path + ".txt", data); }, {".json"});
    testing::write_file(path, "{\"format\": \"other\"}");
    expect_error<IoError>([&] { import_probe_grid(path); }, {"not an SHGI probe grid"});
}

// The JSON is read whole before any EXR: an export that lists more volumes, or larger ones,
// than a grid may hold is refused by name (the EXRs are gone, so reading one would fail with
// its file name instead), not by a bad_alloc after gigabytes of reading.
TEST(ProbeStorage, ImportRefusesTooManyVolumesOrProbesBeforeReadingExrs) {
    const std::string path = test_file_path("probes", "listing.json");
    export_probe_grid(path, sample_data());
    std::ifstream in(path);
    const nlohmann::json original = nlohmann::json::parse(in);
    in.close();
    for (const char* exr : {"listing_volume0.exr", "listing_volume0_visibility.exr",
                            "listing_volume1.exr", "listing_volume1_visibility.exr"})
        std::filesystem::remove(test_file_path("probes", exr));

    nlohmann::json doc = original;
    doc["volumes"] = nlohmann::json::array();
    for (size_t v = 0; v <= kMaxProbeVolumes; ++v) doc["volumes"].push_back(original["volumes"][0]);
    testing::write_file(path, doc.dump());
    expect_error<IoError>([&] { import_probe_grid(path); },
                          {"listing.json", "volumes holds 4097 volumes", "1..4096"});

    doc = original;
    doc["volumes"][1]["resolution"] = {256, 256, 64};
    testing::write_file(path, doc.dump());
    expect_error<IoError>([&] { import_probe_grid(path); },
                          {"listing.json", "hold 4194316 probes", "the limit is 2097152"});

    doc = original;
    doc["volumes"] = nlohmann::json::object();
    testing::write_file(path, doc.dump());
    expect_error<IoError>([&] { import_probe_grid(path); }, {"listing.json", "holds 0 volumes"});
}

TEST(ProbeStorage, InconsistentDataIsRefused) {
    ProbeGridData data = sample_data();
    data.sh[3].data()[4] = std::nanf("");
    expect_error<InvalidArgument>([&] { validate_probe_grid_data(data); }, {"sh[3]", "finite"});
    data = sample_data();
    data.active.pop_back();
    expect_error<InvalidArgument>([&] { validate_probe_grid_data(data); }, {"active", "entries"});
    data = sample_data();
    data.volumes.assign(kMaxProbeVolumes + 1, ProbeVolume{});
    expect_error<InvalidArgument>([&] { validate_probe_grid_data(data); },
                                  {"ProbeGridData.volumes holds 4097 volumes; a probe grid has "
                                   "1..4096"});
    data = sample_data();
    data.volumes[0].resolution = ivec3(256, 256, 32);
    expect_error<InvalidArgument>([&] { validate_probe_grid_data(data); },
                                  {"2097154 probes; the limit is 2097152"});
}

}  // namespace
}  // namespace shgi
