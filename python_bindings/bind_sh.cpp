// shgi.sh: the native/sh module in Python (real orthonormal SH without the Condon–Shortley
// phase, orders 0..4, RGB coefficients as (n, 3) float32 arrays, coefficient-major).
//
// Names mirror the C++ functions without their sh_ prefix (sh_eval -> sh.eval). Arguments are
// checked with the GIL held and a ValueError names the bad argument; the loops over arrays run
// with the GIL released.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "numpy_convert.h"
#include "struct_fields.h"
#include "sh/ggx_zh.h"
#include "sh/lobe_zh.h"
#include "sh/sh_basis.h"
#include "sh/sh_irradiance.h"
#include "sh/sh_projection.h"
#include "sh/sh_window.h"
#include "sh/zonal_harmonics.h"
#include "util/parallel.h"

namespace shgi::python {

namespace {

// Directions per parallel chunk: evaluating 25 basis functions is ~100 ns, so 4096 directions
// amortise TBB's per-chunk overhead.
constexpr uint64_t kDirectionsPerChunk = 4096;

// An SH order argument (any int, or __index__ object such as numpy's integers) in 0..4.
int checked_order(const IndexInt& order, const char* arg_name) {
    return int_arg<int>(order, arg_name, 0, kMaxShOrder);
}

// (N, 3) unit vectors; rejects non-unit rows naming the row.
std::vector<vec3> to_unit_directions(const py::handle& obj, const char* arg_name) {
    std::vector<vec3> directions = to_vec3_array(obj, arg_name);
    for (size_t i = 0; i < directions.size(); ++i) {
        const float length = glm::length(directions[i]);
        if (!(std::abs(length - 1.0f) <= kUnitLengthTolerance))
            throw_value_error(arg_name, "row " + std::to_string(i) + " has length " +
                                            std::to_string(length) +
                                            "; directions must be normalised");
    }
    return directions;
}

// (n, 3) RGB coefficients with n = (order+1)^2, order <= 4.
ShRgb to_sh_rgb(const py::handle& obj, const char* arg_name) {
    const std::vector<float> rows = to_float_rows(obj, arg_name, 3);
    const size_t count = rows.size() / 3;
    int order = -1;
    for (int o = 0; o <= kMaxShOrder; ++o)
        if (static_cast<size_t>(sh_num_coefficients(o)) == count) order = o;
    if (order < 0)
        throw_value_error(arg_name, "expected (n, 3) with n = (order+1)^2 in {1, 4, 9, 16, 25}, "
                                    "got n = " + std::to_string(count));
    ShRgb sh(order);
    for (size_t i = 0; i < count; ++i) sh.coeffs[i] = vec3(rows[3 * i], rows[3 * i + 1],
                                                            rows[3 * i + 2]);
    return sh;
}

// A 1-D array of per-band values (ZH coefficients or band factors), 1..5 entries.
std::array<float, kMaxShOrder + 1> to_band_values(const py::handle& obj, const char* arg_name,
                                                  int& bands) {
    const std::vector<float> values = to_float_rows(obj, arg_name, 0);
    if (values.empty() || values.size() > static_cast<size_t>(kMaxShOrder + 1))
        throw_value_error(arg_name, "expected 1.." + std::to_string(kMaxShOrder + 1) +
                                        " per-band values (bands 0..4), got " +
                                        std::to_string(values.size()));
    std::array<float, kMaxShOrder + 1> out{};
    for (size_t l = 0; l < values.size(); ++l) out[l] = values[l];
    bands = static_cast<int>(values.size());
    return out;
}

// Per-band values must cover every band of the coefficients they scale.
void check_bands_cover(int bands, const ShRgb& coeffs, const char* arg_name) {
    if (bands < coeffs.order + 1)
        throw_value_error(arg_name, "has " + std::to_string(bands) +
                                        " bands but coeffs has order " +
                                        std::to_string(coeffs.order) + "; give order+1 values");
}

float checked_roughness(float roughness) {
    if (!(roughness >= 0.0f && roughness <= 1.0f))
        throw_value_error("roughness",
                          "is " + std::to_string(roughness) + "; it must be in [0, 1]");
    return roughness;
}

py::array_t<float> rgb_to_numpy(const ShRgb& sh) {
    py::array_t<float> out({sh.num_coefficients(), 3});
    std::copy(sh.data(), sh.data() + 3 * sh.num_coefficients(), out.mutable_data());
    return out;
}

py::array_t<float> scalar_to_numpy(const float* values, int count) {
    py::array_t<float> out(count);
    std::copy(values, values + count, out.mutable_data());
    return out;
}

// Fills an (N, 3) array with f(direction) for every direction, GIL released, in parallel.
template <typename F>
py::array_t<float> map_directions(const std::vector<vec3>& directions, F&& f) {
    py::array_t<float> out({static_cast<py::ssize_t>(directions.size()), py::ssize_t{3}});
    float* data = out.mutable_data();
    py::gil_scoped_release release;
    parallel_for(0, directions.size(), kDirectionsPerChunk, [&](uint64_t begin, uint64_t end) {
        for (uint64_t i = begin; i < end; ++i) {
            const vec3 value = f(directions[i]);
            data[3 * i] = value.x;
            data[3 * i + 1] = value.y;
            data[3 * i + 2] = value.z;
        }
    });
    return out;
}

void bind_basis(py::module_& sh) {
    sh.attr("MAX_ORDER") = kMaxShOrder;
    sh.def("num_coefficients", [](const IndexInt& order) {
        return sh_num_coefficients(checked_order(order, "order"));
    }, py::arg("order"), "Number of SH coefficients of an order-`order` expansion: (order+1)^2.");
    sh.def(
        "eval",
        [](const py::handle& directions_obj, const IndexInt& order_arg) {
            const int order = checked_order(order_arg, "order");
            const std::vector<vec3> directions = to_unit_directions(directions_obj, "directions");
            const int n = sh_num_coefficients(order);
            py::array_t<float> out({static_cast<py::ssize_t>(directions.size()),
                                    static_cast<py::ssize_t>(n)});
            float* data = out.mutable_data();
            py::gil_scoped_release release;
            parallel_for(0, directions.size(), kDirectionsPerChunk,
                         [&](uint64_t begin, uint64_t end) {
                             for (uint64_t i = begin; i < end; ++i)
                                 sh_eval(order, directions[i], data + i * n);
                         });
            return out;
        },
        py::arg("directions"), py::arg("order") = 2,
        "Basis functions Y_i at unit `directions` (N, 3): float32 (N, (order+1)^2), index "
        "i = l(l+1)+m, no Condon-Shortley phase (Y1-1 = +0.488603 y).");
    sh.def(
        "evaluate",
        [](const py::handle& coeffs_obj, const py::handle& directions_obj) {
            const ShRgb coeffs = to_sh_rgb(coeffs_obj, "coeffs");
            const std::vector<vec3> directions = to_unit_directions(directions_obj, "directions");
            return map_directions(directions,
                                  [&](const vec3& d) { return sh_evaluate(coeffs, d); });
        },
        py::arg("coeffs"), py::arg("directions"),
        "Reconstructs RGB coefficients (n, 3) at unit `directions` (N, 3): float32 (N, 3).");
}

void bind_projection(py::module_& sh) {
    sh.def(
        "project",
        [](const py::handle& directions_obj, const py::handle& values_obj,
           const py::handle& weights_obj, const IndexInt& order_arg) {
            const int order = checked_order(order_arg, "order");
            const std::vector<vec3> directions = to_unit_directions(directions_obj, "directions");
            const std::vector<vec3> values = to_vec3_array(values_obj, "values");
            if (values.size() != directions.size())
                throw_value_error("values", "has " + std::to_string(values.size()) +
                                                " rows but directions has " +
                                                std::to_string(directions.size()));
            std::vector<float> weights;
            if (!weights_obj.is_none()) {
                weights = to_float_rows(weights_obj, "weights", 0);
                if (weights.size() != directions.size())
                    throw_value_error("weights", "has " + std::to_string(weights.size()) +
                                                     " entries but directions has " +
                                                     std::to_string(directions.size()) + " rows");
            }
            ShRgb result;
            {
                py::gil_scoped_release release;
                result = sh_project(order, directions.data(), values.data(),
                                    weights.empty() ? nullptr : weights.data(), directions.size());
            }
            return rgb_to_numpy(result);
        },
        py::arg("directions"), py::arg("values"), py::arg("weights") = py::none(),
        py::arg("order") = 2,
        "Projects samples: returns sum_k weights[k] * values[k] * Y(directions[k]) as float32 "
        "(n, 3). directions (N, 3) unit, values (N, 3) RGB, weights (N,) or None (all 1). For a "
        "Monte Carlo estimate of the integral use weights = 1 / (N * pdf).");
}

void bind_convolution(py::module_& sh) {
    sh.def(
        "irradiance",
        [](const py::handle& coeffs_obj, const py::handle& normals_obj) {
            const ShRgb radiance = to_sh_rgb(coeffs_obj, "coeffs");
            const std::vector<vec3> normals = to_unit_directions(normals_obj, "normals");
            ShRgb irradiance = radiance;
            sh_convolve_cosine(irradiance);
            return map_directions(normals,
                                  [&](const vec3& n) { return sh_evaluate(irradiance, n); });
        },
        py::arg("coeffs"), py::arg("normals"),
        "Irradiance E(n) = sum A_l L_lm Y_lm(n) (W/m^2, unclamped) of radiance coefficients "
        "(n, 3) at unit normals (N, 3): float32 (N, 3). A_l = pi, 2pi/3, pi/4, 0, -pi/24.");
    sh.def(
        "convolve_cosine",
        [](const py::handle& coeffs_obj) {
            ShRgb coeffs = to_sh_rgb(coeffs_obj, "coeffs");
            sh_convolve_cosine(coeffs);
            return rgb_to_numpy(coeffs);
        },
        py::arg("coeffs"),
        "Radiance coefficients (n, 3) -> irradiance coefficients (n, 3): each band l times A_l.");
    sh.def(
        "scale_bands",
        [](const py::handle& coeffs_obj, const py::handle& factors_obj) {
            ShRgb coeffs = to_sh_rgb(coeffs_obj, "coeffs");
            int bands = 0;
            const BandFactors factors = to_band_values(factors_obj, "factors", bands);
            check_bands_cover(bands, coeffs, "factors");
            sh_scale_bands(coeffs, factors);
            return rgb_to_numpy(coeffs);
        },
        py::arg("coeffs"), py::arg("factors"),
        "Multiplies every coefficient of band l by factors[l] (e.g. ggx_specular_zh or "
        "window_factors); coeffs (n, 3), factors (>= order+1,). Returns float32 (n, 3).");
}

void bind_zonal(py::module_& sh) {
    sh.def(
        "convolve_zonal",
        [](const py::handle& coeffs_obj, const py::handle& zh_obj) {
            ShRgb coeffs = to_sh_rgb(coeffs_obj, "coeffs");
            int bands = 0;
            const ZhCoeffs zh = to_band_values(zh_obj, "zh", bands);
            check_bands_cover(bands, coeffs, "zh");
            sh_scale_bands(coeffs, zonal_band_factors(zh));
            return rgb_to_numpy(coeffs);
        },
        py::arg("coeffs"), py::arg("zh"),
        "Convolution with the zonal kernel `zh` (ZH coefficients z_l, Funk-Hecke): band l times "
        "sqrt(4pi/(2l+1)) z_l. Returns float32 (n, 3).");
    sh.def(
        "rotate_zonal",
        [](const py::handle& zh_obj, const py::handle& axis_obj) {
            int bands = 0;
            const ZhCoeffs zh = to_band_values(zh_obj, "zh", bands);
            const vec3 axis = to_vec3(axis_obj, "axis");
            if (!(std::abs(glm::length(axis) - 1.0f) <= kUnitLengthTolerance))
                throw_value_error("axis", "has length " + std::to_string(glm::length(axis)) +
                                              "; it must be normalised");
            const ShCoeffs rotated = sh_rotate_zonal(bands - 1, zh, axis);
            return scalar_to_numpy(rotated.coeffs.data(), rotated.num_coefficients());
        },
        py::arg("zh"), py::arg("axis"),
        "SH coefficients (bands^2,) of the axially symmetric lobe with ZH coefficients `zh` "
        "(around +Z) turned to the unit `axis`: c_lm = sqrt(4pi/(2l+1)) z_l Y_lm(axis).");
}

void bind_lobes(py::module_& sh) {
    const auto first_bands = [](const ZhCoeffs& zh, const IndexInt& order) {
        return scalar_to_numpy(zh.data(), checked_order(order, "order") + 1);
    };
    sh.def(
        "cosine_lobe_zh",
        [=](const IndexInt& order) { return first_bands(cosine_lobe_zh(), order); },
        py::arg("order") = kMaxShOrder,
        "ZH coefficients z_0..z_order of the clamped cosine max(cos theta, 0): sqrt(pi)/2, "
        "sqrt(pi/3), sqrt(5pi)/8, 0, -sqrt(pi)/16.");
    sh.def(
        "lambert_zh",
        [=](const IndexInt& order, float albedo) {
            return first_bands(lambert_zh(checked_finite(albedo, "albedo")), order);
        },
        py::arg("order") = kMaxShOrder, py::arg("albedo") = 1.0f,
        "ZH coefficients of the Lambertian BRDF times cosine, (albedo/pi) max(cos theta, 0) "
        "(seed 004 3.3.1, corrected even-l formula).");
    sh.def(
        "phong_zh",
        [=](float exponent, const IndexInt& order, float specular) {
            if (!(exponent >= 0.0f) || !std::isfinite(exponent))
                throw_value_error("exponent", "is " + std::to_string(exponent) +
                                                  "; it must be finite and >= 0");
            return first_bands(phong_zh(exponent, checked_finite(specular, "specular")), order);
        },
        py::arg("exponent"), py::arg("order") = kMaxShOrder, py::arg("specular") = 1.0f,
        "ZH coefficients of the normalised Phong lobe specular*(n+1)/(2pi) cos^n theta "
        "(seed 004 3.3.2).");
    sh.def(
        "ggx_specular_zh",
        [](float roughness) {
            const BandFactors factors = ggx_specular_zh(checked_roughness(roughness));
            return scalar_to_numpy(factors.data(), kMaxShOrder + 1);
        },
        py::arg("roughness"),
        "Per-band factors (5,) of the fitted GGX specular lobe (seed 002 Appendix A), factor 0 "
        "= 1. Use with scale_bands; clamp the reconstructed radiance at 0.");
    sh.def(
        "specular_radiance",
        [](const py::handle& coeffs_obj, const py::handle& reflected_obj, float roughness) {
            const ShRgb radiance = to_sh_rgb(coeffs_obj, "coeffs");
            const std::vector<vec3> reflected = to_unit_directions(reflected_obj, "reflected");
            checked_roughness(roughness);
            return map_directions(reflected, [&](const vec3& r) {
                return sh_specular_radiance(radiance, r, roughness);
            });
        },
        py::arg("coeffs"), py::arg("reflected"), py::arg("roughness"),
        "Pre-filtered GGX specular radiance (N, 3), clamped at 0, of radiance coefficients "
        "(n, 3) in unit reflected directions (N, 3).");
}

void bind_window(py::module_& sh) {
    sh.def(
        "window_factors",
        [](const std::string& kind, const IndexInt& order_arg, float width) {
            const ShWindow window = parse_sh_window(kind);
            const int order = checked_order(order_arg, "order");
            const BandFactors factors =
                sh_window_factors(window, order, checked_finite(width, "width"));
            return scalar_to_numpy(factors.data(), order + 1);
        },
        py::arg("kind"), py::arg("order"), py::arg("width") = 0.0f,
        "Windowing factors (order+1,) against ringing: kind 'none', 'hanning' or 'lanczos'; "
        "width in bands, <= 0 means order+1 (Sloan 2008).");
    sh.def(
        "window",
        [](const py::handle& coeffs_obj, const std::string& kind, float width) {
            ShRgb coeffs = to_sh_rgb(coeffs_obj, "coeffs");
            sh_apply_window(coeffs, parse_sh_window(kind), checked_finite(width, "width"));
            return rgb_to_numpy(coeffs);
        },
        py::arg("coeffs"), py::arg("kind") = "hanning", py::arg("width") = 0.0f,
        "Returns the coefficients (n, 3) with a window applied per band (see window_factors).");
}

}  // namespace

void bind_sh(py::module_& m) {
    py::module_ sh = m.def_submodule(
        "sh",
        "Real spherical harmonics, orders 0..4: orthonormal, index i = l(l+1)+m, no "
        "Condon-Shortley phase (Y00 = 0.282095, Y1-1 = +0.488603 y, Y10 = +0.488603 z, "
        "Y11 = +0.488603 x). RGB coefficients are float32 arrays of shape (n, 3), n = "
        "(order+1)^2; directions are unit vectors in Blender's frame (Z up).");
    bind_basis(sh);
    bind_projection(sh);
    bind_convolution(sh);
    bind_zonal(sh);
    bind_lobes(sh);
    bind_window(sh);
}

}  // namespace shgi::python
