// glTF 2.0 scene loading (.gltf with embedded or external buffers, and .glb) into a shgi::Scene,
// following what Blender 3.4's bundled glTF importer (io_scene_gltf2) produces, so that a file
// loaded here and the same file imported into Blender and exported by the add-on agree.
//
// Axes: glTF is right-handed Y-up, SHGI (Blender) is right-handed Z-up. Points, normals and node
// transforms go through blender_from_gltf, (x, y, z)_gltf -> (x, -z, y)_blender, exactly as the
// importer's "+Y Up" option (convert_loc in blender/imp/gltf2_blender_gltf.py). Mesh data is
// converted, so instance transforms are C * world_gltf * C^-1 (C = blender_from_gltf). glTF
// cameras and lights look down their local -Z with +Y up; after the conversion Blender's
// importer appends a +90 degree rotation about local X (camera_correction), which makes
// world_from_camera and world_from_light equal C * world_gltf.
//
// UVs: glTF's texture origin is the top-left corner, Blender's the bottom-left: v = 1 - v_gltf.
// TEXCOORD_n becomes UV set "UVMap" (n = 0) or "UVMap.00n", Blender's importer's names.
// Textures: only the base colour texture is decoded (sRGB -> linear; rows flipped so row 0 is the
// bottom). Material::base_color keeps baseColorFactor (glTF multiplies it with the texture).
//
// Lights (KHR_lights_punctual): glTF point/spot intensity is in candela (lm/sr), directional in
// lux (lm/m^2). In lighting_mode Spec (the importer's default, "Standard"), with
// kPbrWattsToLumens = 683 lm/W (PBR_WATTS_TO_LUMENS, blender/com/gltf2_blender_conversion.py):
//   point and spot power (W) = intensity * 4 pi / 683, sun strength (W/m^2) = lux / 683.
// Spot cones: spot_size = 2 * outerConeAngle, spot_blend = 1 - innerConeAngle / outerConeAngle.
// The importer leaves Blender's new-light defaults for what glTF lacks: point/spot radius 0.25 m
// and sun angle 0.526 degrees (checked in Blender 3.4.1); set them to 0 for truly punctual lights.
//
// Cameras: the first camera node met in a depth-first walk of the scene's nodes. Perspective:
// sensor_fit Vertical, lens = sensor_height / (2 tan(yfov / 2)) (Blender's angle_y setter);
// aspectRatio, when given, sets resolution_x = round(resolution_y * aspectRatio). Orthographic:
// ortho_scale = 2 max(xmag, ymag), resolution from xmag / ymag. An infinite zfar becomes
// kGltfInfiniteClipEnd, as the importer does.
//
// Errors: everything wrong with the file (missing, unparsable, accessor or index out of range,
// unsupported required extensions, sparse or bufferView-less accessors, a node hierarchy with a
// cycle) throws IoError naming the file and the offending element;
// recoverable problems (non-triangle primitives, undecodable images, ...) are log_warning()s.
// Not imported: animations, skins, morph targets, textures other than base colour,
// KHR_texture_transform, alpha.
#pragma once

#include <cstdint>
#include <string>

#include "scene/scene.h"
#include "util/math.h"
#include "util/progress.h"

namespace shgi {

// Source: PBR_WATTS_TO_LUMENS in Blender 3.4's io_scene_gltf2 (the luminous efficacy of
// 555 nm light, which the importer uses for every colour).
inline constexpr float kPbrWattsToLumens = 683.0f;
// Source: the importer's clip_end for a perspective camera without zfar (infinite projection).
inline constexpr float kGltfInfiniteClipEnd = 1e12f;
// Source: bpy.data.lights.new() defaults in Blender 3.4.1 (shadow_soft_size, and sun angle
// DEG2RADF(0.526) in DNA_light_defaults.h), which the glTF importer does not change.
inline constexpr float kBlenderDefaultLightRadius = 0.25f;
inline constexpr float kBlenderDefaultSunAngle = 0.526f * kPi / 180.0f;

// Mirrors the importer's "Lighting Mode" (convert_lighting_mode).
enum class GltfLightingMode : uint8_t {
    Spec,    // "Standard": physically based units, W = lm / 683 (see above)
    Compat,  // "Unitless": W = cd * 4 pi, sun strength = lux
    Raw,     // "Raw (Deprecated)": power = intensity, strength = intensity
};

struct GltfLoadOptions {
    GltfLightingMode lighting_mode = GltfLightingMode::Spec;
    bool import_lights = true;    // KHR_lights_punctual lights -> Scene lights
    bool import_camera = true;    // the first camera node -> Scene camera
    bool import_textures = true;  // decode base colour textures
    float light_radius = kBlenderDefaultLightRadius;  // m: Light::radius of point and spot lights
    float sun_angle = kBlenderDefaultSunAngle;        // rad: Light::angle of suns
};

// Loads the default scene of a .gltf or .glb file (all root nodes when it defines no scenes).
// Each glTF mesh used by a node becomes one Mesh (shared by every node using it), its TRIANGLES
// primitives merged with a material per triangle as Blender's material slots, and each use one
// Instance named after the node. Throws IoError naming `path` on any failure.
// Progress: "reading" (the file, its buffers and images; cancel is polled before and between
// images, as tinygltf parses the JSON and buffers in one call) then "importing" (node by node,
// each mesh built at its first use); Cancelled within one image or one node.
Scene load_gltf(const std::string& path, const GltfLoadOptions& options = {},
                Progress* progress = nullptr);

// C in the header text above: Blender (Z-up) coordinates from glTF (Y-up) coordinates.
mat4 blender_from_gltf();

// Light unit conversions (see above); `intensity` in cd, `illuminance` in lux.
float gltf_point_power(float intensity, GltfLightingMode mode);
float gltf_sun_strength(float illuminance, GltfLightingMode mode);

}  // namespace shgi
