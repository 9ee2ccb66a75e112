#include "scene_use.h"

#include <stdexcept>
#include <unordered_map>

namespace shgi::python {
namespace {

// Objects in use by a call that released the GIL: n > 0 running reads, or -1 for a write.
// Never destroyed, because a worker may still hold a guard while the interpreter shuts down.
std::unordered_map<const void*, int>& object_users() {
    static auto* users = new std::unordered_map<const void*, int>();
    return *users;
}

ObjectUse::Kind object_kind(SceneUse::Kind kind) {
    switch (kind) {
        case SceneUse::Kind::Query: return ObjectUse::Kind::Read;
        case SceneUse::Kind::Commit: return ObjectUse::Kind::Write;
        default: return ObjectUse::Kind::CheckIdle;
    }
}

}  // namespace

ObjectUse::ObjectUse(const void* object, Kind kind, const std::string& method, const char* busy)
    : object_(object), kind_(object != nullptr ? kind : Kind::Check) {
    if (object == nullptr) return;  // no field: nothing to guard
    auto& users = object_users();
    const auto it = users.find(object_);
    const int current = it == users.end() ? 0 : it->second;
    const bool reads = kind == Kind::Read || kind == Kind::Check;
    if (current < 0 || (!reads && current > 0))
        throw std::runtime_error(method + ": " + busy);
    if (kind == Kind::Check || kind == Kind::CheckIdle) return;  // nothing to mark
    users[object_] = kind == Kind::Write ? -1 : current + 1;
}

ObjectUse::~ObjectUse() {
    if (kind_ == Kind::Check || kind_ == Kind::CheckIdle) return;
    auto& users = object_users();
    const auto it = users.find(object_);
    if (it == users.end()) return;
    if (kind_ == Kind::Write || --it->second == 0) users.erase(it);
}

SceneUse::SceneUse(const Scene& scene, Kind kind, const char* method)
    : use_(&scene, object_kind(kind), std::string("Scene.") + method,
           "the scene is being committed or queried in another thread (intersect, occluded or "
           "a render); wait for that call to return") {}

}  // namespace shgi::python
