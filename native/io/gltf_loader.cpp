// glTF loading (see gltf_loader.h). The only file that includes tiny_gltf.h.
//
// Debian ships tinygltf as a shared library (libtinygltf.so, built with stb_image for PNG/JPEG/
// BMP/GIF decoding and nlohmann-json), so this file includes the header without
// TINYGLTF_IMPLEMENTATION or any of its configuration macros: defining them here would disagree
// with how the library was compiled.
//
// Loading runs in steps: read and parse the file (tinygltf), then walk the node hierarchy of the
// chosen scene; meshes, materials and textures are converted on first use and cached, so a mesh
// shared by many nodes is stored once and instanced. Every index read from the file is checked
// before use: a malformed file must end in IoError, never in an out-of-bounds read.
#include "io/gltf_loader.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <new>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "io/image.h"
#include "io/png_image.h"
#include "util/error.h"
#include "util/log.h"

namespace shgi {
namespace {

// JSON nesting a file may have. nlohmann-json (inside tinygltf) parses recursively, so a file of
// a few hundred kilobytes nested tens of thousands deep (in `extras`, say) overflows the stack
// and takes the host down; the glTF schema itself nests under ten deep, and exporters' extras a
// few levels more.
constexpr int kMaxJsonNesting = 256;
// Blender's importer reads at most this many TEXCOORD_n sets (UV_MAX in gltf2_blender_mesh.py).
constexpr int kMaxUvSets = 8;
// The first four bytes of a .glb file (glTF 2.0 spec, "Binary glTF Layout").
constexpr char kGlbMagic[4] = {'g', 'l', 'T', 'F'};
constexpr const char* kLightsExtension = "KHR_lights_punctual";

// Extensions a file may list in extensionsRequired: everything else changes the meaning of the
// data in ways this loader cannot honour (Draco or meshopt compression, Basis textures, ...).
const std::set<std::string>& supported_required_extensions() {
    static const std::set<std::string> extensions = {
        kLightsExtension, "KHR_materials_emissive_strength", "KHR_materials_ior",
        "KHR_materials_transmission", "KHR_mesh_quantization"};
    return extensions;
}

// (x, y, z)_gltf -> (x, -z, y)_blender: a rotation, so it applies to normals unchanged.
vec3 blender_from_gltf_vector(const vec3& v) { return vec3(v.x, -v.z, v.y); }

std::string trimmed(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    return text;
}

// Share of a load's progress given to reading the file (the rest: importing its nodes).
constexpr float kReadingShare = 0.5f;

// ---------------------------------------------------------------------------------------------
// Step 1: reading the file.

// What the image callback needs: the model being read (its buffer views and buffers are parsed
// before the images) and where to record images that do not decode.
struct ImageDecoding {
    const tinygltf::Model* model = nullptr;
    std::vector<std::string> failures;
    Progress* progress = nullptr;  // polled for cancel before each image
};

// tinygltf hands an image stored in a buffer view to the callback as
// &buffer.data[bufferView.byteOffset] with int(bufferView.byteLength) bytes, checking neither
// against the buffer: a view past the buffer's end (a GLB whose image view has byteOffset 2^31)
// made stb_image read unmapped memory (a segfault). The view is checked here before any byte is
// read; one that does not fit its buffer is a damaged file, refused like a bad accessor.
bool image_view_fits(const tinygltf::Image& image, const int image_index,
                     const tinygltf::Model& model, std::string* err) {
    if (image.bufferView < 0) return true;  // a URI: tinygltf read exactly the file's bytes
    // tinygltf checked both indices before calling.
    const tinygltf::BufferView& view = model.bufferViews[size_t(image.bufferView)];
    const tinygltf::Buffer& buffer = model.buffers[size_t(view.buffer)];
    const size_t size = buffer.data.size();
    if (view.byteOffset <= size && view.byteLength <= size - view.byteOffset &&
        view.byteLength <= size_t(std::numeric_limits<int>::max()))
        return true;
    if (err) {
        *err += format_message("image ", image_index, ": bufferView ", image.bufferView,
                               " (byteOffset ", view.byteOffset, ", byteLength ", view.byteLength,
                               ") lies outside buffer ", view.buffer, ", which has ", size,
                               " bytes\n");
    }
    return false;
}

// tinygltf fails the whole load when one image does not decode; an undecodable texture should
// only cost the texture, so the failure is recorded and the image left empty.
bool decode_image_or_record(tinygltf::Image* image, const int image_index, std::string* err,
                            std::string* warn, int req_width, int req_height,
                            const unsigned char* bytes, int size, void* user_data) {
    auto* decoding = static_cast<ImageDecoding*>(user_data);
    throw_if_cancelled(decoding->progress);  // Cancelled passes through tinygltf (read_model)
    if (!image_view_fits(*image, image_index, *decoding->model, err)) return false;
    std::string error;
    if (tinygltf::LoadImageData(image, image_index, &error, warn, req_width, req_height, bytes,
                                size, nullptr))
        return true;
    decoding->failures.push_back(
        format_message("image ", image_index, " could not be decoded (", trimmed(error), ")"));
    image->image.clear();
    image->width = image->height = 0;
    return true;
}

// Used when the caller does not want textures: keeps the image records, decodes nothing.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int,
                const unsigned char*, int, void*) {
    return true;
}

// tinygltf's reader, for regular files only: a buffer or image URI naming a folder made it
// allocate the folder's bogus size (std::bad_alloc), and one naming a device read without end.
bool read_regular_file(std::vector<unsigned char>* out, std::string* error,
                       const std::string& path, void* user_data) {
    if (is_special_file(path)) {
        if (error)
            *error += format_message("'", path, "' is not a regular file (a folder, device, FIFO "
                                     "or socket)\n");
        return false;
    }
    return tinygltf::ReadWholeFile(out, error, path, user_data);
}

// tinygltf's own test opens the file to see that it exists, and opening a FIFO for reading
// blocks until a writer comes, out of reach of cancel and Ctrl-C; stat opens nothing. A special
// file "exists" here so that read_regular_file names it rather than "File not found".
bool file_exists(const std::string& path, void*) {
    std::error_code error;
    return std::filesystem::exists(path, error);
}

// Refuses JSON nested deeper than kMaxJsonNesting before any recursive parser sees it. Brackets
// inside strings (with their escapes) do not count.
void require_shallow_json(const std::string& path, const unsigned char* text, size_t size) {
    int depth = 0;
    bool in_string = false, escaped = false;
    for (size_t i = 0; i < size; ++i) {
        const unsigned char c = text[i];
        if (in_string) {
            if (escaped) escaped = false;
            else if (c == '\\') escaped = true;
            else if (c == '"') in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '{' || c == '[') {
            if (++depth > kMaxJsonNesting) {
                throw IoError(format_message(
                    path, ": its JSON nests deeper than ", kMaxJsonNesting, " levels (at byte ", i,
                    "), which no glTF needs; the file is damaged or hostile: re-export it"));
            }
        } else if (c == '}' || c == ']') {
            --depth;
        }
    }
}

// The JSON of a .glb: the first chunk, after the 12-byte header (glTF 2.0 spec, "Binary glTF
// Layout": magic, version, length, then chunkLength, chunkType, chunkData). A short or
// inconsistent header is left to tinygltf's own message; nothing past the file is read.
void require_shallow_glb_json(const std::string& path, const std::vector<unsigned char>& bytes) {
    constexpr size_t kHeader = 12, kChunkHeader = 8;
    if (bytes.size() < kHeader + kChunkHeader) return;
    uint32_t chunk_length = 0;
    std::memcpy(&chunk_length, bytes.data() + kHeader, sizeof(chunk_length));
    const size_t available = bytes.size() - kHeader - kChunkHeader;
    require_shallow_json(path, bytes.data() + kHeader + kChunkHeader,
                         std::min<size_t>(chunk_length, available));
}

bool starts_with_glb_magic(const std::string& path) {
    require_readable_file(path, "glTF");
    std::ifstream file(path, std::ios::binary);
    if (!file)
        throw IoError(format_message(path, ": cannot open the file (", std::strerror(errno), ")"));
    std::array<char, 4> magic{};
    file.read(magic.data(), magic.size());
    return file.gcount() == 4 && std::memcmp(magic.data(), kGlbMagic, 4) == 0;
}

tinygltf::Model read_model(const std::string& path, const GltfLoadOptions& options,
                           Progress* progress) {
    // The container is told by its content, not its extension: some tools write .glb as .gltf.
    const bool binary = starts_with_glb_magic(path);
    tinygltf::Model model;
    ImageDecoding image_decoding;
    image_decoding.model = &model;
    image_decoding.progress = progress;
    tinygltf::TinyGLTF parser;
    parser.SetFsCallbacks({&file_exists, &tinygltf::ExpandFilePath, &read_regular_file,
                           &tinygltf::WriteWholeFile, nullptr});
    if (options.import_textures)
        parser.SetImageLoader(decode_image_or_record, &image_decoding);
    else
        parser.SetImageLoader(skip_image, nullptr);

    std::string error, warning;
    // Read here rather than by tinygltf, so that the JSON's nesting is checked before parsing.
    std::vector<unsigned char> bytes;
    if (!read_regular_file(&bytes, &error, path, nullptr))
        throw IoError(format_message(path, ": cannot read the file: ", trimmed(error)));
    if (bytes.size() > std::numeric_limits<unsigned int>::max()) {
        throw IoError(format_message(path, ": ", bytes.size(), " bytes, over the 4 GiB a glTF "
                                     "reader takes; split the scene into several files"));
    }
    if (binary) require_shallow_glb_json(path, bytes);
    else require_shallow_json(path, bytes.data(), bytes.size());
    const std::string base_dir = std::filesystem::path(path).parent_path().string();
    bool ok = false;
    // tinygltf reports most damage through `error`, but some reaches a throwing accessor: a GLB
    // whose BIN buffer declares byteLength 0 made it copy into data.at(0), and std::out_of_range
    // reached Python as a bare IndexError. Such a throw is the same damage, so the same IoError.
    try {
        ok = binary ? parser.LoadBinaryFromMemory(&model, &error, &warning, bytes.data(),
                                                  static_cast<unsigned int>(bytes.size()),
                                                  base_dir)
                    : parser.LoadASCIIFromString(&model, &error, &warning,
                                                 reinterpret_cast<const char*>(bytes.data()),
                                                 static_cast<unsigned int>(bytes.size()),
                                                 base_dir);
    } catch (const std::bad_alloc&) {
        throw;  // MemoryError
    } catch (const Cancelled&) {
        throw;  // from the image callback
    } catch (const std::exception& thrown) {
        ok = false;
        error += format_message("the reader stopped at damaged data (", thrown.what(), ")");
    }
    if (!warning.empty()) log_warning(path, ": ", trimmed(warning));
    for (const std::string& failure : image_decoding.failures) log_warning(path, ": ", failure);
    if (!ok) {
        throw IoError(format_message(path, ": not a valid glTF ", binary ? "binary (.glb)" : "JSON",
                                     " file: ", trimmed(error)));
    }
    for (const std::string& extension : model.extensionsRequired) {
        if (!supported_required_extensions().count(extension)) {
            throw IoError(format_message(path, ": requires the glTF extension ", extension,
                                         ", which SHGI does not support; re-export without it"));
        }
    }
    return model;
}

// ---------------------------------------------------------------------------------------------
// Step 2: accessors, with every offset checked against the buffer before anything is read.

struct AccessorView {
    const uint8_t* data = nullptr;
    size_t stride = 0;
    size_t count = 0;
    int component_type = 0;
    int components = 0;
    bool normalized = false;
};

class AccessorReader {
  public:
    AccessorReader(const std::string& path, const tinygltf::Model& model)
        : path_(path), model_(model) {}

