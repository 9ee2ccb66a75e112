// Long native calls from Python (see interruptible.h).
#include "interruptible.h"

#include <pybind11/pybind11.h>

#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

#include "util/error.h"

namespace shgi::python {

namespace py = pybind11;

PythonError::PythonError(py::error_already_set& error)
    : std::runtime_error(error.what()),
      exception_(new py::object(error.value()), [](py::object* exception) {
          py::gil_scoped_acquire gil;
          delete exception;
      }) {
    if (error.trace()) PyException_SetTraceback(error.value().ptr(), error.trace().ptr());
}

namespace {

// Raises what the work's Progress callback raised, when it did (GIL held), and returns when it
// did not: a BaseException that is no Exception (KeyboardInterrupt, SystemExit) as itself, any
// other as the __cause__ of shgi.Cancelled.
void raise_callback_failure(const Progress& progress) {
    const std::exception_ptr failure = progress.callback_failure();
    if (!failure) return;
    py::object exception;
    try {
        std::rethrow_exception(failure);
    } catch (const PythonError& error) {
        exception = error.exception();
    } catch (...) {
        return;  // a native callback's failure: the work's own Cancelled says enough
    }
    PyObject* type = reinterpret_cast<PyObject*>(Py_TYPE(exception.ptr()));
    if (!PyObject_IsInstance(exception.ptr(), PyExc_Exception)) {
        PyErr_SetObject(type, exception.ptr());
        throw py::error_already_set();
    }
    const py::object cancelled_type = py::module_::import("shgi._shgi").attr("Cancelled");
    const py::object cancelled = cancelled_type(
        "the progress callback raised " + py::str(py::handle(type).attr("__name__")).cast<std::string>() +
        ", which cancelled the work: " + py::str(exception).cast<std::string>());
    PyException_SetCause(cancelled.ptr(), exception.release().ptr());  // steals the reference
    PyErr_SetObject(cancelled_type.ptr(), cancelled.ptr());
    throw py::error_already_set();
}

}  // namespace

void run_interruptible_work(Progress* progress, const std::function<void(Progress*)>& work) {
    Progress own_progress;
    Progress* used = progress ? progress : &own_progress;
    if (!_PyOS_IsMainThread()) {
        try {
            py::gil_scoped_release release;
            work(used);
        } catch (const Cancelled&) {
            raise_callback_failure(*used);
            throw;
        }
        return;
    }
    std::mutex mutex;
    std::condition_variable finished;
    bool done = false;
    std::exception_ptr failure;
    bool interrupted = false;
    {
        py::gil_scoped_release release;
        std::thread worker([&] {
            try {
                work(used);
            } catch (...) {
                failure = std::current_exception();
            }
            std::lock_guard<std::mutex> lock(mutex);
            done = true;
            finished.notify_one();
        });
        std::unique_lock<std::mutex> lock(mutex);
        while (!finished.wait_for(lock, kSignalPollInterval, [&] { return done; })) {
            if (interrupted) continue;  // cancelled: only wait for the work to stop
            lock.unlock();
            {
                py::gil_scoped_acquire gil;
                // A raising handler leaves its exception set, for error_already_set below.
                interrupted = PyErr_CheckSignals() != 0;
            }
            if (interrupted) used->cancel();
            lock.lock();
        }
        lock.unlock();
        worker.join();
    }
    if (interrupted) throw py::error_already_set();
    if (failure) {
        raise_callback_failure(*used);
        std::rethrow_exception(failure);
    }
}

}  // namespace shgi::python
