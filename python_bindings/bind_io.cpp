// Bindings for native/io images: EXR write/read (io/exr_image.h), PNG write and the sRGB curve
// (io/png_image.h).
//
// Python sees images as a dict of layers, in channel order: {"Combined": (H, W, 4) float32,
// "Depth": (H, W, 1) float32, ...}, rows top row first (row 0 of the array is the top of the
// image; Blender's pixel buffers start at the bottom, flip with array[::-1]). A layer's
// channels are named in the file "<layer>.<suffix>" with suffixes R G B A for 3 and 4 channels,
// Z for 1 (Blender's Depth and Mist passes), X Y for 2, or the caller's channel_names.
// Arrays are checked and copied with the GIL held; the GIL is released around file I/O.
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "io/exr_image.h"
#include "io/image.h"
#include "io/png_image.h"
#include "numpy_convert.h"
#include "path_arg.h"
#include "struct_fields.h"
#include "util/error.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

// "(H, W, C) float64" for error messages.

// An image-shaped float array: (H, W) or (H, W, C) with a float dtype (float16/32/64) and
// 1 <= H, W <= kMaxImageDimension. Returns it C-contiguous as float32.
FloatArray checked_image_array(const py::handle& obj, const std::string& arg_name) {
    const py::array array = obj.is_none() ? py::array() : py::array::ensure(obj);
    if (!array) throw_value_error(arg_name.c_str(), "expected a numpy array");
    if (array.dtype().kind() != 'f') {
        throw_value_error(arg_name.c_str(), "expected a float16/float32/float64 array, got " +
                                                describe_array(array));
    }
    if (array.ndim() != 2 && array.ndim() != 3) {
        throw_value_error(arg_name.c_str(),
                          "expected shape (H, W) or (H, W, C), got " + describe_array(array));
    }
    for (py::ssize_t axis = 0; axis < array.ndim(); ++axis) {
        if (array.shape(axis) < 1 || (axis < 2 && array.shape(axis) > kMaxImageDimension)) {
            throw_value_error(arg_name.c_str(), "shape " + describe_array(array) +
                                                    " is out of range: each size must be in [1, " +
                                                    std::to_string(kMaxImageDimension) + "]");
        }
    }
    return contiguous_copy<FloatArray>(array, arg_name.c_str());
}

size_t channel_count(const FloatArray& array) {
    return array.ndim() == 3 ? size_t(array.shape(2)) : 1;
}

std::vector<std::string> default_suffixes(size_t channels) {
    switch (channels) {
        case 1: return {"Z"};
        case 2: return {"X", "Y"};
        case 3: return {"R", "G", "B"};
        case 4: return {"R", "G", "B", "A"};
        default: return {};
    }
}

// Channel suffixes for `layer`: channel_names[layer] (a str, one suffix per character, or a
// sequence of str) or the default for its channel count.
std::vector<std::string> layer_suffixes(const std::string& layer, size_t channels,
                                        const py::dict& channel_names) {
    const std::string arg = "channel_names['" + layer + "']";
    std::vector<std::string> suffixes;
    if (channel_names.contains(layer)) {
        const py::object names = channel_names[py::str(layer)];
        if (py::isinstance<py::str>(names)) {
            for (char c : names.cast<std::string>()) suffixes.emplace_back(1, c);
        } else {
            try {
                suffixes = names.cast<std::vector<std::string>>();
            } catch (const py::cast_error&) {
                throw_value_error(arg.c_str(), "expected a str or a sequence of str");
            }
        }
    } else {
        suffixes = default_suffixes(channels);
        if (suffixes.empty()) {
            throw_value_error(("layers['" + layer + "']").c_str(),
                              "has " + std::to_string(channels) +
                                  " channels; name them with channel_names['" + layer + "']");
        }
    }
    if (suffixes.size() != channels) {
        throw_value_error(arg.c_str(), "names " + std::to_string(suffixes.size()) +
                                           " channels, but the layer has " +
                                           std::to_string(channels));
    }
    return suffixes;
}

// pixel_type "half" / "float", or None: half for float16 arrays, float otherwise.
PixelType layer_pixel_type(const std::optional<std::string>& pixel_type, const py::array& array) {
    if (!pixel_type) return array.dtype().itemsize() == 2 ? PixelType::Half : PixelType::Float;
    if (*pixel_type == "half") return PixelType::Half;
    if (*pixel_type == "float") return PixelType::Float;
    throw_value_error("pixel_type", "expected \"half\", \"float\" or None, got \"" +
                                        *pixel_type + "\"");
}

