// GiSolver: the one interface every GI method implements (docs/solvers.md). A solver is a value
// its caller owns: it is built from a committed Scene and its settings struct (the method's row in
// methods/method_registry.h says which), refined pass by pass, and read through an IndirectField.
//
// The contract every method keeps (tests/cpp/methods/method_conformance_test.cpp checks it for
// each registered method):
// - refine(progress): one refinement pass (a photon pass, a probe update pass, ...), reported
//   monotonically on `progress` and cancellable within 0.2 s; a cancelled pass throws Cancelled
//   and leaves the previous solution as it was.
// - current_field(): the field to render, valid (and unchanged) until the next refine() or reset().
//   Methods that publish immutable snapshots (the probe grid) return one that stays valid after
//   later passes; the others return the solver itself, which must not be read while a pass runs
//   (the bindings refuse that). Before the first pass it is a field that holds no light.
// - reset(progress): forgets every pass and re-reads the (re-committed) scene.
// - stage_seconds(): wall time of the stages of the last pass, by name, in pass order.
// - memory_bytes(): bytes the solution holds.
// Results are deterministic: the same seed gives the same bits for any thread count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "render/indirect_field.h"
#include "util/progress.h"

namespace shgi {

// Seconds of one named stage of a pass ("emit_trace", "update", ...).
struct StageSeconds {
    std::string stage;
    double seconds = 0.0;
};

class GiSolver {
  public:
    virtual ~GiSolver() = default;

    virtual void refine(Progress* progress = nullptr) = 0;
    virtual void reset(Progress* progress = nullptr) = 0;
    virtual uint64_t passes() const = 0;
    virtual std::shared_ptr<const IndirectField> current_field() const = 0;
    virtual std::vector<StageSeconds> stage_seconds() const = 0;
    virtual size_t memory_bytes() const = 0;
};

}  // namespace shgi