    // `components` floats per element; integer components are converted (normalised if the
    // accessor says so). `what` names the use, e.g. "mesh 2 primitive 0 POSITION".
    std::vector<float> read_floats(int index, int components, const std::string& what) const;
    // An index accessor: SCALAR of unsigned byte, short or int.
    std::vector<uint32_t> read_indices(int index, const std::string& what) const;

  private:
    AccessorView view(int index, const std::string& what) const;
    [[noreturn]] void fail(const std::string& what, int index, const std::string& problem) const {
        throw IoError(format_message(path_, ": ", what, " (accessor ", index, "): ", problem));
    }

    const std::string& path_;
    const tinygltf::Model& model_;
};

AccessorView AccessorReader::view(int index, const std::string& what) const {
    if (index < 0 || size_t(index) >= model_.accessors.size())
        fail(what, index, format_message("no such accessor, the file has ",
                                         model_.accessors.size()));
    const tinygltf::Accessor& accessor = model_.accessors[size_t(index)];
    if (accessor.sparse.isSparse) fail(what, index, "sparse accessors are not supported");
    AccessorView result;
    result.count = accessor.count;
    result.component_type = accessor.componentType;
    result.components = tinygltf::GetNumComponentsInType(uint32_t(accessor.type));
    result.normalized = accessor.normalized;
    const int component_size = tinygltf::GetComponentSizeInBytes(uint32_t(accessor.componentType));
    if (result.components <= 0 || component_size <= 0)
        fail(what, index, format_message("bad type ", accessor.type, " or componentType ",
                                         accessor.componentType));
    // Without a bufferView an accessor is all zeros unless sparse; nothing bounds its count then,
    // and all-zero geometry is useless, so it is refused rather than allocated.
    if (accessor.bufferView < 0)
        fail(what, index, "accessors without a bufferView (all zeros) are not supported");
    if (size_t(accessor.bufferView) >= model_.bufferViews.size())
        fail(what, index, format_message("bufferView ", accessor.bufferView, " does not exist (",
                                         model_.bufferViews.size(), " buffer views)"));
    const tinygltf::BufferView& buffer_view = model_.bufferViews[size_t(accessor.bufferView)];
    if (buffer_view.buffer < 0 || size_t(buffer_view.buffer) >= model_.buffers.size())
        fail(what, index, format_message("bufferView ", accessor.bufferView, " names buffer ",
                                         buffer_view.buffer, ", which does not exist"));
    const std::vector<unsigned char>& buffer = model_.buffers[size_t(buffer_view.buffer)].data;
    if (buffer_view.byteOffset > buffer.size() ||
        buffer_view.byteLength > buffer.size() - buffer_view.byteOffset)
        fail(what, index, format_message("bufferView ", accessor.bufferView, " (",
                                         buffer_view.byteLength, " bytes at ",
                                         buffer_view.byteOffset, ") exceeds its buffer of ",
                                         buffer.size(), " bytes"));
    const int stride = accessor.ByteStride(buffer_view);
    if (stride <= 0) fail(what, index, "invalid byteStride");
    result.stride = size_t(stride);
    // The last element must end inside the buffer view; computed without overflow.
    const size_t element_size = size_t(component_size) * size_t(result.components);
    bool fits = accessor.byteOffset <= buffer_view.byteLength;
    if (fits && result.count > 0) {
        const size_t room = buffer_view.byteLength - accessor.byteOffset;
        fits = element_size <= room && result.count - 1 <= (room - element_size) / result.stride;
    }
    if (!fits)
        fail(what, index, format_message(result.count, " elements of ", element_size,
                                         " bytes (stride ", stride, ") at offset ",
                                         accessor.byteOffset, " do not fit bufferView ",
                                         accessor.bufferView, " (", buffer_view.byteLength,
                                         " bytes)"));
    result.data = buffer.data() + buffer_view.byteOffset + accessor.byteOffset;
    return result;
}

// One component as float; normalised integers map to [0, 1] or [-1, 1] (glTF spec, "Animation"
// and "Meshes": c / (2^(n-1) - 1) clamped at -1 for signed types).
float read_component(const uint8_t* p, int component_type, bool normalized) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            int8_t v;
            std::memcpy(&v, p, sizeof v);
            return normalized ? std::max(float(v) / 127.0f, -1.0f) : float(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return normalized ? float(*p) / 255.0f : float(*p);
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            int16_t v;
            std::memcpy(&v, p, sizeof v);
            return normalized ? std::max(float(v) / 32767.0f, -1.0f) : float(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t v;
            std::memcpy(&v, p, sizeof v);
            return normalized ? float(v) / 65535.0f : float(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
            uint32_t v;
            std::memcpy(&v, p, sizeof v);
            return float(v);
        }
        case TINYGLTF_COMPONENT_TYPE_FLOAT: {
            float v;
            std::memcpy(&v, p, sizeof v);
            return v;
        }
        default:
            return 0.0f;  // unreachable: view() rejected other types (doubles are not glTF 2.0)
    }
}

std::vector<float> AccessorReader::read_floats(int index, int components,
                                               const std::string& what) const {
    const AccessorView v = view(index, what);
    if (v.components != components)
        fail(what, index, format_message("expected ", components, " components per element, got ",
                                         v.components));
    if (v.component_type == TINYGLTF_COMPONENT_TYPE_DOUBLE)
        fail(what, index, "double components are not valid glTF 2.0");
    const size_t component_size =
        size_t(tinygltf::GetComponentSizeInBytes(uint32_t(v.component_type)));
    std::vector<float> values(v.count * size_t(components), 0.0f);
    for (size_t i = 0; i < v.count; ++i) {
        const uint8_t* element = v.data + i * v.stride;
        for (int c = 0; c < components; ++c) {
            const uint8_t* component = element + size_t(c) * component_size;
            values[i * size_t(components) + size_t(c)] =
                read_component(component, v.component_type, v.normalized);
        }
    }
    return values;
}

std::vector<uint32_t> AccessorReader::read_indices(int index, const std::string& what) const {
    const AccessorView v = view(index, what);
    const bool unsigned_integer = v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                  v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
                                  v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    if (v.components != 1 || !unsigned_integer)
        fail(what, index, "indices must be SCALAR unsigned byte, short or int");
    std::vector<uint32_t> indices(v.count, 0u);
    for (size_t i = 0; i < v.count; ++i)
        indices[i] = uint32_t(read_component(v.data + i * v.stride, v.component_type, false));
    return indices;
}

// ---------------------------------------------------------------------------------------------
// Step 3: converting glTF objects to SHGI ones.

double extension_number(const tinygltf::ExtensionMap& extensions, const char* extension,
                        const char* key, double fallback) {
    const auto found = extensions.find(extension);
    if (found == extensions.end() || !found->second.Has(key)) return fallback;
    const tinygltf::Value& value = found->second.Get(key);
    return value.IsNumber() ? value.GetNumberAsDouble() : fallback;
}

// Blender's names for the n-th UV map: "UVMap", "UVMap.001", "UVMap.002", ...
std::string uv_set_name(int texcoord) {
    if (texcoord == 0) return "UVMap";
    std::ostringstream name;
    name << "UVMap." << std::setw(3) << std::setfill('0') << texcoord;
    return name.str();
}

vec3 vec3_at(const std::vector<float>& values, size_t i) {
    return vec3(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
}

vec3 rgb_or(const std::vector<double>& values, const vec3& fallback) {
    return values.size() >= 3 ? vec3(float(values[0]), float(values[1]), float(values[2]))
                              : fallback;
}

// Per-vertex tangents of a UV set for a mesh without glTF TANGENTs, in the spirit of
// MikkTSpace: each triangle's unit tangent and bitangent (the directions of +U and +V on it)
// are summed at its corners weighted by the corner angle, then the tangent is made orthogonal
// to the vertex normal and the sign is the bitangent's side. On planar and regularly mapped
// meshes this is MikkTSpace's answer; MikkTSpace itself also splits vertices whose corners'
// tangents disagree (mirrored UV islands sharing a vertex), which this does not.
std::vector<vec4> vertex_tangents(const Mesh& mesh, const UvSet& set) {
    const size_t count = mesh.positions.size();
    std::vector<vec3> tangent_sum(count, vec3(0.0f)), bitangent_sum(count, vec3(0.0f));
    std::vector<vec3> face_normal_sum(count, vec3(0.0f));
    for (const uvec3& t : mesh.triangles) {
        const vec3 e1 = mesh.positions[t.y] - mesh.positions[t.x];
        const vec3 e2 = mesh.positions[t.z] - mesh.positions[t.x];
        const vec2 d1 = set.coords[t.y] - set.coords[t.x];
        const vec2 d2 = set.coords[t.z] - set.coords[t.x];
        const float det = d1.x * d2.y - d2.x * d1.y;
        if (!(std::fabs(det) > 0.0f)) continue;  // UVs collapsed: no direction on this face
        const vec3 tangent = (e1 * d2.y - e2 * d1.y) / det;
        const vec3 bitangent = (e2 * d1.x - e1 * d2.x) / det;
        const float tangent_length = glm::length(tangent);
        const float bitangent_length = glm::length(bitangent);
        if (!(tangent_length > 0.0f) || !(bitangent_length > 0.0f)) continue;
        const vec3 face_normal = glm::cross(e1, e2);
        for (int corner = 0; corner < 3; ++corner) {
            const vec3& p = mesh.positions[t[corner]];
            const vec3 a = mesh.positions[t[(corner + 1) % 3]] - p;
            const vec3 b = mesh.positions[t[(corner + 2) % 3]] - p;
            const float cos_angle = glm::dot(a, b) / (glm::length(a) * glm::length(b));
            const float angle = std::acos(std::clamp(cos_angle, -1.0f, 1.0f));
            tangent_sum[t[corner]] += angle * tangent / tangent_length;
            bitangent_sum[t[corner]] += angle * bitangent / bitangent_length;
            face_normal_sum[t[corner]] += face_normal;
        }
    }
    std::vector<vec4> tangents(count, vec4(0.0f));  // zero: no frame (validate_mesh warns)
    for (size_t i = 0; i < count; ++i) {
        const vec3 n = glm::normalize(mesh.normals.empty() ? face_normal_sum[i] : mesh.normals[i]);
        const vec3 t = tangent_sum[i] - glm::dot(tangent_sum[i], n) * n;
        const float length = glm::length(t);
        if (!(length > 0.0f) || !is_finite(n)) continue;
        const float sign = glm::dot(glm::cross(n, t), bitangent_sum[i]) < 0.0f ? -1.0f : 1.0f;
        tangents[i] = vec4(t / length, sign);
    }
    return tangents;
}

// Decoded tinygltf image (8 or 16 bits, 1-4 channels, top row first) -> linear RGBA texture
// with the bottom row first. Colour channels are sRGB-encoded for colour textures (glTF spec,
// baseColorTexture) and plain data for a normalTexture (srgb false).
Texture texture_from_image(const tinygltf::Image& image, const std::string& name, bool srgb) {
    Texture texture;
    texture.name = name;
    texture.width = uint32_t(image.width);
    texture.height = uint32_t(image.height);
    const size_t channels = size_t(image.component);
    const size_t bytes_per_channel = image.bits == 16 ? 2 : 1;
    const float max_value = image.bits == 16 ? 65535.0f : 255.0f;
    texture.texels.resize(size_t(texture.width) * texture.height);
    for (size_t y = 0; y < texture.height; ++y) {
        const size_t source_row = texture.height - 1 - y;
        for (size_t x = 0; x < texture.width; ++x) {
            const size_t first_channel = (source_row * texture.width + x) * channels;
            const uint8_t* pixel = image.image.data() + first_channel * bytes_per_channel;
            float c[4] = {0.0f, 0.0f, 0.0f, 1.0f};
            for (size_t k = 0; k < channels; ++k) {
                uint16_t wide = 0;  // tinygltf stores 16-bit channels in native byte order
                if (bytes_per_channel == 2) std::memcpy(&wide, pixel + 2 * k, sizeof wide);
                c[k] = (bytes_per_channel == 2 ? float(wide) : float(pixel[k])) / max_value;
            }
            if (channels <= 2) {  // grey or grey + alpha
                c[3] = channels == 2 ? c[1] : 1.0f;
                c[1] = c[2] = c[0];
            }
            if (srgb)
                for (int k = 0; k < 3; ++k) c[k] = linear_from_srgb(c[k]);
            texture.texels[y * texture.width + x] = vec4(c[0], c[1], c[2], c[3]);
        }
    }
    return texture;
}

bool image_is_decoded(const tinygltf::Image& image) {
    const size_t bytes = size_t(std::max(image.width, 0)) * size_t(std::max(image.height, 0)) *
                         size_t(std::max(image.component, 0)) * (image.bits == 16 ? 2u : 1u);
    return image.width > 0 && image.height > 0 && image.component >= 1 &&
           image.component <= 4 && (image.bits == 8 || image.bits == 16) &&
           image.image.size() >= bytes;
}

Light light_from_gltf(const tinygltf::Light& source, const mat4& world_from_light,
                      const GltfLoadOptions& options) {
    Light light;
    light.name = source.name.empty() ? source.type : source.name;
    light.color = rgb_or(source.color, vec3(1.0f));
    light.world_from_light = world_from_light;
    const float intensity = float(source.intensity);
    if (source.type == "directional") {
        light.type = LightType::Sun;
        light.strength = gltf_sun_strength(intensity, options.lighting_mode);
        light.angle = options.sun_angle;
        return light;
    }
    light.type = source.type == "spot" ? LightType::Spot : LightType::Point;
    light.power = gltf_point_power(intensity, options.lighting_mode);
    light.radius = options.light_radius;
    if (light.type == LightType::Spot) {
        // gltf2_blender_light.py create_spot(): the cone angles are half angles.
        const float outer = float(source.spot.outerConeAngle);
        const float inner = float(source.spot.innerConeAngle);
        light.spot_size = 2.0f * outer;
        light.spot_blend = outer > 0.0f ? std::clamp(1.0f - inner / outer, 0.0f, 1.0f) : 0.0f;
    }
    return light;
}

Camera camera_from_gltf(const tinygltf::Camera& source, const mat4& world_from_camera) {
    Camera camera;
    camera.world_from_camera = world_from_camera;
    if (source.type == "orthographic") {
        const tinygltf::OrthographicCamera& ortho = source.orthographic;
        camera.type = CameraType::Orthographic;
        camera.sensor_fit = SensorFit::Auto;
        camera.ortho_scale = 2.0f * float(std::max(ortho.xmag, ortho.ymag));
        if (ortho.xmag > 0.0 && ortho.ymag > 0.0)
            camera.resolution_x =
                uint32_t(std::max(1.0, std::round(camera.resolution_y * ortho.xmag / ortho.ymag)));
        camera.clip_start = float(ortho.znear);
        camera.clip_end = float(ortho.zfar);
        return camera;
    }
    const tinygltf::PerspectiveCamera& perspective = source.perspective;
    camera.type = CameraType::Perspective;
    camera.sensor_fit = SensorFit::Vertical;
    camera.lens = 0.5f * camera.sensor_height / std::tan(0.5f * float(perspective.yfov));
    if (perspective.aspectRatio > 0.0)
        camera.resolution_x = uint32_t(
            std::max(1.0, std::round(camera.resolution_y * perspective.aspectRatio)));
    camera.clip_start = float(perspective.znear);
    camera.clip_end = perspective.zfar > 0.0 ? float(perspective.zfar) : kGltfInfiniteClipEnd;
    return camera;
}

mat4 node_local_matrix(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) {
        float m[16];
        for (int i = 0; i < 16; ++i) m[i] = float(node.matrix[size_t(i)]);
        return glm::make_mat4(m);  // both column-major
    }
    mat4 local(1.0f);
    if (node.translation.size() == 3)
        local = glm::translate(local, vec3(float(node.translation[0]), float(node.translation[1]),
                                           float(node.translation[2])));
    if (node.rotation.size() == 4) {
        // glTF stores (x, y, z, w); glm::quat's constructor takes (w, x, y, z).
        const glm::quat q(float(node.rotation[3]), float(node.rotation[0]),
                          float(node.rotation[1]), float(node.rotation[2]));
        local = local * glm::mat4_cast(glm::normalize(q));
    }
    if (node.scale.size() == 3)
        local = glm::scale(local, vec3(float(node.scale[0]), float(node.scale[1]),
                                       float(node.scale[2])));
    return local;
}

// ---------------------------------------------------------------------------------------------
// Step 4: the importer, which walks the nodes and converts what they use on first use.

class GltfImporter {
  public:
    GltfImporter(const std::string& path, const tinygltf::Model& model,
                 const GltfLoadOptions& options, Progress* progress)
        : path_(path), model_(model), options_(options), progress_(progress),
          accessors_(path, model) {}

