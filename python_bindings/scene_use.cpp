#include "scene_use.h"

#include <stdexcept>
#include <string>
#include <unordered_map>

namespace shgi::python {
namespace {

// Scenes in use by a call that released the GIL: n > 0 running queries, or -1 for a commit.
// Never destroyed, because a worker may still hold a guard while the interpreter shuts down.
std::unordered_map<const Scene*, int>& scene_users() {
    static auto* users = new std::unordered_map<const Scene*, int>();
    return *users;
}

}  // namespace

SceneUse::SceneUse(const Scene& scene, Kind kind, const char* method)
    : scene_(&scene), kind_(kind) {
    auto& users = scene_users();
    const auto it = users.find(scene_);
    const int current = it == users.end() ? 0 : it->second;
    if (current < 0 || (kind != Kind::Query && current > 0))
        throw std::runtime_error(std::string("Scene.") + method +
                                 ": the scene is being committed or queried in another thread "
                                 "(intersect, occluded or a render); wait for that call to "
                                 "return");
    if (kind == Kind::Edit) return;  // edits hold the GIL throughout: nothing to mark
    users[scene_] = kind == Kind::Commit ? -1 : current + 1;
}

SceneUse::~SceneUse() {
    if (kind_ == Kind::Edit) return;
    auto& users = scene_users();
    const auto it = users.find(scene_);
    if (it == users.end()) return;
    if (kind_ == Kind::Commit || --it->second == 0) users.erase(it);
}

}  // namespace shgi::python
