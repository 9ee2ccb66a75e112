// Guards native objects against conflicting use from several Python threads.
//
// Bindings release the GIL for native work; without a guard another Python thread could change
// the object meanwhile: add a mesh to a Scene and reallocate the arrays a render is reading,
// solve a PhotonLattice while a render reads its lattices, render twice into one film at once.
// Every binding that releases the GIL over such an object constructs a guard first (so it is
// destroyed after the GIL is taken back); a conflicting use raises RuntimeError naming the
// method and what it waits for, instead of a data race that corrupts the result or crashes the
// host. The bookkeeping is only touched with the GIL held, which serialises it; no guard waits,
// so a progress callback that calls back into a busy object gets the error, not a deadlock.
#pragma once

#include <string>

#include "scene/scene.h"

namespace shgi::python {

// One object's use by one call.
class ObjectUse {
  public:
    // Read: any number at once. Write: alone. Check (a call that holds the GIL throughout, so
    // only needs the object free of writes) and CheckIdle (free of every use) mark nothing.
    enum class Kind { Read, Write, Check, CheckIdle };

    // On a conflict raises RuntimeError("<method>: <busy>").
    ObjectUse(const void* object, Kind kind, const std::string& method, const char* busy);
    ~ObjectUse();
    ObjectUse(const ObjectUse&) = delete;
    ObjectUse& operator=(const ObjectUse&) = delete;

  private:
    const void* object_;
    Kind kind_;
};

class SceneUse {
  public:
    // Query: any number at once (intersect, render). Commit: alone. Edit: holds the GIL
    // throughout, so it only checks that no query or commit is running.
    enum class Kind { Query, Commit, Edit };

    SceneUse(const Scene& scene, Kind kind, const char* method);

  private:
    ObjectUse use_;
};

// A PreviewRenderer or PathTracer: render() writes its film; passes() and timings read it.
inline ObjectUse renderer_use(const void* renderer, const char* type, const char* method,
                              bool render) {
    return ObjectUse(renderer, render ? ObjectUse::Kind::Write : ObjectUse::Kind::Check,
                     std::string(type) + "." + method,
                     "a render() of this renderer is running in another thread; wait for it to "
                     "return");
}

// An IndirectField: solve() and reset() of a PhotonLattice write it; renders, bakes and lookups
// read it. (A ProbeGrid's update() works on a copy and publishes snapshots: it is not guarded.)
inline ObjectUse field_use(const void* field, ObjectUse::Kind kind, const std::string& method) {
    return ObjectUse(field, kind, method,
                     kind == ObjectUse::Kind::Read || kind == ObjectUse::Kind::Check
                         ? "the field is being solved or reset in another thread; wait for "
                           "that call to return"
                         : "the field is in use in another thread (a render, bake or lookup, "
                           "or another solve); wait for that call to return");
}

}  // namespace shgi::python
