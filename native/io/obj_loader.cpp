// OBJ + MTL loading (see obj_loader.h). The only file that includes tiny_obj_loader.h.
//
// tinyobjloader parses; this file checks every face index itself (tinyobjloader only warns about
// indices past the end, and its own triangulation would read through them), triangulates,
// welds corners into vertices and maps MTL statements the way Blender's importer does. Which
// statements a material actually contains is needed for Blender's fallbacks, and tinyobjloader
// fills absent ones with zeros, so the .mtl text is read here and its statement keys recorded
// before tinyobjloader parses it.
#include "io/obj_loader.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <charconv>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "io/image.h"
#include "util/error.h"
#include "util/log.h"
#include "util/text.h"

namespace shgi {
namespace {

// Blender's importer clamps the specular exponent to this range before mapping it to roughness.
constexpr float kMaxSpecularExponent = 1000.0f;
// Blender's importer's IOR for transparent (illum 6, 7) and glass (illum 4, 9) modes without Ni.
constexpr float kTransparentIor = 1.0f;
constexpr float kGlassIor = 1.5f;

std::string trimmed(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    return text;
}

std::string directory_of(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

// ---------------------------------------------------------------------------------------------
// Step 1: reading the .obj and its .mtl files.

// tinyobjloader reads a number it cannot parse ("nan", "inf", "1e39", an index past 2^31) as 0
// or as a wrapped integer, without a word, so "v nan 5 5" loaded as x = 0 and "f 1 2
// 18446744073709551616" as vertex 4. Every numeric statement is checked here first, and a file
// holding a bad number is refused with the line that holds it.
class NumberCheck {
  public:
    explicit NumberCheck(const std::string& path) : path_(path) {}

    // The OBJ statements with numbers: positions, normals, texture coordinates, elements.
    void check_obj(const std::string& text) {
        for_each_statement(text, [this](const std::vector<std::string>& words) {
            const std::string& key = words[0];
            if (key == "v" || key == "vn") require_floats(words, 1, 3, "a coordinate");
            else if (key == "vt") require_floats(words, 1, 1, "a texture coordinate");
            else if (key == "f" || key == "l" || key == "p") require_indices(words);
        });
    }

    // The MTL statements with numbers (a colour may also be "spectral file" or "xyz x y z").
    void check_mtl(const std::string& text) {
        static const std::set<std::string> colours = {"Ka", "Kd", "Ks", "Ke", "Kt", "Tf"};
        static const std::set<std::string> scalars = {"Ns", "Ni", "d",  "Tr", "Pr",    "Pm",
                                                      "Ps", "Pc", "Pcr", "aniso", "anisor"};
        for_each_statement(text, [this](const std::vector<std::string>& words) {
            const std::string& key = words[0];
            if (colours.count(key) && words.size() > 1 && words[1] != "spectral")
                require_floats(words, words[1] == "xyz" ? 2 : 1, 1, ("the " + key).c_str());
            else if (scalars.count(key) && words.size() > 1 && words[1] != "-halo")
                require_floats(words, 1, 1, ("the " + key).c_str());
        });
    }

  private:
    template <class Visit>
    void for_each_statement(const std::string& text, const Visit& visit) {
        std::istringstream lines(text);
        std::string line;
        for (line_ = 1; std::getline(lines, line); ++line_) {
            std::istringstream words_of_line(line);
            std::vector<std::string> words;
            for (std::string word; words_of_line >> word;) words.push_back(word);
            if (!words.empty() && words[0][0] != '#') visit(words);
        }
    }

    void require_floats(const std::vector<std::string>& words, size_t first, size_t at_least,
                        const char* what) const {
        if (words.size() < first + at_least)
            fail(format_message("'", words[0], "' needs at least ", at_least, " number",
                                at_least > 1 ? "s" : "", " after it"));
        for (size_t i = first; i < words.size(); ++i) {
            if (!is_finite_float(words[i]))
                fail(format_message(what, " '", words[i], "' is not a finite number"));
        }
    }

    // std::from_chars, as it ignores the C locale (a "de_DE" one would make strtof stop at the
    // '.'), with the leading '+' it refuses skipped. A number too small for a float reads as 0,
    // as tinyobjloader takes it; one too large, "nan" or "inf" is no finite number.
    static bool is_finite_float(const std::string& word) {
        const char* begin = word.data() + (word[0] == '+' ? 1 : 0);
        const char* end = word.data() + word.size();
        float number = 0.0f;
        const auto [stop, error] = std::from_chars(begin, end, number);
        if (stop != end) return false;
        if (error == std::errc::result_out_of_range)
            return word.find("e-") != std::string::npos || word.find("E-") != std::string::npos;
        return error == std::errc() && std::isfinite(number);
    }

    // "f 1/2/3 4//6 -1": each part an integer other than 0 that fits an int (OBJ counts from 1,
    // negative counts back from the last).
    void require_indices(const std::vector<std::string>& words) const {
        for (size_t i = 1; i < words.size(); ++i) {
            std::istringstream parts(words[i]);
            for (std::string part; std::getline(parts, part, '/');) {
                if (part.empty()) continue;
                int index = 0;
                const auto [stop, error] =
                    std::from_chars(part.data(), part.data() + part.size(), index);
                if (stop != part.data() + part.size() || error != std::errc() || index == 0 ||
                    index == std::numeric_limits<int>::min())
                    fail(format_message("index '", part, "' in '", words[i], "' is not a vertex "
                                        "number (a whole number from 1, or negative from -1, "
                                        "within ", std::numeric_limits<int>::max(), ")"));
            }
        }
    }

    [[noreturn]] void fail(const std::string& problem) const {
        throw IoError(format_message(path_, ":", line_, ": ", problem, "; fix the line or the "
                                     "exporter that wrote it"));
    }

    const std::string& path_;
    int line_ = 0;
};

std::string read_text(const std::string& path, std::ifstream& file) {
    std::ostringstream text;
    text << file.rdbuf();
    if (file.bad()) throw IoError(format_message(path, ": read error (", std::strerror(errno), ")"));
    return text.str();
}

// Statement keys ("Kd", "Ns", "Pr", ...) present in each material, by material name.
using MaterialKeys = std::map<std::string, std::set<std::string>>;

void record_material_keys(const std::string& mtl_text, MaterialKeys& keys) {
    std::istringstream lines(mtl_text);
    std::string line;
    std::set<std::string>* current = nullptr;
    while (std::getline(lines, line)) {
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
            line.pop_back();
        const size_t start = line.find_first_not_of(" \t");
        if (start == std::string::npos || line[start] == '#') continue;
        const size_t end = line.find_first_of(" \t", start);
        const std::string key = line.substr(start, end - start);
        if (key == "newmtl" && end != std::string::npos) {
            // tinyobjloader's name: everything after "newmtl" and one separator.
            current = &keys[line.substr(end + 1)];
        } else if (current) {
            current->insert(key);
        }
    }
}

// Reads .mtl files beside the .obj, recording their keys before tinyobjloader parses them.
class MtlReader : public tinyobj::MaterialReader {
  public:
    MtlReader(std::string directory, MaterialKeys& keys)
        : directory_(std::move(directory)), keys_(keys) {}

    bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                    std::map<std::string, int>* material_map, std::string* warn,
                    std::string* err) override {
        const std::string path = directory_ + name;
        if (is_special_file(path)) {  // "mtllib ../../dev/zero" read until memory ran out
            *warn += format_message("material library '", path, "' is not a regular file (a "
                                    "folder, device, FIFO or socket); its materials are replaced "
                                    "by the default material\n");
            return false;
        }
        std::ifstream file(path, std::ios::binary);
        if (!file) {
            *warn += format_message("material library '", path, "' not found (",
                                    std::strerror(errno), "); its materials are replaced by the "
                                    "default material\n");
            return false;
        }
        const std::string text = read_text(path, file);
        try {
            NumberCheck(path).check_mtl(text);
        } catch (const IoError& error) {
            // Thrown after tinyobjloader returns, not through it.
            if (first_error_.empty()) first_error_ = error.what();
            return false;
        }
        record_material_keys(text, keys_);
        std::istringstream stream(text);
        tinyobj::LoadMtl(material_map, materials, &stream, warn, err);
        return true;
    }

    // The first bad number found in a material library, or "".
    const std::string& first_error() const { return first_error_; }

  private:
    std::string directory_;
    MaterialKeys& keys_;
    std::string first_error_;
};

struct ObjData {
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    MaterialKeys material_keys;
};

ObjData read_obj(const std::string& path) {
    require_readable_file(path, "OBJ");
    std::ifstream file(path, std::ios::binary);
    if (!file)
        throw IoError(format_message(path, ": cannot open the file (", std::strerror(errno), ")"));
    const std::string text = read_text(path, file);
    NumberCheck(path).check_obj(text);
    std::istringstream stream(text);
    ObjData data;
    MtlReader mtl_reader(directory_of(path), data.material_keys);
    std::string warning, error;
    // No triangulation here: it would run before the indices are checked (see the file header).
    const bool ok = tinyobj::LoadObj(&data.attrib, &data.shapes, &data.materials, &warning,
                                     &error, &stream, &mtl_reader, /*triangulate=*/false,
                                     /*default_vcols_fallback=*/false);
    if (!mtl_reader.first_error().empty()) throw IoError(mtl_reader.first_error());
    // Index problems are reported precisely by the checks below; other warnings go to the log.
    std::istringstream warning_lines(warning);
    for (std::string line; std::getline(warning_lines, line);) {
        if (!line.empty() && line.find("indices out of bounds") == std::string::npos)
            log_warning(path, ": ", line);
    }
    if (!ok)
        throw IoError(format_message(path, ": not a valid OBJ file: ",
                                     error.empty() ? "unknown parse error" : trimmed(error)));
    if (!error.empty()) log_warning(path, ": ", trimmed(error));
    return data;
}

// ---------------------------------------------------------------------------------------------
// Step 2: MTL -> Material, after set_bsdf_socket_values() in Blender's obj_import_mtl.cc.

struct IllumModes {
    bool highlight = false, reflection = false, transparency = false, glass = false;
};

IllumModes illum_modes(int illum) {
    IllumModes modes;
    modes.highlight = illum == 2;
    modes.reflection = illum == 3 || illum == 4 || illum == 5 || illum == 6 || illum == 7 ||
                       illum == 8;
    modes.transparency = illum == 4 || illum == 6 || illum == 7 || illum == 9;
    modes.glass = illum == 4 || illum == 9;
    return modes;
}

// A shape or material name as the rest of SHGI takes it, UTF-8: bytes of another encoding
// (Latin-1 from older exporters) become \xNN escapes, with a warning naming them.
std::string utf8_name(const std::string& name, const char* kind, const std::string& path) {
    if (is_utf8(name)) return name;
    const std::string escaped = utf8_escaped(name);
    log_warning(path, ": ", kind, " name '", escaped, "' is not UTF-8; its bytes outside "
                "UTF-8 are kept as \\xNN escapes");
    return escaped;
}

float mean(const tinyobj::real_t rgb[3]) { return (rgb[0] + rgb[1] + rgb[2]) / 3.0f; }
vec3 to_vec3(const tinyobj::real_t rgb[3]) { return vec3(rgb[0], rgb[1], rgb[2]); }

Material material_from_mtl(const tinyobj::material_t& source, const std::set<std::string>& keys,
                           const std::string& path) {
    const auto has = [&keys](const char* key) { return keys.count(key) > 0; };
    const IllumModes modes = illum_modes(has("illum") ? source.illum : -1);
    Material material;
    material.name = utf8_name(source.name, "material", path);
    if (has("Kd")) material.base_color = to_vec3(source.diffuse);
    if (has("Ke")) material.emission_color = glm::max(to_vec3(source.emission), vec3(0.0f));
    material.specular = has("Ks") ? std::clamp(mean(source.specular), 0.0f, 1.0f)
                                  : (modes.highlight ? 1.0f : 0.0f);
    material.roughness = has("Pr")   ? std::clamp(float(source.roughness), 0.0f, 1.0f)
                         : has("Ns") ? obj_roughness_from_exponent(source.shininess)
                                     : (modes.highlight ? 0.0f : 1.0f);
    if (has("Pm"))
        material.metallic = std::clamp(float(source.metallic), 0.0f, 1.0f);
    else if (modes.reflection)
        material.metallic = has("Ka") ? std::clamp(mean(source.ambient), 0.0f, 1.0f) : 1.0f;
    else
        material.metallic = 0.0f;
    if (has("Ni")) {
        material.ior = float(source.ior);
        if (!(material.ior >= 1.0f)) {
            log_warning(path, ": material '", material.name, "' has Ni ", source.ior,
                        "; SHGI needs an IOR >= 1, using 1");
            material.ior = 1.0f;
        }
    } else if (modes.glass) {
        material.ior = kGlassIor;
    } else if (modes.transparency) {
        material.ior = kTransparentIor;
    }
    if (!source.diffuse_texname.empty())
        log_warning(path, ": material '", material.name, "': map_Kd '", source.diffuse_texname,
                    "' is not loaded (OBJ textures are not supported); using Kd");
    return material;
}

// ---------------------------------------------------------------------------------------------
// Step 3: shapes -> meshes.

class ObjImporter {
  public:
    ObjImporter(const std::string& path, const ObjData& data, const ObjLoadOptions& options,
                Progress* progress)
        : path_(path), data_(data), options_(options), progress_(progress) {}

