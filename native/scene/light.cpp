#include "scene/light.h"

#include <algorithm>
#include <limits>

#include "scene/scene.h"
#include "scene/validation.h"
#include "util/error.h"

namespace shgi {

using namespace scene_detail;

void validate_light(const Light& light) {
    const std::string item = label("light", light.name);
    require_non_negative(item, "color", light.color);
    require_non_negative(item, "power", light.power);
    require_non_negative(item, "strength", light.strength);
    require_transform(item, "world_from_light", light.world_from_light);
    require_non_negative(item, "radius", light.radius);
    // The emitted power is color x power (or strength, for a sun): each finite, their product
    // can still overflow float, and commit() would then blame the power for a bright colour.
    // Products past kMaxEmittedPower but within float are left to commit()'s scene-wide check.
    const float brightest = std::max(light.color.x, std::max(light.color.y, light.color.z));
    const char* amount = light.type == LightType::Sun ? "strength" : "power";
    const float amount_value = light.type == LightType::Sun ? light.strength : light.power;
    const double emitted = double(brightest) * double(amount_value);
    if (!(emitted <= double(std::numeric_limits<float>::max())))
        throw InvalidArgument(format_message(
            item, ": color = ", to_string(light.color), " (brightest component ", brightest,
            ") times ", amount, " = ", amount_value, " is ", emitted,
            ", beyond the float range (3.4e38); give the color in [0, 1] (Blender's light "
            "color) and the brightness in ", amount));
    if (light.portal && light.type != LightType::Area)
        throw InvalidArgument(format_message(item, ": portal is set on a light that is not an "
                                             "area light; only area lights can be portals"));
    float size = light.radius;  // the light's extent (m) before world_from_light's scale
    switch (light.type) {
        case LightType::Point:
            break;
        case LightType::Spot:
            require_finite(item, "spot_size", light.spot_size);
            if (!(light.spot_size > 0.0f) || light.spot_size > kPi)
                throw InvalidArgument(format_message(item, ": spot_size = ", light.spot_size,
                                                     " rad must be in (0, pi]"));
            require_in_range(item, "spot_blend", light.spot_blend, 0.0f, 1.0f);
            break;
        case LightType::Sun:
            require_finite(item, "angle", light.angle);
            if (light.angle < 0.0f || light.angle >= kPi)
                throw InvalidArgument(format_message(item, ": angle = ", light.angle,
                                                     " rad must be in [0, pi)"));
            break;
        case LightType::Area:
            // A zero-size area light would need infinite radiance to emit its power.
            require_positive(item, "size_x", light.size_x);
            size = light.size_x;
            if (light.shape == AreaShape::Rectangle || light.shape == AreaShape::Ellipse) {
                require_positive(item, "size_y", light.size_y);
                size = std::max(size, light.size_y);
            }
            break;
        default:
            throw InvalidArgument(format_message(item, ": type = ",
                                                 static_cast<int>(light.type), " is unknown"));
    }
    // Emitted rays start anywhere on the light: its reach must stay within the coordinates
    // scene geometry may use, as its translation does.
    const double scale = max_axis_scale(light.world_from_light);
    const double reach = double(size) * scale;
    if (!(reach <= double(kMaxCoordinate)))
        throw InvalidArgument(format_message(
            item, ": world_from_light scales it by ", scale, ", so its size (", size,
            " m) reaches ", reach, " m, beyond ", kMaxCoordinate,
            " m; lower the light's scale (its object's scale in Blender) or its size"));
}

void validate_world(const World& world) {
    require_non_negative("world", "color", world.color);
    require_non_negative("world", "strength", world.strength);
}

}  // namespace shgi
