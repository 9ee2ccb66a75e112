#include "sh/sh_window.h"

#include <cmath>

#include "util/error.h"

namespace shgi {

ShWindow parse_sh_window(const std::string& name) {
    if (name == "none") return ShWindow::None;
    if (name == "hanning") return ShWindow::Hanning;
    if (name == "lanczos") return ShWindow::Lanczos;
    throw InvalidArgument(format_message("window: '", name,
                                         "' is not a window; use 'none', 'hanning' or 'lanczos'"));
}

const char* sh_window_name(ShWindow window) {
    switch (window) {
        case ShWindow::None: return "none";
        case ShWindow::Hanning: return "hanning";
        case ShWindow::Lanczos: return "lanczos";
    }
    return "none";
}

BandFactors sh_window_factors(ShWindow window, int order, float width) {
    check_sh_order(order, "sh_window_factors");
    if (!std::isfinite(width))
        throw InvalidArgument(format_message("sh_window_factors: width is ", width,
                                             "; use a finite width in bands (<= 0: order + 1)"));
    const double w = width > 0.0f ? width : order + 1.0;
    BandFactors factors{};
    for (int l = 0; l <= order; ++l) {
        const double x = kPiD * l / w;
        if (window == ShWindow::None) {
            factors[l] = 1.0f;
        } else if (l >= w) {
            factors[l] = 0.0f;
        } else if (window == ShWindow::Hanning) {
            factors[l] = static_cast<float>(0.5 * (1.0 + std::cos(x)));
        } else {
            factors[l] = l == 0 ? 1.0f : static_cast<float>(std::sin(x) / x);
        }
    }
    return factors;
}

void sh_apply_window(ShRgb& sh, ShWindow window, float width) {
    sh_scale_bands(sh, sh_window_factors(window, sh.order, width));
}

}  // namespace shgi