// Builds the Image from the layers dict (GIL held: it reads Python objects).
Image image_from_layers(const py::dict& layers, const std::optional<std::string>& pixel_type,
                        const py::dict& channel_names) {
    if (layers.empty()) throw_value_error("layers", "give at least one layer");
    // Iterate over lists of the items, which own references: a dict's own iteration lends them,
    // and a layer's __array__ (or a key's __eq__) may edit the dict while it runs.
    const auto owned_items = [](const py::dict& dict) {
        return py::list(dict.attr("items")());
    };
    for (const py::handle item : owned_items(channel_names)) {
        const py::tuple pair = py::reinterpret_borrow<py::tuple>(item);
        if (!layers.contains(pair[0])) {
            throw_value_error("channel_names", "names channels of " +
                                                   py::repr(pair[0]).cast<std::string>() +
                                                   ", which is not a key of layers");
        }
    }
    std::optional<Image> image;
    py::ssize_t height = 0;
    py::ssize_t width = 0;
    for (const py::handle item : owned_items(layers)) {
        const py::tuple pair = py::reinterpret_borrow<py::tuple>(item);
        const py::object key = pair[0], value = pair[1];
        if (!py::isinstance<py::str>(key)) {
            throw_value_error("layers", "keys must be layer names (str), got " +
                                            py::repr(key).cast<std::string>());
        }
        const std::string layer = key.cast<std::string>();
        const std::string arg = "layers['" + layer + "']";
        const py::array original = py::array::ensure(value);
        const FloatArray array = checked_image_array(value, arg);
        if (!image) {
            height = array.shape(0);
            width = array.shape(1);
            image.emplace(int(width), int(height));
        } else if (array.shape(0) != height || array.shape(1) != width) {
            throw_value_error(arg.c_str(), "is " + std::to_string(array.shape(0)) + " x " +
                                               std::to_string(array.shape(1)) +
                                               " pixels (H x W), but the first layer is " +
                                               std::to_string(height) + " x " +
                                               std::to_string(width));
        }
        const size_t channels = channel_count(array);
        const std::vector<std::string> suffixes = layer_suffixes(layer, channels, channel_names);
        const std::vector<float> pixels(array.data(), array.data() + array.size());
        image->add_layer(layer, suffixes, pixels, layer_pixel_type(pixel_type, original));
    }
    return std::move(*image);
}

py::array_t<float> layer_array(const Image& image, const std::string& layer) {
    const std::vector<float> pixels = image.layer_pixels(layer);
    const size_t channels = image.layer_suffixes(layer).size();
    py::array_t<float> array({py::ssize_t(image.height()), py::ssize_t(image.width()),
                              py::ssize_t(channels)});
    std::copy(pixels.begin(), pixels.end(), array.mutable_data());
    return array;
}

void bind_exr(py::module_& m) {
    m.def(
        "write_exr",
        [](const PathArg& path, const py::dict& layers,
           const std::optional<std::string>& pixel_type, const py::dict& channel_names,
           const std::string& compression) {
            const Image image = image_from_layers(layers, pixel_type, channel_names);
            ExrWriteSettings settings;
            try {
                settings.compression = exr_compression_from_name(compression);
            } catch (const InvalidArgument& error) {
                throw_value_error("compression", error.what());
            }
            py::gil_scoped_release release;
            write_exr(path.value, image, settings);
        },
        py::arg("path"), py::arg("layers"), py::arg("pixel_type") = py::none(),
        py::arg("channel_names") = py::dict(), py::arg("compression") = "zip",
        R"doc(
Writes a multilayer OpenEXR file, atomically (temporary file in the same folder, then rename).

layers: dict of layer name -> float16/32/64 array (H, W) or (H, W, C), all the same H x W, row 0
    at the top. Channels are named "<layer>.<suffix>" (Blender's style: "Combined.R",
    "Depth.Z"); suffixes default to R G B A (4), R G B (3), X Y (2), Z (1). An empty layer name
    writes bare suffixes ("R", "G", "B").
pixel_type: "float" (exact), "half", or None: half for float16 arrays, float otherwise.
channel_names: dict of layer name -> suffixes, a str with one per character ("XYZ") or a list
    of str (["c0", "c1", ...]); needed for layers with more than 4 channels.
compression: lossless codec "zip" (default), "piz", "zips", "rle" or "none".
Raises ValueError for bad arrays or names (naming the argument), OSError when the file cannot
be written.)doc");

    // A channel or layer name read from `path` as a str; IoError when it is not UTF-8 (another
    // writer's Latin-1 name), which pybind11 would make a bare UnicodeDecodeError.
    const auto name_from_file = [](const std::string& name, const std::string& path,
                                   const char* what) {
        PyObject* text = PyUnicode_DecodeUTF8(name.data(), Py_ssize_t(name.size()), nullptr);
        if (text == nullptr) {
            PyErr_Clear();
            throw IoError(format_message("cannot read EXR \"", path, "\": the ", what, " \"",
                                         name, "\" is not UTF-8; rename it when writing the "
                                         "file"));
        }
        return py::reinterpret_steal<py::str>(text);
    };

    m.def(
        "read_exr",
        [name_from_file](const PathArg& path, const IndexInt& max_pixels_arg) {
            const int64_t max_pixels = int_arg<int64_t>(max_pixels_arg, "max_pixels", 1,
                                                        std::numeric_limits<int64_t>::max());
            std::optional<Image> image;
            {
                py::gil_scoped_release release;
                image.emplace(read_exr(path.value, max_pixels));
            }
            py::dict layers;
            for (const std::string& layer : image->layer_names()) {
                const py::str name = name_from_file(layer, path.value, "layer name");
                layers[name] = layer_array(*image, layer);
            }
            return layers;
        },
        py::arg("path"), py::arg("max_pixels") = kDefaultMaxExrPixels,
        R"doc(
Reads an OpenEXR file into a dict of layer name -> float32 array (H, W, C), row 0 at the top.

Layers and channels come back in the order write_exr wrote them; for files from other writers
layers are in the file's (alphabetical) order and channels in Blender's order (R G B A,
X Y Z W, U V, others by name). Half channels are converted to float32. Channels named without a
'.' form the layer "". read_exr_info gives the channel names and pixel types.
max_pixels: refuse images with more than this many pixels (width * height), so that a hostile
    file cannot exhaust memory; raise it only for trusted files.
Raises OSError naming the file when it is missing, corrupt, too large or unsupported.)doc");

    m.def(
        "read_exr_info",
        [name_from_file](const PathArg& path) {
            ExrInfo info;
            {
                py::gil_scoped_release release;
                info = read_exr_info(path.value);
            }
            py::list channels;
            for (const ExrChannelInfo& channel : info.channels) {
                const py::str name = name_from_file(channel.name, path.value, "channel name");
                channels.append(py::make_tuple(name, pixel_type_name(channel.pixel_type)));
            }
            py::dict result;
            result["width"] = info.width;
            result["height"] = info.height;
            result["compression"] = info.compression;
            result["channels"] = channels;
            return result;
        },
        py::arg("path"),
        R"doc(
Reads only the header of an OpenEXR file: {"width", "height", "compression",
"channels": [(full name, "half" | "float"), ...]} with channels in read_exr's order.
Raises OSError naming the file when it is missing, corrupt or unsupported.)doc");
}