    Scene run();

  private:
    std::vector<int> root_nodes() const;
    // Adds the node's instances, light and camera; returns its glTF world transform.
    mat4 visit_node(int node_index, const mat4& gltf_world_from_parent);
    void add_node_light(int node_index, const tinygltf::Node& node, const mat4& world_from_node);
    void add_node_camera(const tinygltf::Node& node, const mat4& world_from_node);
    const std::vector<uint32_t>& mesh_ids(int mesh_index);
    Mesh build_primitive(int mesh_index, int primitive_index, uint32_t material_id) const;
    Mesh merged_primitives(int mesh_index, std::vector<Mesh>& parts) const;
    static Mesh with_flat_normals(const Mesh& part);
    void read_uv_sets(const tinygltf::Primitive& primitive, const std::string& what,
                      size_t vertex_count, Mesh& mesh) const;
    void read_tangents(const tinygltf::Primitive& primitive, const std::string& what,
                       const Material& material, Mesh& mesh) const;
    std::vector<uvec3> read_triangles(const tinygltf::Primitive& primitive,
                                      const std::string& what, size_t vertex_count) const;
    uint32_t material_id(int material_index);
    uint32_t default_material_id();
    // The SHGI texture of glTF texture `index` (sRGB-decoded or data), or kNoTexture.
    int32_t texture_id(int index, bool srgb, const std::string& what);
    void check_index(int index, size_t size, const std::string& what) const;

