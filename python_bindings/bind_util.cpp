// Bindings for native/util: exception mapping, Progress, the log sink, thread count, version.
//
// Exceptions (docs/architecture.md, "Errors"): InvalidArgument -> ValueError, IoError -> OSError,
// OutOfMemory -> MemoryError, Cancelled -> shgi.Cancelled, Internal and other shgi::Error ->
// RuntimeError.
//
// Callbacks into Python (progress, log sink) may run on TBB worker threads: they take the GIL
// themselves. To keep that deadlock-free, every binding that runs parallel work releases the GIL,
// and the Python-side accessors here release it before taking a native mutex.
#include <cstring>
#include <memory>
#include <mutex>

#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <tbb/global_control.h>

#include "interruptible.h"
#include "struct_fields.h"
#include "util/error.h"
#include "util/log.h"
#include "util/memory.h"
#include "util/parallel.h"
#include "util/progress.h"
#include "util/version.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

// Holds a Python callable; copies and the final release take the GIL, so the object can live in
// std::function values owned by native code.
class PyCallable {
  public:
    explicit PyCallable(py::function function)
        : function_(new py::function(std::move(function)), [](py::function* f) {
              py::gil_scoped_acquire gil;
              delete f;
          }) {}

    template <typename... Args>
    void operator()(Args&&... args) const {
        py::gil_scoped_acquire gil;
        try {
            (*function_)(std::forward<Args>(args)...);
        } catch (py::error_already_set& error) {
            // Native code reacts (Progress cancels and keeps it for the caller, see
            // interruptible.h; the log sink reports it and falls back to stderr).
            throw PythonError(error);
        }
    }

  private:
    std::shared_ptr<py::function> function_;
};

std::unique_ptr<tbb::global_control>& thread_limit() {
    static std::unique_ptr<tbb::global_control> limit;
    return limit;
}

// A native message (an error or a log line) as a new str reference, or null with the Python
// error set (out of memory). Messages quote paths and names from files, which need not be UTF-8:
// a strict decode would turn the message into a bare UnicodeDecodeError, so undecodable bytes are
// shown as \xNN escapes.
PyObject* native_text(const char* message, size_t size) {
    return PyUnicode_DecodeUTF8(message, Py_ssize_t(size), "backslashreplace");
}

// Sets the Python error `type` with a native message (PyErr_SetString decodes strictly).
void set_error(PyObject* type, const char* message) {
    PyObject* text = native_text(message, std::strlen(message));
    if (text == nullptr) return;  // out of memory: that error is set
    PyErr_SetObject(type, text);
    Py_DECREF(text);
}

void register_exceptions(py::module_& m) {
    static py::exception<Cancelled> cancelled(m, "Cancelled", PyExc_Exception);
    cancelled.doc() = "Raised when a long operation stops because Progress.cancel() was called.";
    py::register_exception_translator([](std::exception_ptr pointer) {
        if (!pointer) return;
        try {
            std::rethrow_exception(pointer);
        } catch (const Cancelled& error) {
            set_error(cancelled.ptr(), error.what());
        } catch (const InvalidArgument& error) {
            set_error(PyExc_ValueError, error.what());
        } catch (const IoError& error) {
            set_error(PyExc_OSError, error.what());
        } catch (const OutOfMemory& error) {
            set_error(PyExc_MemoryError, error.what());
        } catch (const Error& error) {
            set_error(PyExc_RuntimeError, error.what());
        }
    });
}

void bind_progress(py::module_& m) {
    py::class_<Progress>(m, "Progress", R"doc(
Progress and cancellation of a long operation.

Pass one to any long call (``progress=``). ``cancel()`` from another thread makes the call stop
within one chunk of work and raise ``shgi.Cancelled``. The optional ``callback(fraction, stage)``
is called at most every ``min_interval`` seconds, possibly from a worker thread.)doc")
        .def(py::init([](std::optional<py::function> callback, double min_interval) {
                 if (!callback) return std::make_unique<Progress>();
                 return std::make_unique<Progress>(
                     Progress::Callback(PyCallable(std::move(*callback))), min_interval);
             }),
             py::arg("callback") = py::none(), py::arg("min_interval") = 0.05,
             "Creates a Progress; callback(fraction: float, stage: str) is optional.")
        .def("cancel", &Progress::cancel, "Asks the operation to stop as soon as possible.")
        .def_property_readonly("cancelled", &Progress::cancelled,
                               "True once cancel() was called.")
        .def_property_readonly("fraction", &Progress::fraction,
                               "Fraction of the work done, in [0, 1].")
        .def_property_readonly(
            "stage",
            [](const Progress& progress) { return progress.stage(); },
            "Name of the current stage.");
}