void bind_png(py::module_& m) {
    m.def(
        "write_png",
        [](const PathArg& path, const py::handle& pixels, float exposure,
           bool premultiplied) {
            const FloatArray array = checked_image_array(pixels, "pixels");
            const size_t channels = channel_count(array);
            if (array.ndim() != 3 || (channels != 3 && channels != 4)) {
                throw_value_error("pixels", "expected shape (H, W, 3) or (H, W, 4), got " +
                                                describe_array(array));
            }
            if (!std::isfinite(exposure)) {
                throw_value_error("exposure", "must be finite, got " + std::to_string(exposure));
            }
            const std::vector<float> values(array.data(), array.data() + array.size());
            const int height = int(array.shape(0));
            const int width = int(array.shape(1));
            py::gil_scoped_release release;
            write_png(path.value, values, width, height, int(channels),
                      PngWriteSettings{exposure, premultiplied});
        },
        py::arg("path"), py::arg("pixels"), py::arg("exposure") = 0.0f,
        py::arg("premultiplied") = true,
        R"doc(
Writes linear float pixels as an 8-bit sRGB PNG, atomically.

pixels: float array (H, W, 3) RGB or (H, W, 4) RGBA, linear Rec.709, row 0 at the top.
exposure: stops; colour is multiplied by 2**exposure before encoding.
premultiplied: RGBA colour is premultiplied by alpha (as SHGI and Cycles render it) and is
    divided by alpha before encoding, since PNG stores straight alpha.
Colour is clamped to [0, 1] (NaN -> 0) and encoded with the exact sRGB curve; alpha is stored
linearly. Raises ValueError for bad arguments, OSError when the file cannot be written.)doc");

    m.def("srgb_from_linear", py::vectorize(srgb_from_linear), py::arg("linear"),
          R"doc(
sRGB transfer function (IEC 61966-2-1): 12.92 x up to 0.0031308, 1.055 x**(1/2.4) - 0.055
above. Input is clamped to [0, 1] (NaN -> 0). Accepts a float or an array (float32 result).)doc");

    m.def("linear_from_srgb", py::vectorize(linear_from_srgb), py::arg("encoded"),
          R"doc(
Inverse sRGB transfer function: x / 12.92 up to 0.04045, ((x + 0.055) / 1.055)**2.4 above.
Input is clamped to [0, 1] (NaN -> 0). Accepts a float or an array (float32 result).)doc");
}

}  // namespace

void bind_io(py::module_& m) {
    bind_exr(m);
    bind_png(m);
}

}  // namespace shgi::python