    const std::string& path_;
    const tinygltf::Model& model_;
    const GltfLoadOptions& options_;
    Progress* progress_;
    AccessorReader accessors_;
    Scene scene_;
    std::map<int, std::vector<uint32_t>> mesh_ids_;  // glTF mesh -> its SHGI mesh, if triangles
    std::map<int, uint32_t> material_ids_;           // glTF material -> SHGI material
    std::map<std::pair<int, bool>, int32_t> texture_ids_;  // (glTF image, sRGB) -> SHGI texture
    int64_t default_material_ = -1;
};

void GltfImporter::check_index(int index, size_t size, const std::string& what) const {
    if (index < 0 || size_t(index) >= size)
        throw IoError(format_message(path_, ": ", what, " ", index,
                                     " does not exist (the file has ", size, ")"));
}

std::vector<int> GltfImporter::root_nodes() const {
    if (!model_.scenes.empty()) {
        const int scene = model_.defaultScene >= 0 ? model_.defaultScene : 0;
        check_index(scene, model_.scenes.size(), "default scene");
        return model_.scenes[size_t(scene)].nodes;
    }
    // No scenes: every node without a parent is a root (as Blender's importer does).
    std::vector<uint8_t> is_child(model_.nodes.size(), 0);
    for (const tinygltf::Node& node : model_.nodes) {
        for (int child : node.children) {
            check_index(child, model_.nodes.size(), "child node");
            is_child[size_t(child)] = 1;
        }
    }
    std::vector<int> roots;
    for (size_t i = 0; i < model_.nodes.size(); ++i)
        if (!is_child[i]) roots.push_back(int(i));
    return roots;
}

// Depth-first, parents before children and children in file order (so "the first camera node"
// is the importer's), with an explicit stack: a hostile file's deep hierarchy must not be able to
// overflow the call stack (Python's and Blender's threads have small ones). Each node is visited
// once: glTF 2.0 (§3.5.3, "Nodes and Hierarchy") requires the nodes to form disjoint strict
// trees, and a file of 41 nodes that each list the next one twice would otherwise expand to 2^40
// instances; so the instances are bounded by the file's own node and primitive counts.
Scene GltfImporter::run() {
    struct Pending {
        int node;
        mat4 gltf_world_from_parent;
        bool leaving;  // pops the node off the current path after its subtree
    };
    std::vector<uint8_t> on_path(model_.nodes.size(), 0);  // ancestors of the node being visited
    std::vector<uint8_t> visited(model_.nodes.size(), 0);
    std::vector<Pending> stack;
    const std::vector<int> roots = root_nodes();
    for (auto root = roots.rbegin(); root != roots.rend(); ++root)
        stack.push_back({*root, mat4(1.0f), false});
    uint64_t nodes_done = 0;
    while (!stack.empty()) {
        const Pending item = stack.back();
        stack.pop_back();
        if (item.leaving) {
            on_path[size_t(item.node)] = 0;
            continue;
        }
        check_index(item.node, model_.nodes.size(), "node");
        if (on_path[size_t(item.node)])
            throw IoError(format_message(path_, ": node ", item.node,
                                         " is its own ancestor (the node hierarchy has a cycle)"));
        if (visited[size_t(item.node)])
            throw IoError(format_message(
                path_, ": node ", item.node, " is reached twice (it has two parents, is listed "
                "twice as a child or as a root); glTF 2.0 allows each node one parent: re-export "
                "the file, or use a mesh in several nodes to instance it"));
        on_path[size_t(item.node)] = visited[size_t(item.node)] = 1;
        throw_if_cancelled(progress_);
        if (progress_) progress_->report(nodes_done++, model_.nodes.size());
        stack.push_back({item.node, mat4(1.0f), true});
        const mat4 gltf_world = visit_node(item.node, item.gltf_world_from_parent);
        const std::vector<int>& children = model_.nodes[size_t(item.node)].children;
        for (auto child = children.rbegin(); child != children.rend(); ++child)
            stack.push_back({*child, gltf_world, false});
    }
    if (scene_.instances().empty()) log_warning(path_, ": the scene has no triangle meshes");
    return std::move(scene_);
}

mat4 GltfImporter::visit_node(int node_index, const mat4& gltf_world_from_parent) {
    const tinygltf::Node& node = model_.nodes[size_t(node_index)];
    const mat4 gltf_world = gltf_world_from_parent * node_local_matrix(node);
    const mat4 c = blender_from_gltf();
    // Cameras and lights: C * world (the importer's camera_correction, see the header).
    const mat4 world_from_node = c * gltf_world;

    if (node.mesh >= 0) {
        check_index(node.mesh, model_.meshes.size(), format_message("node ", node_index, ": mesh"));
        const mat4 world_from_object = world_from_node * glm::transpose(c);  // C^-1 = C^T
        const std::string name =
            node.name.empty() ? format_message("node_", node_index) : node.name;
        for (uint32_t mesh_id : mesh_ids(node.mesh))
            scene_.add_instance(mesh_id, world_from_object, name);
    }
    if (options_.import_lights) add_node_light(node_index, node, world_from_node);
    if (options_.import_camera && node.camera >= 0) add_node_camera(node, world_from_node);
    return gltf_world;
}

void GltfImporter::add_node_light(int node_index, const tinygltf::Node& node,
                                  const mat4& world_from_node) {
    const auto found = node.extensions.find(kLightsExtension);
    if (found == node.extensions.end() || !found->second.Has("light")) return;
    const tinygltf::Value& light = found->second.Get("light");
    const int light_index = light.IsNumber() ? light.GetNumberAsInt() : -1;
    check_index(light_index, model_.lights.size(),
                format_message("node ", node_index, ": KHR_lights_punctual light"));
    const tinygltf::Light& source = model_.lights[size_t(light_index)];
    if (source.type != "point" && source.type != "spot" && source.type != "directional") {
        log_warning(path_, ": light ", light_index, " has unknown type '", source.type,
                    "'; skipped");
        return;
    }
    scene_.add_light(light_from_gltf(source, world_from_node, options_));
}

void GltfImporter::add_node_camera(const tinygltf::Node& node, const mat4& world_from_node) {
    check_index(node.camera, model_.cameras.size(), "camera");
    if (scene_.has_camera()) {
        log_info(path_, ": camera ", node.camera, " ignored; the first camera node is used");
        return;
    }
    const tinygltf::Camera& camera = model_.cameras[size_t(node.camera)];
    // Else the lens comes out negative (yfov >= pi) or infinite (yfov = 0), which set_camera
    // refuses without naming the glTF's field.
    const float yfov = float(camera.perspective.yfov);  // as camera_from_gltf converts it
    if (camera.type != "orthographic" && !(yfov > 0.0f && yfov < kPi))
        throw IoError(format_message(path_, ": camera ", node.camera, " has yfov = ", yfov,
                                     " rad; a perspective camera's must be in (0, pi)"));
    scene_.set_camera(camera_from_gltf(camera, world_from_node));
}

const std::vector<uint32_t>& GltfImporter::mesh_ids(int mesh_index) {
    const auto cached = mesh_ids_.find(mesh_index);
    if (cached != mesh_ids_.end()) return cached->second;
    std::vector<Mesh> parts;
    const tinygltf::Mesh& mesh = model_.meshes[size_t(mesh_index)];
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const tinygltf::Primitive& primitive = mesh.primitives[p];
        if (primitive.mode != TINYGLTF_MODE_TRIANGLES) {
            log_warning(path_, ": mesh ", mesh_index, " primitive ", p, " has mode ",
                        primitive.mode, " (only TRIANGLES = 4 is supported); skipped");
            continue;
        }
        const uint32_t material = primitive.material >= 0 ? material_id(primitive.material)
                                                          : default_material_id();
        parts.push_back(build_primitive(mesh_index, int(p), material));
    }
    std::vector<uint32_t> ids;
    if (!parts.empty()) ids.push_back(scene_.add_mesh(merged_primitives(mesh_index, parts)));
    return mesh_ids_.emplace(mesh_index, std::move(ids)).first->second;
}

