// Meshes shared by the scene tests: a unit quad whose hits, normals and UVs are known exactly.
#pragma once

#include <string>
#include <utility>

#include "scene/mesh.h"

namespace shgi::test {

// Unit quad in the XY plane, facing +Z: triangle 0 = (0,0),(1,0),(1,1); triangle 1 the rest.
// Smooth normals +Z, one UV set "UVMap" equal to the xy coordinates, no material indices.
inline Mesh unit_quad(std::string name = "Quad") {
    Mesh mesh;
    mesh.name = std::move(name);
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    mesh.uv_sets = {{"UVMap", {{0, 0}, {1, 0}, {1, 1}, {0, 1}}}};
    return mesh;
}

}  // namespace shgi::test
