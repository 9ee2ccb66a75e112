// Error hierarchy of SHGI (docs/architecture.md, "Errors").
//
// Native code never calls exit/abort: a crash would take Blender and the artist's unsaved work
// down with it. Every failure is one of these exceptions, whose message names the offending
// input and, where there is one, the fix. The Python bindings map them to Python exceptions
// (InvalidArgument -> ValueError, IoError -> OSError, Cancelled -> shgi.Cancelled,
// OutOfMemory -> MemoryError, Internal -> RuntimeError).
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace shgi {

class Error : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// Bad input from the caller: wrong sizes, NaN/Inf, out-of-range indices or values.
class InvalidArgument : public Error {
  public:
    using Error::Error;
};

// A file could not be read or written, or its contents are malformed.
class IoError : public Error {
  public:
    using Error::Error;
};

// The caller asked a long operation to stop (Progress::cancel()).
class Cancelled : public Error {
  public:
    Cancelled() : Error("operation cancelled") {}
    using Error::Error;
};

// A memory budget was exceeded, or an allocation failed.
class OutOfMemory : public Error {
  public:
    using Error::Error;
};

// A broken invariant inside SHGI: a bug, reported instead of aborting.
class Internal : public Error {
  public:
    using Error::Error;
};

// Builds a message from streamable parts: format_message("positions[", i, "] is ", v).
template <typename... Parts>
std::string format_message(Parts&&... parts) {
    std::ostringstream out;
    (out << ... << std::forward<Parts>(parts));
    return out.str();
}

}  // namespace shgi