// One mesh per glTF mesh, as Blender's importer makes one mesh with a material slot per
// primitive: a node is then one object, baked into one lightmap and named once. Triangles keep
// their primitive's material. A primitive without normals among primitives with them gets the
// flat normals glTF 2.0 asks for (§3.7.2.1), on corners of its own; a UV set a primitive lacks
// reads (0, 0) there, as Blender fills it.
Mesh GltfImporter::merged_primitives(int mesh_index, std::vector<Mesh>& parts) const {
    if (parts.size() == 1) return std::move(parts.front());
    const auto has_normals = [](const Mesh& part) { return !part.normals.empty(); };
    const bool any_normals = std::any_of(parts.begin(), parts.end(), has_normals);
    const bool any_tangents = std::any_of(parts.begin(), parts.end(),
                                          [](const Mesh& part) { return !part.tangents.empty(); });
    size_t uv_set_count = 0, vertex_total = 0;
    for (Mesh& part : parts) {
        if (any_normals && !has_normals(part)) part = with_flat_normals(part);
        uv_set_count = std::max(uv_set_count, part.uv_sets.size());
        vertex_total += part.positions.size();
    }
    if (vertex_total > std::numeric_limits<uint32_t>::max())
        throw IoError(format_message(path_, ": mesh ", mesh_index, " has ", vertex_total,
                                     " vertices in all, more than a mesh can index"));
    Mesh merged;
    const tinygltf::Mesh& source = model_.meshes[size_t(mesh_index)];
    merged.name = source.name.empty() ? format_message("mesh_", mesh_index) : source.name;
    merged.uv_sets.resize(uv_set_count);
    for (size_t set = 0; set < uv_set_count; ++set)
        merged.uv_sets[set].name = uv_set_name(int(set));
    for (const Mesh& part : parts) {
        const uint32_t first = uint32_t(merged.positions.size());
        merged.positions.insert(merged.positions.end(), part.positions.begin(),
                                part.positions.end());
        merged.normals.insert(merged.normals.end(), part.normals.begin(), part.normals.end());
        if (any_tangents) {
            // A part without tangents has no normal map (its material has none, or it lacks the
            // map's UVs and was warned about): its placeholder frame is never read; zero where a
            // normal map would read it, so it falls back to the interpolated normal.
            const bool mapped = scene_.materials()[part.material_indices.empty()
                                                       ? 0
                                                       : part.material_indices[0]]
                                    .normal_texture != kNoTexture;
            if (part.tangents.empty())
                merged.tangents.resize(merged.tangents.size() + part.positions.size(),
                                       mapped ? vec4(0.0f) : vec4(1.0f, 0.0f, 0.0f, 1.0f));
            else
                merged.tangents.insert(merged.tangents.end(), part.tangents.begin(),
                                       part.tangents.end());
        }
        for (size_t set = 0; set < uv_set_count; ++set) {
            std::vector<vec2>& coords = merged.uv_sets[set].coords;
            if (set < part.uv_sets.size())
                coords.insert(coords.end(), part.uv_sets[set].coords.begin(),
                              part.uv_sets[set].coords.end());
            else
                coords.resize(coords.size() + part.positions.size(), vec2(0.0f));
        }
        for (const uvec3& t : part.triangles) merged.triangles.push_back(t + first);
        merged.material_indices.insert(merged.material_indices.end(),
                                       part.material_indices.begin(), part.material_indices.end());
    }
    return merged;
}

