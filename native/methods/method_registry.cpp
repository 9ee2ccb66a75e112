#include "methods/method_registry.h"

#include <algorithm>
#include <mutex>

#include "lattice/photon_lattice.h"
#include "probes/probe_grid.h"
#include "radiance/radiance_field.h"
#include "instant/instant_gi.h"
#include "propagation/propagation_volume.h"

namespace shgi {
namespace {

// The built-in methods, in menu order. A new method adds its row here.
std::vector<MethodInfo> built_in_rows() {
    std::vector<MethodInfo> rows;
    rows.push_back({"PATH_TRACE", "Path Tracing",
                    "Reference path tracer: unbiased, matches Cycles, slowest to converge", 0,
                    {"PATH_TRACER"}, "PathTracerSettings", 0, {}});
    rows.push_back({"PHOTON_LATTICE", "Photon Lattice",
                    "Photons shot from the lights fill a 3D grid of indirect light: fast and "
                    "smooth, best for diffuse scenes; exact direct light",
                    1, {}, "PhotonLatticeSettings", 1,
                    solver_factory<PhotonLattice, PhotonLatticeSettings>("PhotonLatticeSettings")});
    // Eight passes: the grid keeps the exact running mean of its passes this early (hysteresis
    // blending starts later, probes/probe_grid.h), so a final solve is one 8x-sized pass.
    rows.push_back({"PROBE_GRID", "Probe Grid",
                    "Light probes (placed by Irradiance Volume objects) gather indirect light "
                    "without leaking through walls, refined in the background; exact direct light",
                    2, {}, "ProbeGridSettings", 8,
                    solver_factory<ProbeGrid, ProbeGridSettings>("ProbeGridSettings")});
    rows.push_back({"RADIANCE_FIELD", "Radiance Field",
                    "Photons shot from the lights are gathered on a grid of surface radiance, and "
                    "rays from points near surfaces turn it into smooth indirect light: photon "
                    "mapping with a cheap final gather; exact direct light",
                    4, {}, "RadianceFieldSettings", 1,
                    solver_factory<RadianceField, RadianceFieldSettings>("RadianceFieldSettings")});
    rows.push_back({"PROPAGATION", "Light Propagation Volumes",
                    "Light from where the lights land spreads cell to cell through a coarse "
                    "grid: a fixed cost, soft and approximate light that may leak through thin "
                    "walls; exact direct light",
                    3, {}, "PropagationSettings", 1,
                    solver_factory<PropagationVolume, PropagationSettings>(
                        "PropagationSettings")});
    rows.push_back({"INSTANT_GI", "Instant GI",
                    "Light from a few hundred virtual point lights with exact shadows, each pixel "
                    "seeing its own set, then blended across neighbouring pixels in SH so normal "
                    "maps keep their detail; exact direct light",
                    5, {}, "InstantGiSettings", 4,
                    solver_factory<InstantGi, InstantGiSettings>("InstantGiSettings")});
    return rows;
}

struct Registry {
    std::mutex mutex;
    std::vector<MethodInfo> rows = built_in_rows();
    size_t built_in = rows.size();
};

Registry& registry() {
    static Registry instance;
    return instance;
}

bool names_row(const MethodInfo& row, std::string_view name) {
    return row.identifier == name ||
           std::find(row.aliases.begin(), row.aliases.end(), name) != row.aliases.end();
}

std::string choices(const std::vector<MethodInfo>& rows) {
    std::string out;
    for (const MethodInfo& row : rows) out += (out.empty() ? "" : ", ") + row.identifier;
    return out;
}

void check_row(const MethodInfo& row, const std::vector<MethodInfo>& rows) {
    if (row.identifier.empty() || row.label.empty() || row.settings_type.empty())
        throw InvalidArgument(format_message("method '", row.identifier,
                                             "': identifier, label and settings_type are needed"));
    if (row.number < 0)
        throw InvalidArgument(format_message("method '", row.identifier, "': number ",
                                             row.number, " must be >= 0"));
    std::vector<std::string> names = row.aliases;
    names.push_back(row.identifier);
    for (const MethodInfo& other : rows) {
        for (const std::string& name : names)
            if (names_row(other, name))
                throw InvalidArgument(format_message("method '", row.identifier, "': the name '",
                                                     name, "' is taken by method '",
                                                     other.identifier, "'"));
        if (other.number == row.number)
            throw InvalidArgument(format_message("method '", row.identifier, "': number ",
                                                 row.number, " is taken by method '",
                                                 other.identifier, "'"));
    }
    for (const auto& [identifier, number] : reserved_method_numbers())
        if (number == row.number && identifier != row.identifier)
            throw InvalidArgument(format_message("method '", row.identifier, "': number ",
                                                 row.number, " is reserved for method '",
                                                 identifier, "'"));
}

}  // namespace

std::vector<MethodInfo> registered_methods() {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.mutex);
    return r.rows;
}

std::vector<std::pair<std::string, int>> reserved_method_numbers() {
    return {};
}

MethodInfo find_method(std::string_view name) {
    const std::vector<MethodInfo> rows = registered_methods();
    for (const MethodInfo& row : rows)
        if (names_row(row, name)) return row;
    throw InvalidArgument(format_message("method '", name, "' is not known; use one of ",
                                         choices(rows)));
}

void register_method(MethodInfo row) {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.mutex);
    check_row(row, r.rows);
    r.rows.push_back(std::move(row));
}

bool unregister_method(std::string_view identifier) {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.mutex);
    const auto first_added = r.rows.begin() + std::ptrdiff_t(r.built_in);
    const auto it = std::find_if(first_added, r.rows.end(), [&](const MethodInfo& row) {
        return row.identifier == identifier;
    });
    if (it == r.rows.end()) return false;
    r.rows.erase(it);
    return true;
}

std::unique_ptr<GiSolver> make_solver(std::string_view method, const Scene& scene,
                                      const std::any& settings, Progress* progress) {
    const MethodInfo row = find_method(method);
    if (!row.solves_field())
        throw InvalidArgument(format_message("method '", row.identifier,
                                             "' solves no field: it renders and bakes by path "
                                             "tracing (render_path_traced, bake_lightmap)"));
    return row.make(scene, settings, progress);
}

}  // namespace shgi
