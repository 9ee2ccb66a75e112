// Lights with Blender's parameters and units (docs/architecture.md, "Light units match Cycles").
//
// A light's frame is Blender's: it emits along its local -Z (spot, sun, area), the area light's
// surface spans local X/Y. `power` is Blender's "Power" in W (point, spot, area); `strength` is the
// sun's "Strength" in W/m^2. What these units mean in radiometric terms (Cycles' conventions) is
// fixed by the calibration tests against Cycles (docs/methods.md, "Calibration against
// Cycles"), which the renderers must follow.
// Emissive triangles are not Lights: they come from materials with emission (Scene collects them
// at commit).
#pragma once

#include <cstdint>
#include <string>

#include "util/math.h"

namespace shgi {

enum class LightType : uint8_t { Point, Spot, Sun, Area };
enum class AreaShape : uint8_t { Square, Rectangle, Disk, Ellipse };

struct Light {
    std::string name = "light";
    LightType type = LightType::Point;
    vec3 color{1.0f};          // linear RGB, each in [0, inf)
    float power = 10.0f;       // W: point, spot, area
    float strength = 1.0f;     // W/m^2: sun
    mat4 world_from_light{1.0f};
    float radius = 0.0f;       // m: point and spot "Radius" (soft shadows); 0 = a true point
    float spot_size = 0.785398f;  // rad: full cone angle, (0, pi]
    float spot_blend = 0.15f;     // [0, 1]
    // Blender 3.x's Cycles multiplies a spot's smoothstep falloff by cos(angle to its axis);
    // Cycles 4.0+ does not (spot.h: smoothstep only). The exporter sets false from Blender 4.0.
    bool spot_cone_cosine = true;
    float angle = 0.0f;           // rad: sun's angular diameter, [0, pi)
    AreaShape shape = AreaShape::Square;
    float size_x = 1.0f;       // m: side (square), width (rectangle), diameter (disk/ellipse)
    float size_y = 1.0f;       // m: height (rectangle), second diameter (ellipse)
    // Blender's Object.visible_camera: whether camera rays see the light's disk, surface or sun
    // cone. False by default, as for every light object Blender 3.4 creates; it never changes
    // the light a surface receives.
    bool visible_camera = false;
    // Blender's Cycles "Portal" (area lights only, light.cycles.is_portal): the light emits
    // nothing and is invisible; it marks an opening (a window) through which the world's light
    // enters, placed like an area light facing into the room. Samplers then aim world light
    // through it (render/light_sampler.h, photon/photon_emitter.h): less noise, same result.
    bool portal = false;

    vec3 position() const { return vec3(world_from_light[3]); }
    // Unit emission axis in world space (the light's local -Z).
    vec3 direction() const { return glm::normalize(-vec3(world_from_light[2])); }
};

// Throws InvalidArgument naming the light and field (NaN/Inf, negative power, bad angles,
// a singular or non-finite transform).
void validate_light(const Light& light);

// Uniform background light (Blender's world colour x strength): radiance in W m^-2 sr^-1.
struct World {
    vec3 color{0.050876f};  // Blender's default world grey (0.05 in sRGB display terms)
    float strength = 1.0f;

    vec3 radiance() const { return color * strength; }
};

void validate_world(const World& world);

}  // namespace shgi