// `part` with three corners of its own per triangle, each holding the face normal.
Mesh GltfImporter::with_flat_normals(const Mesh& part) {
    Mesh flat;
    flat.name = part.name;
    flat.material_indices = part.material_indices;
    flat.uv_sets.resize(part.uv_sets.size());
    for (size_t set = 0; set < part.uv_sets.size(); ++set)
        flat.uv_sets[set].name = part.uv_sets[set].name;
    for (const uvec3& t : part.triangles) {
        const vec3 cross = glm::cross(part.positions[t.y] - part.positions[t.x],
                                      part.positions[t.z] - part.positions[t.x]);
        const float length = glm::length(cross);
        // A degenerate triangle (dropped later by validate_mesh) still needs a unit normal.
        const vec3 normal = length > 0.0f ? cross / length : vec3(0.0f, 0.0f, 1.0f);
        const uint32_t first = uint32_t(flat.positions.size());
        for (int corner = 0; corner < 3; ++corner) {
            flat.positions.push_back(part.positions[t[corner]]);
            flat.normals.push_back(normal);
            if (!part.tangents.empty()) flat.tangents.push_back(part.tangents[t[corner]]);
            for (size_t set = 0; set < part.uv_sets.size(); ++set)
                flat.uv_sets[set].coords.push_back(part.uv_sets[set].coords[t[corner]]);
        }
        flat.triangles.emplace_back(first, first + 1, first + 2);
    }
    return flat;
}