void bind_logging(py::module_& m) {
    named_values_only(py::enum_<LogLevel>(m, "LogLevel", "Severity of a log message.")
        .value("DEBUG", LogLevel::Debug)
        .value("INFO", LogLevel::Info)
        .value("WARNING", LogLevel::Warning)
        .value("ERROR", LogLevel::Error));
    m.def(
        "set_log_sink",
        [](std::optional<py::function> sink) {
            LogSink native_sink;
            if (sink) {
                PyCallable callable(std::move(*sink));
                native_sink = [callable](LogLevel level, const std::string& message) {
                    // A strict decode of a message quoting an OBJ's non-UTF-8 material name
                    // lost the message to a UnicodeDecodeError.
                    py::gil_scoped_acquire gil;
                    PyObject* decoded = native_text(message.data(), message.size());
                    if (decoded == nullptr) throw py::error_already_set();
                    try {
                        callable(level, py::reinterpret_steal<py::str>(decoded));
                    } catch (const PythonError& error) {
                        // Reported the way Python reports errors in callbacks.
                        PyErr_SetObject(reinterpret_cast<PyObject*>(
                                            Py_TYPE(error.exception().ptr())),
                                        error.exception().ptr());
                        py::error_already_set().discard_as_unraisable("shgi log sink");
                        throw;
                    }
                };
            }
            LogSink previous;
            {
                py::gil_scoped_release release;  // a worker may hold the log mutex
                previous = set_log_sink(std::move(native_sink));
            }
        },
        py::arg("sink"),
        "Routes SHGI's log messages to sink(level: LogLevel, message: str); None restores "
        "stderr. The shgi package installs a sink that forwards to logging.getLogger('shgi').");
    m.def("set_log_level", &set_log_level, py::arg("level"),
          "Drops messages below `level` before they reach the sink.");
    m.def("log_level", &log_level, "The current minimum log level.");
}

}  // namespace

void bind_util(py::module_& m) {
    register_exceptions(m);
    bind_progress(m);
    bind_logging(m);
    m.def("version", &version, "SHGI's version string.");
    m.def(
        "set_max_threads",
        [](const IndexInt& threads_arg) {
            // 0 = all cores; TBB takes a size_t, and no machine has 2^31 cores.
            const int threads = int_arg<int>(threads_arg, "threads", 0,
                                             std::numeric_limits<int>::max());
            thread_limit().reset();
            if (threads > 0)
                thread_limit() = std::make_unique<tbb::global_control>(
                    tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
        },
        py::arg("threads"),
        "Limits SHGI's worker threads (0 = all cores). Results do not depend on it.");
    m.def("max_threads", &max_threads, "The number of worker threads SHGI may use.");
    m.def(
        "memory_limits",
        [] {
            const MemoryLimits limits = memory_limits();
            const auto bytes = [](uint64_t value) -> py::object {
                if (value == UINT64_MAX) return py::none();
                return py::int_(value);
            };
            py::dict out;
            out["address_space_left"] = bytes(limits.address_space_left);
            out["cgroup_left"] = bytes(limits.cgroup_left);
            out["available"] = bytes(limits.available);
            out["allowed"] = bytes(limits.allowed());
            out["limited_by"] = limits.binding();
            return out;
        },
        "The bytes this process may still allocate, as every large allocation checks them first "
        "(docs/robustness-memory.md): {'address_space_left': RLIMIT_AS minus the virtual size, "
        "'cgroup_left': the cgroup memory limit minus its usage, 'available': MemAvailable, "
        "'allowed': the smallest, 'limited_by': which}; None where there is no such limit.");
    // Drop Python objects held by native code before the interpreter finalises.
    py::module_::import("atexit").attr("register")(py::cpp_function([]() {
        LogSink previous;
        {
            py::gil_scoped_release release;
            previous = set_log_sink(LogSink());
        }
        thread_limit().reset();
    }));
}

}  // namespace shgi::python
