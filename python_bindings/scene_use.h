// Guards a Scene against edits while another Python thread commits, queries or renders it.
//
// Bindings release the GIL for native work on a Scene; without a guard another Python thread
// could add a mesh meanwhile and reallocate the arrays the work is reading. Every binding that
// releases the GIL over a Scene constructs a SceneUse first (so it is destroyed after the GIL is
// taken back); conflicting uses raise RuntimeError naming the method. The bookkeeping is only
// touched with the GIL held, which serialises it.
#pragma once

#include "scene/scene.h"

namespace shgi::python {

class SceneUse {
  public:
    // Query: any number at once (intersect, render). Commit: alone. Edit: holds the GIL
    // throughout, so it only checks that no query or commit is running.
    enum class Kind { Query, Commit, Edit };

    SceneUse(const Scene& scene, Kind kind, const char* method);
    ~SceneUse();
    SceneUse(const SceneUse&) = delete;
    SceneUse& operator=(const SceneUse&) = delete;

  private:
    const Scene* scene_;
    Kind kind_;
};

}  // namespace shgi::python