Mesh GltfImporter::build_primitive(int mesh_index, int primitive_index,
                                   uint32_t material_id) const {
    const tinygltf::Mesh& source = model_.meshes[size_t(mesh_index)];
    const tinygltf::Primitive& primitive = source.primitives[size_t(primitive_index)];
    const std::string what = format_message("mesh ", mesh_index, " primitive ", primitive_index);
    const auto position = primitive.attributes.find("POSITION");
    if (position == primitive.attributes.end())
        throw IoError(format_message(path_, ": ", what, " has no POSITION attribute"));

    Mesh mesh;
    mesh.name = source.name.empty() ? format_message("mesh_", mesh_index) : source.name;
    const std::vector<float> p = accessors_.read_floats(position->second, 3, what + " POSITION");
    const size_t vertex_count = p.size() / 3;
    for (size_t i = 0; i < vertex_count; ++i)
        mesh.positions.push_back(blender_from_gltf_vector(vec3_at(p, i)));

    const auto normal = primitive.attributes.find("NORMAL");
    if (normal != primitive.attributes.end()) {
        const std::vector<float> n = accessors_.read_floats(normal->second, 3, what + " NORMAL");
        if (n.size() != p.size())
            throw IoError(format_message(path_, ": ", what, " has ", n.size() / 3,
                                         " normals for ", vertex_count, " vertices"));
        for (size_t i = 0; i < vertex_count; ++i)
            mesh.normals.push_back(blender_from_gltf_vector(vec3_at(n, i)));
    }
    read_uv_sets(primitive, what, vertex_count, mesh);

    mesh.triangles = read_triangles(primitive, what, vertex_count);
    mesh.material_indices.assign(mesh.triangles.size(), material_id);
    const Material& material = scene_.materials()[material_id];
    if (material.normal_texture != kNoTexture) read_tangents(primitive, what, material, mesh);
    return mesh;
}

// The primitive's TANGENT attribute, else tangents computed from the normal map's UV set.
// TANGENT's w is kept: glTF's bitangent w cross(normal, tangent) points up the image (its -V),
// which is Blender's +V after the flip of V (read_uv_sets): the same direction in space.
void GltfImporter::read_tangents(const tinygltf::Primitive& primitive, const std::string& what,
                                 const Material& material, Mesh& mesh) const {
    const auto tangent = primitive.attributes.find("TANGENT");
    if (tangent != primitive.attributes.end()) {
        const std::vector<float> t = accessors_.read_floats(tangent->second, 4, what + " TANGENT");
        if (t.size() != 4 * mesh.positions.size())
            throw IoError(format_message(path_, ": ", what, " has ", t.size() / 4,
                                         " tangents for ", mesh.positions.size(), " vertices"));
        for (size_t i = 0; i < mesh.positions.size(); ++i)
            mesh.tangents.emplace_back(
                blender_from_gltf_vector(vec3(t[4 * i], t[4 * i + 1], t[4 * i + 2])),
                t[4 * i + 3]);
        return;
    }
    for (const UvSet& set : mesh.uv_sets)
        if (set.name == material.normal_uv_set) {
            mesh.tangents = vertex_tangents(mesh, set);
            return;
        }
    log_warning(path_, ": ", what, ": its normalTexture reads ", material.normal_uv_set,
                ", which the primitive does not have; it is shaded without its normal map");
}

std::vector<uvec3> GltfImporter::read_triangles(const tinygltf::Primitive& primitive,
                                                const std::string& what,
                                                size_t vertex_count) const {
    std::vector<uint32_t> indices;
    if (primitive.indices >= 0) {
        indices = accessors_.read_indices(primitive.indices, what + " indices");
    } else {  // non-indexed: consecutive vertex triples
        indices.resize(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i) indices[i] = uint32_t(i);
    }
    if (indices.size() % 3 != 0)
        log_warning(path_, ": ", what, " has ", indices.size(),
                    " indices, not a multiple of 3; the last ", indices.size() % 3, " are ignored");
    for (size_t i = 0; i < indices.size(); ++i) {
        if (indices[i] >= vertex_count)
            throw IoError(format_message(path_, ": ", what, " (accessor ", primitive.indices,
                                         "): indices[", i, "] = ", indices[i],
                                         ", but the primitive has only ", vertex_count,
                                         " vertices"));
    }
    std::vector<uvec3> triangles;
    triangles.reserve(indices.size() / 3);
    for (size_t t = 0; t + 2 < indices.size(); t += 3)
        triangles.emplace_back(indices[t], indices[t + 1], indices[t + 2]);
    return triangles;
}

