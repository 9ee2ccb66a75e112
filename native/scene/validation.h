// Input checks shared by the scene module's validate_* functions (mesh, material, light, camera,
// instances).
//
// Each check throws InvalidArgument with a message "<item>: <field> = <value> <what is wrong>"
// so that the artist can find the object in Blender: the item is labelled by kind and name
// ("material 'Red'"), the field by its Blender/SHGI name, and both compared values are printed.
// Private to native/scene, except require_transform, which also checks probe volumes
// (native/probes): other modules see only the validate_* functions.
#pragma once

#include <string>

#include "scene/ray.h"  // kMaxCoordinate
#include "util/math.h"

namespace shgi::scene_detail {

// A 3x3 linear part whose |det| is below this fraction of the product of its column lengths is
// treated as singular: it flattens space (e.g. a Blender scale of 0 along one axis).
inline constexpr double kMinRelativeDeterminant = 1e-9;

// "'Cube'" or "#3" for an unnamed item: labels stay readable when the exporter left names empty.
std::string label(const char* kind, const std::string& name);

std::string to_string(const vec2& v);
std::string to_string(const vec3& v);

void require_finite(const std::string& item, const char* field, float value);
void require_finite(const std::string& item, const char* field, const vec3& value);
// Finite and every component >= 0 (colours, powers).
void require_non_negative(const std::string& item, const char* field, float value);
void require_non_negative(const std::string& item, const char* field, const vec3& value);
void require_positive(const std::string& item, const char* field, float value);
// lo <= value <= hi (closed interval), value finite.
void require_in_range(const std::string& item, const char* field, float value, float lo,
                      float hi);

// True when the upper-left 3x3 of m is singular in the sense of kMinRelativeDeterminant.
bool is_singular(const mat4& m);
// Finite entries, non-singular linear part, translation within kMaxCoordinate, bottom row
// (0, 0, 0, 1). (The scale is the caller's to bound: an instance's reach is checked on its world
// bounds at commit, a light's on its size.)
void require_transform(const std::string& item, const char* field, const mat4& m);
// The largest length of the linear part's columns: how much m stretches an axis.
double max_axis_scale(const mat4& m);

}  // namespace shgi::scene_detail