    Scene run();

  private:
    void check_corner(const tinyobj::index_t& corner, const std::string& shape, size_t face) const;
    Mesh build_mesh(const tinyobj::shape_t& shape, const std::string& name);
    uint32_t add_corner(const tinyobj::index_t& corner, bool with_uv, bool with_normal,
                        Mesh& mesh);
    uint32_t material_id(int obj_material);
    vec3 to_blender(float x, float y, float z) const {
        return options_.up_axis == ObjUpAxis::Y ? vec3(x, -z, y) : vec3(x, y, z);
    }

    const std::string& path_;
    const ObjData& data_;
    const ObjLoadOptions& options_;
    Progress* progress_;
    Scene scene_;
    std::map<int, uint32_t> material_ids_;  // tinyobj material (-1 = none) -> SHGI material
    // Corner (v, vt, vn) -> vertex of the mesh being built.
    std::map<std::array<int, 3>, uint32_t> vertex_of_corner_;
};

Scene ObjImporter::run() {
    for (size_t s = 0; s < data_.shapes.size(); ++s) {
        throw_if_cancelled(progress_);
        if (progress_) progress_->report(s, data_.shapes.size());
        const tinyobj::shape_t& shape = data_.shapes[s];
        const std::string name = shape.name.empty() ? format_message("shape_", s)
                                                    : utf8_name(shape.name, "shape", path_);
        if (shape.mesh.num_face_vertices.empty()) {
            log_info(path_, ": shape '", name, "' has no faces (lines or points only); skipped");
            continue;
        }
        const uint32_t mesh_id = scene_.add_mesh(build_mesh(shape, name));
        scene_.add_instance(mesh_id, mat4(1.0f), name);
    }
    if (scene_.instances().empty()) log_warning(path_, ": the file has no faces");
    return std::move(scene_);
}

void ObjImporter::check_corner(const tinyobj::index_t& corner, const std::string& shape,
                               size_t face) const {
    const auto check = [&](int index, size_t count, const char* kind) {
        if (index < -1 || (index >= 0 && size_t(index) >= count))
            throw IoError(format_message(path_, ": shape '", shape, "' face ", face, " uses ",
                                         kind, " ", index + 1, " (1-based) but the file has ",
                                         count));
    };
    // tinyobjloader resolves a negative (relative) index against the vertices read so far, so
    // one that reaches before the first vertex arrives here below 0, as a missing one would.
    if (corner.vertex_index < 0)
        throw IoError(format_message(
            path_, ": shape '", shape, "' face ", face, " has a corner whose vertex index is "
            "missing or points before the first vertex (a negative index counts back from the "
            "last vertex defined above the face; the file has ", data_.attrib.vertices.size() / 3,
            " vertices)"));
    check(corner.vertex_index, data_.attrib.vertices.size() / 3, "vertex (v)");
    check(corner.texcoord_index, data_.attrib.texcoords.size() / 2, "texture coordinate (vt)");
    check(corner.normal_index, data_.attrib.normals.size() / 3, "normal (vn)");
}

Mesh ObjImporter::build_mesh(const tinyobj::shape_t& shape, const std::string& name) {
    const tinyobj::mesh_t& source = shape.mesh;
    bool with_uv = false, with_normal = true;
    size_t first = 0;
    for (size_t f = 0; f < source.num_face_vertices.size(); ++f) {
        const size_t corners = source.num_face_vertices[f];
        if (first + corners > source.indices.size())
            throw IoError(format_message(path_, ": shape '", name, "' face ", f,
                                         " runs past the end of the index list"));
        for (size_t c = first; c < first + corners; ++c) {
            check_corner(source.indices[c], name, f);
            with_uv = with_uv || source.indices[c].texcoord_index >= 0;
            with_normal = with_normal && source.indices[c].normal_index >= 0;
        }
        first += corners;
    }

    Mesh mesh;
    mesh.name = name;
    if (with_uv) mesh.uv_sets.push_back(UvSet{"UVMap", {}});
    vertex_of_corner_.clear();
    first = 0;
    for (size_t f = 0; f < source.num_face_vertices.size(); ++f) {
        const size_t corners = source.num_face_vertices[f];
        const int obj_material = f < source.material_ids.size() ? source.material_ids[f] : -1;
        const uint32_t material = material_id(obj_material);
        // Fan around the first corner: (0, k, k + 1) keeps the polygon's winding.
        const auto vertex = [&](size_t corner) {
            return add_corner(source.indices[first + corner], with_uv, with_normal, mesh);
        };
        for (size_t k = 1; k + 1 < corners; ++k) {
            // Separate statements: vertices are numbered in corner order on every compiler.
            const uint32_t v0 = vertex(0);
            const uint32_t v1 = vertex(k);
            const uint32_t v2 = vertex(k + 1);
            mesh.triangles.emplace_back(v0, v1, v2);
            mesh.material_indices.push_back(material);
        }
        first += corners;
    }
    return mesh;
}

uint32_t ObjImporter::add_corner(const tinyobj::index_t& corner, bool with_uv, bool with_normal,
                                 Mesh& mesh) {
    const std::array<int, 3> key = {corner.vertex_index, corner.texcoord_index,
                                    corner.normal_index};
    const auto found = vertex_of_corner_.find(key);
    if (found != vertex_of_corner_.end()) return found->second;
    const uint32_t vertex = uint32_t(mesh.positions.size());
    const std::vector<tinyobj::real_t>& v = data_.attrib.vertices;
    const size_t i = size_t(corner.vertex_index) * 3;
    mesh.positions.push_back(to_blender(v[i], v[i + 1], v[i + 2]));
    if (with_normal) {
        const std::vector<tinyobj::real_t>& n = data_.attrib.normals;
        const size_t j = size_t(corner.normal_index) * 3;
        mesh.normals.push_back(to_blender(n[j], n[j + 1], n[j + 2]));
    }
    if (with_uv) {
        const std::vector<tinyobj::real_t>& t = data_.attrib.texcoords;
        const size_t j = size_t(std::max(corner.texcoord_index, 0)) * 2;
        mesh.uv_sets[0].coords.push_back(corner.texcoord_index >= 0 ? vec2(t[j], t[j + 1])
                                                                    : vec2(0.0f));
    }
    vertex_of_corner_.emplace(key, vertex);
    return vertex;
}

uint32_t ObjImporter::material_id(int obj_material) {
    if (obj_material >= int(data_.materials.size())) obj_material = -1;  // defensive
    const auto cached = material_ids_.find(obj_material);
    if (cached != material_ids_.end()) return cached->second;
    Material material;  // faces without usemtl, or whose material was not found
    if (obj_material >= 0) {
        const tinyobj::material_t& source = data_.materials[size_t(obj_material)];
        const auto keys = data_.material_keys.find(source.name);
        material = material_from_mtl(
            source, keys != data_.material_keys.end() ? keys->second : std::set<std::string>{},
            path_);
    }
    const uint32_t id = scene_.add_material(std::move(material));
    material_ids_.emplace(obj_material, id);
    return id;
}

}  // namespace

float obj_roughness_from_exponent(float ns) {
    return 1.0f - std::sqrt(std::clamp(ns, 0.0f, kMaxSpecularExponent) / kMaxSpecularExponent);
}

// Share of a load's progress given to reading the file (the rest: importing its shapes).
constexpr float kReadingShare = 0.5f;

Scene load_obj(const std::string& path, const ObjLoadOptions& options, Progress* progress) {
    if (progress) progress->begin_stage("reading", 0.0f, kReadingShare);
    throw_if_cancelled(progress);
    const ObjData data = read_obj(path);
    if (progress) progress->begin_stage("importing", kReadingShare, 1.0f);
    try {
        Scene scene = ObjImporter(path, data, options, progress).run();
        if (progress) progress->set_fraction(1.0f);
        return scene;
    } catch (const InvalidArgument& error) {
        // Scene::add_* rejected a converted value (NaN vertex, ...).
        throw IoError(format_message(path, ": ", error.what()));
    }
}

}  // namespace shgi