void GltfImporter::read_uv_sets(const tinygltf::Primitive& primitive, const std::string& what,
                                size_t vertex_count, Mesh& mesh) const {
    for (int set = 0; set < kMaxUvSets; ++set) {
        const std::string attribute = format_message("TEXCOORD_", set);
        const auto found = primitive.attributes.find(attribute);
        if (found == primitive.attributes.end()) break;  // sets are numbered consecutively
        const std::vector<float> uv =
            accessors_.read_floats(found->second, 2, what + " " + attribute);
        if (uv.size() != 2 * vertex_count)
            throw IoError(format_message(path_, ": ", what, " has ", uv.size() / 2, " ", attribute,
                                         " coordinates for ", vertex_count, " vertices"));
        UvSet uv_set;
        uv_set.name = uv_set_name(set);
        uv_set.coords.reserve(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i)
            uv_set.coords.emplace_back(uv[2 * i], 1.0f - uv[2 * i + 1]);  // top-left -> bottom-left
        mesh.uv_sets.push_back(std::move(uv_set));
    }
}

uint32_t GltfImporter::default_material_id() {
    // Blender leaves such faces without material, which renders as its default surface.
    if (default_material_ < 0) default_material_ = scene_.add_material(Material{});
    return uint32_t(default_material_);
}

uint32_t GltfImporter::material_id(int material_index) {
    const auto cached = material_ids_.find(material_index);
    if (cached != material_ids_.end()) return cached->second;
    check_index(material_index, model_.materials.size(), "material");
    const tinygltf::Material& source = model_.materials[size_t(material_index)];
    const tinygltf::PbrMetallicRoughness& pbr = source.pbrMetallicRoughness;
    const std::string what = format_message("material ", material_index);

    Material material;
    material.name = source.name.empty() ? format_message("material_", material_index) : source.name;
    material.base_color = rgb_or(pbr.baseColorFactor, vec3(1.0f));  // glTF's default is white
    material.metallic = float(pbr.metallicFactor);
    material.roughness = float(pbr.roughnessFactor);
    material.emission_color = rgb_or(source.emissiveFactor, vec3(0.0f));
    material.emission_strength = float(extension_number(
        source.extensions, "KHR_materials_emissive_strength", "emissiveStrength", 1.0));
    // Blender keeps its own IOR (1.45) unless the file has KHR_materials_ior (default 1.5).
    material.ior = float(extension_number(source.extensions, "KHR_materials_ior", "ior",
                                          source.extensions.count("KHR_materials_ior") ? 1.5
                                                                                       : 1.45));
    if (material.ior < 1.0f) {  // the extension allows 0 ("infinite"); SHGI needs >= 1
        log_warning(path_, ": ", what, " has ior ", material.ior, "; using 1.45");
        material.ior = 1.45f;
    }
    material.transmission = float(extension_number(source.extensions, "KHR_materials_transmission",
                                                   "transmissionFactor", 0.0));
    if (pbr.baseColorTexture.index >= 0 && options_.import_textures) {
        material.base_color_texture =
            texture_id(pbr.baseColorTexture.index, true, what + ": baseColorTexture");
        if (material.base_color_texture != kNoTexture)
            material.base_color_uv_set = uv_set_name(pbr.baseColorTexture.texCoord);
    }
    // normalTexture: tangent space; its scale becomes the Normal Map node's Strength, as Blender's
    // importer sets it (glTF scales the texel's x and y instead: the same for scale 1).
    if (source.normalTexture.index >= 0 && options_.import_textures) {
        material.normal_texture =
            texture_id(source.normalTexture.index, false, what + ": normalTexture");
        if (material.normal_texture != kNoTexture) {
            material.normal_uv_set = uv_set_name(source.normalTexture.texCoord);
            material.normal_strength = float(source.normalTexture.scale);
            if (!(material.normal_strength >= 0.0f && material.normal_strength <= kMaxNormalStrength)) {
                log_warning(path_, ": ", what, ": normalTexture.scale ", material.normal_strength,
                            " is outside [0, ", kMaxNormalStrength, "]; using 1");
                material.normal_strength = 1.0f;
            }
        }
    }
    const uint32_t id = scene_.add_material(std::move(material));
    material_ids_.emplace(material_index, id);
    return id;
}

int32_t GltfImporter::texture_id(int index, bool srgb, const std::string& what) {
    check_index(index, model_.textures.size(), what);
    const int image_index = model_.textures[size_t(index)].source;
    if (image_index < 0) {
        log_warning(path_, ": ", what, ": texture ", index,
                    " has no source image (extension-only textures are not supported)");
        return kNoTexture;
    }
    check_index(image_index, model_.images.size(), what + ": image");
    const auto cached = texture_ids_.find({image_index, srgb});
    if (cached != texture_ids_.end()) return cached->second;
    const tinygltf::Image& image = model_.images[size_t(image_index)];
    int32_t id = kNoTexture;
    if (image_is_decoded(image)) {
        const std::string name =
            !image.name.empty() ? image.name : format_message("image_", image_index);
        id = int32_t(scene_.add_texture(texture_from_image(image, name, srgb)));
    } else {
        log_warning(path_, ": ", what, ": image ", image_index, " ('", image.uri,
                    "') has no decoded pixels; the texture is left out");
    }
    texture_ids_.emplace(std::make_pair(image_index, srgb), id);
    return id;
}

}  // namespace

mat4 blender_from_gltf() {
    // Columns are the images of the glTF axes: +X -> +X, +Y -> +Z, +Z -> -Y.
    return mat4(vec4(1, 0, 0, 0), vec4(0, 0, 1, 0), vec4(0, -1, 0, 0), vec4(0, 0, 0, 1));
}

float gltf_point_power(float intensity, GltfLightingMode mode) {
    // gltf2_blender_light.py _calc_energy_pointlike().
    switch (mode) {
        case GltfLightingMode::Spec: return intensity / kPbrWattsToLumens * kFourPi;
        case GltfLightingMode::Compat: return intensity * kFourPi;
        case GltfLightingMode::Raw: return intensity;
    }
    return intensity;
}

float gltf_sun_strength(float illuminance, GltfLightingMode mode) {
    // gltf2_blender_light.py create_directional().
    return mode == GltfLightingMode::Spec ? illuminance / kPbrWattsToLumens : illuminance;
}

Scene load_gltf(const std::string& path, const GltfLoadOptions& options, Progress* progress) {
    if (progress) progress->begin_stage("reading", 0.0f, kReadingShare);
    throw_if_cancelled(progress);
    const tinygltf::Model model = read_model(path, options, progress);
    if (progress) progress->begin_stage("importing", kReadingShare, 1.0f);
    try {
        Scene scene = GltfImporter(path, model, options, progress).run();
        if (progress) progress->set_fraction(1.0f);
        return scene;
    } catch (const InvalidArgument& error) {
        // Scene::add_* rejected a converted value (NaN vertex, bad light angle, ...).
        throw IoError(format_message(path, ": ", error.what()));
    }
}

}  // namespace shgi
