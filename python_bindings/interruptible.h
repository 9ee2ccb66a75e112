// Long native calls from Python, with the GIL released and Ctrl-C answered.
//
// With the GIL released, Python sees a SIGINT only when its main thread next runs bytecode, and
// a long native call holds that off: a render or a solve ignored Ctrl-C for 20 s and more in a
// plain script. On Python's main thread the work therefore runs on a worker thread while the
// calling thread waits, taking the GIL every kSignalPollInterval only to run Python's pending
// signal handlers (PyErr_CheckSignals). When a handler raises (KeyboardInterrupt, from Ctrl-C),
// the work's Progress is cancelled, the work stops at its next cancel poll (< 0.2 s, see
// util/progress.h) and the handler's exception is raised in place of the work's Cancelled. A
// handler that does not raise changes nothing. On any other thread (Blender's workers, a
// script's threads), where Python runs no signal handlers, the work runs in place.
//
// The work gets a Progress in every case: the caller's, or one of its own when the caller passed
// none, so that a Ctrl-C has something to cancel. When the work was cancelled because the
// Progress's Python callback raised, that exception is raised instead of a bare Cancelled: a
// KeyboardInterrupt (or another BaseException) as itself, anything else as the __cause__ of
// shgi.Cancelled.
#pragma once

#include <pybind11/pybind11.h>

#include <chrono>
#include <functional>
#include <memory>
#include <stdexcept>
#include <optional>
#include <type_traits>

#include "util/progress.h"

namespace shgi::python {

// A Python exception carried through native code: a Python callback (progress, log sink) that
// raised on any thread throws it, native code holds it without the GIL, and the binding that
// called into native code raises it again in Python.
class PythonError : public std::runtime_error {
  public:
    // Takes the exception of `error` (GIL held), its traceback attached.
    explicit PythonError(pybind11::error_already_set& error);
    // The exception object (GIL held).
    pybind11::object exception() const { return *exception_; }

  private:
    std::shared_ptr<pybind11::object> exception_;  // released with the GIL taken
};

// Often enough that the wait adds little to the work's own cancel latency (< 0.2 s in all).
constexpr std::chrono::milliseconds kSignalPollInterval{20};

// Runs work(Progress*) with the GIL released (call it with the GIL held); on the main thread, as
// the file header says. Rethrows what the work threw.
void run_interruptible_work(Progress* progress, const std::function<void(Progress*)>& work);

// run_interruptible_work, returning what the work returns.
template <class Work>
auto run_interruptible(Progress* progress, Work&& work) {
    using Result = decltype(work(progress));
    if constexpr (std::is_void_v<Result>) {
        run_interruptible_work(progress, work);
    } else {
        std::optional<Result> result;
        run_interruptible_work(progress, [&](Progress* used) { result.emplace(work(used)); });
        return std::move(*result);
    }
}

}  // namespace shgi::python
